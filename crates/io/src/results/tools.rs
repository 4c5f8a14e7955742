//! The tools as triangle meshes, so that a results folder shows the formed
//! part in its mould: ParaView's `tools.pvd` series and the tool's outline
//! in the oblique picture.
//!
//! Analytic surfaces are tessellated once, in the tool's own frame (its
//! geometry before any motion); a frame moves each tool rigidly along its
//! axis by its displacement then. Mesh tools are written as given (after
//! the merging of duplicate vertices their reader does).
//!
//! | surface | tessellation |
//! |---|---|
//! | plane | a square centred on the blank's projection, 1.5 × the blank's diagonal on a side (a plane has no extent of its own) |
//! | sphere | 48 meridians × 24 parallels |
//! | revolution | the profile sampled (lines whole, arcs every 3° at most), swept about the axis in 96 steps |
//! | mesh | its triangles |
//!
//! Every triangle is wound counter-clockwise seen from the fabric's side,
//! so its normal points where the fabric may be, as the contact's normals
//! do (tested against [`drape_contact::Surface::project`]).
//!
//! What it is not: not a contact geometry (the contact queries the exact
//! surfaces) and not a CAD export.

use drape_contact::{ProfileSegment, Surface, Tool};
use nalgebra::Vector3;

/// Steps of a full turn about a revolution's axis.
const TURN_STEPS: usize = 96;
/// Largest angle of an arc between two samples (degrees).
const ARC_STEP_DEG: f64 = 3.0;
/// Meridians and parallels of a sphere.
const SPHERE_STEPS: (usize, usize) = (48, 24);
/// Side of a plane's square over the blank's diagonal.
const PLANE_SIDE: f64 = 1.5;

/// One tool as triangles in its own frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolMesh {
    /// The tool's name.
    pub name: String,
    /// Vertices at zero displacement (mm).
    pub vertices: Vec<Vector3<f64>>,
    /// Counter-clockwise seen from the fabric's side.
    pub triangles: Vec<[u32; 3]>,
    /// The axis the tool moves along (zero for a fixed tool).
    pub direction: Vector3<f64>,
}

impl ToolMesh {
    /// The vertices with the tool displaced by `displacement` along its axis.
    pub fn vertices_at(&self, displacement: f64) -> impl Iterator<Item = Vector3<f64>> + '_ {
        let shift = self.direction * displacement;
        self.vertices.iter().map(move |v| v + shift)
    }
}

/// Every tool of a model, tessellated once.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ToolMeshes {
    /// In the model's tool order.
    pub tools: Vec<ToolMesh>,
}

impl ToolMeshes {
    /// Tessellates `tools`; `blank` (the blank's reference nodes) sizes and
    /// places the square that stands for an infinite plane.
    pub fn new(tools: &[Tool], blank: &[Vector3<f64>]) -> Self {
        let (mut low, mut high) = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        for p in blank.iter().filter(|p| p.iter().all(|c| c.is_finite())) {
            low = low.inf(p);
            high = high.sup(p);
        }
        let (centre, diagonal) = if low.x <= high.x {
            (0.5 * (low + high), (high - low).norm().max(1.0))
        } else {
            (Vector3::zeros(), 100.0)
        };
        let tools = tools
            .iter()
            .map(|t| {
                let (vertices, triangles) = tessellate(&t.surface, centre, diagonal);
                ToolMesh {
                    name: t.name.clone(),
                    vertices,
                    triangles,
                    direction: t.motion.direction(),
                }
            })
            .collect();
        Self { tools }
    }

    /// Whether there is no tool.
    pub fn is_empty(&self) -> bool {
        self.tools.is_empty()
    }
}

