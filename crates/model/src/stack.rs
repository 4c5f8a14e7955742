//! Laminates: several plies, each a blank model of its own, stacked by
//! their thicknesses into one [`Model`] whose nodes, element batches and
//! node sets are the plies' one after the other, bottom to top.
//!
//! A model of one ply (`[fabric]`) has no [`Ply`] list at all, so
//! nothing about it changes. What it is not: the ply–ply contact itself
//! (`drape_contact::PlyContact`, which [`Model::ply_layers`] feeds).

use std::ops::Range;

use drape_contact::{PlyInterface, PlyLayer};
use nalgebra::Vector3;

use serde::Serialize;

use crate::measures::{self, DrawIn, ProfileLine, ProfilePoint};
use crate::{BlankInfo, ElementFields, Model, ModelError};

/// One ply of a laminate.
#[derive(Debug, Clone)]
pub struct Ply {
    /// Its name (node sets `NAME` and `NAME.SET`, results, exports).
    pub name: String,
    /// Its nodes.
    pub nodes: Range<u32>,
    /// Its membrane batches (indices into [`Model::membranes`]).
    pub membranes: Range<usize>,
    /// Its membrane elements, in the order of [`crate::ElementFields`].
    pub elements: Range<usize>,
    /// Its thickness (mm).
    pub thickness: f64,
    /// Warp angle from x (degrees).
    pub orientation_deg: f64,
    /// Coulomb coefficient against the ply below (0 for the bottom ply).
    pub friction_below: f64,
    /// Its rectangle's edges and corners (for its draw-in), if it is one.
    pub blank: Option<BlankInfo>,
}

/// What summary.json reports of each ply at a state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlyMeasures {
    /// The ply's name.
    pub name: String,
    /// Largest |shear angle| of its elements (degrees).
    pub max_shear_deg: f64,
    /// Its wrinkle indicator: the largest element waviness (degrees)...
    pub max_waviness_deg: f64,
    /// ...and the area above the threshold (mm²).
    pub wrinkle_area_mm2: f64,
    /// Its draw-in, for a rectangle.
    pub draw_in: Option<DrawIn>,
}

/// One ply's shear profiles (`profiles.csv`'s rows of that ply): along
/// its own blank's diagonal and median, of its own elements only. A
/// laminate's plies lie one above the other in the blank plane, so the
/// stack's lines would pick up every ply's elements at once.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlyProfiles {
    /// The ply's name.
    pub name: String,
    /// Shear along its diagonal (empty for a ply from a mesh file).
    pub diagonal: Vec<ProfilePoint>,
    /// Shear along its median parallel to x.
    pub median: Vec<ProfilePoint>,
}

/// A ply to stack: its model (built alone, in its own blank plane) and
/// what the stack needs to know of it.
#[derive(Debug, Clone)]
pub struct PlyModel {
    /// The ply's own model (nodes, batches, node sets, blank).
    pub model: Model,
    /// Its name.
    pub name: String,
    /// Its thickness (mm).
    pub thickness: f64,
    /// Warp angle (degrees).
    pub orientation_deg: f64,
    /// Coulomb coefficient against the ply below.
    pub friction_below: f64,
}

impl Model {
    /// Half the thickness of each node's ply, node by node (for the
    /// tools' contact of a laminate whose plies differ in thickness);
    /// `contact_offset` for a node of no ply.
    pub fn ply_half_thickness_per_node(&self) -> Vec<f64> {
        let mut half = vec![self.contact_offset; self.x0.len()];
        for ply in &self.plies {
            for node in ply.nodes.clone() {
                half[node as usize] = 0.5 * ply.thickness;
            }
        }
        half
    }

