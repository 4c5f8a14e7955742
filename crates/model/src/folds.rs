//! The fold check at the end of a run: whether the formed ply has folded
//! over itself or wrinkled over an area that makes its answer doubtful, and
//! where.
//!
//! A membrane without bending stiffness folds at no cost, so a run can end
//! "completed" with a ply lying doubled on itself and a shear field that
//! means nothing there. This module reads the end state for two signs of
//! that, each with a stated limit:
//!
//! - **Turned back**: two elements that share an edge with normals more
//!   than [`TURNED_BACK_DEG`] apart. A smooth ply on a tool of curvature κ
//!   turns by about κ·h from one element to the next; only a crease
//!   sharper than a right angle over one edge, the ply going back over
//!   itself, reaches 90°. Any such edge counts.
//! - **Creased**: the elements whose waviness
//!   ([`crate::measures::waviness`]) exceeds [`FOLD_WAVINESS_DEG`], over
//!   more than [`WAVY_AREA_SHARE`] of the blank's reference area. The
//!   wrinkle indicator's 5° ([`crate::measures::WRINKLE_THRESHOLD_DEG`])
//!   is too fine for this: flaps hanging free between holding points wave
//!   past it over 40 % of the shipped hemisphere's area without folding.
//!
//! What it is not: a wrinkle predictor. It says that the end state is not
//! a smoothly formed ply, not whether the part would wrinkle in the shop
//! (a membrane without bending folds where a real fabric would not, and a
//! fold on a coarse mesh may be a wrinkle on a fine one).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Angle between the normals of two elements sharing an edge beyond which
/// the ply has turned back over itself there (degrees) **\[choice\]**: a
/// right angle, which no smooth draping reaches between neighbours unless
/// the tool has an edge sharper than a right angle at the mesh's scale.
pub const TURNED_BACK_DEG: f64 = 90.0;

/// Waviness above which an element counts as creased in the fold check
/// (degrees) **\[choice\]**: 45°. A wave of wavelength λ = 6h on cells of
/// size h reads 2π²·a·h²/λ² ([`crate::measures::waviness`]), so 45° is an
/// amplitude of 1.4 cells: a crease at the mesh's scale, not a ripple.
/// The shipped hemisphere (40 × 40 cells, 300 mm stroke) with yarn
/// bending has waves up to 39° in the flaps that hang free between its
/// holding springs and none above 45°; without bending, 4.3 % of its area
/// is above 45° and 42 elements turn back over a neighbour.
pub const FOLD_WAVINESS_DEG: f64 = 45.0;

/// Share of the blank's reference area that may be creased
/// ([`FOLD_WAVINESS_DEG`]) before the check warns **\[choice\]**: 1 %,
/// so that a few elements at a flapping free corner do not warn, while a
/// fold along a line of elements does (a 40 × 40 blank: 16 elements).
pub const WAVY_AREA_SHARE: f64 = 0.01;

/// Yarn stretch below which a truss counts as gathered (shortened)
/// **\[choice\]**: 0.95. Yarns that buckle at no cost (`compression_factor
/// = 0`), or for less than shearing costs (the presets' Euler load,
/// `buckling_stress`), let a ply lie on a double-curved mould by
/// shortening instead of shearing, gathering material below the mesh's
/// scale where a real fabric wrinkles; waviness cannot see it. The shipped
/// hemisphere's yarns end no shorter than 0.969 (0.7 % of them below
/// 0.98; before the presets' buckling law); the open tray formed by a
/// punch has 17.5 % of its yarns' length below 0.95, down to 0.83, in the
/// corners where a pin-jointed net shears 45° and the run 24°.
pub const GATHERED_STRETCH: f64 = 0.95;

/// Share of the yarns' reference length that may be gathered
/// ([`GATHERED_STRETCH`]) before the check warns **\[choice\]**: 1 %, as
/// for the creased area.
pub const GATHERED_SHARE: f64 = 0.01;

