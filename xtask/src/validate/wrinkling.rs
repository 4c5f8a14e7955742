//! Validation of wrinkling (beyond the paper): a fabric strip on an
//! elastic foundation, compressed along its warp until it wrinkles. With
//! yarn bending the wrinkle wavelength is the strip's own and converges
//! with the mesh, near the classical λ_c = 2π·(B/k)^(1/4) of a beam on a
//! Winkler foundation; without bending the mesh sets it (two cells).
//!
//! # The case
//!
//! A 200 × 4 mm strip, one cell wide, warp along its length, rests on a
//! foundation of stiffness k per unit area (N/mm³): at every node a spring
//! of stiffness k·A (A the node's share of the strip's area) to an anchor
//! 10⁶ mm straight below, so it holds the node's height and, to 10⁻⁶ of
//! that, nothing in the plane. The foundation stands for whatever holds a
//! wrinkling ply back towards its mean surface — the transverse tension of
//! a sheared or stretched sheet, a soft under-ply — in the one form whose
//! wrinkle is known in closed form. Both ends are pinned (held in y and z,
//! free to turn); one end is pushed in along the strip by a smooth ramp.
//! The foundation's rest surface is rough: every sine mode the mesh can
//! carry with a deterministic amplitude of up to 0.1 µm, the same on every
//! mesh ([`rough_surface`]); that seeds the wrinkle.
//!
//! For a beam of bending rigidity B per unit width on a foundation k under
//! an axial compression P per unit width, the mode sin(qx) is neutral when
//! P·q² = B·q⁴ + k; the lowest such P is P_c = 2·√(k·B), at
//! q_c = (k/B)^(1/4), the wavelength λ_c = 2π·(B/k)^(1/4) (Hetényi, *Beams
//! on Elastic Foundation*, 1946; Timoshenko & Gere, *Theory of Elastic
//! Stability*, §2.10). Pinned ends admit only sin(mπx/L), so the strip
//! (L = 10·λ_c) picks the half-wave count m nearest 2L/λ_c; neighbouring
//! m buckle at loads within 0.5 % of each other, and the imperfection and
//! the loading pick among them. The membrane alone has no bending
//! stiffness: the same strip without bending buckles at P = k·h²/4 in the
//! zigzag of wavelength 2h, the shortest the mesh has.
//!
//! # What is measured
//!
//! The height profile z(x) of the strip's centre line at the first output
//! frame where the wrinkle stands 0.1 mm high (a hundred times its seed,
//! 1/200 of λ_c: grown out of the noise, still the linear pattern; a
//! longer push coarsens it, the strip on a linear foundation being
//! unstable after buckling). The wavelength is the sine spectrum's peak
//! ([`spectral_wavelength`]): λ = 2L/m̄, m̄ the power-weighted mean
//! half-wave count around the largest coefficient. The mean spacing of
//! the zero crossings ([`zero_crossing_wavelength`]) is reported beside
//! it; it is exact on a clean wave but counts too few crossings where the
//! envelope dips, so the checks use the spectrum.
//!
//! With bending the discrete strip has its own critical wavelength,
//! λ_h = π·h/asin(π·h/λ_c) ([`discrete_wavelength`]), which tends to λ_c
//! as O(h²); the checks are listed at [`wrinkling_checks`]. The push,
//! 2 mm over 0.6 s by a smooth step, is slow beside the foundation's
//! period (2.5 ms), so the strip buckles within ~4 % of P_c.

use drape_constitutive::Material;
use drape_elements::{ForceTable, SpringBatch};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Amplitude, BoundaryCondition, Model, Motion};
use drape_time::{Control, Explicit, ExplicitSettings, Frame, Observer, Progress};
use nalgebra::Vector3;

use super::{Case, Check};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "wrinkling/strip-on-foundation-quick",
        quick: true,
        run: wrinkling_quick,
    },
    Case {
        name: "wrinkling/strip-on-foundation",
        quick: false,
        run: wrinkling_full,
    },
];

/// Foundation stiffness k (N/mm³): with the glass preset's B = 0.465 N·mm,
/// λ_c = 20.0 mm.
const FOUNDATION: f64 = 4.5e-3;
/// Strip width (mm): one cell.
const WIDTH: f64 = 4.0;
/// Largest amplitude of one sine mode of the foundation's rest surface (mm).
const ROUGHNESS: f64 = 1e-4;
/// Distance of the foundation's anchors below the strip (mm).
const ANCHOR_DEPTH: f64 = 1e6;

