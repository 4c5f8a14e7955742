//! Two-node fibre trusses (T3D2-like).

use drape_constitutive::FibreLaw;
use drape_kinematics::{FibreKinematics, truss_stretch};
use nalgebra::{DMatrix, Matrix3, Vector3};
use rayon::prelude::*;

use crate::lanes::LANES;
use crate::{ElementError, KinematicsError, TRUSS_PIECE, lowest_error, truss_lanes};

/// A batch of trusses of one fibre law, usually one yarn family.
///
/// Each truss carries the yarns of a strip of fabric: its section A₀ is the
/// strip's (SPEC §2), given by the mesher. Trusses carry no mass of their
/// own: the fabric's mass is lumped at the nodes.
#[derive(Debug, Clone)]
pub struct TrussBatch {
    /// The yarns' law.
    pub law: FibreLaw,
    /// The two nodes of each truss.
    pub nodes: Vec<[u32; 2]>,
    /// Reference length L₀.
    pub length: Vec<f64>,
    /// Fibre section A₀.
    pub section: Vec<f64>,
}

/// Output fields of one truss.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrussOutput {
    /// λ = l/L₀.
    pub stretch: f64,
    /// The fibre stress τ(ln λ) (MPa).
    pub stress: f64,
    /// The axial force N = A₀·τ/λ (N).
    pub tension: f64,
}

impl TrussBatch {
    /// Trusses between `nodes` of the reference positions `x0`, each with
    /// its fibre section.
    pub fn new(
        law: FibreLaw,
        x0: &[Vector3<f64>],
        nodes: Vec<[u32; 2]>,
        section: Vec<f64>,
    ) -> Result<Self, ElementError> {
        assert_eq!(nodes.len(), section.len());
        let mut length = Vec::with_capacity(nodes.len());
        for (e, &[i, j]) in nodes.iter().enumerate() {
            let l = (x0[j as usize] - x0[i as usize]).norm();
            if !(l > 0.0 && l.is_finite()) {
                return Err(ElementError {
                    element: e,
                    point: 0,
                    cause: KinematicsError::DegenerateReference { size: l },
                });
            }
            length.push(l);
        }
        Ok(Self {
            law,
            nodes,
            length,
            section,
        })
    }

    /// Number of trusses.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the batch is empty.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    #[inline]
    fn kinematics(&self, e: usize, x: &[Vector3<f64>]) -> Result<FibreKinematics, ElementError> {
        let [i, j] = self.nodes[e];
        truss_stretch(&x[i as usize], &x[j as usize], self.length[e]).map_err(|cause| {
            ElementError {
                element: e,
                point: 0,
                cause,
            }
        })
    }

    /// The nodal forces [f₁, f₂] of truss `e`: f₂ = −f₁ = N·n.
    #[inline]
    pub fn element_force(
        &self,
        e: usize,
        x: &[Vector3<f64>],
    ) -> Result<[Vector3<f64>; 2], ElementError> {
        let k = self.kinematics(e, x)?;
        let n = self.section[e] * self.law.stress(k.log_strain) / k.stretch;
        let f = k.direction * n;
        Ok([-f, f])
    }

    /// [`Self::element_force`] of a yarn with `clearance` (mm) to bow out
    /// into ([`FibreLaw::confined_stress_and_tangent`]; infinite: free).
    #[inline]
    pub fn element_force_confined(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        clearance: f64,
    ) -> Result<[Vector3<f64>; 2], ElementError> {
        let k = self.kinematics(e, x)?;
        let tau = self.law.confined_stress(k.log_strain, clearance);
        let n = self.section[e] * tau / k.stretch;
        let f = k.direction * n;
        Ok([-f, f])
    }

    /// [`Self::element_tangent`] of a yarn with `clearance` (mm), for the
    /// law's tests and a driver that holds the clearance fixed in a step.
    pub fn element_tangent_confined(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        clearance: f64,
        k_out: &mut DMatrix<f64>,
    ) -> Result<(), ElementError> {
        let k = self.kinematics(e, x)?;
        let (tau, e_t) = self
            .law
            .confined_stress_and_tangent(k.log_strain, clearance);
        self.tangent_block(&k, e, tau, e_t, k_out);
        Ok(())
    }