/// Triangles of `surface` (counter-clockwise seen from the fabric), a plane
/// as a square about the projection of `centre` with side
/// [`PLANE_SIDE`]·`diagonal`.
fn tessellate(
    surface: &Surface,
    centre: Vector3<f64>,
    diagonal: f64,
) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
    match surface {
        Surface::Plane { point, normal } => {
            let c = centre - normal * (centre - point).dot(normal);
            // Any unit vector across the normal, then the third axis so
            // that (t1, t2, n) is right-handed: the square's corners in
            // order turn counter-clockwise about n.
            let helper = if normal.x.abs() < 0.9 {
                Vector3::x()
            } else {
                Vector3::y()
            };
            let t1 = normal.cross(&helper).normalize();
            let t2 = normal.cross(&t1);
            let a = 0.5 * PLANE_SIDE * diagonal;
            let vertices = vec![
                c - t1 * a - t2 * a,
                c + t1 * a - t2 * a,
                c + t1 * a + t2 * a,
                c - t1 * a + t2 * a,
            ];
            (vertices, vec![[0, 1, 2], [0, 2, 3]])
        }
        Surface::Sphere { center, radius } => {
            let (meridians, parallels) = SPHERE_STEPS;
            // A meridian from the north pole to the south: travelling down
            // the outside is on its left, the fabric's side of a revolution.
            let profile: Vec<[f64; 2]> = (0..=parallels)
                .map(|k| {
                    let a = std::f64::consts::FRAC_PI_2
                        - std::f64::consts::PI * k as f64 / parallels as f64;
                    [radius * a.cos(), radius * a.sin()]
                })
                .collect();
            revolve(*center, &profile, meridians)
        }
        Surface::Revolution {
            origin, profile, ..
        } => revolve(*origin, &sample_profile(profile), TURN_STEPS),
        Surface::Mesh(mesh) => (mesh.vertices().collect(), mesh.triangles().to_vec()),
    }
}

/// The profile as a polyline in (r, z): lines by their ends, arcs every
/// [`ARC_STEP_DEG`] at most; consecutive equal points merged.
fn sample_profile(profile: &[ProfileSegment]) -> Vec<[f64; 2]> {
    let mut points: Vec<[f64; 2]> = Vec::new();
    let mut push = |p: [f64; 2]| {
        if points.last() != Some(&p) {
            points.push(p);
        }
    };
    for s in profile {
        match *s {
            ProfileSegment::Line { from, to } => {
                push(from);
                push(to);
            }
            ProfileSegment::Arc {
                center,
                radius,
                from_deg,
                to_deg,
            } => {
                let n = ((to_deg - from_deg).abs() / ARC_STEP_DEG).ceil().max(1.0) as usize;
                for k in 0..=n {
                    let a = (from_deg + (to_deg - from_deg) * k as f64 / n as f64).to_radians();
                    push([center[0] + radius * a.cos(), center[1] + radius * a.sin()]);
                }
            }
        }
    }
    points
}

