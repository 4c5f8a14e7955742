//! Holding springs from a node to a fixed anchor with a tabulated
//! force–extension law (the paper's nonlinear springs).

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// A piecewise-linear force F(δ) of the extension δ = l − L₀, through the
/// table's points and continued beyond its ends with the end slopes.
///
/// A preloaded spring has F(0) > 0; a spring that only pulls has F = 0 for
/// δ ≤ 0 (give a point at negative extension with zero force).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "Vec<[f64; 2]>", into = "Vec<[f64; 2]>")]
pub struct ForceTable {
    extension: Vec<f64>,
    force: Vec<f64>,
}

/// A force table that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ForceTableError {
    /// Fewer than two points.
    #[error("a force–extension table needs at least 2 points, it has {0}")]
    TooShort(usize),
    /// Extensions not strictly increasing at the given point.
    #[error("extensions must increase strictly: point {index} ({value}) does not")]
    NotIncreasing {
        /// Index of the offending point.
        index: usize,
        /// Its extension.
        value: f64,
    },
    /// A NaN or infinite entry.
    #[error("point {index} of the force–extension table is not finite")]
    NonFinite {
        /// Index of the offending point.
        index: usize,
    },
}

impl TryFrom<Vec<[f64; 2]>> for ForceTable {
    type Error = ForceTableError;
    fn try_from(points: Vec<[f64; 2]>) -> Result<Self, Self::Error> {
        Self::new(&points)
    }
}

impl From<ForceTable> for Vec<[f64; 2]> {
    fn from(t: ForceTable) -> Self {
        t.extension
            .iter()
            .zip(&t.force)
            .map(|(&d, &f)| [d, f])
            .collect()
    }
}

impl ForceTable {
    /// A table through `points` = [extension, force] pairs.
    pub fn new(points: &[[f64; 2]]) -> Result<Self, ForceTableError> {
        if points.len() < 2 {
            return Err(ForceTableError::TooShort(points.len()));
        }
        for (index, p) in points.iter().enumerate() {
            if !(p[0].is_finite() && p[1].is_finite()) {
                return Err(ForceTableError::NonFinite { index });
            }
            if index > 0 && p[0] <= points[index - 1][0] {
                return Err(ForceTableError::NotIncreasing { index, value: p[0] });
            }
        }
        Ok(Self {
            extension: points.iter().map(|p| p[0]).collect(),
            force: points.iter().map(|p| p[1]).collect(),
        })
    }

    /// A linear spring F = preload + k·δ.
    pub fn linear(stiffness: f64, preload: f64) -> Self {
        Self {
            extension: vec![0.0, 1.0],
            force: vec![preload, preload + stiffness],
        }
    }

    /// The segment that holds δ (the end segments extend to ±∞).
    #[inline]
    fn segment(&self, delta: f64) -> usize {
        let last = self.extension.len() - 2;
        self.extension[1..=last].partition_point(|&d| d <= delta)
    }

    /// F(δ) and dF/dδ.
    #[inline]
    pub fn force_and_stiffness(&self, delta: f64) -> (f64, f64) {
        let i = self.segment(delta);
        let (d0, d1) = (self.extension[i], self.extension[i + 1]);
        let (f0, f1) = (self.force[i], self.force[i + 1]);
        let k = (f1 - f0) / (d1 - d0);
        (f0 + k * (delta - d0), k)
    }

    /// The largest slope of the table.
    pub fn max_stiffness(&self) -> f64 {
        (0..self.extension.len() - 1)
            .map(|i| {
                (self.force[i + 1] - self.force[i]) / (self.extension[i + 1] - self.extension[i])
            })
            .fold(0.0, f64::max)
    }

    /// ∫₀^δ F, exact for the piecewise-linear law.
    pub fn energy(&self, delta: f64) -> f64 {
        // Integrate from 0 to δ across the breakpoints in between.
        let (lo, hi, sign) = if delta >= 0.0 {
            (0.0, delta, 1.0)
        } else {
            (delta, 0.0, -1.0)
        };
        let mut cuts: Vec<f64> = vec![lo];
        cuts.extend(self.extension.iter().copied().filter(|&d| d > lo && d < hi));
        cuts.push(hi);
        let w: f64 = cuts
            .windows(2)
            .map(|c| {
                0.5 * (self.force_and_stiffness(c[0]).0 + self.force_and_stiffness(c[1]).0)
                    * (c[1] - c[0])
            })
            .sum();
        sign * w
    }
}