/// Yarns shortened beyond [`GATHERED_STRETCH`]: material gathered below
/// the mesh's scale.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Gathering {
    /// Share of the yarns' reference length shortened beyond the limit.
    pub share: f64,
    /// The shortest yarn's stretch l/L₀.
    pub shortest_stretch: f64,
    /// Where that yarn is (its midpoint, mm).
    pub at: [f64; 3],
}

impl Gathering {
    /// The gathering of yarns given as (stretch, reference length, current
    /// midpoint); `None` when no yarn is shorter than the limit.
    pub fn of(yarns: impl Iterator<Item = (f64, f64, Vector3<f64>)>) -> Option<Self> {
        let (mut total, mut short) = (0.0, 0.0);
        let mut shortest: Option<(f64, Vector3<f64>)> = None;
        for (stretch, length, mid) in yarns {
            total += length;
            if stretch < GATHERED_STRETCH {
                short += length;
            }
            if shortest.is_none_or(|(s, _)| stretch < s) {
                shortest = Some((stretch, mid));
            }
        }
        let (stretch, at) = shortest?;
        (short > 0.0).then(|| Self {
            share: short / total,
            shortest_stretch: stretch,
            at: at.into(),
        })
    }
}

/// One element the check points at.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct FoldSite {
    /// Its index among the membranes (the order of the result files).
    pub element: usize,
    /// Its current centroid (mm).
    pub at: [f64; 3],
    /// Its largest angle to an edge neighbour's normal (degrees).
    pub turn_deg: f64,
    /// Its waviness (degrees).
    pub waviness_deg: f64,
}

/// What the fold check found.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct FoldCheck {
    /// Whether the ply folds by either limit: the run warns.
    pub folded: bool,
    /// Elements with an edge neighbour turned back beyond
    /// [`TURNED_BACK_DEG`].
    pub turned_back_elements: usize,
    /// Their reference area (mm²).
    pub turned_back_area_mm2: f64,
    /// Reference area of the elements wavier than [`FOLD_WAVINESS_DEG`] (mm²).
    pub wavy_area_mm2: f64,
    /// The limit on it: [`WAVY_AREA_SHARE`] of the blank's area (mm²).
    pub wavy_area_limit_mm2: f64,
    /// The element most turned back, or else the waviest one; `None` for
    /// a ply without either.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub worst: Option<FoldSite>,
    /// Yarns shortened beyond [`GATHERED_STRETCH`] (trusses only; `None`
    /// when none is).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gathered: Option<Gathering>,
}