    /// [`Self::element_energy`] of a yarn with `clearance` (mm).
    pub fn element_energy_confined(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        clearance: f64,
    ) -> Result<f64, ElementError> {
        let k = self.kinematics(e, x)?;
        Ok(self.section[e] * self.length[e] * self.law.confined_energy(k.log_strain, clearance))
    }

    /// The energy the tools put into truss `e` at positions `x` when its
    /// clearance moves from `old` to `new` (mJ,
    /// `FibreLaw::confinement_energy_change` over the truss's volume).
    pub fn element_confinement_work(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        old: f64,
        new: f64,
    ) -> Result<f64, ElementError> {
        if old == new {
            return Ok(0.0);
        }
        let k = self.kinematics(e, x)?;
        Ok(self.section[e]
            * self.length[e]
            * self.law.confinement_energy_change(k.log_strain, old, new))
    }

    /// The 6×6 tangent ∂f/∂x of truss `e` (material + geometric):
    /// K₂₂ = A₀/(λ²L₀)·((E_t − 2τ)·n⊗n + τ·I), K₁₁ = K₂₂ = −K₁₂.
    pub fn element_tangent(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        k_out: &mut DMatrix<f64>,
    ) -> Result<(), ElementError> {
        let k = self.kinematics(e, x)?;
        let (tau, e_t) = self.law.stress_and_tangent(k.log_strain);
        self.tangent_block(&k, e, tau, e_t, k_out);
        Ok(())
    }

    fn tangent_block(
        &self,
        k: &FibreKinematics,
        e: usize,
        tau: f64,
        e_t: f64,
        k_out: &mut DMatrix<f64>,
    ) {
        let scale = self.section[e] / (k.stretch * k.stretch * self.length[e]);
        let nn = k.direction * k.direction.transpose();
        let block: Matrix3<f64> = (nn * (e_t - 2.0 * tau) + Matrix3::identity() * tau) * scale;
        k_out.fill(0.0);
        for (a, b, sign) in [(0, 0, 1.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 1.0)] {
            k_out
                .fixed_view_mut::<3, 3>(3 * a, 3 * b)
                .copy_from(&(block * sign));
        }
    }

    /// Writes every truss's two nodal forces into `slots` (2 per truss, in
    /// truss order), in parallel.
    pub fn forces_into(
        &self,
        x: &[Vector3<f64>],
        slots: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        self.forces_with_damping_into(x, None, slots)
    }

    /// [`Self::forces_into`], and when `dashpots` = (velocities,
    /// coefficient per truss) is given, the dashpot forces of
    /// [`Self::add_damping_into`] added piece by piece in the same pass
    /// (the same operations on each slot in the same order as the two
    /// calls one after the other, so the same bits, with one parallel
    /// region and one sweep over the slots instead of two).
    pub fn forces_with_damping_into(
        &self,
        x: &[Vector3<f64>],
        dashpots: Option<(&[Vector3<f64>], &[f64])>,
        slots: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        self.forces_confined_into(x, dashpots, None, slots)
    }

