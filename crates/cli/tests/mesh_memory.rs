//! The memory estimates that guard imported meshes
//! ([`drape_io::scene::BLANK_BYTES_PER_ELEMENT`],
//! [`drape_io::scene::TOOL_BYTES_PER_TRIANGLE`]) against what reading a
//! scene and running its first steps take: an estimate below the peak
//! would let through a mesh that does not fit, one far above it would
//! refuse meshes that do.
//!
//! A global allocator that tracks the bytes live and their peak: this
//! file is its own test binary and holds a single test, so nothing else
//! allocates while it measures. One rayon thread: the peak of the pool's
//! queues is not the mesh's.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use drape::RunControl;
use drape_io::scene::{BLANK_BYTES_PER_ELEMENT, Scene, TOOL_BYTES_PER_TRIANGLE};

struct Peak;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(bytes: usize) {
    let now = LIVE.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Peak {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        grew(layout.size());
        // SAFETY: the caller's contract, passed on.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: the caller's contract, passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size >= layout.size() {
            grew(new_size - layout.size());
        } else {
            LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
        }
        // SAFETY: the caller's contract, passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Peak = Peak;

/// A k × k plate of quads (M3D4) as an Abaqus .inp, 1 mm cells.
fn plate_inp(k: usize) -> String {
    let mut s = String::from("*NODE\n");
    for j in 0..=k {
        for i in 0..=k {
            let _ = writeln!(s, "{}, {}, {}, 0", j * (k + 1) + i + 1, i, j);
        }
    }
    s.push_str("*ELEMENT, TYPE=M3D4, ELSET=plate\n");
    for j in 0..k {
        for i in 0..k {
            let n = j * (k + 1) + i + 1;
            let _ = writeln!(
                s,
                "{}, {}, {}, {}, {}",
                j * k + i + 1,
                n,
                n + 1,
                n + k + 2,
                n + k + 1
            );
        }
    }
    s
}

/// A k × k grid of 2k² triangles 1 mm below z = 0, as an ASCII STL.
fn floor_stl(k: usize) -> String {
    let mut s = String::from("solid floor\n");
    let h = 200.0 / k as f64;
    for j in 0..k {
        for i in 0..k {
            let (x, y) = (i as f64 * h - 100.0, j as f64 * h - 100.0);
            for t in [
                [(x, y), (x + h, y), (x + h, y + h)],
                [(x, y), (x + h, y + h), (x, y + h)],
            ] {
                s.push_str("facet normal 0 0 1\nouter loop\n");
                for (a, b) in t {
                    let _ = writeln!(s, "vertex {a} {b} -1");
                }
                s.push_str("endloop\nendfacet\n");
            }
        }
    }
    s.push_str("endsolid floor\n");
    s
}

/// The peak of live bytes above those live at the start, while `f` runs.
fn peak_of(f: impl FnOnce()) -> usize {
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    f();
    PEAK.load(Ordering::Relaxed) - base
}

/// Reads and runs three steps of the scene `text` in `dir`.
fn read_and_run(dir: &Path, text: &str) {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let mut scene = Scene::from_file(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    scene.settings.max_steps = Some(3);
    drape::run_scene(&scene, &dir.join("out"), &mut |_| RunControl::Continue).unwrap();
}

const OUTPUT: &str = "[output]\nvtu = false\npictures = false\n";

#[test]
fn the_mesh_memory_estimates_cover_the_peak_and_not_twice_over() {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a rayon pool")
        .install(measure);
}

fn measure() {
    let dir = common::temp("mesh-memory");
    // The blank: 150 × 150 quads (22 500) on a plane, so the tool is
    // a few bytes.
    let k = 150;
    std::fs::write(dir.join("plate.inp"), plate_inp(k)).unwrap();
    let blank = format!(
        "[simulation]\nend_time = 1e-3\n\n[fabric]\nmaterial = \"glass-serge-4x3\"\n\
         fibres = \"embedded\"\nblank = {{ mesh = \"plate.inp\" }}\n\n[[tools]]\nname = \"floor\"\n\
         friction = 0.1\ngeometry = {{ kind = \"plane\", point = [0, 0, -1], normal = [0, 0, 1] }}\n\n{OUTPUT}"
    );
    let per_element = peak_of(|| read_and_run(&dir, &blank)) as f64 / (k * k) as f64;
    // The tool: 2 × 200² triangles (80 000) under a 4 × 4 rectangle.
    let t = 200;
    std::fs::write(dir.join("floor.stl"), floor_stl(t)).unwrap();
    let tool = format!(
        "[simulation]\nend_time = 1e-3\n\n[fabric]\nmaterial = \"glass-serge-4x3\"\n\
         fibres = \"trusses\"\nblank = {{ width = 40, height = 40, cells = [4, 4] }}\n\n[[tools]]\n\
         name = \"floor\"\nfriction = 0.1\ngeometry = {{ kind = \"mesh\", file = \"floor.stl\" }}\n\n{OUTPUT}"
    );
    let per_triangle = peak_of(|| read_and_run(&dir, &tool)) as f64 / (2 * t * t) as f64;
    eprintln!("peak: {per_element:.0} B per blank element, {per_triangle:.0} B per tool triangle");
    for (what, estimate, measured) in [
        ("blank element", BLANK_BYTES_PER_ELEMENT as f64, per_element),
        (
            "tool triangle",
            TOOL_BYTES_PER_TRIANGLE as f64,
            per_triangle,
        ),
    ] {
        assert!(
            measured <= estimate && estimate <= 2.0 * measured,
            "{what}: the estimate {estimate} B is not within [1, 2] × the measured peak {measured:.0} B"
        );
    }
}
