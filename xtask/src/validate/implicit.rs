//! Validation of the implicit driver (SPEC §7 "Implicit", §6 "Normal,
//! implicit"): every contact case of [`super::contact`] run again with
//! Newton increments and the condensed contact solve, with the same
//! references and tolerances; the picture frame and the bias extension of
//! [`super::explicit`] with the same references and tolerances; the
//! driver's determinism (`implicit/determinism`: the 10 × 10 ±45
//! hemisphere on 1 and 2 threads, positions bit for bit, same solver
//! path); and the paper's hemisphere laying-up run by both drivers, which
//! must agree:
//!
//! - `implicit/hemisphere-agreement` (full: the shipped 40 × 40 scenes,
//!   0/90 and ±45, μ = 0.1): maximum shear within 0.5°, RMS of the
//!   diagonal profiles' difference ≤ 0.5°, draw-in DX/DY/DD within 0.5 mm;
//! - `implicit/hemisphere-agreement-coarse`: the same checks on a 10 × 10
//!   blank, both orientations (in `--quick` since the regularised stick:
//!   the implicit runs take seconds, the explicit ones without mass scaling
//!   most of the case's time);
//! - `implicit/hemisphere-shipped` (full): the shipped 40 × 40 scenes with
//!   their mass scaling (250 × the blank's mass), which both drivers honour
//!   (checked: the implicit run integrates with the explicit run's scaled
//!   masses, the same added mass; both complete). The differences in
//!   maximum shear, draw-in and diagonal profile are reported, not
//!   checked, with each run's mirror asymmetry along the diagonal (the
//!   largest difference between the shear at d and at −d): the mass-scaled
//!   explicit run is not determined to the agreement's 0.5° there. With
//!   bending its 0/90 diagonal differs between mirror points by 2.24°
//!   (physical mass: 0.043°; the implicit runs: within 0.02°), so the
//!   profile RMS between the solvers was 0.85° while the maximum shear
//!   differed by 0.22° and the draw-ins by 0.18 mm (measured at d99ac1a).
//!   The mass-scaling error itself is measured against a physical-mass
//!   reference by `cargo xtask bench work-precision`. Until 2026-11-24
//!   this case checked the agreement and failed on that profile; a check
//!   whose reference is not determined to its tolerance cannot tell a
//!   driver's error, so the agreement is checked at the physical mass
//!   (the two cases above) and reported here.
//!
//! Two clamped scenes are run by the implicit driver with each contact
//! solver, checked for completion and energy balance and their forming
//! reported: `implicit/ring-clamp` (the shipped hemisphere-ring at
//! 20 × 20) and `implicit/holder-force-doubled` (the ±45 deep drawing at
//! 20 × 20 under twice its holder force); the active set stopped on both
//! until 2026-11-30.
//!
//! Both drivers run with yarn bending (`fabric.bending`, SPEC §4 "Beyond
//! the paper", the preset's rigidities).
//! Without it the blank has no out-of-plane stiffness where it is in
//! compression, and the explicit run's wrinkles there are picked by
//! round-off: on 10 × 10 (0/90, μ = 0.1, physical mass) its diagonal
//! profile differs between mirror points by up to 1.4° (2.4° at μ = 0;
//! 0.7° with the shipped mass scaling), while the implicit run (Bossak
//! dissipation, Newton converged at every increment) is mirror-symmetric
//! within 0.02°. With bending the explicit profile is symmetric within 0.23°.
//!
//! The first two run both drivers with the blank's physical mass: the
//! scene's mass scaling is switched off (its target set below every
//! element's stable step, so no node gets mass — checked). Same mass, same
//! loads, same tools: the two must give the same forming, so what is left
//! is the drivers' own error. The shipped
//! explicit scenes add mass (+3 860 % at 16 × 16) and differ from the
//! physical-mass answer by the mass-scaling error, which is measured and
//! reported by `cargo xtask bench work-precision`, not here (at 16 × 16
//! the mass-scaled explicit run's maximum shear is 22.5° against 19.7°
//! with the physical mass).

use std::path::Path;

use drape_io::scene::{Scene, Solver};

