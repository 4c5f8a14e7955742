//! The memory estimate of a kinematic drape (`drape::memory::net_bytes`,
//! which refuses nets that cannot fit) against the peak a drape really
//! takes. Alone in its test binary: the process's high-water mark is the
//! drape's.

/// A process's resident size now and at its peak (kB), from
/// `/proc/self/status`.
#[cfg(target_os = "linux")]
fn rss_kb() -> (u64, u64) {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let field = |name: &str| -> u64 {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.trim().strip_suffix("kB"))
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or_else(|| panic!("{name} in /proc/self/status"))
    };
    (field("VmRSS:"), field("VmHWM:"))
}

/// The hemisphere's 350 mm blank at 1 mm spacing (126 000 lattice
/// crossings, 122 500 cells) with its VTU frame, pictures and
/// orientations: the estimate covers the peak, and by no more than 60 %
/// (a guard that over-estimates refuses nets that fit).
#[cfg(target_os = "linux")]
#[test]
fn the_estimate_covers_the_peak_of_a_drape_and_not_by_much() {
    use drape_io::scene::Scene;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scene = Scene::from_file(
        &root.join("scenes/hemisphere-0-90.toml"),
        &[("kinematic.spacing".to_owned(), "1".to_owned())],
    )
    .unwrap();
    let estimate = drape::memory::net_bytes(&scene.kinematic.as_ref().unwrap().net);
    let out = std::env::temp_dir().join(format!("drape-memory-{}", std::process::id()));
    let (before, _) = rss_kb();
    let report = drape::kinematic_scene(&scene, &out).unwrap();
    let (_, peak) = rss_kb();
    assert_eq!(report.stats.draped_cells, 122_500);
    let used = (peak - before) * 1024;
    eprintln!("estimate {estimate} bytes, peak above the start {used} bytes");
    assert!(used <= estimate, "used {used} > estimate {estimate}");
    assert!(
        estimate as f64 <= 1.6 * used as f64,
        "estimate {estimate} far above the {used} used"
    );
    std::fs::remove_dir_all(out).unwrap();
}