    /// [`Self::forces_with_damping_into`], with each truss's yarn confined
    /// by its `clearance` (mm, one per truss; infinite: free) when given
    /// ([`FibreLaw::confined_stress_and_tangent`]); the lanes call the
    /// scalar law per lane, so the same bits as the scalar path.
    pub fn forces_confined_into(
        &self,
        x: &[Vector3<f64>],
        dashpots: Option<(&[Vector3<f64>], &[f64])>,
        clearance: Option<&[f64]>,
        slots: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        assert_eq!(slots.len(), 2 * self.len());
        if let Some((_, c)) = dashpots {
            assert_eq!(c.len(), self.len());
        }
        if let Some(c) = clearance {
            assert_eq!(c.len(), self.len());
        }
        // A law that confines nothing ignores the clearance: the free path.
        let clearance = clearance.filter(|_| self.law.confines());
        // Tasks of TRUSS_PIECE trusses, each a plain loop over blocks of
        // LANES trusses on the lanes (crate::truss_lanes, same bits) that
        // stops at its first failure (its lowest element): a per-truss
        // reduction of results cost a third of the pass. A block with a
        // failing truss, and the last partial block, run on the scalar path.
        const _: () = assert!(TRUSS_PIECE % LANES == 0);
        lowest_error(
            slots
                .par_chunks_mut(2 * TRUSS_PIECE)
                .enumerate()
                .map(|(c, out)| {
                    let first = c * TRUSS_PIECE;
                    self.piece_forces_into(first, x, clearance, out)?;
                    if let Some((v, coefficient)) = dashpots {
                        self.piece_damping_into(first, x, v, coefficient, out);
                    }
                    Ok(())
                }),
        )
    }

    /// The forces of trusses `first..first + out.len() / 2` into `out`,
    /// blocks of [`LANES`] on the lanes.
    fn piece_forces_into(
        &self,
        first: usize,
        x: &[Vector3<f64>],
        clearance: Option<&[f64]>,
        out: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        let done = out.len() / (2 * LANES) * LANES;
        let mut blocks = out.chunks_exact_mut(2 * LANES);
        for (b, block) in blocks.by_ref().enumerate() {
            let e0 = first + b * LANES;
            let range = e0..e0 + LANES;
            if !truss_lanes::block_forces(
                &self.law,
                &self.nodes[range.clone()],
                &self.length[range.clone()],
                &self.section[range.clone()],
                clearance.map(|c| &c[range]),
                x,
                block,
            ) {
                self.scalar_forces_into(e0, x, clearance, block)?;
            }
        }
        self.scalar_forces_into(first + done, x, clearance, blocks.into_remainder())
    }

    /// The forces of trusses `first..` into `slots` (2 per truss), one by
    /// one: the reference the lanes are tested against.
    fn scalar_forces_into(
        &self,
        first: usize,
        x: &[Vector3<f64>],
        clearance: Option<&[f64]>,
        slots: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        for (k, pair) in slots.chunks_exact_mut(2).enumerate() {
            let e = first + k;
            let f = match clearance {
                Some(c) => self.element_force_confined(e, x, c[e])?,
                None => self.element_force(e, x)?,
            };
            pair.copy_from_slice(&f);
        }
        Ok(())
    }

    /// Strain energy A₀·L₀·w(ln λ) of truss `e`.
    pub fn element_energy(&self, e: usize, x: &[Vector3<f64>]) -> Result<f64, ElementError> {
        let k = self.kinematics(e, x)?;
        Ok(self.section[e] * self.length[e] * self.law.energy(k.log_strain))
    }

    /// Total strain energy of the batch.
    pub fn energy(&self, x: &[Vector3<f64>]) -> Result<f64, ElementError> {
        (0..self.len()).map(|e| self.element_energy(e, x)).sum()
    }

    /// The stable time step 2/ω of truss `e` alone between two masses, its
    /// nodes' shares `mass` of the lumped mass: ω² = k·(1/m₁ + 1/m₂), with
    /// k = E_f·A₀/l in its current length (SPEC §7: the full modulus).
    ///
    /// With each node's mass shared equally among the batch's trusses at it,
    /// this is exact for a chain of equal trusses (2/ω = l/c) and bounds a
    /// chain's free end, where a light node would outrun l/c.
    pub fn element_stable_time_step(&self, e: usize, x: &[Vector3<f64>], mass: [f64; 2]) -> f64 {
        let [i, j] = self.nodes[e];
        let l = (x[j as usize] - x[i as usize]).norm();
        let k = self.law.wave_modulus() * self.section[e] / l;
        2.0 / (k * (1.0 / mass[0] + 1.0 / mass[1])).sqrt()
    }