/// The strip's material: the glass preset (its bending rigidity) with
/// straight yarns of 200 MPa that carry compression, and a 2 MPa resin.
/// The wrinkle does not depend on the in-plane stiffness; a soft one only
/// lengthens the stable step. With these the strip buckles at ~0.3 %
/// strain.
fn strip_material() -> Material {
    let mut m = Material::preset("glass-serge-4x3").expect("preset");
    m.fibre.modulus = 200.0;
    m.fibre.crimp_strain = 0.0;
    m.fibre.compression_factor = 1.0;
    m.fibre.buckling_stress = 0.0;
    m.resin.young = 2.0;
    m
}

/// A deterministic white noise in [−1, 1] (SplitMix64 of the index).
fn noise(i: u64) -> f64 {
    let mut z = i
        .wrapping_add(0x9E37_79B9_7F4A_7C15)
        .wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    2.0 * (z >> 11) as f64 / (1u64 << 53) as f64 - 1.0
}

/// The wrinkle is taken at the first frame where it stands this high (mm),
/// see the module documentation.
const ONSET: f64 = 0.1;

/// Heights of the foundation's rest surface at the stations i = 0 … N
/// of an N-cell strip: Σ_m a_m·sin(mπi/N) over the sine modes the mesh
/// can carry (m < N), each with the same amplitude a_m = ROUGHNESS·noise(m)
/// on every mesh. So the modes near the wrinkle's are seeded alike on all
/// meshes and each mesh has a white seed up to its shortest wave.
fn rough_surface(cells: usize) -> Vec<f64> {
    let amplitude: Vec<f64> = (1..cells as u64).map(|m| ROUGHNESS * noise(m)).collect();
    (0..=cells)
        .map(|i| {
            amplitude
                .iter()
                .enumerate()
                .map(|(k, a)| {
                    a * (std::f64::consts::PI * ((k + 1) * i) as f64 / cells as f64).sin()
                })
                .sum()
        })
        .collect()
}

/// One run's result.
struct Wrinkle {
    /// Centre-line stations x and heights z at the onset frame, in x order
    /// (empty if the strip never wrinkled).
    profile: Vec<(f64, f64)>,
    /// The largest axial end force up to the onset, per unit width (N/mm).
    peak_force: f64,
    /// Time of the onset frame (s).
    time: f64,
}

struct Recorder {
    /// The node pairs across the width, in x order.
    stations: Vec<[u32; 2]>,
    pushed: Vec<u32>,
    wrinkle: Wrinkle,
    done: bool,
}

impl Observer for Recorder {
    fn frame(&mut self, frame: &Frame<'_>) {
        if self.done {
            return;
        }
        let x = &frame.state.x;
        let profile: Vec<(f64, f64)> = self
            .stations
            .iter()
            .map(|&[a, b]| {
                let p = 0.5 * (x[a as usize] + x[b as usize]);
                (p.x, p.z)
            })
            .collect();
        let force: f64 = self
            .pushed
            .iter()
            .map(|&n| frame.reactions[n as usize].x)
            .sum();
        let w = &mut self.wrinkle;
        w.peak_force = w.peak_force.max(force.abs() / WIDTH);
        if profile.iter().any(|p| p.1.abs() >= ONSET) {
            w.profile = profile;
            w.time = frame.state.time;
            self.done = true;
        }
    }

    fn progress(&mut self, _progress: &Progress) -> Control {
        if self.done {
            Control::Stop
        } else {
            Control::Continue
        }
    }
}

