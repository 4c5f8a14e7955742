//! Rigid tool surfaces and their closest-point queries.
//!
//! Every surface answers, for a point x in its own (local) frame, the
//! [`Projection`]: the closest surface point, the outward unit normal there
//! and the signed gap (positive outside, where the fabric may be).

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::mesh::{MeshError, MeshSurface};

/// The closest point of a surface to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// The closest surface point.
    pub point: Vector3<f64>,
    /// Outward unit normal (towards the side the fabric belongs to).
    pub normal: Vector3<f64>,
    /// Signed distance of the query point along the normal: > 0 outside.
    pub gap: f64,
}

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vector3<f64>,
    /// Upper corner.
    pub max: Vector3<f64>,
}

impl Aabb {
    /// The box of everything.
    pub fn everything() -> Self {
        Self {
            min: Vector3::repeat(f64::NEG_INFINITY),
            max: Vector3::repeat(f64::INFINITY),
        }
    }

    /// The box grown by `margin` on every side.
    pub fn grown(&self, margin: f64) -> Self {
        Self {
            min: self.min.add_scalar(-margin),
            max: self.max.add_scalar(margin),
        }
    }

    /// The box moved by `d`.
    pub fn translated(&self, d: &Vector3<f64>) -> Self {
        Self {
            min: self.min + d,
            max: self.max + d,
        }
    }

    /// Whether `x` is inside.
    pub fn contains(&self, x: &Vector3<f64>) -> bool {
        (0..3).all(|k| x[k] >= self.min[k] && x[k] <= self.max[k])
    }
}

/// One segment of a profile in the (r, z) half-plane of a surface of
/// revolution. The fabric's side is on the left of the direction of travel
/// (z up, r to the right: a punch's profile runs from the axis outwards).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum ProfileSegment {
    /// A straight segment.
    Line {
        /// Start (r, z).
        from: [f64; 2],
        /// End (r, z).
        to: [f64; 2],
    },
    /// A circular arc from angle `from_deg` to `to_deg` (measured from +r
    /// towards +z), counter-clockwise when `to_deg > from_deg`.
    Arc {
        /// Centre (r, z).
        center: [f64; 2],
        /// Radius.
        radius: f64,
        /// Start angle (degrees).
        from_deg: f64,
        /// End angle (degrees).
        to_deg: f64,
    },
}

/// The point of the circle (centre, radius) at `deg` degrees from +r.
fn on_circle(center: [f64; 2], radius: f64, deg: f64) -> Vector2<f64> {
    let a = deg.to_radians();
    Vector2::from(center) + Vector2::new(a.cos(), a.sin()) * radius
}

impl ProfileSegment {
    fn start(&self) -> Vector2<f64> {
        match *self {
            Self::Line { from, .. } => from.into(),
            Self::Arc {
                center,
                radius,
                from_deg,
                ..
            } => on_circle(center, radius, from_deg),
        }
    }

    fn end(&self) -> Vector2<f64> {
        match *self {
            Self::Line { to, .. } => to.into(),
            Self::Arc {
                center,
                radius,
                to_deg,
                ..
            } => on_circle(center, radius, to_deg),
        }
    }

    /// Closest point of the segment to `q` and the left normal there.
    fn closest(&self, q: &Vector2<f64>) -> (Vector2<f64>, Vector2<f64>) {
        match *self {
            Self::Line { from, to } => {
                let (a, b) = (Vector2::from(from), Vector2::from(to));
                let t = b - a;
                let s = ((q - a).dot(&t) / t.norm_squared()).clamp(0.0, 1.0);
                let n = Vector2::new(-t.y, t.x).normalize();
                (a + t * s, n)
            }
            Self::Arc {
                center,
                radius,
                from_deg,
                to_deg,
            } => {
                let c = Vector2::from(center);
                let (a0, a1) = (from_deg.to_radians(), to_deg.to_radians());
                let d = q - c;
                let (lo, hi) = (a0.min(a1), a0.max(a1));
                // The query's angle, brought into [lo, lo + 2π).
                let mut a = d.y.atan2(d.x);
                while a < lo {
                    a += std::f64::consts::TAU;
                }
                while a >= lo + std::f64::consts::TAU {
                    a -= std::f64::consts::TAU;
                }
                let a = if a <= hi {
                    a
                } else if a - hi < lo + std::f64::consts::TAU - a {
                    hi
                } else {
                    lo
                };
                let radial = Vector2::new(a.cos(), a.sin());
                // Counter-clockwise travel has the centre on its left.
                let n = if a1 > a0 { -radial } else { radial };
                (c + radial * radius, n)
            }
        }
    }