    /// The coefficient c = 2ξ·√(k·m̄) (N·s/mm) of a dashpot parallel to
    /// truss `e` that damps the truss's own mode, two masses `mass` on a
    /// spring k = E_f·A₀/L₀ (reduced mass m̄ = m₁m₂/(m₁ + m₂)), at the
    /// fraction `ratio` of critical damping: an axial "bulk viscosity" that
    /// damps the highest frequencies of the mesh and hardly the slow ones
    /// (a mode of frequency ω is damped at about ratio·ω/ω_max).
    pub fn damping_coefficient(&self, e: usize, mass: [f64; 2], ratio: f64) -> f64 {
        let k = self.law.wave_modulus() * self.section[e] / self.length[e];
        let reduced = mass[0] * mass[1] / (mass[0] + mass[1]);
        2.0 * ratio * (k * reduced).sqrt()
    }

    /// Adds the forces of a dashpot along each truss, N_d = c·dl/dt with
    /// dl/dt = n·(v₂ − v₁), to `slots` (laid out as in
    /// [`Self::forces_into`]), `coefficient` per truss
    /// ([`Self::damping_coefficient`]). Velocities are the caller's (an
    /// explicit driver passes the mid-step ones): the force is rate
    /// dependent, with no stiffness and no stored energy.
    pub fn add_damping_into(
        &self,
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        coefficient: &[f64],
        slots: &mut [Vector3<f64>],
    ) {
        assert_eq!(slots.len(), 2 * self.len());
        assert_eq!(coefficient.len(), self.len());
        slots
            .par_chunks_mut(2 * TRUSS_PIECE)
            .enumerate()
            .for_each(|(c, out)| self.piece_damping_into(c * TRUSS_PIECE, x, v, coefficient, out));
    }

    /// The dashpot forces of trusses `first..first + out.len() / 2` added
    /// to `out`.
    fn piece_damping_into(
        &self,
        first: usize,
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        coefficient: &[f64],
        out: &mut [Vector3<f64>],
    ) {
        for (k, pair) in out.chunks_exact_mut(2).enumerate() {
            let e = first + k;
            let [i, j] = self.nodes[e];
            let (i, j) = (i as usize, j as usize);
            let d = x[j] - x[i];
            let l = d.norm();
            if l > 0.0 {
                let n = d / l;
                let f = n * (coefficient[e] * n.dot(&(v[j] - v[i])));
                pair[0] -= f;
                pair[1] += f;
            }
        }
    }

    /// How many trusses of the batch meet at each of `node_count` nodes.
    pub fn node_degree(&self, node_count: usize) -> Vec<u32> {
        let mut degree = vec![0; node_count];
        for &[i, j] in &self.nodes {
            degree[i as usize] += 1;
            degree[j as usize] += 1;
        }
        degree
    }