/// The fold check of a state: `elements` are the node lists of every
/// membrane element (consistently oriented, as for
/// [`crate::measures::waviness`]), `x` the current positions, `waviness`,
/// `area` (reference) and `centroid` (current) per element.
pub fn fold_check(
    elements: &[&[u32]],
    x: &[Vector3<f64>],
    waviness: &[f64],
    area: &[f64],
    centroid: &[Vector3<f64>],
) -> FoldCheck {
    debug_assert!(waviness.len() == elements.len() && area.len() == elements.len());
    let normals: Vec<Vector3<f64>> = elements
        .iter()
        .map(|nodes| crate::measures::element_normal(nodes, x))
        .collect();
    // Each edge with the elements that have it, by sorted node pair.
    let mut edges: Vec<([u32; 2], usize)> = Vec::new();
    for (e, nodes) in elements.iter().enumerate() {
        for k in 0..nodes.len() {
            let (a, b) = (nodes[k], nodes[(k + 1) % nodes.len()]);
            edges.push(([a.min(b), a.max(b)], e));
        }
    }
    edges.sort_unstable();
    let mut turn = vec![0.0f64; elements.len()];
    for pair in edges.windows(2) {
        let ((ea, a), (eb, b)) = (pair[0], pair[1]);
        if ea == eb {
            let angle = normals[a]
                .dot(&normals[b])
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
            turn[a] = turn[a].max(angle);
            turn[b] = turn[b].max(angle);
        }
    }
    let total_area: f64 = area.iter().sum();
    let mut check = FoldCheck {
        wavy_area_limit_mm2: WAVY_AREA_SHARE * total_area,
        ..FoldCheck::default()
    };
    for e in 0..elements.len() {
        if turn[e] > TURNED_BACK_DEG {
            check.turned_back_elements += 1;
            check.turned_back_area_mm2 += area[e];
        }
        if waviness[e] > FOLD_WAVINESS_DEG {
            check.wavy_area_mm2 += area[e];
        }
    }
    let site = |e: usize| FoldSite {
        element: e,
        at: centroid[e].into(),
        turn_deg: turn[e],
        waviness_deg: waviness[e],
    };
    // Ties keep the lowest index, so the site does not depend on anything
    // but the state.
    let worst_by = |value: &[f64]| {
        (0..elements.len()).fold(None, |best: Option<usize>, e| match best {
            Some(b) if value[b] >= value[e] => Some(b),
            _ => Some(e),
        })
    };
    check.worst = if check.turned_back_elements > 0 {
        worst_by(&turn).map(site)
    } else {
        worst_by(waviness)
            .filter(|&e| waviness[e] > FOLD_WAVINESS_DEG)
            .map(site)
    };
    check.folded =
        check.turned_back_elements > 0 || check.wavy_area_mm2 > check.wavy_area_limit_mm2;
    check
}

impl FoldCheck {
    /// Adds the yarns' gathering to the check: past [`GATHERED_SHARE`] the
    /// ply counts as folded.
    pub fn with_gathering(mut self, gathered: Option<Gathering>) -> Self {
        self.gathered = gathered;
        self.folded |= gathered.is_some_and(|g| g.share > GATHERED_SHARE);
        self
    }

    /// Whether the yarns' gathering is past its limit.
    fn gathers(&self) -> bool {
        self.gathered.is_some_and(|g| g.share > GATHERED_SHARE)
    }

    /// The warning a run ends with when the ply folds (`None` when it does
    /// not): what, where, and what to change; `bending` says whether the
    /// run had yarn bending.
    pub fn warning(&self, bending: bool) -> Option<String> {
        self.warning_advising(if bending {
            "Yarn bending was on: refine the mesh there, hold the blank more (holder force, \
             springs), or check the material's bending_rigidity"
        } else {
            "Yarn bending was off, so the membrane folded at no cost: turn it on \
             (fabric.bending = true, with the material's bending_rigidity = [warp, weft] in \
             N·mm), or hold the blank more (holder force, springs) and refine the mesh"
        })
    }

    fn warning_advising(&self, advice: &str) -> Option<String> {
        if !self.folded {
            return None;
        }
        if self.turned_back_elements == 0
            && self.wavy_area_mm2 <= self.wavy_area_limit_mm2
            && let Some(g) = self.gathered.filter(|_| self.gathers())
        {
            return Some(format!(
                "the ply gathers: {:.1} % of its yarns' length is shorter than {:.0} % of its start \
                 (the shortest at {:.3} of its length, at ({:.1}, {:.1}, {:.1}) mm): the yarns buckle \
                 there below the mesh's scale, so the ply lies on the tool by gathering material where \
                 a fabric shears or wrinkles. Shear there is not that of a formed ply (see stretch in \
                 trusses.pvd): hold the blank so that it shears instead (holder force, springs), or \
                 give the yarns more compressive stiffness (fibre.buckling_stress, or \
                 fibre.compression_factor)",
                100.0 * g.share,
                100.0 * GATHERED_STRETCH,
                g.shortest_stretch,
                g.at[0],
                g.at[1],
                g.at[2],
            ));
        }
        let mut text = String::from("the ply folds: ");
        if self.turned_back_elements > 0 {
            text.push_str(&format!(
                "{} elements ({:.0} mm²) turn back over a neighbour by more than {:.0}°",
                self.turned_back_elements, self.turned_back_area_mm2, TURNED_BACK_DEG
            ));
            if self.wavy_area_mm2 > 0.0 {
                text.push_str(", and ");
            }
        }
        if self.wavy_area_mm2 > 0.0 {
            text.push_str(&format!(
                "{:.0} mm² is wavier than {:.0}° (the limit is {:.0} mm², {:.0} % of the blank)",
                self.wavy_area_mm2,
                FOLD_WAVINESS_DEG,
                self.wavy_area_limit_mm2,
                100.0 * WAVY_AREA_SHARE
            ));
        }
        if let Some(w) = &self.worst {
            text.push_str(&format!(
                "; worst at element {} at ({:.1}, {:.1}, {:.1}) mm, turned {:.1}° from a \
                 neighbour, waviness {:.1}°",
                w.element, w.at[0], w.at[1], w.at[2], w.turn_deg, w.waviness_deg
            ));
        }
        text.push_str(
            ". Shear and draw-in there are not those of a formed ply (see waviness in the \
             VTU frames). ",
        );
        text.push_str(advice);
        Some(text)
    }
}