    fn check(&self, index: usize) -> Result<(), SurfaceError> {
        let bad = |what: &'static str| SurfaceError::Profile { index, what };
        match *self {
            Self::Line { from, to } => {
                if !from.iter().chain(&to).all(|v| v.is_finite()) {
                    return Err(bad("a coordinate is not finite"));
                }
                if from == to {
                    return Err(bad("a line has zero length"));
                }
            }
            Self::Arc {
                center,
                radius,
                from_deg,
                to_deg,
            } => {
                if !(center.iter().all(|v| v.is_finite())
                    && from_deg.is_finite()
                    && to_deg.is_finite())
                {
                    return Err(bad("a value is not finite"));
                }
                if radius.is_nan() || radius <= 0.0 {
                    return Err(bad("an arc needs a positive radius"));
                }
                if from_deg == to_deg || (to_deg - from_deg).abs() > 360.0 {
                    return Err(bad("an arc must span more than 0° and at most 360°"));
                }
            }
        }
        Ok(())
    }
}

/// A surface that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceError {
    /// A bad profile segment.
    #[error("profile segment {index}: {what}")]
    Profile {
        /// Index of the segment.
        index: usize,
        /// What is wrong.
        what: &'static str,
    },
    /// Consecutive segments do not meet.
    #[error("profile segments {index} and {next} do not meet (gap {gap:e} mm)", next = index + 1)]
    Disconnected {
        /// Index of the first segment.
        index: usize,
        /// Distance between its end and the next start.
        gap: f64,
    },
    /// A bad parameter.
    #[error("{what}")]
    Invalid {
        /// What is wrong.
        what: &'static str,
    },
    /// A triangle mesh that cannot be used.
    #[error("triangle mesh: {0}")]
    Mesh(#[from] MeshError),
}

/// A rigid surface in its local frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Surface {
    /// An infinite plane through `point`; the fabric is on the `normal` side.
    Plane {
        /// A point of the plane.
        point: Vector3<f64>,
        /// Unit normal towards the fabric.
        normal: Vector3<f64>,
    },
    /// A sphere; the fabric is outside.
    Sphere {
        /// Centre.
        center: Vector3<f64>,
        /// Radius.
        radius: f64,
    },
    /// A surface of revolution about the vertical axis through `origin`.
    Revolution {
        /// A point of the axis (profile z = 0 there).
        origin: Vector3<f64>,
        /// The profile, segments meeting end to start.
        profile: Vec<ProfileSegment>,
    },
    /// A triangle mesh (CAD tools from STL or OBJ); the fabric is on the
    /// side of the counter-clockwise triangle normals, outside a closed
    /// mesh (see [`MeshSurface`]).
    Mesh(MeshSurface),
}

impl Surface {
    /// A plane, normalising `normal`.
    pub fn plane(point: Vector3<f64>, normal: Vector3<f64>) -> Result<Self, SurfaceError> {
        let n = normal.norm();
        if !(n > 0.0 && n.is_finite() && point.iter().all(|v| v.is_finite())) {
            return Err(SurfaceError::Invalid {
                what: "a plane needs a finite point and a non-zero normal",
            });
        }
        Ok(Self::Plane {
            point,
            normal: normal / n,
        })
    }

    /// A sphere.
    pub fn sphere(center: Vector3<f64>, radius: f64) -> Result<Self, SurfaceError> {
        if radius.is_nan() || radius <= 0.0 || !center.iter().all(|v| v.is_finite()) {
            return Err(SurfaceError::Invalid {
                what: "a sphere needs a finite centre and a positive radius",
            });
        }
        Ok(Self::Sphere { center, radius })
    }

    /// A surface of revolution, checking that its segments are valid and
    /// connected (to 1e-9 of the profile's size).
    pub fn revolution(
        origin: Vector3<f64>,
        profile: Vec<ProfileSegment>,
    ) -> Result<Self, SurfaceError> {
        if profile.is_empty() {
            return Err(SurfaceError::Invalid {
                what: "a profile needs at least one segment",
            });
        }
        for (i, s) in profile.iter().enumerate() {
            s.check(i)?;
        }
        let size = profile
            .iter()
            .flat_map(|s| [s.start().norm(), s.end().norm()])
            .fold(1.0, f64::max);
        for (i, pair) in profile.windows(2).enumerate() {
            let gap = (pair[0].end() - pair[1].start()).norm();
            if gap > 1e-9 * size {
                return Err(SurfaceError::Disconnected { index: i, gap });
            }
        }
        Ok(Self::Revolution { origin, profile })
    }