use super::contact::{self, Driver};
use super::{Case, Check};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "implicit/incline",
        quick: true,
        run: incline,
    },
    Case {
        name: "implicit/capstan",
        quick: true,
        run: capstan,
    },
    Case {
        name: "implicit/no-penetration",
        quick: true,
        run: no_penetration,
    },
    Case {
        name: "implicit/pinching",
        quick: true,
        run: pinching,
    },
    Case {
        name: "implicit/picture-frame",
        quick: true,
        run: picture_frame,
    },
    Case {
        name: "implicit/bias-extension",
        quick: true,
        run: bias_extension,
    },
    Case {
        name: "implicit/viscoelastic-rate",
        quick: true,
        run: viscoelastic_rate,
    },
    Case {
        name: "implicit/determinism",
        quick: true,
        run: determinism,
    },
    Case {
        name: "implicit/hemisphere-agreement",
        quick: false,
        run: hemisphere_agreement,
    },
    // Quick: with the regularised stick the implicit ±45 run is 232
    // increments (it was 1 083 with 231 cutbacks, 5.4 min); the explicit
    // runs without mass scaling are most of the case (~35 s idle).
    Case {
        name: "implicit/hemisphere-agreement-coarse",
        quick: true,
        run: hemisphere_agreement_coarse,
    },
    Case {
        name: "implicit/hemisphere-shipped",
        quick: false,
        run: hemisphere_shipped,
    },
    // The contact cases and the coarse agreement again with the active-set
    // contact solver, same references and tolerances.
    Case {
        name: "implicit/active-set-incline",
        quick: true,
        run: || contact::incline_with(Driver::ImplicitActiveSet),
    },
    Case {
        name: "implicit/active-set-capstan",
        quick: true,
        run: || contact::capstan_with(Driver::ImplicitActiveSet),
    },
    Case {
        name: "implicit/active-set-no-penetration",
        quick: true,
        run: || contact::no_penetration_with(Driver::ImplicitActiveSet),
    },
    Case {
        name: "implicit/active-set-pinching",
        quick: true,
        run: || contact::pinching_with(Driver::ImplicitActiveSet),
    },
    Case {
        name: "implicit/active-set-determinism",
        quick: true,
        run: determinism_active_set,
    },
    Case {
        name: "implicit/active-set-hemisphere-agreement-coarse",
        quick: true,
        run: hemisphere_agreement_coarse_active_set,
    },
    Case {
        name: "implicit/active-set-hemisphere-agreement",
        quick: false,
        run: hemisphere_agreement_active_set,
    },
    Case {
        name: "implicit/ring-clamp",
        quick: true,
        run: ring_clamp,
    },
    Case {
        name: "implicit/holder-force-doubled",
        quick: true,
        run: holder_force_doubled,
    },
];

fn incline() -> Vec<Check> {
    contact::incline_with(Driver::Implicit)
}

fn capstan() -> Vec<Check> {
    contact::capstan_with(Driver::Implicit)
}

fn no_penetration() -> Vec<Check> {
    contact::no_penetration_with(Driver::Implicit)
}

fn pinching() -> Vec<Check> {
    contact::pinching_with(Driver::Implicit)
}

fn picture_frame() -> Vec<Check> {
    super::explicit::picture_frame_with(Driver::Implicit)
}

fn bias_extension() -> Vec<Check> {
    super::explicit::bias_extension_with(Driver::Implicit)
}

