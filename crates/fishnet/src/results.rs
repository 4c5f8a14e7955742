//! A draped net as drape's model types, so that the results writer of a
//! forming run (drape-io) writes it unchanged and a user compares the two
//! with the same tools.
//!
//! The model is the flat net: one quad per draped cell (counter-clockwise
//! seen from +z, the fabric's membranes with embedded fibres along the
//! warp), its nodes the crossings at their flat positions. The state puts
//! the crossings on the mould. The element fields are the net's own:
//!
//! | field | kinematic value |
//! |---|---|
//! | shear | the cell's shear angle (not an element's Gauss-point mean) |
//! | fibre stretch | the cell's mean segment length over the spacing: 1 to the placement tolerance |
//! | fibre direction | the cell's warp and weft directions |
//! | fibre stress, tension, resin stress | 0: the net carries no load |
//! | thickness | h₀·(flat area / draped area): the fabric's volume kept, h₀/cos γ on a flat cell |
//!
//! The measures are those of a forming run, by the same functions
//! ([`drape_model::measures`]): largest |γ| and where, the diagonal and
//! median profiles (flat cell centres within half a cell of the line),
//! the flat area above the locking angle, and the draw-in of the blank's
//! edge midpoints and corners, read at those flat points by bilinear
//! interpolation in their draped cell (DX, DY or DD NaN when one of its
//! points is off the draped net).

use drape_constitutive::Material;
use drape_model::blank::{BlankMesh, FibreRepresentation};
use drape_model::measures::{self, ProfileLine};
use drape_model::{ElementFields, Measures, Model, ModelError, State};
use nalgebra::Vector3;

use crate::Net;

/// A draped net as a forming run's results.
#[derive(Debug, Clone)]
pub struct NetResults {
    /// The flat net: one quad per draped cell.
    pub model: Model,
    /// The crossings on the mould (velocities zero, time 0).
    pub state: State,
    /// Per cell, in the model's element order.
    pub fields: ElementFields,
    /// The derived measures.
    pub measures: Measures,
}

impl Net {
    /// The net as drape's model types, its crossings moved by `shift` (the
    /// mould's displacement, so that the net lies where the formed part of
    /// a run does), `material` giving the thickness and the model's
    /// elements, `locking_deg` the locking angle of the area at risk.
    pub fn results(
        &self,
        material: &Material,
        shift: Vector3<f64>,
        locking_deg: f64,
    ) -> Result<NetResults, ModelError> {
        let (warp0, _) = self.fibre_axes();
        let [dw, df] = self.spec().spacing;
        let mut id: std::collections::HashMap<[i32; 2], u32> = std::collections::HashMap::new();
        let mut mesh = BlankMesh {
            warp: warp0,
            ..BlankMesh::default()
        };
        let mut x = Vec::new();
        for cell in self.cells() {
            let [i, j] = cell.index;
            let quad = [[i, j], [i + 1, j], [i + 1, j + 1], [i, j + 1]].map(|[a, b]| {
                *id.entry([a, b]).or_insert_with(|| {
                    mesh.x0.push(self.flat(a, b));
                    x.push(
                        self.node(a, b)
                            .expect("a draped cell's crossings are placed")
                            + shift,
                    );
                    (mesh.x0.len() - 1) as u32
                })
            });
            mesh.quads.push(quad);
        }
        let model = Model::from_mesh(&mesh, material, FibreRepresentation::Embedded)?;
        let mut state = model.initial_state();
        state.x = x;

        let flat_area = dw * df;
        let mut fields = ElementFields::default();
        for cell in self.cells() {
            let [i, j] = cell.index;
            fields.shear.push(cell.shear);
            fields.fibre_stretch.push(cell.stretch);
            fields.fibre_direction.push([cell.warp, cell.weft]);
            fields.fibre_stress.push([0.0; 2]);
            fields.fibre_tension.push([0.0; 2]);
            fields.resin_stress.push([0.0; 3]);
            fields
                .thickness
                .push(material.thickness * flat_area / cell.area);
            fields
                .centroid0
                .push((self.flat(i, j) + self.flat(i + 1, j + 1)) / 2.0);
            fields.centroid.push(cell.centroid + shift);
            fields.area.push(flat_area);
        }
        fields.waviness = model.waviness(&state.x);

        let frame = self.spec().outline;
        let mut m = Measures::default();
        if let Some((k, g)) = fields
            .shear
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        {
            m.max_shear_deg = g.abs().to_degrees();
            m.max_shear_at = fields.centroid[k].into();
        }
        m.area_above_locking =
            measures::area_above(&fields.shear, &fields.area, locking_deg.to_radians());
        // The wrinkle indicator as a forming run's (`Model::measures`).
        (m.max_waviness_deg, m.wrinkle_area) =
            measures::wrinkle_indicator(&fields.waviness, &fields.area);
        let band = 0.5 * flat_area.sqrt();
        let profile =
            |line| measures::shear_profile(&frame, &fields.centroid0, &fields.shear, line, band);
        m.profile_diagonal = profile(ProfileLine::Diagonal);
        m.profile_median = profile(ProfileLine::MedianX);

        // Draw-in at the flat edge midpoints [left, right, bottom, top]
        // and corners [bottom-left, bottom-right, top-right, top-left].
        let (c, w, h) = (frame.center, 0.5 * frame.width, 0.5 * frame.height);
        let points: Vec<Vector3<f64>> = [
            (-w, 0.0),
            (w, 0.0),
            (0.0, -h),
            (0.0, h),
            (-w, -h),
            (w, -h),
            (w, h),
            (-w, h),
        ]
        .iter()
        .map(|&(a, b)| c + Vector3::new(a, b, 0.0))
        .collect();
        // Each measure needs its own points only: a net that stops short
        // of the corners (an open mould's edge) still has DX and DY.
        let moved: Vec<Option<Vector3<f64>>> = points
            .iter()
            .map(|p| self.position_at(p).map(|q| q + shift))
            .collect();
        let filled: Vec<Vector3<f64>> = moved
            .iter()
            .zip(&points)
            .map(|(m, p)| m.unwrap_or(*p))
            .collect();
        let mut draw_in = measures::draw_in(&frame, &points, &filled, [0, 1, 2, 3], [4, 5, 6, 7]);
        let missing = |r: std::ops::Range<usize>| moved[r].iter().any(Option::is_none);
        for (range, value) in [
            (0..2, &mut draw_in.dx),
            (2..4, &mut draw_in.dy),
            (4..8, &mut draw_in.dd),
        ] {
            if missing(range) {
                *value = f64::NAN;
            }
        }
        m.draw_in = Some(draw_in);
        Ok(NetResults {
            model,
            state,
            fields,
            measures: m,
        })
    }
}