    /// A triangle mesh from its vertices and counter-clockwise triangles
    /// (see [`MeshSurface::new`] for the checks and the sign convention).
    pub fn triangle_mesh(
        vertices: Vec<Vector3<f64>>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, SurfaceError> {
        Ok(Self::Mesh(MeshSurface::new(vertices, triangles)?))
    }

    /// A hemispherical punch of radius `radius` on a cylindrical shank of
    /// length `shank`, its pole at `pole`, pointing up (+z).
    pub fn hemispherical_punch(
        pole: Vector3<f64>,
        radius: f64,
        shank: f64,
    ) -> Result<Self, SurfaceError> {
        let centre = pole - Vector3::new(0.0, 0.0, radius);
        Self::revolution(
            centre,
            vec![
                ProfileSegment::Arc {
                    center: [0.0, 0.0],
                    radius,
                    from_deg: 90.0,
                    to_deg: 0.0,
                },
                ProfileSegment::Line {
                    from: [radius, 0.0],
                    to: [radius, -shank],
                },
            ],
        )
    }

    /// The same punch pointing down (−z), its pole at `pole`, the shank
    /// above.
    pub fn hemispherical_punch_down(
        pole: Vector3<f64>,
        radius: f64,
        shank: f64,
    ) -> Result<Self, SurfaceError> {
        let centre = pole + Vector3::new(0.0, 0.0, radius);
        Self::revolution(
            centre,
            vec![
                ProfileSegment::Line {
                    from: [radius, shank],
                    to: [radius, 0.0],
                },
                ProfileSegment::Arc {
                    center: [0.0, 0.0],
                    radius,
                    from_deg: 0.0,
                    to_deg: -90.0,
                },
            ],
        )
    }

    /// The closest point, outward normal and signed gap of `x` (local frame).
    pub fn project(&self, x: &Vector3<f64>) -> Projection {
        match self {
            Self::Plane { point, normal } => {
                let gap = (x - point).dot(normal);
                Projection {
                    point: x - normal * gap,
                    normal: *normal,
                    gap,
                }
            }
            Self::Sphere { center, radius } => {
                let d = x - center;
                let r = d.norm();
                // At the centre every direction is the normal: take +z.
                let normal = if r > 0.0 { d / r } else { Vector3::z() };
                Projection {
                    point: center + normal * *radius,
                    normal,
                    gap: r - radius,
                }
            }
            Self::Revolution { origin, profile } => {
                let d = x - origin;
                let r = d.x.hypot(d.y);
                let e_r = if r > 0.0 {
                    Vector3::new(d.x / r, d.y / r, 0.0)
                } else {
                    Vector3::x()
                };
                let q = Vector2::new(r, d.z);
                let (mut best, mut best_d2) = ((Vector2::zeros(), Vector2::zeros()), f64::INFINITY);
                for s in profile {
                    let (p, n) = s.closest(&q);
                    let d2 = (q - p).norm_squared();
                    if d2 < best_d2 {
                        best = (p, n);
                        best_d2 = d2;
                    }
                }
                let (p, n_left) = best;
                let v = q - p;
                let dist = v.norm();
                let sign = if v.dot(&n_left) >= 0.0 { 1.0 } else { -1.0 };
                // Off a corner the direction to the point is the normal.
                let n2 = if dist > 1e-12 {
                    v / dist * sign
                } else {
                    n_left
                };
                Projection {
                    point: origin + e_r * p.x + Vector3::z() * p.y,
                    normal: e_r * n2.x + Vector3::z() * n2.y,
                    gap: sign * dist,
                }
            }
            Self::Mesh(mesh) => mesh.project(x),
        }
    }

    /// A box around the surface (infinite for a plane).
    pub fn aabb(&self) -> Aabb {
        match self {
            Self::Plane { .. } => Aabb::everything(),
            Self::Sphere { center, radius } => Aabb {
                min: center.add_scalar(-radius),
                max: center.add_scalar(*radius),
            },
            Self::Revolution { origin, profile } => {
                let (mut r_max, mut z_min, mut z_max) = (0.0f64, f64::INFINITY, f64::NEG_INFINITY);
                for s in profile {
                    let mut points = vec![s.start(), s.end()];
                    if let ProfileSegment::Arc { center, radius, .. } = *s {
                        // Conservative: the whole circle's extent.
                        points.push(Vector2::from(center) + Vector2::new(radius, radius));
                        points.push(Vector2::from(center) - Vector2::new(0.0, radius));
                    }
                    for p in points {
                        r_max = r_max.max(p.x.abs());
                        z_min = z_min.min(p.y);
                        z_max = z_max.max(p.y);
                    }
                }
                Aabb {
                    min: origin + Vector3::new(-r_max, -r_max, z_min),
                    max: origin + Vector3::new(r_max, r_max, z_max),
                }
            }
            Self::Mesh(mesh) => mesh.aabb(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn plane_and_sphere_gaps() {
        let p = Surface::plane(Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.0, 0.0, 2.0)).unwrap();
        let q = p.project(&Vector3::new(3.0, 4.0, 1.5));
        assert_eq!(q.gap, 0.5);
        assert_eq!(q.point, Vector3::new(3.0, 4.0, 1.0));
        let s = Surface::sphere(Vector3::zeros(), 2.0).unwrap();
        let q = s.project(&Vector3::new(0.0, 3.0, 4.0));
        assert!((q.gap - 3.0).abs() < 1e-15);
        assert!((q.normal - Vector3::new(0.0, 0.6, 0.8)).norm() < 1e-15);
        assert!(Surface::sphere(Vector3::zeros(), -1.0).is_err());
        assert!(Surface::plane(Vector3::zeros(), Vector3::zeros()).is_err());
    }

    proptest! {
        #[test]
        fn punch_cap_agrees_with_a_sphere_and_shank_with_a_cylinder(
            x in -200.0f64..200.0, y in -200.0f64..200.0, z in -100.0f64..200.0,
        ) {
            let punch = Surface::hemispherical_punch(Vector3::new(0.0, 0.0, 120.0), 120.0, 300.0).unwrap();
            let sphere = Surface::sphere(Vector3::zeros(), 120.0).unwrap();
            let p = Vector3::new(x, y, z);
            let q = punch.project(&p);
            if z >= 0.0 {
                // Above the equator the cap is the sphere.
                let s = sphere.project(&p);
                prop_assert!((q.gap - s.gap).abs() < 1e-9, "{} vs {}", q.gap, s.gap);
                prop_assert!((q.normal - s.normal).norm() < 1e-9);
            } else {
                // Beside the shank, the distance to the cylinder r = 120.
                let r = x.hypot(y);
                prop_assert!((q.gap - (r - 120.0)).abs() < 1e-9, "{} vs {}", q.gap, r - 120.0);
            }
            prop_assert!((q.normal.norm() - 1.0).abs() < 1e-12);
            // The projection is on the surface: its own gap is zero.
            prop_assert!(punch.project(&q.point).gap.abs() < 1e-9);
        }
    }

    #[test]
    fn a_punch_pointing_down_mirrors_one_pointing_up() {
        let up = Surface::hemispherical_punch(Vector3::new(0.0, 0.0, 0.0), 50.0, 100.0).unwrap();
        let down =
            Surface::hemispherical_punch_down(Vector3::new(0.0, 0.0, 0.0), 50.0, 100.0).unwrap();
        for p in [
            Vector3::new(10.0, 5.0, 3.0),
            Vector3::new(60.0, 0.0, -80.0),
            Vector3::new(20.0, -30.0, -40.0),
        ] {
            let mirrored = Vector3::new(p.x, p.y, -p.z);
            let (a, b) = (up.project(&p), down.project(&mirrored));
            assert!((a.gap - b.gap).abs() < 1e-12, "{} vs {}", a.gap, b.gap);
            assert!((a.normal.z + b.normal.z).abs() < 1e-12);
        }
    }

    #[test]
    fn die_with_fillet_has_the_fabric_above_and_in_the_opening() {
        // Die: top face z = 0 from r = 60 out to 200, fillet of radius 10
        // into an opening of radius 50, wall down to z = −100.
        let die = Surface::revolution(
            Vector3::zeros(),
            vec![
                ProfileSegment::Line {
                    from: [50.0, -100.0],
                    to: [50.0, -10.0],
                },
                ProfileSegment::Arc {
                    center: [60.0, -10.0],
                    radius: 10.0,
                    from_deg: 180.0,
                    to_deg: 90.0,
                },
                ProfileSegment::Line {
                    from: [60.0, 0.0],
                    to: [200.0, 0.0],
                },
            ],
        )
        .unwrap();
        let above = die.project(&Vector3::new(100.0, 0.0, 3.0));
        assert!((above.gap - 3.0).abs() < 1e-12);
        assert!((above.normal - Vector3::z()).norm() < 1e-12);
        let in_opening = die.project(&Vector3::new(0.0, 30.0, -50.0));
        assert!((in_opening.gap - 20.0).abs() < 1e-12);
        let inside = die.project(&Vector3::new(120.0, 0.0, -2.0));
        assert!((inside.gap + 2.0).abs() < 1e-12);
        // On the fillet at 45°.
        let p = Vector3::new(60.0 - 12.0 / 2f64.sqrt(), 0.0, -10.0 + 12.0 / 2f64.sqrt());
        let q = die.project(&p);
        assert!((q.gap - 2.0).abs() < 1e-12);
        let bad = Surface::revolution(
            Vector3::zeros(),
            vec![
                ProfileSegment::Line {
                    from: [0.0, 0.0],
                    to: [1.0, 0.0],
                },
                ProfileSegment::Line {
                    from: [2.0, 0.0],
                    to: [3.0, 0.0],
                },
            ],
        );
        assert!(matches!(
            bad,
            Err(SurfaceError::Disconnected { index: 0, .. })
        ));
    }
}