/// The carbon prepreg's resin (paper Table 1: six Prony terms, τ from
/// 10 ms to 1000 s) sheared by the picture frame to 10° in 1 s and in
/// 100 s — process speeds a factor 100 apart, affordable only with
/// increments far above the explicit stable step. At the end (frame at
/// rest) the frame force must match linear viscoelasticity along the
/// frame's path: the shear stress τ₁₂(T) = 2G₀∫₀ᵀ g(T − s)·ė₁₂(s) ds with
/// g(t) = g_∞ + Σ g_k·e^(−t/τ_k) and e₁₂ the frame's log shear strain
/// (coaxial, so the rate of deformation is ė₁₂), the normal strains
/// elastic (the Prony series relaxes the shear only); and forming slower
/// must leave a lower force.
fn viscoelastic_rate() -> Vec<Check> {
    use super::explicit::{
        Frames, frame_energy, frame_force, frame_log_strain, frame_travel_rate,
        picture_frame_model, smooth_step,
    };
    let (side, cells, gamma_max) = (100.0, 8usize, 10f64.to_radians());
    let material =
        drape_constitutive::Material::paper_preset("carbon-prepreg-2x2").expect("preset");
    let resin = &material.resin;
    let g0 = resin.young / (2.0 * (1.0 + resin.poisson));
    let h_m = (1.0 - material.fibre_volume_fraction) * material.thickness;
    let volume = side * side * h_m;
    let relaxation = |t: f64| {
        1.0 - resin.prony.iter().map(|p| p.g).sum::<f64>()
            + resin
                .prony
                .iter()
                .map(|p| p.g * (-t / p.tau).exp())
                .sum::<f64>()
    };
    let d = 1e-6;
    let derivative = |f: &dyn Fn(f64) -> f64, x: f64| (f(x + d) - f(x - d)) / (2.0 * d);
    let mut checks = Vec::new();
    let mut ends = Vec::new();
    for duration in [1.0, 100.0] {
        // τ₁₂(T) by the midpoint rule on a fine grid in s/T (the smooth
        // step makes ė₁₂ smooth, the shortest τ is resolved at 1/10⁵ of T).
        let e12 = |s: f64| frame_log_strain(gamma_max * smooth_step(s / duration)).1;
        let n = 100_000;
        let ds = duration / n as f64;
        let tau12 = 2.0
            * g0
            * (0..n)
                .map(|i| {
                    let s = (i as f64 + 0.5) * ds;
                    relaxation(duration - s) * derivative(&e12, s)
                })
                .sum::<f64>()
            * ds;
        let normal = |g: f64| frame_energy(&material, side, g).0;
        let shear_rate = derivative(&|g| frame_log_strain(g).1, gamma_max);
        let reference = (volume * 2.0 * tau12 * shear_rate + derivative(&normal, gamma_max))
            / frame_travel_rate(side, gamma_max);
        let total = |g: f64| {
            let (normal, shear) = frame_energy(&material, side, g);
            normal + shear
        };
        let elastic = derivative(&total, gamma_max) / frame_travel_rate(side, gamma_max);
        let model = picture_frame_model(&material, side, cells, gamma_max, duration);
        let mut last = f64::NAN;
        let mut observer = Frames(|f: &drape_time::Frame<'_>| {
            last = frame_force(f, side, gamma_max * smooth_step(f.state.time / duration));
        });
        let settings = drape_time::ExplicitSettings {
            end_time: duration,
            frames: 2,
            ..drape_time::ExplicitSettings::default()
        };
        contact::run(Driver::Implicit, &model, settings, &mut observer);
        checks.push(Check::rel(
            format!(
                "frame force at 10° after {duration} s, linear viscoelastic \
                 (unrelaxed {elastic:.1} N) (N)"
            ),
            reference,
            last,
            1e-3,
        ));
        ends.push(last);
    }
    checks.push(Check::abs(
        format!(
            "100 times slower: force ratio slow/fast {:.3} below 1 (shown: 1 − ratio > 0)",
            ends[1] / ends[0]
        ),
        0.0,
        (1.0 - ends[1] / ends[0]).min(0.0),
        0.0,
    ));
    checks
}

/// A mass-scaling target below every element's stable step: no node gets
/// mass.
const PHYSICAL_MASS: (&str, &str) = ("simulation.mass_scaling_dt", "1e-9");

/// The hemisphere 10 × 10 at ±45 (contact, stick and slip, cutbacks) run
/// by the implicit driver on 1 and 2 threads: the same positions bit for
/// bit and the same solver path. The assembly, the residual and the
/// contact passes run on rayon; what they sum must not depend on how the
/// work was split.
fn determinism() -> Vec<Check> {
    determinism_with("condensed")
}

fn determinism_active_set() -> Vec<Check> {
    determinism_with("active_set")
}