    /// Stacks `plies` (bottom to top) into one model: each ply raised from
    /// the one below by half of each one's thickness along the bottom ply's
    /// normal (+z for a rectangle: the side its elements face), its nodes
    /// and batches renumbered behind the ones below. Node sets are the
    /// union of the plies' sets of the same name, each ply's own as
    /// `NAME.SET`, and all its nodes as `NAME`. The blank (for draw-in and
    /// profiles) is the bottom ply's; the tools' contact offset is the
    /// largest half thickness.
    pub fn stack(plies: Vec<PlyModel>) -> Result<Self, ModelError> {
        let Some(first) = plies.first() else {
            return Err(ModelError::Tool("a stack needs at least one ply".into()));
        };
        let normal = first.model.mean_normal();
        let mut out = Model {
            blank: first.model.blank.clone(),
            ..Model::default()
        };
        let mut lift = 0.0;
        let mut elements = 0;
        let mut previous_half = 0.0;
        for (p, ply) in plies.into_iter().enumerate() {
            let PlyModel {
                mut model,
                name,
                thickness,
                orientation_deg,
                friction_below,
            } = ply;
            if p > 0 {
                lift += previous_half + 0.5 * thickness;
            }
            previous_half = 0.5 * thickness;
            let shift = out.x0.len() as u32;
            let batch0 = out.membranes.len();
            let count: usize = model.membranes.iter().map(|b| b.len()).sum();
            for x in &mut model.x0 {
                *x += normal * lift;
            }
            out.x0.extend_from_slice(&model.x0);
            out.mass.extend_from_slice(&model.mass);
            for mut b in model.trusses {
                b.nodes.iter_mut().flatten().for_each(|n| *n += shift);
                out.trusses.push(b);
            }
            for mut b in model.membranes {
                b.shift_nodes(shift);
                out.membranes.push(b);
            }
            for mut b in model.bending {
                b.nodes.iter_mut().flatten().for_each(|n| *n += shift);
                out.bending.push(b);
            }
            for (set, nodes) in model.node_sets {
                let shifted: Vec<u32> = nodes.iter().map(|n| n + shift).collect();
                out.node_sets
                    .entry(set.clone())
                    .or_default()
                    .extend_from_slice(&shifted);
                out.node_sets.insert(format!("{name}.{set}"), shifted);
            }
            let end = out.x0.len() as u32;
            out.node_sets.insert(name.clone(), (shift..end).collect());
            let blank = model.blank.map(|mut b| {
                b.frame.center += normal * lift;
                b.midpoints.iter_mut().for_each(|n| *n += shift);
                b.corners.iter_mut().for_each(|n| *n += shift);
                b
            });
            out.contact_offset = out.contact_offset.max(0.5 * thickness);
            out.plies.push(Ply {
                name,
                nodes: shift..end,
                membranes: batch0..out.membranes.len(),
                elements: elements..elements + count,
                thickness,
                orientation_deg,
                friction_below: if p == 0 { 0.0 } else { friction_below },
                blank,
            });
            elements += count;
        }
        Ok(out)
    }

    /// The area-weighted normal of the membranes' reference elements, by
    /// their node order (+z for drape's own rectangles); +z for none.
    pub fn mean_normal(&self) -> Vector3<f64> {
        let mut n = Vector3::zeros();
        for b in &self.membranes {
            for e in 0..b.len() {
                let p: Vec<_> = b
                    .element_nodes(e)
                    .iter()
                    .map(|&i| self.x0[i as usize])
                    .collect();
                for k in 1..p.len() - 1 {
                    n += (p[k] - p[0]).cross(&(p[k + 1] - p[0]));
                }
            }
        }
        let len = n.norm();
        if len > 0.0 { n / len } else { Vector3::z() }
    }

    /// Each ply's peaks at positions `x` with the element `fields` there:
    /// largest shear, wrinkle indicator and draw-in (empty for one ply).
    pub fn ply_measures(&self, x: &[Vector3<f64>], fields: &ElementFields) -> Vec<PlyMeasures> {
        self.plies
            .iter()
            .map(|ply| {
                let e = ply.elements.clone();
                let max_shear_deg = fields.shear[e.clone()]
                    .iter()
                    .fold(0.0f64, |m, g| m.max(g.abs()))
                    .to_degrees();
                let (max_waviness_deg, wrinkle_area_mm2) =
                    measures::wrinkle_indicator(&fields.waviness[e.clone()], &fields.area[e]);
                PlyMeasures {
                    name: ply.name.clone(),
                    max_shear_deg,
                    max_waviness_deg,
                    wrinkle_area_mm2,
                    draw_in: ply
                        .blank
                        .as_ref()
                        .map(|b| measures::draw_in(&b.frame, &self.x0, x, b.midpoints, b.corners)),
                }
            })
            .collect()
    }

    /// Each ply's shear profiles with the element `fields` of a state,
    /// read on the ply's own blank (its frame and half its element size
    /// as the band, as [`Model::measures`] reads one ply's); empty for
    /// fewer than two plies, whose profiles are the model's.
    pub fn ply_profiles(&self, fields: &ElementFields) -> Vec<PlyProfiles> {
        if self.plies.len() < 2 {
            return Vec::new();
        }
        self.plies
            .iter()
            .map(|ply| {
                let e = ply.elements.clone();
                let profile = |line| match &ply.blank {
                    Some(b) => measures::shear_profile(
                        &b.frame,
                        &fields.centroid0[e.clone()],
                        &fields.shear[e.clone()],
                        line,
                        0.5 * b.cell_size,
                    ),
                    None => Vec::new(),
                };
                PlyProfiles {
                    name: ply.name.clone(),
                    diagonal: profile(ProfileLine::Diagonal),
                    median: profile(ProfileLine::MedianX),
                }
            })
            .collect()
    }

    /// The ply each node belongs to (0 for every node of a one-ply model).
    pub fn node_plies(&self) -> Vec<u32> {
        let mut out = vec![0; self.x0.len()];
        for (p, ply) in self.plies.iter().enumerate() {
            for n in ply.nodes.clone() {
                out[n as usize] = p as u32;
            }
        }
        out
    }

    /// The ply of each membrane element, in the order of
    /// [`crate::ElementFields`] (all 0 for a one-ply model).
    pub fn element_plies(&self) -> Vec<u32> {
        let count: usize = self.membranes.iter().map(|b| b.len()).sum();
        let mut out = vec![0; count];
        for (p, ply) in self.plies.iter().enumerate() {
            out[ply.elements.clone()]
                .iter_mut()
                .for_each(|v| *v = p as u32);
        }
        out
    }