/// The strip with `cells` cells along its length `length`, with or
/// without bending, pushed in by `shortening` (mm) over `duration` (s),
/// run until it wrinkles (or to 1.2·`duration`).
fn run_strip(length: f64, cells: usize, bending: bool, shortening: f64, duration: f64) -> Wrinkle {
    let material = strip_material();
    let blank = RectangleBlank {
        width: length,
        height: WIDTH,
        center: Vector3::new(0.5 * length, 0.0, 0.0),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([cells, 1]),
        fibres: FibreRepresentation::Trusses,
    };
    let mut model = Model::from_blank(&blank, &material).expect("model");
    let n = model.node_count();
    let h = length / cells as f64;
    let x0 = model.x0.clone();
    let station = |i: usize| (x0[i].x / h).round() as usize;
    // Foundation: nodal area = lumped mass / (ρ·h) of the membranes.
    let areal = material.density * material.thickness;
    let roughness = rough_surface(cells);
    // One batch per spring stiffness (the strip's ends carry half).
    let mut springs: Vec<SpringBatch> = Vec::new();
    for i in 0..n {
        let stiffness = FOUNDATION * model.mass[i] / areal;
        let anchor = Vector3::new(
            x0[i].x,
            x0[i].y,
            x0[i].z - ANCHOR_DEPTH + roughness[station(i)],
        );
        let table = ForceTable::linear(stiffness, 0.0);
        let k = match springs.iter().position(|b| b.table == table) {
            Some(k) => k,
            None => {
                springs.push(SpringBatch {
                    table,
                    nodes: Vec::new(),
                    anchors: Vec::new(),
                    rest_length: Vec::new(),
                });
                springs.len() - 1
            }
        };
        springs[k].nodes.push(i as u32);
        springs[k].anchors.push(anchor);
        springs[k].rest_length.push(ANCHOR_DEPTH);
    }
    model.springs = springs;
    let ends = |at: f64| -> Vec<u32> {
        (0..n as u32)
            .filter(|&i| (model.x0[i as usize].x - at).abs() < 1e-9 * length)
            .collect()
    };
    let (fixed, pushed) = (ends(0.0), ends(length));
    model.boundary.push(BoundaryCondition::fixed(fixed));
    model.boundary.push(BoundaryCondition {
        nodes: pushed.clone(),
        components: [true; 3],
        motion: Motion::Displacement {
            value: Vector3::new(-shortening, 0.0, 0.0),
            amplitude: Amplitude::SmoothStep { duration },
        },
    });
    if bending {
        let b = material.bending_rigidity.expect("preset rigidity");
        model
            .add_yarn_bending(Vector3::x(), Vector3::z(), b)
            .expect("bending");
    }
    let mut stations: Vec<[u32; 2]> = vec![[u32::MAX; 2]; cells + 1];
    for i in 0..n {
        let s = &mut stations[station(i)];
        let slot = usize::from(x0[i].y > 0.0);
        s[slot] = i as u32;
    }
    let omega_foundation = (FOUNDATION / areal).sqrt();
    let settings = ExplicitSettings {
        end_time: 1.2 * duration,
        frames: 300,
        damping: 0.04 * omega_foundation,
        ..ExplicitSettings::default()
    };
    let mut state = model.initial_state();
    let mut recorder = Recorder {
        stations,
        pushed,
        wrinkle: Wrinkle {
            profile: Vec::new(),
            peak_force: 0.0,
            time: f64::NAN,
        },
        done: false,
    };
    Explicit::new(&model, settings)
        .expect("driver")
        .run(&mut state, &mut recorder)
        .expect("run");
    recorder.wrinkle
}

/// The wavelength of a profile from its zero crossings (see the module
/// documentation), with the number of crossings; None with fewer than 2.
pub fn zero_crossing_wavelength(profile: &[(f64, f64)]) -> Option<(f64, usize)> {
    let peak = profile.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    let significant: Vec<(f64, f64)> = profile
        .iter()
        .copied()
        .filter(|p| p.1.abs() >= 0.1 * peak && peak > 0.0)
        .collect();
    let crossings: Vec<f64> = significant
        .windows(2)
        .filter(|w| (w[0].1 > 0.0) != (w[1].1 > 0.0))
        .map(|w| {
            let ((x0, z0), (x1, z1)) = (w[0], w[1]);
            x0 + (x1 - x0) * z0 / (z0 - z1)
        })
        .collect();
    (crossings.len() >= 2).then(|| {
        let span = crossings[crossings.len() - 1] - crossings[0];
        (2.0 * span / (crossings.len() - 1) as f64, crossings.len())
    })
}