/// [`determinism`] with the contact solver `solver`.
fn determinism_with(solver: &str) -> Vec<Check> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives inside the workspace");
    let overrides: Vec<(String, String)> = [
        ("fabric.blank.cells", "[10, 10]"),
        ("fabric.bending", "true"),
        ("simulation.end_time", "0.5"),
        ("simulation.solver", "\"implicit\""),
        ("simulation.contact_solver", solver),
    ]
    .iter()
    .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
    .collect();
    let scene = Scene::from_file(&root.join("scenes/hemisphere-45.toml"), &overrides)
        .expect("the scene loads");
    let out = super::target_dir(root).join("validation");
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| {
                drape::run_scene(
                    &scene,
                    &out.join(format!("implicit-determinism-{solver}-{threads}")),
                    &mut |_| drape::RunControl::Continue,
                )
                .expect("the run writes its results")
            })
    };
    let (one, two) = (run(1), run(2));
    let differing = super::explicit::coordinates_differing(&one.state.x, &two.state.x);
    let counts = |r: &drape::RunReport| {
        r.summary.run.implicit.map_or([f64::NAN; 3], |t| {
            [
                t.newton_iterations as f64,
                t.contact_iterations as f64,
                t.cutbacks as f64,
            ]
        })
    };
    let (c1, c2) = (counts(&one), counts(&two));
    let mut checks = vec![
        Check::abs(
            "both runs completed (1 thread, 2 threads)",
            0.0,
            [&one, &two]
                .iter()
                .map(|r| {
                    if r.summary.status == "completed" {
                        0.0
                    } else {
                        1.0
                    }
                })
                .sum::<f64>(),
            0.0,
        ),
        Check::abs(
            "coordinates differing between 1 and 2 threads",
            0.0,
            if one.state.x.len() == two.state.x.len() {
                differing as f64
            } else {
                f64::NAN
            },
            0.0,
        ),
        Check::abs(
            "increments, 2 threads vs 1 thread",
            one.state.step as f64,
            two.state.step as f64,
            0.0,
        ),
    ];
    for (what, (a, b)) in ["Newton iterations", "contact-solve products", "cutbacks"]
        .iter()
        .zip(c1.into_iter().zip(c2))
    {
        checks.push(Check::abs(
            format!("{what}, 2 threads vs 1 thread"),
            a,
            b,
            0.0,
        ));
    }
    checks
}

/// The condensed contact solver, named: the cases without `active-set` in
/// their names are the paper's solver whichever is the default.
const CONDENSED: (&str, &str) = ("simulation.contact_solver", "condensed");

fn hemisphere_agreement() -> Vec<Check> {
    let physical = [PHYSICAL_MASS, CONDENSED];
    let mut checks = agreement("hemisphere-0-90", &physical, Gate::Checked);
    checks.extend(agreement("hemisphere-45", &physical, Gate::Checked));
    checks
}

fn hemisphere_agreement_coarse() -> Vec<Check> {
    let coarse = [("fabric.blank.cells", "[10, 10]"), PHYSICAL_MASS, CONDENSED];
    let mut checks = agreement("hemisphere-0-90", &coarse, Gate::Checked);
    checks.extend(agreement("hemisphere-45", &coarse, Gate::Checked));
    checks
}

fn hemisphere_agreement_coarse_active_set() -> Vec<Check> {
    let coarse = [
        ("fabric.blank.cells", "[10, 10]"),
        PHYSICAL_MASS,
        ("simulation.contact_solver", "active_set"),
    ];
    let mut checks = agreement("hemisphere-0-90", &coarse, Gate::Checked);
    checks.extend(agreement("hemisphere-45", &coarse, Gate::Checked));
    checks
}

fn hemisphere_agreement_active_set() -> Vec<Check> {
    let physical = [PHYSICAL_MASS, ("simulation.contact_solver", "active_set")];
    let mut checks = agreement("hemisphere-0-90", &physical, Gate::Checked);
    checks.extend(agreement("hemisphere-45", &physical, Gate::Checked));
    checks
}

fn hemisphere_shipped() -> Vec<Check> {
    let mut checks = agreement("hemisphere-0-90", &[CONDENSED], Gate::Reported);
    checks.extend(agreement("hemisphere-45", &[CONDENSED], Gate::Reported));
    checks
}

