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