/// The polyline `profile` in (r, z) swept about the vertical axis through
/// `origin` in `steps` steps. With the profile's tangent T = (dr, dz) and
/// e_φ the direction of increasing azimuth, T × e_φ = dr·e_z − dz·e_r, the
/// left normal of travel: the triangles (s₀φ₀, s₁φ₀, s₁φ₁) and
/// (s₀φ₀, s₁φ₁, s₀φ₁) face the side the profile has on its left. Triangles
/// that close onto the axis (r = 0) are dropped as degenerate.
fn revolve(
    origin: Vector3<f64>,
    profile: &[[f64; 2]],
    steps: usize,
) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
    let mut vertices = Vec::with_capacity(profile.len() * steps);
    for &[r, z] in profile {
        for j in 0..steps {
            let phi = std::f64::consts::TAU * j as f64 / steps as f64;
            vertices.push(origin + Vector3::new(r * phi.cos(), r * phi.sin(), z));
        }
    }
    let id = |i: usize, j: usize| (i * steps + j % steps) as u32;
    let mut triangles = Vec::new();
    let on_axis = |i: usize| profile[i][0].abs() <= 1e-12 * (1.0 + profile[i][1].abs());
    for i in 0..profile.len().saturating_sub(1) {
        for j in 0..steps {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if !on_axis(i + 1) {
                triangles.push([a, b, c]);
            }
            if !on_axis(i) {
                triangles.push([a, c, d]);
            }
        }
    }
    (vertices, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use drape_contact::ToolMotion;

    fn tool(surface: Surface) -> Tool {
        Tool {
            name: "t".into(),
            surface,
            motion: ToolMotion::Fixed,
            friction: 0.0,
        }
    }

    /// Every triangle's normal points to the fabric's side (the surface's
    /// outward normal at the triangle's centroid), and every vertex lies on
    /// the surface.
    fn check_faces_the_fabric(surface: Surface) {
        let blank = [
            Vector3::new(-50.0, -50.0, 0.0),
            Vector3::new(50.0, 50.0, 0.0),
        ];
        let meshes = ToolMeshes::new(&[tool(surface.clone())], &blank);
        let m = &meshes.tools[0];
        assert!(!m.triangles.is_empty());
        for v in &m.vertices {
            assert!(surface.project(v).gap.abs() < 1e-9, "{v:?} off the surface");
        }
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            let n = (b - a).cross(&(c - a));
            assert!(n.norm() > 0.0, "degenerate triangle {t:?}");
            let centroid = (a + b + c) / 3.0;
            let outward = surface.project(&centroid).normal;
            assert!(
                n.normalize().dot(&outward) > 0.9,
                "triangle {t:?} faces away from the fabric: {n:?} vs {outward:?}"
            );
        }
    }

    #[test]
    fn tessellated_tools_face_the_fabric() {
        check_faces_the_fabric(
            Surface::plane(Vector3::new(0.0, 0.0, -3.0), Vector3::new(0.2, 0.1, 1.0)).unwrap(),
        );
        check_faces_the_fabric(Surface::sphere(Vector3::new(1.0, 2.0, -40.0), 40.0).unwrap());
        check_faces_the_fabric(
            Surface::hemispherical_punch(Vector3::new(0.0, 0.0, -1.0), 120.0, 200.0).unwrap(),
        );
        check_faces_the_fabric(
            Surface::hemispherical_punch_down(Vector3::new(0.0, 0.0, 20.0), 50.0, 30.0).unwrap(),
        );
        // A die as scenes build it: the opening's wall up, the fillet, the
        // face outwards; the fabric above the face and inside the opening.
        check_faces_the_fabric(
            Surface::revolution(
                Vector3::zeros(),
                vec![
                    ProfileSegment::Line {
                        from: [50.0, -80.0],
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
                        to: [150.0, 0.0],
                    },
                ],
            )
            .unwrap(),
        );
    }

    #[test]
    fn a_plane_is_a_square_about_the_blank_and_moves_with_its_tool() {
        let blank = [
            Vector3::new(-30.0, -40.0, 5.0),
            Vector3::new(30.0, 40.0, 5.0),
        ];
        let mut t = tool(Surface::plane(Vector3::zeros(), Vector3::z()).unwrap());
        t.motion = ToolMotion::Displacement {
            direction: Vector3::z(),
            distance: 10.0,
            amplitude: drape_contact::Amplitude::Constant,
        };
        let meshes = ToolMeshes::new(&[t], &blank);
        let m = &meshes.tools[0];
        // Diagonal 100 mm: a square 150 mm on a side, in z = 0, about (0, 0).
        let side = (m.vertices[1] - m.vertices[0]).norm();
        assert!((side - 150.0).abs() < 1e-9, "{side}");
        let centre: Vector3<f64> = m.vertices.iter().sum::<Vector3<f64>>() / 4.0;
        assert!(centre.norm() < 1e-9, "{centre:?}");
        let moved: Vec<_> = m.vertices_at(2.5).collect();
        assert!(moved.iter().all(|v| (v.z - 2.5).abs() < 1e-12));
    }
}