    /// The direction up the stack: the bottom ply's mean normal
    /// ([`Self::mean_normal`]; +z for drape's own rectangles). The plies
    /// are laid on each other along it, and their faces are wound to it.
    pub fn stack_up(&self) -> Vector3<f64> {
        let Some(first) = self.plies.first() else {
            return self.mean_normal();
        };
        let part = Model {
            x0: self.x0.clone(),
            membranes: self.membranes[first.membranes.clone()].to_vec(),
            ..Model::default()
        };
        part.mean_normal()
    }

    /// The plies as the contact sees them (triangles wound up the stack,
    /// half thicknesses) and their interfaces; empty for fewer than two
    /// plies.
    pub fn ply_layers(&self) -> (Vec<PlyLayer>, Vec<PlyInterface>) {
        if self.plies.len() < 2 {
            return (Vec::new(), Vec::new());
        }
        let up = self.stack_up();
        let mut layers = Vec::new();
        for ply in &self.plies {
            let mut faces = Vec::new();
            for b in &self.membranes[ply.membranes.clone()] {
                for e in 0..b.len() {
                    let n = b.element_nodes(e);
                    for k in 1..n.len() - 1 {
                        faces.push([n[0], n[k], n[k + 1]]);
                    }
                }
            }
            // Wound up the stack, triangle by triangle (a mesh file's
            // elements may face either way).
            for f in &mut faces {
                let [a, b, c] = f.map(|i| self.x0[i as usize]);
                if (b - a).cross(&(c - a)).dot(&up) < 0.0 {
                    f.swap(1, 2);
                }
            }
            layers.push(PlyLayer {
                first_node: ply.nodes.start,
                node_count: ply.nodes.end - ply.nodes.start,
                faces,
                half_thickness: 0.5 * ply.thickness,
            });
        }
        let interfaces = (1..self.plies.len())
            .map(|p| PlyInterface {
                lower: p - 1,
                upper: p,
                friction: self.plies[p].friction_below,
            })
            .collect();
        (layers, interfaces)
    }

    /// Each node's reference area: Σ ∫Nₐ dA of its membranes (mm²).
    pub fn nodal_area(&self) -> Vec<f64> {
        let mut area = vec![0.0; self.x0.len()];
        for b in &self.membranes {
            for e in 0..b.len() {
                for (&n, a) in b.element_nodes(e).iter().zip(b.nodal_areas(e)) {
                    area[n as usize] += a;
                }
            }
        }
        area
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
    use drape_constitutive::Material;

    fn ply(orientation_deg: f64, thickness: f64, name: &str) -> PlyModel {
        let mut material = Material::preset("glass-serge-4x3").unwrap();
        material.thickness = thickness;
        let blank = RectangleBlank {
            width: 40.0,
            height: 20.0,
            center: Vector3::zeros(),
            orientation_deg,
            element: ElementKind::Quad,
            meshing: Meshing::Cells([4, 2]),
            fibres: FibreRepresentation::Embedded,
        };
        PlyModel {
            model: Model::from_blank(&blank, &material).unwrap(),
            name: name.into(),
            thickness,
            orientation_deg,
            friction_below: 0.3,
        }
    }

    #[test]
    fn plies_are_stacked_by_their_thicknesses_and_renumbered() {
        let one = ply(0.0, 0.5, "a");
        let n = one.model.x0.len() as u32;
        let model = Model::stack(vec![one, ply(90.0, 0.3, "b"), ply(45.0, 0.2, "c")]).unwrap();
        assert_eq!(model.x0.len() as u32, 3 * n);
        assert_eq!(model.plies[1].nodes, n..2 * n);
        // Mid-surfaces 0.4 then 0.25 apart.
        assert!((model.x0[n as usize].z - 0.4).abs() < 1e-15);
        assert!((model.x0[2 * n as usize].z - 0.65).abs() < 1e-15);
        assert_eq!(model.plies[0].friction_below, 0.0);
        assert_eq!(model.plies[2].friction_below, 0.3);
        assert_eq!(model.node_set("b").unwrap().len() as u32, n);
        assert_eq!(
            model.node_set("left").unwrap().len(),
            3 * model.node_set("a.left").unwrap().len()
        );
        // Every element's nodes within its own ply.
        let plies = model.node_plies();
        let element_ply = model.element_plies();
        let mut e = 0;
        for b in &model.membranes {
            for k in 0..b.len() {
                assert!(
                    b.element_nodes(k)
                        .iter()
                        .all(|&i| plies[i as usize] == element_ply[e])
                );
                e += 1;
            }
        }
        assert_eq!(e, model.plies[2].elements.end);
        let (layers, interfaces) = model.ply_layers();
        assert_eq!(layers.len(), 3);
        assert_eq!(interfaces.len(), 2);
        assert!((layers[1].half_thickness - 0.15).abs() < 1e-15);
        for l in &layers {
            for f in &l.faces {
                let [a, b, c] = f.map(|i| model.x0[i as usize]);
                assert!((b - a).cross(&(c - a)).z > 0.0);
            }
        }
    }
}
