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

/// Where on a segment its closest point to a query lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Clamp {
    /// Strictly between the ends.
    Inside,
    /// At the start.
    Start,
    /// At the end.
    End,
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

    /// Closest point of the segment to `q`, the left normal there, and
    /// whether that point is the segment's start or end (clamped there).
    fn closest(&self, q: &Vector2<f64>) -> (Vector2<f64>, Vector2<f64>, Clamp) {
        match *self {
            Self::Line { from, to } => {
                let (a, b) = (Vector2::from(from), Vector2::from(to));
                let t = b - a;
                let s = (q - a).dot(&t) / t.norm_squared();
                let n = Vector2::new(-t.y, t.x).normalize();
                if s <= 0.0 {
                    (a, n, Clamp::Start)
                } else if s >= 1.0 {
                    (b, n, Clamp::End)
                } else {
                    (a + t * s, n, Clamp::Inside)
                }
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
                // Beyond the arc: the nearer end by angle, which is the
                // nearer by distance on a circle.
                let (a, at_lo) = if a <= hi {
                    (a, None)
                } else if a - hi < lo + std::f64::consts::TAU - a {
                    (hi, Some(false))
                } else {
                    (lo, Some(true))
                };
                let clamp = match at_lo {
                    None => Clamp::Inside,
                    // The start is at `from_deg`: lo when counter-clockwise.
                    Some(at_lo) if at_lo == (a1 > a0) => Clamp::Start,
                    Some(_) => Clamp::End,
                };
                let radial = Vector2::new(a.cos(), a.sin());
                // Counter-clockwise travel has the centre on its left.
                let n = if a1 > a0 { -radial } else { radial };
                (c + radial * radius, n, clamp)
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
    /// A surface of revolution about the vertical axis through `origin`
    /// (built by [`Surface::revolution`]; see there for closed profiles and
    /// free ends).
    Revolution {
        /// A point of the axis (profile z = 0 there).
        origin: Vector3<f64>,
        /// The profile, segments meeting end to start.
        profile: Vec<ProfileSegment>,
        /// Whether the profile's start and its end are free: neither on the
        /// axis nor joined to the other end.
        free_ends: [bool; 2],
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
    ///
    /// # Closed profiles and free ends
    ///
    /// The profile bounds a solid when it is **closed**: its end meets its
    /// start, or both lie on the axis (a punch's pole and the centre of its
    /// top). The gap is then the signed distance to that solid of
    /// revolution: exact, continuous and 1-Lipschitz in the point
    /// (|g(a) − g(b)| ≤ |a − b|), which the contact guard relies on. The
    /// built-in tools ([`Surface::hemispherical_punch`], [`Surface::die`],
    /// [`Surface::ring`]) are closed.
    ///
    /// An end that is neither on the axis nor joined to the other end is a
    /// **free end**, the rim of an open surface. A point whose closest
    /// profile point is a free end is outside: its gap is the distance to
    /// that rim, positive, and the normal points from the rim to it. A
    /// fabric node beside a holder's opening or beyond a die's outer edge is
    /// therefore never "inside" the tool.
    ///
    /// No signed gap of an open surface can be continuous everywhere: behind
    /// the surface, next to the line through a free end along the normal
    /// (the *cut*), a point at depth δ behind the last segment has the gap
    /// −δ while its neighbour across the cut, whose closest point is the free
    /// end, has +δ. Away from the cut the gap is 1-Lipschitz as for a closed
    /// profile. A node can reach the cut only by passing through the tool;
    /// the contact guard reports such a jump of the gap as a fault (see
    /// [`crate::ContactFault`]). Close a profile whenever the fabric can come
    /// near the back of its rims.
    pub fn revolution(
        origin: Vector3<f64>,
        profile: Vec<ProfileSegment>,
    ) -> Result<Self, SurfaceError> {
        if profile.is_empty() {
            return Err(SurfaceError::Invalid {
                what: "a profile needs at least one segment",
            });
        }
        if !origin.iter().all(|v| v.is_finite()) {
            return Err(SurfaceError::Invalid {
                what: "the axis point of a surface of revolution is not finite",
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
        let (start, end) = (profile[0].start(), profile[profile.len() - 1].end());
        let joined = (start - end).norm() <= 1e-9 * size;
        let free = |p: Vector2<f64>| !joined && p.x.abs() > 1e-9 * size;
        Ok(Self::Revolution {
            origin,
            free_ends: [free(start), free(end)],
            profile,
        })
    }

    /// The distance from `point` (on the surface) to the nearest free end
    /// of a profile, measured in its (r, z) half-plane: how far from the
    /// rim circle. None for a surface without free ends (meshes: see
    /// [`crate::ToolPlace`]).
    pub(crate) fn free_end_distance(&self, point: &Vector3<f64>) -> Option<f64> {
        let Self::Revolution {
            origin,
            profile,
            free_ends,
        } = self
        else {
            return None;
        };
        let d = point - origin;
        let q = Vector2::new(d.xy().norm(), d.z);
        let ends = [profile[0].start(), profile[profile.len() - 1].end()];
        ends.iter()
            .zip(free_ends)
            .filter(|(_, free)| **free)
            .map(|(e, _)| (q - e).norm())
            .reduce(f64::min)
    }

    /// Whether the surface bounds a solid (no free end, no open edge): its
    /// gap is then continuous and 1-Lipschitz everywhere.
    pub fn is_closed(&self) -> bool {
        match self {
            Self::Plane { .. } | Self::Sphere { .. } => true,
            Self::Revolution { free_ends, .. } => !free_ends[0] && !free_ends[1],
            Self::Mesh(mesh) => mesh.is_closed(),
        }
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
    /// length `shank`, its pole at `pole`, pointing up (+z). The shank is
    /// closed by a flat end, so the punch is a solid.
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
                ProfileSegment::Line {
                    from: [radius, -shank],
                    to: [0.0, -shank],
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
                    from: [0.0, shank],
                    to: [radius, shank],
                },
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

    /// A die: a flat face at the height of `center` (the fabric above it)
    /// from the opening's fillet out to `outer_radius`, a fillet of radius
    /// `fillet_radius` rounding the edge of a round opening of radius
    /// `opening_radius`, whose wall goes down `depth` below the fillet. The
    /// die is a closed solid: an outer wall and a bottom close it.
    pub fn die(
        center: Vector3<f64>,
        opening_radius: f64,
        fillet_radius: f64,
        depth: f64,
        outer_radius: f64,
    ) -> Result<Self, SurfaceError> {
        let (a, f) = (opening_radius, fillet_radius);
        let finite = [a, f, depth, outer_radius].iter().all(|v| v.is_finite());
        if !(finite && a > 0.0 && f > 0.0 && depth > 0.0 && outer_radius > a + f) {
            return Err(SurfaceError::Invalid {
                what: "a die needs positive opening, fillet and depth and an outer radius beyond opening + fillet",
            });
        }
        let bottom = -f - depth;
        Self::revolution(
            center,
            vec![
                ProfileSegment::Line {
                    from: [a, bottom],
                    to: [a, -f],
                },
                ProfileSegment::Arc {
                    center: [a + f, -f],
                    radius: f,
                    from_deg: 180.0,
                    to_deg: 90.0,
                },
                ProfileSegment::Line {
                    from: [a + f, 0.0],
                    to: [outer_radius, 0.0],
                },
                ProfileSegment::Line {
                    from: [outer_radius, 0.0],
                    to: [outer_radius, bottom],
                },
                ProfileSegment::Line {
                    from: [outer_radius, bottom],
                    to: [a, bottom],
                },
            ],
        )
    }

    /// A blank holder: a ring whose flat face, at the height of `center`,
    /// faces down onto the fabric, from `inner_radius + edge_radius` out to
    /// `outer_radius`. Its inner edge is rounded with `edge_radius` (0 for a
    /// sharp edge) up into an inner wall; the ring is `thickness` tall and
    /// closed by its top and an outer wall, so a node in the holder's
    /// opening is outside it, however high it rises.
    pub fn ring(
        center: Vector3<f64>,
        inner_radius: f64,
        outer_radius: f64,
        edge_radius: f64,
        thickness: f64,
    ) -> Result<Self, SurfaceError> {
        let (ri, ro, rho, t) = (inner_radius, outer_radius, edge_radius, thickness);
        let finite = [ri, ro, rho, t].iter().all(|v| v.is_finite());
        if !(finite && ri > 0.0 && rho >= 0.0 && ro > ri + rho && t > 0.0 && t >= rho) {
            return Err(SurfaceError::Invalid {
                what: "a ring needs 0 < inner radius, an outer radius beyond inner + edge radius, \
                       an edge radius ≥ 0 and a thickness > 0 of at least the edge radius",
            });
        }
        let mut profile = vec![ProfileSegment::Line {
            from: [ro, 0.0],
            to: [ri + rho, 0.0],
        }];
        if rho > 0.0 {
            profile.push(ProfileSegment::Arc {
                center: [ri + rho, rho],
                radius: rho,
                from_deg: -90.0,
                to_deg: -180.0,
            });
        }
        if t > rho {
            profile.push(ProfileSegment::Line {
                from: [ri, rho],
                to: [ri, t],
            });
        }
        profile.extend([
            ProfileSegment::Line {
                from: [ri, t],
                to: [ro, t],
            },
            ProfileSegment::Line {
                from: [ro, t],
                to: [ro, 0.0],
            },
        ]);
        Self::revolution(center, profile)
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
            Self::Revolution {
                origin,
                profile,
                free_ends,
            } => {
                let d = x - origin;
                let r = d.x.hypot(d.y);
                let e_r = if r > 0.0 {
                    Vector3::new(d.x / r, d.y / r, 0.0)
                } else {
                    Vector3::x()
                };
                let q = Vector2::new(r, d.z);
                let last = profile.len() - 1;
                let (mut best, mut best_d2) =
                    ((Vector2::zeros(), Vector2::zeros(), false), f64::INFINITY);
                for (k, s) in profile.iter().enumerate() {
                    let (p, n, clamp) = s.closest(&q);
                    let d2 = (q - p).norm_squared();
                    if d2 < best_d2 {
                        let at_free_end = (k == 0 && clamp == Clamp::Start && free_ends[0])
                            || (k == last && clamp == Clamp::End && free_ends[1]);
                        best = (p, n, at_free_end);
                        best_d2 = d2;
                    }
                }
                let (p, n_left, at_free_end) = best;
                let v = q - p;
                let dist = v.norm();
                // A rim is outside from every side (see `revolution`).
                let sign = if at_free_end || v.dot(&n_left) >= 0.0 {
                    1.0
                } else {
                    -1.0
                };
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

    /// [`Self::project`] with a hint for a triangle mesh: the triangle the
    /// point found last, updated to the one it finds now (see
    /// [`MeshSurface::project_from`]); the same answer, bit for bit. Other
    /// surfaces leave the hint alone.
    pub fn project_from(&self, x: &Vector3<f64>, hint: &mut u32) -> Projection {
        match self {
            Self::Mesh(mesh) => mesh.project_from(x, hint),
            _ => self.project(x),
        }
    }

    /// A lower bound of the distance from `x` to the surface's rim (its
    /// free ends or open edges, where the gap can jump), infinite for a
    /// closed surface.
    ///
    /// While a point stays nearer the surface than the rim, its closest
    /// point is never on the rim, so its gap cannot cross the cut behind
    /// the rim: it changes sign only through the surface. With the gap's
    /// magnitude 1-Lipschitz, a point at gap g > 0 and rim distance ρ that
    /// moves by s relative to the surface, with g − s > 0 and g + s < ρ,
    /// is still outside, at a gap ≥ g − s. The explicit contact pass skips
    /// far nodes of open tools by that bound.
    pub fn rim_clearance(&self, x: &Vector3<f64>) -> f64 {
        match self {
            Self::Plane { .. } | Self::Sphere { .. } => f64::INFINITY,
            Self::Revolution {
                origin,
                profile,
                free_ends,
            } => {
                let d = x - origin;
                let q = Vector2::new(d.x.hypot(d.y), d.z);
                let ends = [profile[0].start(), profile[profile.len() - 1].end()];
                ends.iter()
                    .zip(free_ends)
                    .filter(|(_, free)| **free)
                    // The end's circle: its nearest point is in x's
                    // half-plane, at the end's |r| (a profile may run at
                    // r < 0).
                    .map(|(e, _)| (q - Vector2::new(e.x.abs(), e.y)).norm())
                    .fold(f64::INFINITY, f64::min)
            }
            Self::Mesh(mesh) => mesh.rim_distance(x),
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
            Self::Revolution {
                origin, profile, ..
            } => {
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
pub(crate) mod tests {
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

    /// The ring the deep-drawing scenes shipped with before they had a real
    /// holder: one open segment, the face at z = 0.3 from r = 250 in to 95.
    fn flat_ring() -> Surface {
        Surface::revolution(
            Vector3::new(0.0, 0.0, 0.3),
            vec![ProfileSegment::Line {
                from: [250.0, 0.0],
                to: [95.0, 0.0],
            }],
        )
        .unwrap()
    }

    #[test]
    fn a_point_in_the_holders_opening_is_outside_it() {
        // Above the face's plane but in the opening (r = 86.3 < 95): the
        // closest point is the ring's free inner end, so the point is
        // outside at the distance to it. It used to read 8.7 mm "inside"
        // and was thrown onto the ring's edge.
        let p = Vector3::new(86.3, 0.0, 0.72);
        let expected = (8.7f64.powi(2) + 0.42f64.powi(2)).sqrt();
        let open = flat_ring();
        assert!(!open.is_closed());
        let q = open.project(&p);
        assert!(q.gap > 0.0 && (q.gap - expected).abs() < 1e-12, "{}", q.gap);
        assert!((q.normal - Vector3::new(-8.7, 0.0, 0.42) / expected).norm() < 1e-12);
        // Under the face it is the same surface as before.
        let q = open.project(&Vector3::new(120.0, 0.0, 0.1));
        assert!((q.gap - 0.2).abs() < 1e-12 && (q.normal + Vector3::z()).norm() < 1e-12);
        // Above the face, inside its extent: behind it, inside.
        assert!((open.project(&Vector3::new(120.0, 0.0, 0.5)).gap + 0.2).abs() < 1e-12);
        // The holder as a tool (edge radius 5, 20 mm tall): the same point
        // is outside, at the distance to the rounded edge.
        let holder = Surface::ring(Vector3::new(0.0, 0.0, 0.3), 95.0, 250.0, 5.0, 20.0).unwrap();
        assert!(holder.is_closed());
        let q = holder.project(&p);
        let to_edge: f64 = (Vector2::new(100.0, 5.0) - Vector2::new(86.3, 0.42)).norm() - 5.0;
        assert!((q.gap - to_edge).abs() < 1e-12, "{} vs {to_edge}", q.gap);
        // Under the rounded edge at 45°: 1 mm clear of it.
        let c = Vector2::new(100.0, 5.3);
        let p45 = c + Vector2::new(-1.0, -1.0).normalize() * 6.0;
        let q = holder.project(&Vector3::new(0.0, p45.x, p45.y));
        assert!((q.gap - 1.0).abs() < 1e-12);
        // Inside the holder's material: negative.
        assert!((holder.project(&Vector3::new(150.0, 0.0, 1.3)).gap + 1.0).abs() < 1e-12);
        // In the opening beside the inner wall, any height: outside.
        let q = holder.project(&Vector3::new(0.0, -93.0, 12.0));
        assert!((q.gap - 2.0).abs() < 1e-12 && (q.normal - Vector3::y()).norm() < 1e-12);
    }

    #[test]
    fn free_ends_are_outside_and_ends_on_the_axis_or_joined_are_not_free() {
        let Surface::Revolution { free_ends, .. } = flat_ring() else {
            unreachable!()
        };
        assert_eq!(free_ends, [true, true]);
        for s in tools() {
            assert!(s.is_closed(), "{s:?}");
        }
        // An open die face beyond its outer edge, below the face's plane:
        // outside at the distance to the edge.
        let face = Surface::revolution(
            Vector3::zeros(),
            vec![ProfileSegment::Line {
                from: [10.0, 0.0],
                to: [50.0, 0.0],
            }],
        )
        .unwrap();
        let q = face.project(&Vector3::new(0.0, 53.0, -4.0));
        assert!((q.gap - 5.0).abs() < 1e-12);
        let q = face.project(&Vector3::new(0.0, 49.0, -4.0));
        assert!((q.gap + 4.0).abs() < 1e-12);
        // The end of an arc is a free end too, clamped by angle.
        let cap = Surface::revolution(
            Vector3::zeros(),
            vec![ProfileSegment::Arc {
                center: [0.0, 0.0],
                radius: 10.0,
                from_deg: 90.0,
                to_deg: 30.0,
            }],
        )
        .unwrap();
        let Surface::Revolution { free_ends, .. } = &cap else {
            unreachable!()
        };
        // The pole is on the axis: not free.
        assert_eq!(*free_ends, [false, true]);
        let rim = Vector2::new(10.0 * 30f64.to_radians().cos(), 5.0);
        let p = Vector2::new(rim.x - 1.0, rim.y - 3.0);
        let q = cap.project(&Vector3::new(p.x, 0.0, p.y));
        assert!((q.gap - 10f64.sqrt()).abs() < 1e-12, "{}", q.gap);
    }

    /// Every closed tool kind the analytic surfaces offer, as the scenes
    /// build them.
    fn tools() -> Vec<Surface> {
        vec![
            Surface::plane(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.3, -0.2, 1.0)).unwrap(),
            Surface::sphere(Vector3::new(5.0, -3.0, 20.0), 60.0).unwrap(),
            Surface::hemispherical_punch(Vector3::new(0.0, 0.0, 20.0), 75.0, 150.0).unwrap(),
            Surface::hemispherical_punch_down(Vector3::new(3.0, 0.0, 16.5), 75.0, 150.0).unwrap(),
            Surface::die(Vector3::new(0.0, 0.0, -0.3), 80.0, 10.0, 150.0, 250.0).unwrap(),
            Surface::ring(Vector3::new(0.0, 0.0, 0.3), 95.0, 250.0, 5.0, 20.0).unwrap(),
            Surface::ring(Vector3::new(0.0, 0.0, 0.3), 95.0, 250.0, 5.0, 5.0).unwrap(),
            Surface::ring(Vector3::new(0.0, 0.0, 0.3), 95.0, 250.0, 0.0, 10.0).unwrap(),
        ]
    }

    /// |g(a) − g(b)| ≤ |a − b|, up to round-off of the coordinates.
    pub(crate) fn lipschitz(s: &Surface, a: &Vector3<f64>, b: &Vector3<f64>) -> Result<(), String> {
        let (ga, gb) = (s.project(a).gap, s.project(b).gap);
        let d = (a - b).norm();
        if (ga - gb).abs() <= d + 1e-12 * (1.0 + a.norm() + b.norm()) {
            Ok(())
        } else {
            Err(format!("g({a:?}) = {ga}, g({b:?}) = {gb}, |a − b| = {d}"))
        }
    }

    /// The joins of a profile in the world frame (at azimuth `phi`).
    fn joins(s: &Surface, phi: f64) -> Vec<Vector3<f64>> {
        let Surface::Revolution {
            origin, profile, ..
        } = s
        else {
            return Vec::new();
        };
        profile
            .iter()
            .map(|seg| {
                let p = seg.start();
                origin + Vector3::new(p.x * phi.cos(), p.x * phi.sin(), p.y)
            })
            .collect()
    }

    proptest! {
        /// The gap of every closed tool is 1-Lipschitz: for pairs anywhere
        /// (short and long), and for pairs straddling every join of a
        /// profile (line to arc, a sharp corner, the axis), where a wrong
        /// side would show as a jump.
        #[test]
        fn the_gap_of_every_closed_tool_is_1_lipschitz(
            a in proptest::array::uniform3(-300.0f64..300.0),
            dir in proptest::array::uniform3(-1.0f64..1.0),
            log_d in -6.0f64..2.7,
            phi in 0.0f64..std::f64::consts::TAU,
            k in 0usize..8,
        ) {
            let dir = Vector3::from(dir);
            prop_assume!(dir.norm() > 1e-3);
            let step = dir.normalize() * 10f64.powf(log_d);
            let a = Vector3::from(a);
            for s in tools() {
                lipschitz(&s, &a, &(a + step)).map_err(TestCaseError::fail)?;
                let joins = joins(&s, phi);
                if !joins.is_empty() {
                    let j = joins[k % joins.len()];
                    lipschitz(&s, &(j - step), &(j + step)).map_err(TestCaseError::fail)?;
                    lipschitz(&s, &j, &(j + step)).map_err(TestCaseError::fail)?;
                }
            }
        }

        /// An open profile's gap is 1-Lipschitz away from the cut behind its
        /// free ends (see `Surface::revolution`), and across the cut it
        /// jumps by twice the depth: the jump the contact guard catches.
        #[test]
        fn an_open_profile_is_1_lipschitz_off_its_cut(
            r in 0.0f64..300.0, z in -50.0f64..50.0,
            dir in proptest::array::uniform2(-1.0f64..1.0),
            log_d in -6.0f64..0.0,
        ) {
            let ring = flat_ring();
            let dir = Vector2::from(dir);
            prop_assume!(dir.norm() > 1e-3);
            let d = 10f64.powf(log_d);
            let step = dir.normalize() * d;
            // The cut: behind the face (above it), at the free ends' radii.
            let near_cut = |r: f64, z: f64| {
                z > 0.3 - 2.0 * d && [95.0, 250.0].iter().any(|e| (r - e).abs() < 2.0 * d)
            };
            prop_assume!(!near_cut(r, z));
            let a = Vector3::new(r, 0.0, z);
            let b = Vector3::new(r + step.x, 0.0, z + step.y);
            lipschitz(&ring, &a, &b).map_err(TestCaseError::fail)?;
            // Across the inner cut, 1 mm behind the face.
            let inside = ring.project(&Vector3::new(95.0 + 1e-3, 0.0, 1.3)).gap;
            let beside = ring.project(&Vector3::new(95.0 - 1e-3, 0.0, 1.3)).gap;
            prop_assert!((inside + 1.0).abs() < 1e-9 && (beside - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn tool_shapes_reject_bad_dimensions() {
        let c = Vector3::zeros();
        assert!(Surface::ring(c, 95.0, 250.0, 5.0, 4.0).is_err());
        assert!(Surface::ring(c, 95.0, 99.0, 5.0, 10.0).is_err());
        assert!(Surface::ring(c, 0.0, 250.0, 5.0, 10.0).is_err());
        assert!(Surface::ring(c, 95.0, 250.0, -1.0, 10.0).is_err());
        assert!(Surface::ring(c, 95.0, 250.0, f64::NAN, 10.0).is_err());
        assert!(Surface::die(c, 80.0, 10.0, 150.0, 85.0).is_err());
        assert!(Surface::die(c, 80.0, 0.0, 150.0, 250.0).is_err());
        assert!(Surface::die(c, 80.0, 10.0, f64::INFINITY, 250.0).is_err());
    }
}