/// The dominant wavelength of a profile sampled at equally spaced
/// stations x₀ … x_N with z₀ = z_N = 0 (pinned ends): the sine
/// coefficients b_m = Σᵢ zᵢ·sin(mπi/N), m = 1 … N − 1 (the discrete sine
/// transform, exact and orthogonal on these samples), the index m* of the
/// largest |b_m|², refined to the power-weighted mean m̄ of the indices
/// within 2 of it; λ = 2L/m̄, with m* returned beside it.
pub fn spectral_wavelength(profile: &[(f64, f64)]) -> (f64, usize) {
    let n = profile.len() - 1;
    let length = profile[n].0 - profile[0].0;
    let power: Vec<f64> = (1..n)
        .map(|m| {
            let b: f64 = profile
                .iter()
                .enumerate()
                .map(|(i, p)| p.1 * (std::f64::consts::PI * (m * i) as f64 / n as f64).sin())
                .sum();
            b * b
        })
        .collect();
    let peak = (0..power.len())
        .max_by(|&a, &b| power[a].total_cmp(&power[b]))
        .expect("profile with interior stations");
    let band = peak.saturating_sub(2)..(peak + 3).min(power.len());
    let weight: f64 = power[band.clone()].iter().sum();
    let mean = band.map(|j| (j + 1) as f64 * power[j]).sum::<f64>() / weight;
    (2.0 * length / mean, peak + 1)
}

/// λ_h = π·h/asin(π·h/λ_c): the discrete strip's critical wavelength on
/// cells of length h. On sin(qx) the triplets' curvature and the yarns'
/// shortening both see Q = (2/h)·sin(qh/2) in place of q (to leading
/// order in the amplitude), so P = B·Q² + k/Q² is least at Q = q_c.
fn discrete_wavelength(h: f64, lambda_c: f64) -> f64 {
    let pi = std::f64::consts::PI;
    pi * h / (pi * h / lambda_c).asin()
}

/// The strip with and without bending on `meshes` (cells along it,
/// doubling), see the module documentation.
///
/// With bending, on every mesh the wavelength against the discrete λ_h
/// and on the finest against λ_c, both within 5 %: the strip takes the
/// admissible 2L/m nearest the fastest-growing wave (half the spacing of
/// neighbouring m, 2.5 %), and the push overshoots P_c while the wrinkle
/// grows from its seed, which shortens the fastest-growing wave to
/// λ_c·√(P_c/P) (2 % at a 4 % overshoot); the change between the two
/// finest meshes below 10 % (the criterion); the end force at
/// the onset within 10 % of P_c. Without bending: λ within 10 % of 2h,
/// the zigzag (the spectrum's peak sits at m = N − 1 or next to it), and
/// λ halving with h: the ratio 0.5 ± 0.1 between meshes.
fn wrinkling_checks(meshes: &[usize]) -> Vec<Check> {
    let material = strip_material();
    let b = material.bending_rigidity.expect("rigidity")[0];
    let lambda_c = 2.0 * std::f64::consts::PI * (b / FOUNDATION).powf(0.25);
    let p_c = 2.0 * (FOUNDATION * b).sqrt();
    let length = 10.0 * lambda_c;
    let (shortening, duration) = (2.0, 0.6);
    let mut checks = Vec::new();
    for bending in [true, false] {
        let label = if bending { "bending" } else { "no bending" };
        let mut lambdas = Vec::new();
        for &cells in meshes {
            let h = length / cells as f64;
            let w = run_strip(length, cells, bending, shortening, duration);
            let (lambda, peak) = if w.profile.is_empty() {
                (f64::NAN, 0)
            } else {
                spectral_wavelength(&w.profile)
            };
            let crossings = zero_crossing_wavelength(&w.profile)
                .map_or("none".to_owned(), |(l, n)| {
                    format!("{l:.2} mm from {n} crossings")
                });
            let what = format!(
                "{label}, {cells} cells (h = {h:.3} mm): wavelength (mm; peak m = {peak}; \
                 zero crossings: {crossings}; at t = {:.3} s)",
                w.time
            );
            if bending {
                checks.push(Check::rel(
                    format!("{what} vs discrete λ_h"),
                    discrete_wavelength(h, lambda_c),
                    lambda,
                    0.05,
                ));
                checks.push(Check::rel(
                    format!(
                        "{label}, {cells} cells: end force at the onset vs P_c = 2√(kB) (N/mm)"
                    ),
                    p_c,
                    w.peak_force,
                    0.10,
                ));
            } else {
                checks.push(Check::rel(format!("{what} vs 2h"), 2.0 * h, lambda, 0.10));
            }
            lambdas.push(lambda);
        }
        let n = meshes.len();
        if bending {
            checks.push(Check::rel(
                format!(
                    "bending, {} cells: wavelength vs λ_c = 2π(B/k)^(1/4) (mm)",
                    meshes[n - 1]
                ),
                lambda_c,
                lambdas[n - 1],
                0.05,
            ));
            checks.push(Check::abs(
                format!(
                    "bending: wavelength change {} → {} cells (relative; < 10 %)",
                    meshes[n - 2],
                    meshes[n - 1]
                ),
                0.0,
                (lambdas[n - 1] / lambdas[n - 2] - 1.0).abs(),
                0.10,
            ));
        } else {
            for (pair, cells) in lambdas.windows(2).zip(meshes.windows(2)) {
                checks.push(Check::abs(
                    format!(
                        "no bending: wavelength ratio {} / {} cells (the mesh sets it: 0.5)",
                        cells[1], cells[0]
                    ),
                    0.5,
                    pair[1] / pair[0],
                    0.1,
                ));
            }
        }
    }
    checks
}

