//! The physical range of a scene's lengths and places, checked where the
//! key is read so that a value past it is named rather than met later as
//! a consequence (a degenerate element, a tool that "starts close to" the
//! blank, a direction that is "not a unit vector").
//!
//! drape works in millimetres with f64: within ±1e9 mm (1000 km) a
//! coordinate still resolves 1e-7 mm, far below any element; past it,
//! differences of coordinates (edges, gaps) lose the digits the mechanics
//! needs, and past 1e154 their squares overflow. A mesh smaller than
//! 1e-6 mm across (a nanometre) is a unit mistake, not a part.
//!
//! Not for a value's type or form (serde's), nor for settings that are not
//! lengths (`build`'s).

use nalgebra::Vector3;

use super::SceneError;
use super::locate::Locator;

/// The largest coordinate or length drape accepts (mm).
pub const MAX_COORDINATE_MM: f64 = 1e9;

/// The smallest size across of a mesh read from a file (mm).
pub const MIN_MESH_SIZE_MM: f64 = 1e-6;

/// A point (mm): finite, every coordinate within ±[`MAX_COORDINATE_MM`].
pub(super) fn position(
    at: &Locator<'_>,
    field: &str,
    v: [f64; 3],
) -> Result<Vector3<f64>, SceneError> {
    if !v.iter().all(|x| x.is_finite()) {
        return Err(at.error(field, "every component must be a finite number"));
    }
    match v.iter().find(|x| x.abs() > MAX_COORDINATE_MM) {
        Some(x) => Err(at.error(field, beyond(*x, "a coordinate"))),
        None => Ok(Vector3::from(v)),
    }
}

/// A length (mm): positive and at most [`MAX_COORDINATE_MM`].
pub(super) fn length(at: &Locator<'_>, field: &str, v: f64) -> Result<f64, SceneError> {
    if !(v.is_finite() && v > 0.0) {
        return Err(at.error(
            field,
            format!("{v} is not allowed: expected a positive length in mm"),
        ));
    }
    if v > MAX_COORDINATE_MM {
        return Err(at.error(field, beyond(v, "a length")));
    }
    Ok(v)
}

/// The stiffest spring drape accepts (N/mm). A steel block 1 m² across
/// and 1 mm long is 2.1e11 N/mm; a stiffer holder is a typing slip, and
/// past about 1e300 the explicit step it would need underflows, so the
/// value would otherwise surface as a mass-scaling or time-step fault.
pub const MAX_STIFFNESS_N_PER_MM: f64 = 1e12;

/// The largest force drape accepts (N): 1e12 N is about 1e8 tonnes-force.
pub const MAX_FORCE_N: f64 = 1e12;

/// A spring stiffness (N/mm): positive and at most
/// [`MAX_STIFFNESS_N_PER_MM`].
pub(super) fn stiffness(at: &Locator<'_>, field: &str, k: f64) -> Result<f64, SceneError> {
    if !(k.is_finite() && k > 0.0) {
        return Err(at.error(
            field,
            format!("{k} is not allowed: expected a positive stiffness in N/mm"),
        ));
    }
    if k > MAX_STIFFNESS_N_PER_MM {
        return Err(at.error(
            field,
            format!(
                "{k:e} N/mm is not allowed: a spring stiffer than {MAX_STIFFNESS_N_PER_MM:e} \
                 N/mm (a steel block 1 m² across and 1 mm long is 2.1e11 N/mm) is a slip"
            ),
        ));
    }
    Ok(k)
}

/// A force (N): finite, at least 0, at most [`MAX_FORCE_N`].
pub(super) fn force(at: &Locator<'_>, field: &str, f: f64) -> Result<f64, SceneError> {
    if !(f.is_finite() && f >= 0.0) {
        return Err(at.error(field, "expected a force ≥ 0"));
    }
    if f > MAX_FORCE_N {
        return Err(at.error(
            field,
            format!("{f:e} N is not allowed: forces must be at most {MAX_FORCE_N:e} N"),
        ));
    }
    Ok(f)
}

/// The message for `value` past the range, as `what` (mm).
pub(super) fn beyond(value: f64, what: &str) -> String {
    format!(
        "{value:e} is not allowed: {what} must lie within ±{MAX_COORDINATE_MM:e} mm (drape's \
         lengths are in mm; beyond that f64 loses the digits the mechanics needs)"
    )
}