/// The shipped hemisphere-ring (the blank clamped at its rim between a
/// die ring and a force-driven holder ring, both with rounded inner
/// edges) at 20 × 20 cells, run by the implicit driver with each contact
/// solver: both must reach the end of the stroke with the energy balance
/// closed up to the Newton residual's work. Until 2026-11-30 the active set
/// did not (stopped at t = 0.55 s at this mesh, t ≈ 0.49 s as shipped):
/// the clamp's sharing pulled on the die under nodes the fabric lifts,
/// and the two rings' normals, leaning alike where the flat faces meet
/// the rounds, made their rows nearly dependent (multipliers of −5·10⁴ N
/// on a 45 N clamp); see `drape_contact`'s `active_set` module. The two
/// runs' forming is reported, not checked: the free flaps of this blank
/// are not determined to a tolerance (at the physical mass the explicit
/// and implicit drivers' draw-ins differ by 16 mm there).
fn ring_clamp() -> Vec<Check> {
    both_contact_solvers(
        "hemisphere-ring",
        &[("fabric.blank.cells", "[20, 20]")],
        "ring-clamp",
    )
}

/// The ±45 deep drawing at 20 × 20 cells under twice its holder force
/// (380.8 kN), by the implicit driver with each contact solver, the same
/// checks as [`ring_clamp`]. Until 2026-11-30 the active set stopped at
/// t = 0.45 s on the energy guard: an attempt cut for divergence left the
/// tangent's largest stiffness at the diverged iterate's, the next
/// attempts' force scale at 2.5e11 N, and every predictor passed the
/// force test at its first iteration (`SparseTangent::begin_attempt`).
fn holder_force_doubled() -> Vec<Check> {
    both_contact_solvers(
        "deep-drawing-45",
        &[
            ("fabric.blank.cells", "[20, 20]"),
            ("tools.2.motion.force", "380800"),
        ],
        "holder-force-doubled",
    )
}

/// Runs the shipped scene `name` with `overrides` by the implicit driver
/// with each contact solver: checks that each reaches its end time with
/// the energy balance closed up to the Newton residual's work (and within
/// 1e-5 in all) and at rest (kinetic energy within
/// [`drape::QUASI_STATIC_KINETIC_SHARE`] of the internal), and reports the
/// two runs' counts and forming side by side.
fn both_contact_solvers(name: &str, overrides: &[(&str, &str)], tag: &str) -> Vec<Check> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives inside the workspace");
    let out = super::target_dir(root).join("validation");
    let mut checks = Vec::new();
    let settings: Vec<String> = overrides.iter().map(|(k, v)| format!("{k}={v}")).collect();
    let mut table = format!(
        "**{name}, {}, implicit** (reported, not checked)\n\n\
         | contact_solver | increments | cutbacks | factorisations | wall s | balance error | max shear (°) | DX (mm) | DY (mm) | DD (mm) |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
        settings.join(" ")
    );
    for solver in ["active_set", "condensed"] {
        let overrides: Vec<(String, String)> = overrides
            .iter()
            .chain(&[
                ("simulation.solver", "implicit"),
                ("simulation.contact_solver", solver),
            ])
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect();
        let scene = Scene::from_file(&root.join(format!("scenes/{name}.toml")), &overrides)
            .expect("the scene loads");
        let report = drape::run_scene(&scene, &out.join(format!("{tag}-{solver}")), &mut |_| {
            drape::RunControl::Continue
        })
        .expect("the run writes its results");
        let summary = &report.summary;
        if summary.status != "completed" {
            eprintln!("{tag}, {solver}: {:?}", summary.reason);
        }
        checks.push(Check::abs(
            format!("{solver}: the run reached its end time (s)"),
            scene.spec.simulation.end_time,
            if summary.status == "completed" {
                summary.time
            } else {
                f64::NAN
            },
            0.0,
        ));
        // The balance error of an implicit run is the work of the residual
        // its increments are accepted with (within the Newton tolerance),
        // and grows with the increments' length: the doubled holder's
        // 8.7e-7 came out at 1.13e-6 with the punch's μ at 0.1001 instead
        // of 0.1. What the balance can tell is a force whose work it
        // misses: beyond that residual work the error must be round-off
        // (at most 1.5e-15 measured: both cases, the shipped hemisphere and
        // the 0/90 deep drawing at 20 × 20). Its size is held to the
        // guard's range of a sound quasi-static run (`drape_time::guard`).
        checks.push(Check::abs(
            format!("{solver}: energy balance error (of the largest energy)"),
            0.0,
            summary.energy.balance_error,
            1e-5,
        ));
        let residual = summary.energy.newton_residual_work.unwrap_or(f64::NAN);
        checks.push(Check::abs(
            format!(
                "{solver}: energy balance error beyond the Newton residual's work \
                 (of the largest energy)"
            ),
            0.0,
            summary.energy.balance_error - residual.abs(),
            1e-12,
        ));
        // A run can close its balance and still end wrong: a path of the
        // condensed solve on the ring (2026-11-30) threw the blank off the
        // punch (its force 0.02 N at the end of the stroke, DX 49.6 / DY
        // 74.3 mm on a symmetric part) and ended moving. Quasi-static
        // forming ends at rest: the run's own warning's bound.
        checks.push(Check::abs(
            format!("{solver}: kinetic / internal energy at the end (quasi-static)"),
            0.0,
            summary.energy.kinetic_to_internal,
            drape::QUASI_STATIC_KINETIC_SHARE,
        ));
        let d = report.measures.draw_in.unwrap_or_default();
        let t = summary.run.implicit.as_ref();
        table += &format!(
            "| {solver} | {} | {} | {} | {:.1} | {:.2e} | {:.2} | {:.2} | {:.2} | {:.2} |\n",
            summary.run.steps,
            t.map_or(0, |t| t.cutbacks),
            t.map_or(0, |t| t.factorisations),
            summary.run.wall_s,
            summary.energy.balance_error,
            report.measures.max_shear_deg,
            d.dx,
            d.dy,
            d.dd
        );
    }
    super::note(table);
    checks
}