fn wrinkling_quick() -> Vec<Check> {
    wrinkling_checks(&[40, 80, 160])
}

fn wrinkling_full() -> Vec<Check> {
    wrinkling_checks(&[40, 80, 160, 320, 640])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_crossings_of_a_sine_give_its_wavelength() {
        let profile: Vec<(f64, f64)> = (0..=400)
            .map(|i| {
                let x = i as f64 * 0.5;
                (x, (2.0 * std::f64::consts::PI * x / 23.0 + 0.3).sin())
            })
            .collect();
        let (lambda, crossings) = zero_crossing_wavelength(&profile).unwrap();
        assert_eq!(crossings, 17);
        assert!((lambda - 23.0).abs() < 1e-3, "{lambda}");
        // A zigzag: two cells.
        let zigzag: Vec<(f64, f64)> = (0..50)
            .map(|i| (i as f64, if i % 2 == 0 { 1.0 } else { -1.0 }))
            .collect();
        assert_eq!(zero_crossing_wavelength(&zigzag).unwrap().0, 2.0);
        // Noise below a tenth of the peak does not count.
        let mut bump = vec![(0.0, 0.0); 21];
        for (i, p) in bump.iter_mut().enumerate() {
            *p = (i as f64, 0.01 * noise(i as u64));
        }
        bump[10].1 = 1.0;
        assert!(zero_crossing_wavelength(&bump).is_none());
    }

    #[test]
    fn the_sine_spectrum_finds_the_half_wave_count() {
        // 13 half-waves plus a weaker 30 on 100 cells: λ = 2L/13.
        let (l, n) = (60.0, 100);
        let profile: Vec<(f64, f64)> = (0..=n)
            .map(|i| {
                let x = l * i as f64 / n as f64;
                let s = |m: f64| (m * std::f64::consts::PI * x / l).sin();
                (x, s(13.0) + 0.3 * s(30.0))
            })
            .collect();
        let (lambda, peak) = spectral_wavelength(&profile);
        assert_eq!(peak, 13);
        assert!((lambda - 2.0 * l / 13.0).abs() < 1e-12, "{lambda}");
        // Between two modes the mean moves toward the stronger.
        let mixed: Vec<(f64, f64)> = profile
            .iter()
            .map(|&(x, _)| {
                let s = |m: f64| (m * std::f64::consts::PI * x / l).sin();
                (x, s(20.0) + 0.5 * s(21.0))
            })
            .collect();
        let (lambda, peak) = spectral_wavelength(&mixed);
        assert_eq!(peak, 20);
        let mean = (20.0 + 0.25 * 21.0) / 1.25;
        assert!((lambda - 2.0 * l / mean).abs() < 1e-12, "{lambda}");
    }

    #[test]
    fn the_discrete_wavelength_tends_to_the_continuous_one_as_h_squared() {
        let e = |h: f64| discrete_wavelength(h, 20.0) / 20.0 - 1.0;
        assert!(e(2.5) < 0.0);
        assert!(
            (e(1.25) / e(2.5) - 0.25).abs() < 0.01,
            "{}",
            e(1.25) / e(2.5)
        );
        // h = λ_c/4: π/4 → λ_h = 5π/asin(π/4).
        assert!((discrete_wavelength(5.0, 20.0) - 17.388778).abs() < 1e-5);
    }

    #[test]
    fn noise_is_in_range_and_not_constant() {
        let v: Vec<f64> = (0..1000).map(noise).collect();
        assert!(v.iter().all(|x| (-1.0..1.0).contains(x)));
        let mean = v.iter().sum::<f64>() / 1000.0;
        assert!(mean.abs() < 0.1, "{mean}");
    }
}
