//! The free space a yarn has between two tools, from the explicit contact
//! pass's projections: what a confined yarn law
//! (`FibreLaw::confined_stress_and_tangent` in drape-constitutive) needs.
//!
//! Not for contact itself: nothing here constrains a node; it reads the
//! gaps the last narrow phase found.

use nalgebra::Vector3;

use super::ExplicitContact;

/// Per node, the nearest tool's gap and normal found so far while looking
/// for the tool on the other side (scratch of [`ExplicitContact::clearance_into`]).
pub type Nearest = (f64, Vector3<f64>);

impl ExplicitContact {
    /// Per node, the clearance c (mm) between the ply's faces and two tools
    /// on either side of it: g₁ + g₂ − 2·offset (offset: the half ply
    /// thickness the contact keeps), from each tool's last projection of
    /// the node, for the nearest tool and the nearest one whose normal
    /// opposes it (n₁·n₂ < 0: the node lies between them); infinite where
    /// no two tools face each other across the node, 0 where the gaps are
    /// already closed (a node the step pushed in).
    ///
    /// The gaps are the ones the last narrow phase projected. A tool
    /// farther than the offset and [`crate::ContactSettings::clearance_reach`]
    /// from the node is no wall (room a confined yarn never meets); the
    /// nearer ones were all projected at this step, so the clearance
    /// depends on the positions alone (a node the narrow phase skipped
    /// keeps the gap it had when last projected, which a resumed run does
    /// not have). `nearest` is scratch, grown to the node count on the
    /// first call only. Deterministic: each node's result is a minimum
    /// over the tools and candidates in their fixed order.
    pub fn clearance_into(&self, nearest: &mut Vec<Nearest>, out: &mut [f64]) {
        let none = (f64::INFINITY, Vector3::zeros());
        nearest.resize(out.len(), none);
        nearest.fill(none);
        out.fill(f64::INFINITY);
        let wall = self.settings.offset + self.settings.clearance_reach;
        let projections = || {
            self.candidates
                .iter()
                .zip(&self.scratch.projected)
                .flat_map(|(c, p)| c.iter().zip(p))
                .filter(|(_, p)| p.gap <= wall)
        };
        for (&i, p) in projections() {
            let n = &mut nearest[i as usize];
            if p.gap < n.0 {
                *n = (p.gap, p.normal);
            }
        }
        for (&i, p) in projections() {
            let (gap, normal) = nearest[i as usize];
            if p.normal.dot(&normal) < 0.0 {
                let offset = super::offset_at(&self.node_offset, self.settings.offset, i as usize);
                let c = &mut out[i as usize];
                *c = c.min((gap + p.gap - 2.0 * offset).max(0.0));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::Surface;
    use crate::tool::{Tool, ToolMotion};
    use crate::{ContactSettings, ExplicitContact};

    fn plane(name: &str, z: f64, up: bool) -> Tool {
        let normal = if up { Vector3::z() } else { -Vector3::z() };
        Tool {
            name: name.into(),
            surface: Surface::plane(Vector3::new(0.0, 0.0, z), normal).unwrap(),
            motion: ToolMotion::Fixed,
            friction: 0.0,
        }
    }

    fn clearance(tools: Vec<Tool>, z: &[f64]) -> Vec<f64> {
        clearance_within(tools, z, 2.0)
    }

    fn clearance_within(tools: Vec<Tool>, z: &[f64], reach: f64) -> Vec<f64> {
        let n = z.len();
        let settings = ContactSettings {
            offset: 0.1,
            margin: 5.0,
            clearance_reach: reach,
            ..ContactSettings::default()
        };
        let mut contact = ExplicitContact::new(tools, n, settings);
        let mut x: Vec<_> = z
            .iter()
            .enumerate()
            .map(|(i, &z)| Vector3::new(i as f64, 0.5 * i as f64, z))
            .collect();
        let mut v = vec![Vector3::zeros(); n];
        contact
            .enforce(&mut x, &mut v, &vec![1e-6; n], &vec![true; n], 0.01, 0.01)
            .unwrap();
        let (mut nearest, mut out) = (Vec::new(), vec![f64::NAN; n]);
        contact.clearance_into(&mut nearest, &mut out);
        // Scratch sized once: a second call does not grow it.
        let capacity = nearest.capacity();
        contact.clearance_into(&mut nearest, &mut out);
        assert_eq!(nearest.capacity(), capacity);
        out
    }

    #[test]
    fn clearance_is_the_gap_between_facing_tools_less_the_thickness() {
        // A mould at z = 0 (normal up) and a punch at z = 1.3 (normal
        // down), offset 0.1 (a 0.2 mm ply): 1.1 mm of room wherever the
        // node sits between them, pressed on the mould or not.
        let c = clearance(
            vec![plane("mould", 0.0, true), plane("punch", 1.3, false)],
            &[0.1, 0.65, 1.2, 0.12],
        );
        for c in c {
            assert!((c - 1.1).abs() < 1e-12, "{c}");
        }
        // A tool farther than the offset and the clearance reach (1.1 mm)
        // from the node is no wall: the punch 1.2 mm above a node on the
        // mould; a node midway has both within it.
        let c = clearance_within(
            vec![plane("mould", 0.0, true), plane("punch", 1.3, false)],
            &[0.1, 0.65],
            1.0,
        );
        assert_eq!(c[0], f64::INFINITY);
        assert!((c[1] - 1.1).abs() < 1e-12, "{c:?}");
        // Closed to the thickness: none.
        let c = clearance(
            vec![plane("mould", 0.0, true), plane("punch", 0.2, false)],
            &[0.1],
        );
        assert!(c[0].abs() < 1e-12, "{c:?}");
        // One tool, or two on the same side: nothing to confine between.
        for tools in [
            vec![plane("mould", 0.0, true)],
            vec![plane("mould", 0.0, true), plane("holder", -0.5, true)],
        ] {
            assert_eq!(clearance(tools, &[0.1, 0.4]), [f64::INFINITY; 2]);
        }
    }

    /// A yarn's clearance is the positions' alone: a contact pass that
    /// remembers its projections (and skips a node far from a tool) gives
    /// a node pressed on a mould, under a punch coming down within the
    /// clearance reach, the same clearance at every step as a pass made
    /// new at each step (what a resumed run has). Without the reach, the
    /// punch's gap was the one of the step it was last projected at.
    #[test]
    fn a_clearance_does_not_depend_on_when_the_node_was_projected() {
        let punch = || Tool {
            name: "punch".into(),
            surface: Surface::plane(Vector3::new(0.0, 0.0, 0.8), -Vector3::z()).unwrap(),
            motion: ToolMotion::Displacement {
                direction: -Vector3::z(),
                distance: 0.5,
                amplitude: crate::tool::Amplitude::Ramp { duration: 1.0 },
            },
            friction: 0.0,
        };
        let settings = ContactSettings {
            offset: 0.1,
            margin: 5.0,
            clearance_reach: 1.0,
            ..ContactSettings::default()
        };
        let n = 3;
        let tools = || vec![plane("mould", 0.0, true), punch()];
        let mut remembering = ExplicitContact::new(tools(), n, settings);
        let (mut nearest, mut kept, mut new) = (Vec::new(), vec![0.0; n], vec![0.0; n]);
        let dt = 0.01;
        for k in 1..=50 {
            let t = k as f64 * dt;
            let mut x: Vec<_> = (0..n).map(|i| Vector3::new(i as f64, 0.0, 0.1)).collect();
            let mut v = vec![Vector3::zeros(); n];
            let (mut x_new, mut v_new) = (x.clone(), v.clone());
            let mut fresh = ExplicitContact::new(tools(), n, settings);
            fresh.tool_state.clone_from(&remembering.tool_state);
            remembering
                .enforce(&mut x, &mut v, &[1e-6; 3], &[true; 3], t, dt)
                .unwrap();
            fresh
                .enforce(&mut x_new, &mut v_new, &[1e-6; 3], &[true; 3], t, dt)
                .unwrap();
            remembering.clearance_into(&mut nearest, &mut kept);
            fresh.clearance_into(&mut nearest, &mut new);
            assert_eq!(kept, new, "step {k}");
            // The punch 0.6 mm above the nodes, closing 5 µm a step.
            let expected = 0.6 - 0.5 * t;
            assert!((new[0] - expected).abs() < 1e-12, "step {k}: {new:?}");
        }
    }
}
