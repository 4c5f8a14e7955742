//! Memory guards from estimates: what a piece of work will need, against
//! what the machine has, checked before the work starts, so that a size
//! that cannot fit is refused with its estimate (bad input, exit 2)
//! instead of aborting on a failed allocation half-way.
//!
//! The memory available is the kernel's own estimate of what can be
//! allocated without swapping (`MemAvailable` in `/proc/meminfo`), lowered
//! to a cgroup's (v2) limit less its usage when the process runs under one
//! (a container, a batch scheduler's job). Where neither can be read
//! (another operating system) a fixed [`FALLBACK_BYTES`] stands in:
//! refusing a large net there is better than an abort, and the message
//! says the figure is assumed.
//!
//! Not here: the step and frame counts of a run (`limits.rs`).

use drape_fishnet::NetSpec;

/// Bytes per draped cell of a kinematic net beyond the net's own arrays
/// ([`NetSpec::lattice_bytes`]): the net as a model, state, element fields
/// and measures, and the frame, pictures and orientations written from
/// them. Measured as the peak resident size of `drape kinematic` on the
/// hemisphere scene with VTU and pictures on: 209 MB at 1 mm spacing
/// (122 500 cells), 810 MB at 0.5 mm (490 000 cells), 1.64 kB a cell from
/// the difference; this is that less the lattice's ~0.1 kB, rounded up.
/// `tests/kinematic_memory.rs` checks the estimate against a measured peak.
pub const NET_RESULTS_BYTES_PER_CELL: u64 = 1600;

/// What any kinematic drape needs besides its cells (the program, a mould
/// mesh, the picture canvases).
pub const NET_BASE_BYTES: u64 = 64 << 20;

/// The memory assumed available where the system does not say (8 GiB).
pub const FALLBACK_BYTES: u64 = 8 << 30;

/// The bytes a kinematic drape of `spec` needs at its peak, from its
/// lattice: every lattice crossing counted as a cell that is draped (an
/// unrotated net's lattice is its cells and one more row all round).
pub fn net_bytes(spec: &NetSpec) -> u64 {
    spec.lattice_bytes()
        .saturating_add(
            spec.lattice_crossings()
                .saturating_mul(NET_RESULTS_BYTES_PER_CELL),
        )
        .saturating_add(NET_BASE_BYTES)
}

/// Memory this process can use: bytes, and where the figure comes from.
#[derive(Debug, Clone, PartialEq)]
pub struct Available {
    /// Bytes.
    pub bytes: u64,
    /// Where the figure comes from, for messages.
    pub source: &'static str,
}

/// The memory available now (see the module's docs).
pub fn available_memory() -> Available {
    let meminfo = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| mem_available(&t));
    let cgroup = cgroup_room();
    match (meminfo, cgroup) {
        (Some(m), Some(c)) if c < m => Available {
            bytes: c,
            source: "this process's cgroup memory limit less its usage",
        },
        (Some(m), _) => Available {
            bytes: m,
            source: "MemAvailable in /proc/meminfo",
        },
        (None, Some(c)) => Available {
            bytes: c,
            source: "this process's cgroup memory limit less its usage",
        },
        (None, None) => Available {
            bytes: FALLBACK_BYTES,
            source: "assumed: the system does not say",
        },
    }
}

/// `MemAvailable` of a `/proc/meminfo` text, in bytes.
fn mem_available(meminfo: &str) -> Option<u64> {
    meminfo.lines().find_map(|line| {
        let rest = line.strip_prefix("MemAvailable:")?;
        let kib: u64 = rest.trim().strip_suffix("kB")?.trim().parse().ok()?;
        Some(kib.saturating_mul(1024))
    })
}

/// A cgroup v2 limit less its usage, for the process's own cgroup; None
/// without one (or with `max`).
fn cgroup_room() -> Option<u64> {
    let own = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = own.lines().find_map(|l| l.strip_prefix("0::"))?.trim();
    let dir = std::path::Path::new("/sys/fs/cgroup").join(path.trim_start_matches('/'));
    let read = |name: &str| -> Option<u64> {
        std::fs::read_to_string(dir.join(name))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    let max = read("memory.max")?;
    Some(max.saturating_sub(read("memory.current").unwrap_or(0)))
}

/// Bytes as a person reads them: "80.2 GB".
pub fn bytes_text(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else {
        format!("{:.0} MB", b / 1e6)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_mem_available_in_bytes() {
        let text = "MemTotal:       24000000 kB\nMemFree:  100 kB\nMemAvailable:   23000000 kB\n";
        assert_eq!(mem_available(text), Some(23_000_000 * 1024));
        assert_eq!(mem_available("MemTotal: 5 kB\n"), None);
        assert_eq!(mem_available("MemAvailable: lots\n"), None);
    }

    #[test]
    fn available_memory_is_positive_and_named() {
        let a = available_memory();
        assert!(a.bytes > 0, "{a:?}");
        assert!(!a.source.is_empty());
    }

    #[test]
    fn bytes_read_as_a_person_reads_them() {
        assert_eq!(bytes_text(80_200_000_000), "80.2 GB");
        assert_eq!(bytes_text(64 << 20), "67 MB");
    }
}