#[cfg(test)]
mod gathering_tests {
    use super::*;

    #[test]
    fn yarns_shortened_past_the_limit_over_their_share_fold_the_ply() {
        let mid = |i: f64| Vector3::new(i, 0.0, 0.0);
        // 100 yarns of 1 mm: one at 0.9, the rest taut: 1 % gathered, at
        // the limit, not past it.
        let one =
            Gathering::of((0..100).map(|i| (if i == 7 { 0.9 } else { 1.0 }, 1.0, mid(i as f64))))
                .expect("one yarn is short");
        assert_eq!(one.share, 0.01);
        assert_eq!((one.shortest_stretch, one.at), (0.9, [7.0, 0.0, 0.0]));
        let check = FoldCheck::default().with_gathering(Some(one));
        assert!(!check.folded && check.warning(true).is_none());
        // Two of them (one at exactly the limit does not count): past it.
        let two = Gathering::of((0..100).map(|i| {
            let s = match i {
                3 => 0.94,
                7 => 0.9,
                9 => GATHERED_STRETCH,
                _ => 1.0,
            };
            (s, 1.0, mid(i as f64))
        }))
        .unwrap();
        assert_eq!(two.share, 0.02);
        let check = FoldCheck::default().with_gathering(Some(two));
        let text = check.warning(true).expect("past the share, it warns");
        assert!(
            check.folded && text.starts_with("the ply gathers: 2.0 %"),
            "{text}"
        );
        assert!(
            text.contains("(7.0, 0.0, 0.0)") && text.contains("compression_factor"),
            "{text}"
        );
        // Taut yarns: nothing.
        assert_eq!(
            Gathering::of((0..10).map(|i| (1.001, 1.0, mid(i as f64)))),
            None
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `n` unit quads along x in the plane z = 0, nodes
    /// 0..=n along y = 0 and n+1..=2n+1 along y = 1.
    fn strip(n: u32) -> (Vec<[u32; 4]>, Vec<Vector3<f64>>) {
        let mut x = Vec::new();
        for row in 0..2 {
            for i in 0..=n {
                x.push(Vector3::new(i as f64, row as f64, 0.0));
            }
        }
        let quads = (0..n).map(|i| [i, i + 1, n + 2 + i, n + 1 + i]).collect();
        (quads, x)
    }

    fn check(quads: &[[u32; 4]], x: &[Vector3<f64>], waviness: &[f64]) -> FoldCheck {
        let elements: Vec<&[u32]> = quads.iter().map(|q| q.as_slice()).collect();
        let area = vec![1.0; quads.len()];
        let centroid: Vec<Vector3<f64>> = quads
            .iter()
            .map(|q| q.iter().map(|&n| x[n as usize]).sum::<Vector3<f64>>() / 4.0)
            .collect();
        fold_check(&elements, x, waviness, &area, &centroid)
    }

    #[test]
    fn a_flat_or_gently_bent_strip_does_not_fold() {
        let (quads, mut x) = strip(10);
        let flat = check(&quads, &x, &[0.0; 10]);
        assert!(!flat.folded && flat.worst.is_none(), "{flat:?}");
        assert_eq!(flat.wavy_area_limit_mm2, 0.1);
        assert_eq!(flat.warning(false), None);
        // Rolled onto a cylinder of radius 2 about the y axis: 28.6°
        // between neighbours, far below a right angle.
        for p in &mut x {
            let phi = p.x / 2.0;
            *p = Vector3::new(2.0 * phi.sin(), p.y, 2.0 * (1.0 - phi.cos()));
        }
        let rolled = check(&quads, &x, &[0.0; 10]);
        assert!(!rolled.folded, "{rolled:?}");
        assert_eq!(rolled.turned_back_elements, 0);
    }

    #[test]
    fn a_strip_folded_over_itself_is_found_and_located() {
        // Nodes beyond x = 6 folded back over the strip, 0.1 above it:
        // elements 0–5 point up, 6 stands on its edge, 7–9 point down.
        let (quads, mut x) = strip(10);
        for p in &mut x {
            if p.x > 6.0 {
                *p = Vector3::new(12.0 - p.x, p.y, 0.1);
            }
        }
        let c = check(&quads, &x, &[0.0; 10]);
        assert!(c.folded, "{c:?}");
        // Element 6 rises 0.1 over its unit length and points down: it
        // turns 180° − atan(0.1) from element 5 and atan(0.1) from 7, so
        // 5 and 6 are the pair, tied, and the lower index is reported.
        assert_eq!(c.turned_back_elements, 2, "{c:?}");
        assert_eq!(c.turned_back_area_mm2, 2.0);
        let worst = c.worst.unwrap();
        assert_eq!(worst.element, 5);
        let expected = 180.0 - 0.1f64.atan().to_degrees();
        assert!((worst.turn_deg - expected).abs() < 1e-9, "{worst:?}");
        assert_eq!(worst.at, [5.5, 0.5, 0.0]);
        let text = c.warning(false).unwrap();
        assert!(
            text.contains("element 5")
                && text.contains("(5.5, 0.5, 0.0)")
                && text.contains("2 elements (2 mm²)")
                && text.contains("fabric.bending = true"),
            "{text}"
        );
        assert!(c.warning(true).unwrap().contains("refine the mesh"));
    }

    #[test]
    fn the_creased_area_warns_past_its_share_only() {
        let (quads, x) = strip(100);
        let mut waviness = vec![0.0; 100];
        // Ripples below the crease limit count for nothing.
        waviness[20] = 44.0;
        waviness[30] = 30.0;
        // 1 of 100 unit elements creased: exactly the 1 % limit, not past it.
        waviness[40] = 60.0;
        let at_limit = check(&quads, &x, &waviness);
        assert_eq!(at_limit.wavy_area_mm2, 1.0);
        assert_eq!(at_limit.wavy_area_limit_mm2, 1.0);
        assert!(!at_limit.folded, "{at_limit:?}");
        assert_eq!(at_limit.warning(true), None);
        // The site is still reported: the waviest element.
        assert_eq!(at_limit.worst.unwrap().element, 40);
        waviness[70] = 46.0;
        let past = check(&quads, &x, &waviness);
        assert!(past.folded && past.turned_back_elements == 0, "{past:?}");
        let text = past.warning(true).unwrap();
        assert!(text.contains("2 mm² is wavier than 45°"), "{text}");
        // At the limit itself an element is not creased.
        waviness[70] = FOLD_WAVINESS_DEG;
        assert!(!check(&quads, &x, &waviness).folded);
    }
}