/// A direction scaled to length 1; its components may be of any finite
/// size (`[1e300, 1e300, 0]` is the diagonal), zero is refused.
pub(super) fn direction(
    at: &Locator<'_>,
    field: &str,
    v: [f64; 3],
) -> Result<Vector3<f64>, SceneError> {
    if !v.iter().all(|x| x.is_finite()) {
        return Err(at.error(field, "every component must be a finite number"));
    }
    let d = Vector3::from(v);
    // Divided by its largest component first, its norm can neither
    // overflow (1e300²) nor underflow (subnormals²).
    let largest = d.amax();
    if largest == 0.0 {
        return Err(at.error(field, "a direction must not be zero"));
    }
    let d = d / largest;
    Ok(d / d.norm())
}

/// Bytes a blank element read from a mesh file takes to read the scene
/// and run (model, state, the driver's buffers; measured at its peak by
/// `crates/cli/tests/mesh_memory.rs`).
pub const BLANK_BYTES_PER_ELEMENT: usize = 3000;

/// Bytes a tool mesh's triangle takes to read, repair and search
/// (vertices, topology, bounding-volume tree; measured likewise).
pub const TOOL_BYTES_PER_TRIANGLE: usize = 3200;

/// The most elements a blank read from a mesh file may have: the same as
/// a rectangle's ([`drape_model::blank::MAX_ELEMENTS`]).
pub const MAX_BLANK_ELEMENTS: usize = drape_model::blank::MAX_ELEMENTS;

/// The machine's memory (bytes), where the system says (Linux).
fn machine_memory() -> Option<usize> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib: usize = info
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

/// Refuses a mesh of `count` `what`s (of `bytes_each`) at `field` whose
/// estimate is past `cap` items or past the machine's memory, with the
/// estimate.
pub(super) fn mesh_size(
    at: &Locator<'_>,
    field: &str,
    count: usize,
    what: &str,
    bytes_each: usize,
    cap: Option<usize>,
) -> Result<(), SceneError> {
    let need = count as f64 * bytes_each as f64;
    let estimate = format!(
        "{count} {what}s need about {:.1} GB to read and run ({bytes_each} B each)",
        need / 1e9
    );
    if let Some(cap) = cap.filter(|&cap| count > cap) {
        return Err(at.error(
            field,
            format!("{estimate}: drape takes at most {cap} {what}s (a unit mistake or an unmeshed export?)"),
        ));
    }
    if let Some(memory) = machine_memory().filter(|&m| need > m as f64) {
        return Err(at.error(
            field,
            format!(
                "{estimate}, more than this machine's {:.1} GB of memory: coarsen the mesh",
                memory as f64 / 1e9
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn locator() -> Locator<'static> {
        Locator {
            file: std::path::Path::new("s.toml"),
            text: None,
            overrides: &[],
            warnings: Default::default(),
        }
    }

    #[test]
    fn a_mesh_past_the_cap_or_the_memory_is_refused_with_the_estimate() {
        let at = locator();
        let cap = Some(MAX_BLANK_ELEMENTS);
        mesh_size(
            &at,
            "fabric.blank.mesh",
            MAX_BLANK_ELEMENTS,
            "element",
            3000,
            cap,
        )
        .unwrap();
        let e = mesh_size(
            &at,
            "fabric.blank.mesh",
            MAX_BLANK_ELEMENTS + 1,
            "element",
            3000,
            cap,
        )
        .unwrap_err();
        assert_eq!(e.field, "fabric.blank.mesh");
        assert!(
            e.message.contains("4000001 elements need about 12.0 GB"),
            "{e}"
        );
        assert!(e.message.contains("at most 4000000 elements"), "{e}");
        if let Some(memory) = machine_memory() {
            let count = memory / 3200 + 1;
            let e = mesh_size(&at, "tools[0].geometry.file", count, "triangle", 3200, None)
                .unwrap_err();
            assert_eq!(e.field, "tools[0].geometry.file");
            assert!(e.message.contains("more than this machine's"), "{e}");
            mesh_size(
                &at,
                "tools[0].geometry.file",
                count / 2,
                "triangle",
                3200,
                None,
            )
            .unwrap();
        }
    }

    #[test]
    fn directions_are_scaled_before_they_are_normalised() {
        let at = locator();
        let d = direction(&at, "d", [1e300, 0.0, -1e300]).unwrap();
        assert!((d - Vector3::new(1.0, 0.0, -1.0) / 2f64.sqrt()).norm() <= 1e-15);
        assert_eq!(
            direction(&at, "d", [0.0, -5e-324, 0.0]).unwrap(),
            -Vector3::y()
        );
        assert!(direction(&at, "d", [0.0; 3]).is_err());
        assert!(direction(&at, "d", [f64::INFINITY, 0.0, 0.0]).is_err());
    }
}