/// Whether [`agreement`] checks the two drivers' formed shapes against the
/// 0.5° / 0.5 mm tolerances or only reports their differences.
#[derive(Clone, Copy)]
enum Gate {
    Checked,
    Reported,
}

/// The largest difference between the shear at a signed distance d along
/// a profile and at −d (points paired when their distances sum to less
/// than 1e-6 mm): zero for a mirror-symmetric forming.
fn mirror_asymmetry(profile: &[drape_model::measures::ProfilePoint]) -> f64 {
    profile
        .iter()
        .filter(|p| p.distance > 0.0)
        .filter_map(|p| {
            profile
                .iter()
                .find(|q| (q.distance + p.distance).abs() < 1e-6)
                .map(|q| (p.shear_deg - q.shear_deg).abs())
        })
        .fold(0.0, f64::max)
}

/// Runs the shipped scene `name` (with `overrides`) with each driver and
/// compares the formed shapes (checked or reported, as `gate` says).
fn agreement(name: &str, overrides: &[(&str, &str)], gate: Gate) -> Vec<Check> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives inside the workspace");
    // Yarn bending: see the module docs.
    let overrides: Vec<(String, String)> = overrides
        .iter()
        .chain(&[("fabric.bending", "true")])
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
    let physical = overrides
        .iter()
        .any(|(k, v)| (k.as_str(), v.as_str()) == PHYSICAL_MASS);
    let scene = Scene::from_file(&root.join(format!("scenes/{name}.toml")), &overrides)
        .expect("the scene loads");
    let cells = scene.model.membranes.iter().map(|b| b.len()).sum::<usize>();
    let label = format!("{name}, {cells} cells");
    let out = super::target_dir(root).join("validation");
    let run = |solver: Solver, dir: &str| {
        let mut s = scene.clone();
        s.spec.simulation.solver = solver;
        drape::run_scene(&s, &out.join(dir), &mut |_| drape::RunControl::Continue)
            .expect("the run writes its results")
    };
    let solver_tag = if overrides
        .iter()
        .any(|(k, v)| k == "simulation.contact_solver" && v == "active_set")
    {
        "-active-set"
    } else {
        ""
    };
    let tag = format!("{name}-{cells}{solver_tag}");
    let explicit = run(Solver::Explicit, &format!("{tag}-explicit"));
    let implicit = run(Solver::Implicit, &format!("{tag}-implicit"));
    let completed = |r: &drape::RunReport| {
        if r.summary.status == "completed" {
            0.0
        } else {
            eprintln!("{label}: {:?}", r.summary.reason);
            f64::NAN
        }
    };
    let mut checks = vec![
        Check::abs(
            format!("{label}: explicit run completed"),
            0.0,
            completed(&explicit),
            0.0,
        ),
        Check::abs(
            format!("{label}: implicit run completed"),
            0.0,
            completed(&implicit),
            0.0,
        ),
        {
            let added = |r: &drape::RunReport| {
                r.summary
                    .setup
                    .as_ref()
                    .map_or(f64::NAN, |s| s.added_mass_fraction)
            };
            if physical {
                Check::abs(
                    format!("{label}: mass added to the explicit run (fraction)"),
                    0.0,
                    added(&explicit),
                    0.0,
                )
            } else {
                Check::abs(
                    format!("{label}: mass added, implicit vs explicit run (fraction)"),
                    added(&explicit),
                    added(&implicit),
                    0.0,
                )
            }
        },
    ];
    // Each comparison: what, explicit's value, implicit's (tolerance 0.5).
    let mut compared = vec![(
        "max shear, implicit vs explicit (°)".to_owned(),
        explicit.measures.max_shear_deg,
        implicit.measures.max_shear_deg,
    )];
    let (e, i) = (explicit.measures.draw_in, implicit.measures.draw_in);
    for (what, pick) in [
        (
            "DX",
            (|d: &drape_model::measures::DrawIn| d.dx) as fn(&_) -> f64,
        ),
        ("DY", |d| d.dy),
        ("DD", |d| d.dd),
    ] {
        compared.push((
            format!("draw-in {what}, implicit vs explicit (mm)"),
            e.as_ref().map_or(f64::NAN, pick),
            i.as_ref().map_or(f64::NAN, pick),
        ));
    }
    // The diagonal profiles sample the same elements in the same order.
    let (pe, pi) = (
        &explicit.measures.profile_diagonal,
        &implicit.measures.profile_diagonal,
    );
    let rms = if pe.len() == pi.len() && !pe.is_empty() {
        (pe.iter()
            .zip(pi)
            .map(|(a, b)| (a.shear_deg - b.shear_deg).powi(2))
            .sum::<f64>()
            / pe.len() as f64)
            .sqrt()
    } else {
        f64::NAN
    };
    compared.push((
        format!(
            "RMS of the diagonal profiles' difference ({} points) (°)",
            pe.len()
        ),
        0.0,
        rms,
    ));
    let (asym_e, asym_i) = (mirror_asymmetry(pe), mirror_asymmetry(pi));
    match gate {
        Gate::Checked => checks.extend(
            compared
                .into_iter()
                .map(|(what, e, i)| Check::abs(format!("{label}: {what}"), e, i, 0.5)),
        ),
        Gate::Reported => {
            let mut table = format!(
                "**{label}** (reported, not checked)\n\n| quantity | explicit | implicit | implicit − explicit |\n|---|---|---|---|\n"
            );
            for (what, e, i) in &compared {
                table += &format!("| {what} | {e:.3} | {i:.3} | {:+.3} |\n", i - e);
            }
            table += &format!(
                "| diagonal profile's mirror asymmetry (°) | {asym_e:.3} | {asym_i:.3} | |\n"
            );
            super::note(table);
        }
    }
    eprintln!(
        "{label}: the diagonal profile's mirror asymmetry {asym_e:.3}° explicit, {asym_i:.3}° implicit"
    );
    if let Some(t) = implicit.summary.run.implicit {
        eprintln!(
            "{label}: explicit {} steps {:.1} s; implicit {} increments, {} Newton ({} wasted), \
             {} PCG, {} cutbacks, {:.1} s wall, factorisation {:.1} s ({:.0} %), assembly {:.1} s, \
             contact {:.1} s",
            explicit.summary.run.steps,
            explicit.summary.run.wall_s,
            implicit.summary.run.steps,
            t.newton_iterations,
            t.wasted_iterations,
            t.contact_iterations,
            t.cutbacks,
            implicit.summary.run.wall_s,
            t.factor_s,
            100.0 * t.factor_share,
            t.assembly_s,
            t.contact_s
        );
    }
    checks
}
