//! The mould as the net sees it: the tool surface's closest-point query
//! ([`Surface::project`], the code contact uses), a line search for the
//! seed and the root finder that puts a yarn crossing on the surface.
//!
//! Every placement in the net is the same problem: the crossing must lie on
//! a known circle (the points at one yarn length from one crossing in a
//! given plane, or at the two yarn lengths from two crossings) and on the
//! surface. On the circle X(φ) = c + r·(cos φ·e₁ + sin φ·e₂), φ = 0 being
//! the flat guess, the signed gap g(φ) of X(φ) is zero on the surface, and
//! its derivative is n·X′(φ) with n the projection's normal (the gradient
//! of the signed distance, for analytic surfaces and for meshes alike). A
//! safeguarded Newton iteration finds the root nearest the flat guess.

use drape_contact::{Projection, Surface};
use nalgebra::Vector3;

use crate::FishnetError;

/// Largest |φ| accepted on a circle (radians): beyond about 80° the yarn
/// would fold back on the side it comes from.
const MAX_TURN: f64 = 1.4;
/// Largest Newton step in φ (radians): keeps the iteration near the flat
/// guess while it has no bracket.
const MAX_STEP: f64 = 0.3;
/// Newton iterations before a placement is given up.
const MAX_ITERATIONS: usize = 40;

/// A mould surface with the tolerance its crossings are placed to.
pub(crate) struct Mould<'a> {
    surface: &'a Surface,
    /// |gap| below which a point is on the surface (mm).
    pub tolerance: f64,
    /// Closest-point queries made so far.
    pub queries: usize,
}

impl<'a> Mould<'a> {
    pub fn new(surface: &'a Surface, tolerance: f64) -> Self {
        Self {
            surface,
            tolerance,
            queries: 0,
        }
    }

    pub fn project(&mut self, x: &Vector3<f64>) -> Projection {
        self.queries += 1;
        self.surface.project(x)
    }

    /// The first point of the mould met by the line through `flat` along
    /// the unit `direction`, coming from outside the mould's box.
    ///
    /// Sphere tracing: the |signed gap| is a distance to the surface, so a
    /// step of that length along the line never crosses it, and the steps
    /// shrink to zero at the first hit.
    pub fn seed(
        &mut self,
        flat: &Vector3<f64>,
        direction: &Vector3<f64>,
    ) -> Result<Projection, FishnetError> {
        let miss = || FishnetError::SeedMissesMould {
            point: [flat.x, flat.y, flat.z],
            direction: [direction.x, direction.y, direction.z],
        };
        if let Surface::Plane { point, normal } = self.surface {
            // The fabric comes from the normal's side, so it must travel
            // against the normal.
            let approach = direction.dot(normal);
            if approach >= 0.0 {
                return Err(miss());
            }
            let x = flat + direction * ((point - flat).dot(normal) / approach);
            return Ok(self.project(&x));
        }
        let aabb = self.surface.aabb();
        let corners = (0..8).map(|k| {
            Vector3::new(
                if k & 1 == 0 { aabb.min.x } else { aabb.max.x },
                if k & 2 == 0 { aabb.min.y } else { aabb.max.y },
                if k & 4 == 0 { aabb.min.z } else { aabb.max.z },
            )
        });
        let (mut before, mut beyond) = (0.0f64, 0.0f64);
        for c in corners {
            let along = (c - flat).dot(direction);
            before = before.max(-along);
            beyond = beyond.max(along);
        }
        let size = (aabb.max - aabb.min).norm();
        if !size.is_finite() {
            return Err(miss());
        }
        let margin = 1.0 + 1e-6 * size;
        let start = flat - direction * (before + margin);
        let length = before + beyond + 2.0 * margin;
        let mut x = start;
        let mut travelled = 0.0;
        for step in 0..100_000 {
            let p = self.project(&x);
            if step == 0 && p.gap < 0.0 {
                return Err(FishnetError::SeedBehindMould {
                    point: [flat.x, flat.y, flat.z],
                });
            }
            if p.gap <= self.tolerance {
                return Ok(p);
            }
            x += direction * p.gap;
            travelled += p.gap;
            if travelled > length {
                break;
            }
        }
        Err(miss())
    }

    /// The point of the circle c + r·(cos φ·e₁ + sin φ·e₂) on the surface
    /// nearest φ = 0 (within ±80°), with its projection, or None when the
    /// circle does not meet the surface there (the mould's edge).
    pub fn on_circle(
        &mut self,
        c: &Vector3<f64>,
        r: f64,
        e1: &Vector3<f64>,
        e2: &Vector3<f64>,
    ) -> Option<(Vector3<f64>, Projection)> {
        let mut phi = 0.0f64;
        // The last angles seen outside (gap > 0) and inside (gap < 0).
        let (mut outside, mut inside): (Option<f64>, Option<f64>) = (None, None);
        for _ in 0..MAX_ITERATIONS {
            let (s, co) = phi.sin_cos();
            let x = c + (e1 * co + e2 * s) * r;
            let p = self.project(&x);
            if !p.gap.is_finite() {
                return None;
            }
            if p.gap.abs() <= self.tolerance {
                return Some((x, p));
            }
            if p.gap > 0.0 {
                outside = Some(phi);
            } else {
                inside = Some(phi);
            }
            let slope = p.normal.dot(&((e2 * co - e1 * s) * r));
            let mut next = phi - p.gap / slope;
            if !next.is_finite() {
                next = phi;
            }
            next = phi + (next - phi).clamp(-MAX_STEP, MAX_STEP);
            if let (Some(a), Some(b)) = (outside, inside) {
                // Bracketed: Newton only while it stays inside the bracket.
                let (lo, hi) = (a.min(b), a.max(b));
                if !(next > lo && next < hi) {
                    next = 0.5 * (lo + hi);
                }
                if hi - lo < 1e-15 {
                    return None;
                }
            } else if next == phi {
                return None;
            }
            if next.abs() > MAX_TURN {
                return None;
            }
            phi = next;
        }
        None
    }
}