/// Node-to-anchor springs sharing one force table.
#[derive(Debug, Clone)]
pub struct SpringBatch {
    /// The force–extension law.
    pub table: ForceTable,
    /// The node each spring holds.
    pub nodes: Vec<u32>,
    /// Its fixed anchor point.
    pub anchors: Vec<Vector3<f64>>,
    /// Its rest length L₀ (extension δ = |x − anchor| − L₀).
    pub rest_length: Vec<f64>,
}

/// Below this length a spring has no direction and carries no force.
const NO_DIRECTION: f64 = 1e-12;

impl SpringBatch {
    /// Number of springs.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the batch is empty.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    #[inline]
    fn geometry(&self, e: usize, x: &[Vector3<f64>]) -> Option<(Vector3<f64>, f64)> {
        let d = x[self.nodes[e] as usize] - self.anchors[e];
        let l = d.norm();
        (l > NO_DIRECTION).then(|| (d / l, l))
    }

    /// The internal force ∂W/∂x on spring `e`'s node: F(δ)·n, n from the
    /// anchor to the node (zero at zero length, where n is undefined).
    #[inline]
    pub fn element_force(&self, e: usize, x: &[Vector3<f64>]) -> Vector3<f64> {
        match self.geometry(e, x) {
            Some((n, l)) => n * self.table.force_and_stiffness(l - self.rest_length[e]).0,
            None => Vector3::zeros(),
        }
    }

    /// The 3×3 tangent dF/dδ·n⊗n + F/l·(I − n⊗n).
    pub fn element_tangent(&self, e: usize, x: &[Vector3<f64>]) -> Matrix3<f64> {
        match self.geometry(e, x) {
            Some((n, l)) => {
                let (f, k) = self.table.force_and_stiffness(l - self.rest_length[e]);
                let nn = n * n.transpose();
                nn * k + (Matrix3::identity() - nn) * (f / l)
            }
            None => Matrix3::identity() * self.table.force_and_stiffness(-self.rest_length[e]).1,
        }
    }

    /// Writes each spring's force into `slots` (one per spring).
    pub fn forces_into(&self, x: &[Vector3<f64>], slots: &mut [Vector3<f64>]) {
        for (e, s) in slots.iter_mut().enumerate() {
            *s = self.element_force(e, x);
        }
    }

    /// The energy stored in spring `e`, ∫₀^δ F.
    pub fn element_energy(&self, e: usize, x: &[Vector3<f64>]) -> f64 {
        let l = (x[self.nodes[e] as usize] - self.anchors[e]).norm();
        self.table.energy(l - self.rest_length[e])
    }

    /// The stable time step 2·√(m/k) of spring `e`'s node, of mass
    /// `node_mass`, on this spring alone at positions `x`: k the larger of
    /// the table's largest slope and the transverse stiffness |F|/l, which
    /// a preloaded spring near its anchor makes the larger by far (zero at
    /// zero length with a force: no step is stable there).
    pub fn element_stable_time_step(&self, e: usize, x: &[Vector3<f64>], node_mass: f64) -> f64 {
        let l = (x[self.nodes[e] as usize] - self.anchors[e]).norm();
        let f = self.table.force_and_stiffness(l - self.rest_length[e]).0;
        let k = self.table.max_stiffness().max(f.abs() / l);
        if k > 0.0 {
            2.0 * (node_mass / k).sqrt()
        } else {
            f64::INFINITY
        }
    }