    /// Output fields of truss `e`.
    pub fn element_output(
        &self,
        e: usize,
        x: &[Vector3<f64>],
    ) -> Result<TrussOutput, ElementError> {
        let k = self.kinematics(e, x)?;
        let stress = self.law.stress(k.log_strain);
        Ok(TrussOutput {
            stretch: k.stretch,
            stress,
            tension: self.section[e] * stress / k.stretch,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::LANES;
    use crate::test_support::{assert_tangent_matches, random_rotation};

    fn batch(law: FibreLaw) -> (TrussBatch, Vec<Vector3<f64>>) {
        let x0 = vec![Vector3::new(0.0, 0.0, 0.0), Vector3::new(4.0, 0.0, 0.0)];
        let t = TrussBatch::new(law, &x0, vec![[0, 1]], vec![0.3]).unwrap();
        (t, x0)
    }

    #[test]
    fn tangent_matches_finite_differences_stretched_and_compressed() {
        let laws = [
            FibreLaw::new(230_000.0, 0.005).unwrap(),
            FibreLaw {
                compression_factor: 0.2,
                ..FibreLaw::new(75_000.0, 0.012).unwrap()
            },
            // The glass preset's buckling yarn.
            FibreLaw {
                buckling_stress: 1.556,
                ..FibreLaw::new(75_000.0, 0.012).unwrap()
            },
        ];
        for law in laws {
            let (t, _) = batch(law);
            for (stretch, seed) in [(1.003, 1), (1.02, 2), (0.97, 3), (1.0001, 4)] {
                let q = random_rotation(seed);
                let x = vec![
                    Vector3::new(1.0, 2.0, 3.0),
                    Vector3::new(1.0, 2.0, 3.0) + q * Vector3::new(4.0 * stretch, 0.0, 0.0),
                ];
                let mut k = DMatrix::zeros(6, 6);
                t.element_tangent(0, &x, &mut k).unwrap();
                assert_tangent_matches(
                    &k,
                    &x,
                    |x| t.element_force(0, x).unwrap().to_vec(),
                    &[0, 1],
                );
            }
        }
    }

    #[test]
    fn force_is_the_gradient_of_energy_and_rotates_with_the_body() {
        let (t, _) = batch(FibreLaw::new(230_000.0, 0.005).unwrap());
        let x = vec![Vector3::new(0.0, 0.0, 0.0), Vector3::new(4.05, 0.1, -0.2)];
        let f = t.element_force(0, &x).unwrap();
        let h = 1e-7;
        for d in 0..3 {
            let mut xp = x.clone();
            let mut xm = x.clone();
            xp[1][d] += h;
            xm[1][d] -= h;
            let fd =
                (t.element_energy(0, &xp).unwrap() - t.element_energy(0, &xm).unwrap()) / (2.0 * h);
            assert!(
                (fd - f[1][d]).abs() <= 1e-6 * f[1].norm(),
                "{fd} vs {}",
                f[1][d]
            );
        }
        let q = random_rotation(7);
        let xr: Vec<_> = x
            .iter()
            .map(|p| q * p + Vector3::new(5.0, -3.0, 1.0))
            .collect();
        let fr = t.element_force(0, &xr).unwrap();
        assert!((fr[1] - q * f[1]).norm() < 1e-12 * f[1].norm());
        let (t, x0) = batch(FibreLaw::new(230_000.0, 0.005).unwrap());
        assert_eq!(t.element_force(0, &x0).unwrap(), [Vector3::zeros(); 2]);
    }

    #[test]
    fn stable_time_step_is_the_chain_frequency() {
        // A long chain of these trusses with nodal masses m: each truss gets
        // m/2 from each node, and ω_max = 2√(k/m) exactly.
        let (t, x0) = batch(FibreLaw::new(1000.0, 0.0).unwrap());
        let m = 4e-9;
        let dt = t.element_stable_time_step(0, &x0, [m / 2.0, m / 2.0]);
        let k: f64 = 1000.0 * 0.3 / 4.0;
        assert!((dt - 1.0 / (k / m).sqrt()).abs() < 1e-15 * dt);
        assert_eq!(t.node_degree(3), vec![1, 1, 0]);
    }

    #[test]
    fn the_dashpot_damps_the_two_mass_mode_at_its_ratio_and_only_stretching() {
        let (t, x0) = batch(FibreLaw::new(1000.0, 0.0).unwrap());
        let m = [2e-9, 6e-9];
        let ratio = 0.06;
        let c = t.damping_coefficient(0, m, ratio);
        // ζ = c/(2·√(k·m̄)) with k = 1000·0.3/4 and m̄ = 1.5e-9.
        let k: f64 = 75.0;
        assert!((c / (2.0 * (k * 1.5e-9).sqrt()) - ratio).abs() < 1e-15);
        // Nodes moving apart along the truss at 3 mm/s: N_d = 3c, resisting.
        let v = vec![Vector3::new(-1.0, 0.0, 0.0), Vector3::new(2.0, 0.0, 0.0)];
        let mut slots = vec![Vector3::zeros(); 2];
        t.add_damping_into(&x0, &v, &[c], &mut slots);
        assert!((slots[1] - Vector3::new(3.0 * c, 0.0, 0.0)).norm() < 1e-15 * c);
        assert_eq!(slots[0], -slots[1]);
        // It dissipates: the power of the internal forces is positive.
        assert!(slots[0].dot(&v[0]) + slots[1].dot(&v[1]) > 0.0);
        // A rigid motion (translation, rotation about the truss's centre)
        // stretches nothing and gets no force.
        let rigid = vec![Vector3::new(5.0, -1.0, 2.0), Vector3::new(5.0, 3.0, 2.0)];
        let mut slots = vec![Vector3::zeros(); 2];
        t.add_damping_into(&x0, &rigid, &[c], &mut slots);
        assert!(slots.iter().all(|f| f.norm() < 1e-15 * c));
    }

    /// 203 trusses (50 blocks of lanes and a scalar tail of 3) from one
    /// node to nodes in random directions, a quarter each compressed (to
    /// −3 %), in the crimp law's series range (0 < ε < 4e-6, below
    /// 1e-3·ε_sh), on its closed form (to +5 %), and at λ = 1 ± 1e-9 or 1.
    fn spread(law: FibreLaw) -> (TrussBatch, Vec<Vector3<f64>>) {
        spread_n(law, 203)
    }

    /// [`spread`] with `count` trusses.
    fn spread_n(law: FibreLaw, count: usize) -> (TrussBatch, Vec<Vector3<f64>>) {
        let mut x0 = vec![Vector3::new(1.0, -2.0, 0.5)];
        let mut x = x0.clone();
        let mut seed = 12345u64;
        let mut uniform = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for e in 0..count {
            let length = 2.0 + 3.0 * uniform();
            let stretch = match e % 4 {
                0 => 1.0 - 0.03 * uniform(),
                1 => 1.0 + 4e-6 * uniform(),
                2 => 1.0001 + 0.05 * uniform(),
                _ => [1.0 - 1e-9, 1.0, 1.0 + 1e-9][e % 3],
            };
            let dir = random_rotation(e as u64 + 11) * Vector3::x();
            x0.push(x0[0] + dir * length);
            x.push(x[0] + dir * (length * stretch));
        }
        let nodes = (1..=count as u32).map(|j| [0, j]).collect();
        let section = (0..count).map(|_| 0.05 + 0.2 * uniform()).collect();
        (TrussBatch::new(law, &x0, nodes, section).unwrap(), x)
    }

    fn laws() -> [FibreLaw; 4] {
        [
            // Crimped carbon, slack in compression.
            FibreLaw::new(230_000.0, 0.005).unwrap(),
            // Crimped glass carrying a fifth in compression.
            FibreLaw {
                compression_factor: 0.2,
                ..FibreLaw::new(75_000.0, 0.012).unwrap()
            },
            // Uncrimped.
            FibreLaw {
                compression_factor: 0.5,
                ..FibreLaw::new(75_000.0, 0.0).unwrap()
            },
            // Crimped glass buckling as an imperfect column.
            FibreLaw {
                buckling_stress: 1.556,
                ..FibreLaw::new(75_000.0, 0.012).unwrap()
            },
        ]
    }

    #[test]
    fn truss_lanes_equal_the_scalar_path_bit_for_bit() {
        for law in laws() {
            let (t, x) = spread(law);
            let mut slots = vec![Vector3::repeat(f64::NAN); 2 * t.len()];
            t.forces_into(&x, &mut slots).unwrap();
            // Stated round-off: none (same operations, same order, the same
            // ln and exp_m1 per lane).
            for e in 0..t.len() {
                let f = t.element_force(e, &x).unwrap();
                assert_eq!(slots[2 * e], f[0], "truss {e}");
                assert_eq!(slots[2 * e + 1], f[1], "truss {e}");
            }
            // Both builds of the kernel, and the blocks really on the lanes.
            for b in 0..t.len() / LANES {
                let r = b * LANES..(b + 1) * LANES;
                let mut base = [Vector3::zeros(); 2 * LANES];
                let mut best = [Vector3::zeros(); 2 * LANES];
                let args = (&t.nodes[r.clone()], &t.length[r.clone()], &t.section[r]);
                assert!(truss_lanes::block_forces_lanes(
                    &t.law, args.0, args.1, args.2, None, &x, &mut base
                ));
                assert!(truss_lanes::block_forces(
                    &t.law, args.0, args.1, args.2, None, &x, &mut best
                ));
                assert_eq!(base, best);
                assert_eq!(base[..], slots[2 * b * LANES..2 * (b + 1) * LANES]);
            }
        }
    }

    /// The glass preset's yarn, confined (L = 4.55 mm, a₀ = 0.317 mm).
    fn confined_glass() -> FibreLaw {
        FibreLaw {
            buckling_stress: 1.556,
            segment_length: 10.0 / 2.2,
            ..FibreLaw::new(75_000.0, 0.012).unwrap()
        }
    }

    #[test]
    fn confined_truss_tangent_and_force_are_derivatives() {
        // Shortened 3 % and 10 %, with 0.05 mm of room: past the wall
        // (x_c = 0.33, 0.4 % shortening), and with the room infinite.
        let (t, _) = batch(confined_glass());
        for (stretch, clearance, seed) in [
            (0.97, 0.05, 1),
            (0.90, 0.05, 2),
            (0.90, 0.0, 3),
            (0.97, f64::INFINITY, 4),
            (1.01, 0.0, 5),
        ] {
            let q = random_rotation(seed);
            let x = vec![
                Vector3::new(1.0, 2.0, 3.0),
                Vector3::new(1.0, 2.0, 3.0) + q * Vector3::new(4.0 * stretch, 0.1, 0.0),
            ];
            let mut k = DMatrix::zeros(6, 6);
            t.element_tangent_confined(0, &x, clearance, &mut k)
                .unwrap();
            assert_tangent_matches(
                &k,
                &x,
                |x| t.element_force_confined(0, x, clearance).unwrap().to_vec(),
                &[0, 1],
            );
            let f = t.element_force_confined(0, &x, clearance).unwrap();
            let h = 1e-7;
            for d in 0..3 {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[1][d] += h;
                xm[1][d] -= h;
                let w = |x: &[Vector3<f64>]| t.element_energy_confined(0, x, clearance).unwrap();
                let fd = (w(&xp) - w(&xm)) / (2.0 * h);
                assert!(
                    (fd - f[1][d]).abs() <= 1e-6 * f[1].norm(),
                    "{fd} vs {}",
                    f[1][d]
                );
            }
        }
        // Confined, a yarn shortened 10 % pushes back 9.4 times harder than
        // a free one.
        let x = vec![Vector3::zeros(), Vector3::new(4.0 * 0.9, 0.0, 0.0)];
        let free = t.element_force(0, &x).unwrap()[1].x;
        let walled = t.element_force_confined(0, &x, 0.05).unwrap()[1].x;
        assert!(walled < 5.0 * free && free < 0.0, "{walled} vs {free}");
    }

    #[test]
    fn confined_truss_lanes_equal_the_scalar_path_bit_for_bit() {
        // Clearances from closed to infinite, so that lanes of one block
        // sit on the free column, at the wall and beyond it.
        let (t, x) = spread(confined_glass());
        let room = [0.0, 0.01, 0.05, 0.1, 0.3, 1.0, f64::INFINITY];
        let clearance: Vec<f64> = (0..t.len()).map(|e| room[e % room.len()]).collect();
        let mut slots = vec![Vector3::repeat(f64::NAN); 2 * t.len()];
        t.forces_confined_into(&x, None, Some(&clearance), &mut slots)
            .unwrap();
        let mut walled = 0;
        for e in 0..t.len() {
            let f = t.element_force_confined(e, &x, clearance[e]).unwrap();
            assert_eq!(slots[2 * e..2 * e + 2], f, "truss {e}");
            walled += usize::from(f != t.element_force(e, &x).unwrap());
        }
        // The case has trusses beyond their wall (shortened up to 3 %).
        assert!(walled >= 10, "{walled} trusses past the wall");
        for b in 0..t.len() / LANES {
            let r = b * LANES..(b + 1) * LANES;
            let mut base = [Vector3::zeros(); 2 * LANES];
            let mut best = [Vector3::zeros(); 2 * LANES];
            let c = Some(&clearance[r.clone()]);
            let args = (&t.nodes[r.clone()], &t.length[r.clone()], &t.section[r]);
            assert!(truss_lanes::block_forces_lanes(
                &t.law, args.0, args.1, args.2, c, &x, &mut base
            ));
            assert!(truss_lanes::block_forces(
                &t.law, args.0, args.1, args.2, c, &x, &mut best
            ));
            assert_eq!(base, best);
        }
        // Infinite room everywhere: the free forces, bit for bit.
        let far = vec![f64::INFINITY; t.len()];
        let mut free = vec![Vector3::repeat(f64::NAN); 2 * t.len()];
        t.forces_confined_into(&x, None, Some(&far), &mut free)
            .unwrap();
        let mut plain = vec![Vector3::repeat(f64::NAN); 2 * t.len()];
        t.forces_into(&x, &mut plain).unwrap();
        assert_eq!(free, plain);
    }

    #[test]
    fn forces_with_dashpots_in_one_pass_equal_each_truss_alone_bit_for_bit() {
        // Three pieces, the last partial with a scalar tail of 1.
        let count = 2 * crate::TRUSS_PIECE + 41;
        let (t, x) = spread_n(laws()[2], count);
        let v: Vec<_> = (0..x.len())
            .map(|i| random_rotation(i as u64 + 3) * Vector3::new(1.0 + i as f64 * 1e-3, 0.5, 0.0))
            .collect();
        let c: Vec<f64> = (0..count).map(|e| 1e-4 * (1.0 + (e % 7) as f64)).collect();
        let mut fused = vec![Vector3::repeat(f64::NAN); 2 * count];
        t.forces_with_damping_into(&x, Some((&v, &c)), &mut fused)
            .unwrap();
        let mut apart = vec![Vector3::repeat(f64::NAN); 2 * count];
        t.forces_into(&x, &mut apart).unwrap();
        t.add_damping_into(&x, &v, &c, &mut apart);
        // Stated round-off: none. The reference is each truss on its own:
        // its elastic force, then its dashpot N_d = c·n·(v₂ − v₁) added.
        for e in 0..count {
            let mut f = t.element_force(e, &x).unwrap();
            let [i, j] = t.nodes[e].map(|n| n as usize);
            let d = x[j] - x[i];
            let n = d / d.norm();
            let fd = n * (c[e] * n.dot(&(v[j] - v[i])));
            f[0] -= fd;
            f[1] += fd;
            assert_eq!(fused[2 * e..2 * e + 2], f, "truss {e}");
            assert_eq!(apart[2 * e..2 * e + 2], f, "truss {e}");
        }
    }

    #[test]
    fn a_collapsed_truss_in_a_block_is_named_as_on_the_scalar_path() {
        let (t, mut x) = spread(laws()[0]);
        // Truss 6 (second block) collapsed onto its first node, truss 9
        // (third block) with a NaN: the lowest is named.
        x[10].x = f64::NAN;
        x[7] = x[0];
        let mut slots = vec![Vector3::zeros(); 2 * t.len()];
        let err = t.forces_into(&x, &mut slots).unwrap_err();
        assert_eq!(err, t.element_force(6, &x).unwrap_err());
        assert!(matches!(err.cause, KinematicsError::DegenerateFibre { .. }));
        x[7] = x[0] + Vector3::new(0.0, 0.0, 3.0);
        let err = t.forces_into(&x, &mut slots).unwrap_err();
        assert_eq!(err.element, 9);
        assert!(matches!(err.cause, KinematicsError::NonFinite { .. }));
    }

    #[test]
    fn collapsed_truss_is_reported_with_its_index() {
        let (t, _) = batch(FibreLaw::new(1000.0, 0.0).unwrap());
        let x = vec![Vector3::zeros(); 2];
        let mut slots = vec![Vector3::zeros(); 2];
        let err = t.forces_into(&x, &mut slots).unwrap_err();
        assert_eq!(err.element, 0);
        assert!(matches!(err.cause, KinematicsError::DegenerateFibre { .. }));
    }
}