    /// The stable time step 2·√(m/k) of a node of mass `node_mass` on this
    /// spring alone, with k the table's largest slope.
    pub fn stable_time_step(&self, node_mass: f64) -> f64 {
        let k = self.table.max_stiffness();
        if k > 0.0 {
            2.0 * (node_mass / k).sqrt()
        } else {
            f64::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::assert_tangent_matches;
    use nalgebra::DMatrix;

    fn table() -> ForceTable {
        ForceTable::new(&[[-1.0, 0.0], [0.0, 5.0], [2.0, 25.0], [4.0, 30.0]]).unwrap()
    }

    #[test]
    fn a_preloaded_spring_near_its_anchor_has_a_short_step() {
        // F = 5 N at zero extension, 10 N/mm: at 0.1 mm from its anchor the
        // transverse stiffness F/l = 60 N/mm beats the slope.
        let springs = SpringBatch {
            table: ForceTable::linear(10.0, 5.0),
            nodes: vec![0],
            anchors: vec![Vector3::zeros()],
            rest_length: vec![0.0],
        };
        let m = 1e-6;
        let near = [Vector3::new(0.1, 0.0, 0.0)];
        let far = [Vector3::new(10.0, 0.0, 0.0)];
        let dt = |x: &[Vector3<f64>]| springs.element_stable_time_step(0, x, m);
        assert!((dt(&near) - 2.0 * (m / 60.0f64).sqrt()).abs() < 1e-15);
        // At 10 mm it is still F/l = 105/10 (k + F₀/l: a preload always adds).
        assert!((dt(&far) - 2.0 * (m / 10.5f64).sqrt()).abs() < 1e-15);
        // Without a preload, F/l = k on a zero rest length: the slope.
        let plain = SpringBatch {
            table: ForceTable::linear(10.0, 0.0),
            ..springs.clone()
        };
        assert!(
            (plain.element_stable_time_step(0, &far, m) - 2.0 * (m / 10.0f64).sqrt()).abs() < 1e-15
        );
        // The transverse stiffness is the tangent's: F/l across n.
        let k = springs.element_tangent(0, &near);
        assert!((k[(1, 1)] - 60.0).abs() < 1e-12);
        assert_eq!(dt(&[Vector3::zeros()]), 0.0);
    }

    #[test]
    fn table_interpolates_extrapolates_and_integrates() {
        let t = table();
        assert_eq!(t.force_and_stiffness(1.0), (15.0, 10.0));
        assert_eq!(t.force_and_stiffness(6.0), (35.0, 2.5));
        assert_eq!(t.force_and_stiffness(-2.0), (-5.0, 5.0));
        // ∫₀³ F = (5 + 25)/2·2 + (25 + 27.5)/2·1.
        assert!((t.energy(3.0) - (30.0 + 26.25)).abs() < 1e-13);
        assert!((t.energy(-1.0) - (-2.5)).abs() < 1e-13);
        assert_eq!(t.max_stiffness(), 10.0);
        let h = 1e-6;
        for d in [-1.5, -0.3, 0.7, 2.9, 5.0] {
            let fd = (t.energy(d + h) - t.energy(d - h)) / (2.0 * h);
            assert!((fd - t.force_and_stiffness(d).0).abs() < 1e-8);
        }
    }

    #[test]
    fn bad_tables_are_rejected() {
        assert_eq!(
            ForceTable::new(&[[0.0, 1.0]]),
            Err(ForceTableError::TooShort(1))
        );
        assert!(matches!(
            ForceTable::new(&[[0.0, 1.0], [0.0, 2.0]]),
            Err(ForceTableError::NotIncreasing { index: 1, .. })
        ));
        assert!(matches!(
            ForceTable::new(&[[0.0, 1.0], [1.0, f64::NAN]]),
            Err(ForceTableError::NonFinite { index: 1 })
        ));
    }

    #[test]
    fn tangent_matches_finite_differences() {
        let s = SpringBatch {
            table: table(),
            nodes: vec![0],
            anchors: vec![Vector3::new(1.0, -2.0, 0.5)],
            rest_length: vec![3.0],
        };
        for x in [Vector3::new(4.0, 1.0, 0.0), Vector3::new(1.5, -1.0, 1.0)] {
            let xs = vec![x];
            let k = s.element_tangent(0, &xs);
            let k = DMatrix::from_iterator(3, 3, k.iter().copied());
            assert_tangent_matches(&k, &xs, |x| vec![s.element_force(0, x)], &[0]);
        }
    }
}
