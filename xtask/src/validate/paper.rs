//! The paper's two experiments beside drape (El Hami, Radi, Cherouat
//! 2009; /work/shared/reference, §5.1 Table 2 and §5.2 Table 4), the
//! hemisphere's holding, and the hemisphere's mesh convergence.
//!
//! - `paper/hemisphere-table2`: the laying-up on the hemisphere at
//!   μ = 0, 0.1, 0.2, 0.5 for 0/90 and ±45 fibres; the maximum shear beside
//!   the experiment and the paper's simulation, with both errors, and the
//!   shear profiles like the paper's Fig. 7 (PNG).
//! - `paper/deep-drawing-table4`: the deep drawing's draw-in DX, DY, DD at
//!   μ = 0.01, 0.1, 0.2, 0.4, the same way, and the profiles like Fig. 12.
//! - Both tables also carry shear-law sensitivity rows at μ = 0.1 (full
//!   mode): the resin's shear modulus halved and doubled and a
//!   shear-locking law ([`locking_law`]), with what each moves and how
//!   much of drape's miss of the experiment it accounts for.
//! - `paper/hemisphere-holding`: the shipped point springs against a frame
//!   of springs distributed along the blank's edge (`per_length`), over
//!   their stiffness, and the blank-holder ring of
//!   `scenes/hemisphere-ring.toml` over its holder force and the mesh: the
//!   maximum shear anywhere and away from the holding, and where it is.
//! - `paper/mesh-convergence`: the hemisphere at 10×10 … 80×80 (160×160 in
//!   full mode; `DRAPE_CONVERGENCE_MAX_CELLS=80` stops at 80×80) with the
//!   observed order and the Richardson extrapolation.
//!
//! Every case is also quick: under `--quick` it runs a coarse version
//! (20×20 cells, the hemisphere's mass-scaling step doubled with the cell
//! size) whose checks are the runs' health only, since a coarse mesh is not
//! the paper's. What each full-mode check asserts, and why, is written
//! beside it. The runs go through `scenes.rs`'s [`Run`] and
//! [`execute_all`] (the shipped scene files changed only by `--set`-style
//! overrides). The PNGs go to `<target>/validation/paper/`.
//!
//! Not for: the speed of these runs (`cargo xtask bench`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use drape_constitutive::{Material, ShearLocking};
use drape_io::results::write_profile_comparison;
use drape_io::scene::{MaterialSpec, SceneFile};
use drape_model::measures::ProfilePoint;

use super::scenes::{
    AWAY_FROM_HOLDING_MM, Orientation, Outcome, Run, execute_all, friction, mesh, run_table,
    stroke_checks,
};
use super::{Case, Check, note, quick_mode};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "paper/hemisphere-table2",
        quick: true,
        run: hemisphere_table_2,
    },
    Case {
        name: "paper/deep-drawing-table4",
        quick: true,
        run: deep_drawing_table_4,
    },
    Case {
        name: "paper/hemisphere-holding",
        quick: true,
        run: hemisphere_holding,
    },
    Case {
        name: "paper/mesh-convergence",
        quick: true,
        run: mesh_convergence,
    },
];

/// The runs with the paper's element: its membrane and trusses have no
/// bending stiffness and its yarns no compression stiffness, so every run
/// here turns off the presets' yarn buckling and the yarn bending that the
/// shipped scenes get by default, and the tables put the paper's model
/// beside the paper's simulation and experiment, as before bending was
/// the default (the shipped scenes' own runs, with bending, are checked by
/// `scenes/*`).
fn execute_paper(runs: &[Run]) -> Vec<Outcome> {
    let runs: Vec<Run> = runs
        .iter()
        .cloned()
        .map(|mut run| {
            run.overrides
                .push(("fabric.bending".to_owned(), "false".to_owned()));
            // The paper's yarn buckles at no cost (c_c = 0): without the
            // presets' buckling law.
            run.overrides
                .push(("fabric.yarn_buckling".to_owned(), "false".to_owned()));
            run
        })
        .collect();
    execute_all(&runs)
}

/// The shipped hemisphere's mesh and mass-scaling step (a test checks
/// that they are the scene files').
const HEMISPHERE_CELLS: usize = 40;
const HEMISPHERE_MASS_SCALING_DT: f64 = 2e-5;

/// The hemisphere at `cells`×`cells` with the mass-scaling step in
/// proportion to the cell size, so every mesh carries the same added mass
/// per area: the stable step of a membrane is ∝ h·√(ρ/E), so a step ∝ h
/// needs the same ρ at every h, and a finer mesh solves the same
/// (mass-scaled) problem instead of a heavier one.
fn hemisphere_mesh(cells: usize) -> Vec<(&'static str, String)> {
    let dt = HEMISPHERE_MASS_SCALING_DT * HEMISPHERE_CELLS as f64 / cells as f64;
    vec![
        ("fabric.blank.cells", format!("[{cells}, {cells}]")),
        ("simulation.mass_scaling_dt", format!("{dt:e}")),
    ]
}

/// The mesh of this mode: 20×20 under `--quick`, the shipped 40×40 else.
fn hemisphere_cells() -> usize {
    if quick_mode() { 20 } else { HEMISPHERE_CELLS }
}

fn hemisphere_run(
    orientation: Orientation,
    label: impl Into<String>,
    overrides: &[(&str, String)],
) -> Run {
    let mut all = hemisphere_mesh(hemisphere_cells());
    all.extend(overrides.iter().cloned());
    Run::of(orientation.scene("hemisphere"), orientation, label, &all)
}

/// The shipped blank-holder ring scene (0/90 fibres): the hemisphere
/// clamped at its rim between a fixed die ring and a force-driven holder.
fn ring_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .join("scenes")
        .join("hemisphere-ring.toml")
}

/// The ring scene's holder force (N) and where it is set (a test checks
/// both against the scene file).
const RING_FORCE_N: f64 = 8000.0;
const RING_FORCE_KEY: &str = "tools.2.motion.force";

/// Lift off the blank's initial plane (mm) beyond which an element is no
/// longer in the clamp: the clamp holds the blank's mid-plane at z = 0
/// within the faces' 0.2 mm, and a drawn-out flap or the fabric wrapping
/// the holder's edge rises above it.
const CLAMP_LIFT_MM: f64 = 1.0;

/// The ring scene at `cells`×`cells` (mass-scaling step ∝ cell size, as
/// [`hemisphere_mesh`]) with the holder pressed by `force` N.
fn ring_run(cells: usize, force: f64, label: impl Into<String>) -> Run {
    let mut all = hemisphere_mesh(cells);
    all.push((RING_FORCE_KEY, force.to_string()));
    Run::of(ring_scene(), Orientation::ZeroNinety, label, &all)
}

/// The fabric of the scene file at `path` (a preset or an inline card).
fn scene_material(path: &Path) -> Material {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let spec: SceneFile =
        toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    match spec.fabric.material {
        MaterialSpec::Preset(name) => Material::paper_preset(&name)
            .unwrap_or_else(|| panic!("{}: unknown preset {name}", path.display())),
        MaterialSpec::Inline(m) => m,
    }
}

/// The onset of the sensitivity rows' shear-locking law (degrees).
const LOCKING_ONSET_DEG: f64 = 40.0;

/// A shear-locking law for a fabric that has none measured: τ_s =
/// c₅·γ⁵, whose force per width h·τ_s equals the resin's own linear
/// shear G₀·h_m·γ at [`LOCKING_ONSET_DEG`] (G₀ the resin's instantaneous
/// shear modulus, h_m its thickness). Below the onset it adds little
/// (a third of the resin's at 30°), beyond it dominates (5× the resin's
/// at 60°): the shape of a published picture-frame curve, with its scale
/// tied to the material's own resin rather than chosen freely. An assumption: neither
/// fabric's picture-frame curve is published with the paper.
fn locking_law(material: &Material) -> ShearLocking {
    let onset = LOCKING_ONSET_DEG.to_radians();
    let c5 = material.resin.shear_modulus() * material.resin_thickness()
        / (material.thickness * onset.powi(4));
    ShearLocking {
        coefficients: vec![0.0, 0.0, c5],
        friction: None,
    }
}

/// The shear laws the scene format offers beside the preset's linear
/// resin, as (label, `fabric.material` override): the resin's shear
/// modulus halved and doubled (E_m scaled, ν_m kept, so G_m scales with it;
/// the resin's normal stiffness scales too, but the yarns carry that
/// direction), and [`locking_law`] added to the preset's resin.
fn shear_law_variants(scene: &Path) -> Vec<(String, (&'static str, String))> {
    let base = scene_material(scene);
    let mut variants = Vec::new();
    for factor in [0.5, 2.0] {
        let mut m = base.clone();
        m.resin.young *= factor;
        variants.push((format!("resin G × {factor}"), m));
    }
    let mut m = base.clone();
    m.resin.shear_locking = Some(locking_law(&base));
    variants.push((format!("locking from {LOCKING_ONSET_DEG}°"), m));
    variants
        .into_iter()
        .map(|(label, m)| (label, ("fabric.material", material_card(&m))))
        .collect()
}

/// `material` as an inline TOML table, the value of a `fabric.material`
/// override.
fn material_card(material: &Material) -> String {
    toml::Value::try_from(material)
        .expect("a material is plain data")
        .to_string()
}

/// Where the PNGs go.
fn pictures_dir() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace");
    super::target_dir(root).join("validation").join("paper")
}

/// Writes one PNG of profiles (the paper's Figs. 7 and 12) and returns a
/// line for the report naming it.
fn profile_picture(file: &str, title: &str, curves: &[(String, &[ProfilePoint])]) -> String {
    let dir = pictures_dir();
    let path = dir.join(file);
    let written = std::fs::create_dir_all(&dir)
        .map_err(|e| e.to_string())
        .and_then(|()| write_profile_comparison(&path, title, curves).map_err(|e| e.to_string()));
    match written {
        Ok(()) => format!("Profiles: `{}`.", path.display()),
        Err(e) => panic!("could not write {}: {e}", path.display()),
    }
}

/// The paper's profile figures of `experiment` (`hemisphere` or
/// `deep-drawing`): 0/90 along the diagonal and ±45 along the median, as
/// its `figure`, one curve per run that `curves` picks for an orientation
/// and a line; the Markdown that names the PNGs.
fn paper_figures<'a>(
    experiment: &str,
    figure: &str,
    cells: usize,
    curves: impl Fn(Orientation, &str) -> Vec<(String, &'a [ProfilePoint])>,
) -> String {
    let mut text = String::new();
    for (orientation, line, suffix) in [
        (Orientation::ZeroNinety, "diagonal", "0-90-diagonal"),
        (Orientation::PlusMinus45, "median", "45-median"),
    ] {
        let mut name = experiment.replace('-', " ");
        name[..1].make_ascii_uppercase();
        let title = format!(
            "{name} {}: shear along the {line} (paper {figure}), {cells}×{cells}",
            orientation.label()
        );
        let file = format!("{experiment}-{suffix}.png");
        text.push_str(&profile_picture(&file, &title, &curves(orientation, line)));
        text.push('\n');
    }
    text
}

/// The checks every hemisphere run must pass: it reaches the end time with
/// the punch at its full stroke and the energy balance closes to 1e-3 of
/// the largest energy. (Not E_kin/E_int < 1e-3 as for the deep drawing:
/// the shipped hemisphere ends at 1.4e-3 with its hanging skirt still
/// swinging, which the summary reports.)
fn hemisphere_checks(o: &Outcome) -> Vec<Check> {
    let mut checks = stroke_checks(o);
    checks.truncate(3);
    checks
}

/// The paper's Table 2 (maximum shear, degrees): (orientation, experiment,
/// simulation at μ = 0, 0.1, 0.2, 0.5).
const TABLE_2: [(Orientation, f64, [f64; 4]); 2] = [
    (Orientation::ZeroNinety, 31.0, [29.12, 29.85, 27.7, 25.247]),
    (
        Orientation::PlusMinus45,
        28.0,
        [30.57, 29.72, 25.22, 23.501],
    ),
];
const TABLE_2_FRICTIONS: [f64; 4] = [0.0, 0.1, 0.2, 0.5];

/// The friction of the shear-law sensitivity rows: Table 2's middle
/// friction and Table 4's stated one.
const LAW_MU: f64 = 0.1;

/// The paper's largest |simulation − experiment| of an orientation's row:
/// the accuracy its authors reached with their own undocumented choices.
fn paper_error_band(paper: &[f64], experiment: f64) -> f64 {
    paper
        .iter()
        .map(|p| (p - experiment).abs())
        .fold(0.0, f64::max)
}

fn hemisphere_table_2() -> Vec<Check> {
    // Quick: the two extreme frictions only.
    let frictions: &[f64] = if quick_mode() {
        &[0.0, 0.5]
    } else {
        &TABLE_2_FRICTIONS
    };
    let mut runs = Vec::new();
    for (orientation, _, _) in TABLE_2 {
        for &mu in frictions {
            runs.push(hemisphere_run(
                orientation,
                format!("μ = {mu}"),
                &[("tools.0.friction", mu.to_string())],
            ));
        }
    }
    // The shear-law rows at the paper's middle friction: every variant
    // for both orientations in full mode; one coarse 0/90 row in quick
    // mode, for the runs' health only.
    for (orientation, _, _) in TABLE_2 {
        if quick_mode() && orientation != Orientation::ZeroNinety {
            continue;
        }
        for (law, card) in shear_law_variants(&orientation.scene("hemisphere")) {
            if quick_mode() && !law.starts_with("locking") {
                continue;
            }
            runs.push(hemisphere_run(
                orientation,
                format!("μ = {LAW_MU}, {law}"),
                &[("tools.0.friction", LAW_MU.to_string()), card],
            ));
        }
    }
    let outcomes = execute_paper(&runs);
    let mut checks: Vec<Check> = outcomes.iter().flat_map(hemisphere_checks).collect();
    let cells = hemisphere_cells();
    let mut text = format!(
        "Table 2 of the paper (maximum shear angle, degrees) beside drape, {cells}×{cells} cells, \
         the shipped scenes (8 point springs of 1 N/mm) with the friction changed. \"Away\" is the \
         largest shear more than {AWAY_FROM_HOLDING_MM} mm (in the flat blank) from every spring's \
         node. Errors against the experiment.\n\n\
         | fibres | μ | exp. | paper | drape, anywhere | drape, away | paper − exp. | drape − exp. (anywhere) | drape − exp. (away) |\n\
         |---|--:|--:|--:|--:|--:|--:|--:|--:|\n"
    );
    for (orientation, experiment, paper) in TABLE_2 {
        let band = paper_error_band(&paper, experiment);
        for (k, mu) in TABLE_2_FRICTIONS.into_iter().enumerate() {
            let Some(o) = outcomes
                .iter()
                .find(|o| o.run.orientation == orientation && o.run.label == format!("μ = {mu}"))
            else {
                continue;
            };
            let _ = writeln!(
                text,
                "| {} | {mu} | {experiment} | {} | {:.2} | {:.2} | {:+.2} | {:+.2} | {:+.2} |",
                orientation.label(),
                paper[k],
                o.max_shear_deg,
                o.max_shear_away_deg,
                paper[k] - experiment,
                o.max_shear_deg - experiment,
                o.max_shear_away_deg - experiment,
            );
            // The experiment is the truth; the paper's spread over μ is the
            // accuracy reached with its own undocumented choices (springs,
            // tool mesh). Table 2's measure is the maximum anywhere. A
            // coarse mesh is not the paper's, so only full mode asserts it.
            if !quick_mode() {
                checks.push(Check::abs(
                    format!(
                        "{} μ = {mu}: max shear (°) within the paper's own error band of the experiment",
                        orientation.label()
                    ),
                    experiment,
                    o.max_shear_deg,
                    band,
                ));
            }
        }
    }
    text.push_str(
        "\nSource: El Hami, Radi, Cherouat (2009), Table 2; the experiment is one test per \
         orientation (no friction given), so the table has no experimental trend with μ.\n\n\
         Why drape and the paper differ, by undocumented choice: the holding (the paper's 24 \
         nonlinear springs are not described; drape's 8 linear ones are stretched about 200 mm \
         by the 300 mm stroke, so their force, and the shear, follow their stiffness: the \
         sensitivity rows are `paper/hemisphere-holding`); the mesh (the maximum is not converged \
         at 40×40, see `paper/mesh-convergence`); the tool is documented (r = 120 mm) but its \
         faceting (1600 rigid elements in the paper, an exact sphere here) is not a free choice; \
         the shear law is the carbon preset's (Table 1) linear resin in both, which the paper \
         gives but whose fabric may lock (the shear-law rows below). With point springs the \
         maximum anywhere sits beside a spring (anywhere > away), where Table 2 cannot tell \
         whether the paper's did.\n\n",
    );
    text.push_str(&hemisphere_law_table(&outcomes));
    text.push_str(&paper_figures(
        "hemisphere",
        "Fig. 7",
        cells,
        |orientation, line| {
            frictions
                .iter()
                .map(|mu| {
                    let o = find(&outcomes, orientation, &format!("μ = {mu}"));
                    (format!("μ = {mu}"), o.profile(line))
                })
                .collect()
        },
    ));
    text.push('\n');
    text.push_str(&run_table(&outcomes));
    note(text);
    checks
}

/// Of `orientation`'s runs at friction `mu`: the preset's (labelled
/// "μ = {mu}") and the shear-law rows ("μ = {mu}, `<law>`").
fn law_rows(
    outcomes: &[Outcome],
    orientation: Orientation,
    mu: f64,
) -> (Option<&Outcome>, Vec<&Outcome>) {
    let base_label = format!("μ = {mu}");
    let ours = || outcomes.iter().filter(|o| o.run.orientation == orientation);
    let base = ours().find(|o| o.run.label == base_label);
    let rows = ours()
        .filter(|o| o.run.label.starts_with(&format!("{base_label},")))
        .collect();
    (base, rows)
}

/// The hemisphere's shear-law rows beside the preset's run at the same
/// friction, with what they change, and the finding stated from those
/// numbers.
fn hemisphere_law_table(outcomes: &[Outcome]) -> String {
    let mut text = format!(
        "Shear-law sensitivity (μ = {LAW_MU}): the preset's linear resin against the choices \
         the scene format offers, its shear modulus ×0.5 and ×2 and a shear-locking law from \
         {LOCKING_ONSET_DEG}° (τ_s = c₅·γ⁵ equal to the resin's own shear at the onset; an \
         assumption, see `locking_law` in xtask/src/validate/paper.rs). Δ against the preset.\n\n\
         | fibres | shear law | max anywhere | max away | Δ anywhere | Δ away | DX | DD |\n\
         |---|---|--:|--:|--:|--:|--:|--:|\n"
    );
    let base_label = format!("μ = {LAW_MU}");
    let mut findings = String::new();
    for (orientation, experiment, _) in TABLE_2 {
        let (base, rows) = law_rows(outcomes, orientation, LAW_MU);
        if rows.is_empty() {
            continue;
        }
        let delta =
            |v: f64, b: Option<f64>| b.map_or("—".to_owned(), |b| format!("{:+.2}", v - b));
        if let Some(b) = base {
            let _ = writeln!(
                text,
                "| {} | preset (linear resin) | {:.2} | {:.2} | — | — | {:.2} | {:.2} |",
                orientation.label(),
                b.max_shear_deg,
                b.max_shear_away_deg,
                b.draw_in.dx,
                b.draw_in.dd
            );
        }
        for o in &rows {
            let law = o.run.label.trim_start_matches(&format!("{base_label}, "));
            let _ = writeln!(
                text,
                "| {} | {law} | {:.2} | {:.2} | {} | {} | {:.2} | {:.2} |",
                orientation.label(),
                o.max_shear_deg,
                o.max_shear_away_deg,
                delta(o.max_shear_deg, base.map(|b| b.max_shear_deg)),
                delta(o.max_shear_away_deg, base.map(|b| b.max_shear_away_deg)),
                o.draw_in.dx,
                o.draw_in.dd
            );
        }
        if let Some(b) = base {
            let range = |of: fn(&Outcome) -> f64| {
                rows.iter()
                    .map(|o| of(o) - of(b))
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                        (lo.min(d), hi.max(d))
                    })
            };
            let (away_lo, away_hi) = range(|o| o.max_shear_away_deg);
            let (any_lo, any_hi) = range(|o| o.max_shear_deg);
            let _ = write!(
                findings,
                "{}: the shear law moves the maximum away from the springs by {away_lo:+.2}…{away_hi:+.2}° \
                 and the maximum anywhere by {any_lo:+.2}…{any_hi:+.2}°; with the preset, drape (away) − \
                 experiment is {:+.2}° and drape (anywhere) − experiment {:+.2}°. ",
                orientation.label(),
                b.max_shear_away_deg - experiment,
                b.max_shear_deg - experiment
            );
        }
    }
    if !findings.is_empty() {
        text.push('\n');
        text.push_str(findings.trim_end());
        text.push('\n');
    }
    text.push('\n');
    text
}

fn find<'a>(outcomes: &'a [Outcome], orientation: Orientation, label: &str) -> &'a Outcome {
    outcomes
        .iter()
        .find(|o| o.run.orientation == orientation && o.run.label == label)
        .unwrap_or_else(|| panic!("no run {} {label}", orientation.label()))
}

/// The paper's Table 4: (orientation, quantity, experiment, simulation at
/// μ = 0.01, 0.1, 0.2, 0.4). DY equals DX in every entry.
const TABLE_4: [(Orientation, &str, f64, [f64; 4]); 4] = [
    (
        Orientation::ZeroNinety,
        "DX = DY",
        44.0,
        [43.8, 42.3, 41.0, 40.2],
    ),
    (Orientation::ZeroNinety, "DD", 10.0, [9.6, 8.7, 8.64, 8.33]),
    (
        Orientation::PlusMinus45,
        "DX = DY",
        10.0,
        [8.3, 8.3, 8.3, 8.21],
    ),
    (
        Orientation::PlusMinus45,
        "DD",
        42.0,
        [38.3, 38.3, 38.3, 37.38],
    ),
];

const TABLE_4_FRICTIONS: [f64; 4] = [0.01, 0.1, 0.2, 0.4];

/// The friction the paper states for its deep drawing (§5.2).
const TABLE_4_PAPER_MU: f64 = 0.1;

/// Table 4: full mode at the shipped mesh (40×40 quads), all four
/// frictions; quick mode at 20×20, μ = 0.01 and 0.2. Not 0.4 in quick
/// mode: at 20×20 the 0/90 run stops at t = 0.398 s with a contact fault
/// (a node under the die's fillet moves 0.5701 mm in one step, beyond the
/// 0.57 mm the contact resolves), which 40×40 does not show; that is a
/// finding about coarse meshes at high friction, reported, not a CI guard.
fn deep_drawing_table_4() -> Vec<Check> {
    let (frictions, cells): (&[f64], usize) = if quick_mode() {
        (&[0.01, 0.2], 20)
    } else {
        (&TABLE_4_FRICTIONS, 40)
    };
    let mut runs = Vec::new();
    for orientation in Orientation::BOTH {
        for &mu in frictions {
            let mut overrides = friction(mu);
            overrides.extend(mesh(cells, "quad"));
            runs.push(Run::new(orientation, format!("μ = {mu}"), &overrides));
        }
        // The shear-law rows at the stated friction, full mode only (each
        // ±45 run is about a minute of CPU; quick mode's one shear-law row
        // is the hemisphere's).
        if !quick_mode() {
            for (law, card) in shear_law_variants(&orientation.scene("deep-drawing")) {
                let mut overrides = friction(TABLE_4_PAPER_MU);
                overrides.extend(mesh(cells, "quad"));
                overrides.push(card);
                runs.push(Run::new(
                    orientation,
                    format!("μ = {TABLE_4_PAPER_MU}, {law}"),
                    &overrides,
                ));
            }
        }
    }
    let outcomes = execute_paper(&runs);
    let mut checks: Vec<Check> = outcomes.iter().flat_map(stroke_checks).collect();
    // The band: the paper's largest error at the friction it states.
    let k_paper = TABLE_4_FRICTIONS
        .iter()
        .position(|&m| m == TABLE_4_PAPER_MU)
        .expect("the paper's μ is in the table");
    let band = TABLE_4
        .iter()
        .map(|(_, _, exp, paper)| (paper[k_paper] - exp).abs())
        .fold(0.0, f64::max);
    let mut text = format!(
        "Table 4 of the paper (draw-in, mm) beside drape, {cells}×{cells} quads, trusses, the \
         shipped scenes with the friction of all three tools changed. Errors against the \
         experiment.\n\n\
         | fibres | draw-in | exp. | μ | paper | drape | paper − exp. | drape − exp. |\n\
         |---|---|--:|--:|--:|--:|--:|--:|\n"
    );
    for (orientation, quantity, exp, paper) in TABLE_4 {
        for (k, mu) in TABLE_4_FRICTIONS.into_iter().enumerate() {
            let Some(o) = outcomes
                .iter()
                .find(|o| o.run.orientation == orientation && o.run.label == format!("μ = {mu}"))
            else {
                continue;
            };
            let drape = if quantity == "DD" {
                o.draw_in.dd
            } else {
                o.draw_in.dx
            };
            let _ = writeln!(
                text,
                "| {} | {quantity} | {exp} | {mu} | {} | {drape:.2} | {:+.2} | {:+.2} |",
                orientation.label(),
                paper[k],
                paper[k] - exp,
                drape - exp
            );
            // At the friction the paper states (μ = 0.1), drape is asked to
            // be as close to the experiment as the paper's worst column
            // there (3.7 mm, ±45 DD): the paper's own accuracy with its own
            // undocumented tools. Only in full mode (the shipped mesh).
            if !quick_mode() && mu == TABLE_4_PAPER_MU {
                checks.push(Check::abs(
                    format!(
                        "{} μ = {mu}: {quantity} (mm) within the paper's error band ({band} mm) of the experiment",
                        orientation.label()
                    ),
                    exp,
                    drape,
                    band,
                ));
            }
        }
    }
    text.push_str(
        "\nSource: El Hami, Radi, Cherouat (2009), Table 4 (one experiment per orientation). \
         Where drape misses by more than the paper: the ±45 DX (the tool radii and holder force \
         move it by < 2 mm, see `scenes/deep-drawing-sensitivity`; the shear law's share is in \
         the rows below) and 0/90 DD at μ = 0.01.\n\n",
    );
    text.push_str(&deep_drawing_law_table(&outcomes));
    text.push_str(&paper_figures(
        "deep-drawing",
        "Fig. 12",
        cells,
        |orientation, line| {
            outcomes
                .iter()
                .filter(|o| o.run.orientation == orientation)
                .map(|o| (o.run.label.clone(), o.profile(line)))
                .collect()
        },
    ));
    text.push('\n');
    text.push_str(&run_table(&outcomes));
    note(text);
    checks
}

/// The deep drawing's shear-law rows beside the preset's run at the
/// paper's friction, and how much of each draw-in's miss of the
/// experiment the closest row removes.
fn deep_drawing_law_table(outcomes: &[Outcome]) -> String {
    let base_label = format!("μ = {TABLE_4_PAPER_MU}");
    let rows_of = |orientation| law_rows(outcomes, orientation, TABLE_4_PAPER_MU);
    if Orientation::BOTH.iter().all(|&o| rows_of(o).1.is_empty()) {
        return String::new();
    }
    let mut text = format!(
        "Shear-law sensitivity (μ = {TABLE_4_PAPER_MU}): the preset's linear resin against its \
         shear modulus ×0.5 and ×2 and a shear-locking law from {LOCKING_ONSET_DEG}° (as for the \
         hemisphere). Δ against the preset.\n\n\
         | fibres | shear law | DX | DY | DD | max shear | Δ DX | Δ DD | Δ max shear |\n\
         |---|---|--:|--:|--:|--:|--:|--:|--:|\n"
    );
    let mut findings = String::new();
    for orientation in Orientation::BOTH {
        let (Some(base), rows) = rows_of(orientation) else {
            continue;
        };
        let _ = writeln!(
            text,
            "| {} | preset (linear resin) | {:.2} | {:.2} | {:.2} | {:.2} | — | — | — |",
            orientation.label(),
            base.draw_in.dx,
            base.draw_in.dy,
            base.draw_in.dd,
            base.max_shear_deg
        );
        for o in &rows {
            let law = o.run.label.trim_start_matches(&format!("{base_label}, "));
            let _ = writeln!(
                text,
                "| {} | {law} | {:.2} | {:.2} | {:.2} | {:.2} | {:+.2} | {:+.2} | {:+.2} |",
                orientation.label(),
                o.draw_in.dx,
                o.draw_in.dy,
                o.draw_in.dd,
                o.max_shear_deg,
                o.draw_in.dx - base.draw_in.dx,
                o.draw_in.dd - base.draw_in.dd,
                o.max_shear_deg - base.max_shear_deg
            );
        }
        // Each draw-in against the experiment: how much of the preset's
        // miss the closest shear-law row removes.
        for (quantity, exp, _) in TABLE_4
            .iter()
            .filter(|(o, ..)| *o == orientation)
            .map(|(_, q, e, p)| (q, e, p))
        {
            let of = |o: &Outcome| {
                if *quantity == "DD" {
                    o.draw_in.dd
                } else {
                    o.draw_in.dx
                }
            };
            let miss = of(base) - exp;
            let (lo, hi) = rows
                .iter()
                .map(|o| of(o) - of(base))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                    (lo.min(d), hi.max(d))
                });
            let Some(best) = rows
                .iter()
                .min_by(|a, b| (of(a) - exp).abs().total_cmp(&(of(b) - exp).abs()))
            else {
                continue;
            };
            let removed = 100.0 * (miss.abs() - (of(best) - exp).abs()) / miss.abs();
            let best_law = best
                .run
                .label
                .trim_start_matches(&format!("{base_label}, "));
            let verdict = if removed > 0.0 {
                format!("the closest ({best_law}) removes {removed:.0} % of the miss")
            } else {
                format!(
                    "none comes closer (the closest, {best_law}, adds {:.0} %)",
                    -removed
                )
            };
            let _ = write!(
                findings,
                "{} {quantity}: the preset misses the experiment ({exp} mm) by {miss:+.2} mm; the \
                 shear-law rows move it by {lo:+.2}…{hi:+.2} mm, and {verdict}. ",
                orientation.label(),
            );
        }
    }
    text.push('\n');
    text.push_str(findings.trim_end());
    text.push_str("\n\n");
    text
}

/// The blank's outline length of the shipped hemisphere (mm): a frame of
/// edge springs with the same total stiffness as the 8 point springs has
/// 8·k / 1400 N/mm per mm of edge.
const HEMISPHERE_OUTLINE_MM: f64 = 4.0 * 350.0;

/// The ring's holder forces of full mode (N): a quarter to twice the
/// scene's, whose face friction 2·μ·F equals the point springs' pull at the
/// end of their stroke.
const RING_FORCES_N: [f64; 4] = [2000.0, 4000.0, 8000.0, 16000.0];

/// The ring's meshes of full mode at the scene's force (the 40×40 run is
/// the force sweep's).
const RING_MESHES: [usize; 3] = [20, 40, 60];

fn ring_label(force: f64) -> String {
    format!("ring, holder {} kN", force / 1000.0)
}

/// Point springs against edge springs of the same total stiffness, over
/// the stiffness, and the blank-holder ring over its force and the mesh,
/// 0/90 at μ = 0.1.
fn hemisphere_holding() -> Vec<Check> {
    let stiffnesses: &[f64] = if quick_mode() {
        &[0.5, 2.0]
    } else {
        &[0.5, 1.0, 2.0, 5.0]
    };
    let o = Orientation::ZeroNinety;
    let mut runs = Vec::new();
    for &k in stiffnesses {
        runs.push(hemisphere_run(
            o,
            format!("8 point springs, {k} N/mm each"),
            &[("springs.0.stiffness", k.to_string())],
        ));
        let per_mm = 8.0 * k / HEMISPHERE_OUTLINE_MM;
        runs.push(hemisphere_run(
            o,
            format!(
                "edge springs, {per_mm:.3e} N/mm per mm (total {} N/mm)",
                8.0 * k
            ),
            &[
                ("springs.0.nodes", "\"boundary\"".into()),
                ("springs.0.per_length", "true".into()),
                ("springs.0.stiffness", format!("{per_mm:e}")),
            ],
        ));
    }
    // The ring: quick mode one coarse run at the scene's force (health
    // only); full mode the force sweep on the shipped mesh and the scene's
    // force on the other meshes.
    let cells = hemisphere_cells();
    let ring_forces: &[f64] = if quick_mode() {
        &[RING_FORCE_N]
    } else {
        &RING_FORCES_N
    };
    for &force in ring_forces {
        runs.push(ring_run(cells, force, ring_label(force)));
    }
    let ring_meshes: Vec<usize> = if quick_mode() {
        Vec::new()
    } else {
        RING_MESHES
            .iter()
            .copied()
            .filter(|&n| n != cells)
            .collect()
    };
    for &n in &ring_meshes {
        runs.push(ring_run(
            n,
            RING_FORCE_N,
            format!("{}, {n}×{n}", ring_label(RING_FORCE_N)),
        ));
    }
    let outcomes = execute_paper(&runs);
    let mut checks: Vec<Check> = outcomes.iter().flat_map(hemisphere_checks).collect();
    // The edge frame's claim: the largest shear is not made by the holding,
    // i.e. it lies outside the holding's neighbourhood (the two maxima are
    // the same element's, so equal to the bit).
    for o in outcomes.iter().filter(|o| o.run.label.starts_with("edge")) {
        checks.push(Check::abs(
            format!(
                "{}: max shear away from the edge (°) = max anywhere",
                o.run.name()
            ),
            o.max_shear_deg,
            o.max_shear_away_deg,
            0.0,
        ));
    }
    // The ring's claim: the largest shear is not in the clamp. The clamp
    // holds the blank in its plane, so an element still clamped at the end
    // sits within the faces' 0.2 mm of z = 0; the maximum's element must
    // have risen more than CLAMP_LIFT_MM off it (on the dome, the free
    // span or a drawn-out flap). Fails for a maximum between the faces, and
    // for NaN.
    let ring: Vec<&Outcome> = outcomes
        .iter()
        .filter(|o| o.run.label.starts_with("ring"))
        .collect();
    if !quick_mode() {
        for o in &ring {
            let z = o.max_shear_at[2];
            let shortfall = if z.is_nan() {
                f64::NAN
            } else {
                (CLAMP_LIFT_MM - z).max(0.0)
            };
            checks.push(Check::abs(
                format!(
                    "{}: the maximum is off the clamp (its element's lift short of {CLAMP_LIFT_MM} mm above the blank's plane, mm)",
                    o.run.name()
                ),
                0.0,
                shortfall,
                0.0,
            ));
        }
    }
    let mut text = format!(
        "Holding of the hemisphere (0/90, μ = 0.1, {cells}×{cells}): the shipped 8 point springs \
         against a frame of springs along the whole edge (`per_length = true` on the set \
         `boundary`) with the same total stiffness, and the blank-holder ring \
         (`scenes/hemisphere-ring.toml`: the rim clamped between a fixed die ring below and a \
         holder above pressed by a constant force, μ = 0.1 on every tool, a 150 mm stroke — a \
         clamped 350 mm blank cannot follow the paper's 300 mm, see the scene's comments). \
         \"Away\" leaves out the elements within {AWAY_FROM_HOLDING_MM} mm of a node held by a \
         spring (for the edge frame: a band along the edge; the ring holds no node, so away = \
         anywhere, and its check is instead that the maximum's element has left the clamp). \
         r and z: where the maximum is at the end (its element's centroid). The paper: 29.85°; \
         the experiment 31°.\n\n\
         | holding | max shear anywhere | max shear away | max at r, z (mm) | DX | DD |\n\
         |---|--:|--:|--:|--:|--:|\n"
    );
    for o in &outcomes {
        let [x, y, z] = o.max_shear_at;
        let _ = writeln!(
            text,
            "| {} | {:.2} | {:.2} | {:.1}, {:.1} | {:.2} | {:.2} |",
            o.run.label,
            o.max_shear_deg,
            o.max_shear_away_deg,
            x.hypot(y),
            z,
            o.draw_in.dx,
            o.draw_in.dd
        );
    }
    // The ring on the meshes, at the scene's force.
    let mut by_mesh: Vec<(usize, &Outcome)> = Vec::new();
    for &n in &RING_MESHES {
        let label = if n == cells {
            ring_label(RING_FORCE_N)
        } else {
            format!("{}, {n}×{n}", ring_label(RING_FORCE_N))
        };
        if let Some(o) = ring.iter().find(|o| o.run.label == label) {
            by_mesh.push((n, o));
        }
    }
    if by_mesh.len() >= 2 {
        let _ = write!(
            text,
            "\nThe ring at {} kN on meshes {} (mass-scaling step ∝ cell size, as \
             `paper/mesh-convergence`); order and extrapolation from the three meshes \
             (refinement ratios {}).\n\n",
            RING_FORCE_N / 1000.0,
            by_mesh
                .iter()
                .map(|(n, _)| format!("{n}×{n}"))
                .collect::<Vec<_>>()
                .join(", "),
            by_mesh
                .windows(2)
                .map(|w| format!("{:.2}", w[1].0 as f64 / w[0].0 as f64))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let sizes: Vec<f64> = by_mesh.iter().map(|(n, _)| 350.0 / *n as f64).collect();
        let meshed: Vec<Outcome> = by_mesh.iter().map(|(_, o)| (*o).clone()).collect();
        text.push_str(&convergence_table(&meshed, &sizes));
    }
    let curves: Vec<(String, &[ProfilePoint])> = outcomes
        .iter()
        .map(|o| (o.run.label.clone(), o.profile_diagonal.as_slice()))
        .collect();
    text.push('\n');
    text.push_str(&profile_picture(
        "hemisphere-holding-diagonal.png",
        &format!("Hemisphere 0/90, μ = 0.1: shear along the diagonal by holding, {cells}×{cells}"),
        &curves,
    ));
    text.push_str("\n\n");
    text.push_str(&run_table(&outcomes));
    note(text);
    checks
}

/// One scalar of the mesh-convergence table.
struct Measure {
    name: &'static str,
    of: fn(&Outcome) -> f64,
}

/// The mean |γ| along the diagonal within `reach` mm of the centre, by the
/// trapezoidal rule over the mean curve (elements at equal distances
/// averaged): a profile as one number that converges like the field.
fn diagonal_mean(o: &Outcome, reach: f64) -> f64 {
    let curve = mean_curve(&o.profile_diagonal);
    let inside: Vec<(f64, f64)> = curve.into_iter().filter(|p| p.0.abs() <= reach).collect();
    let (mut area, mut span) = (0.0, 0.0);
    for w in inside.windows(2) {
        let h = w[1].0 - w[0].0;
        area += 0.5 * h * (w[0].1 + w[1].1);
        span += h;
    }
    if span > 0.0 { area / span } else { f64::NAN }
}

/// |γ| along the diagonal at distance `d`, linear between element centroids.
fn diagonal_at(o: &Outcome, d: f64) -> f64 {
    let curve = mean_curve(&o.profile_diagonal);
    curve
        .windows(2)
        .find(|w| w[0].0 <= d && d <= w[1].0)
        .map_or(f64::NAN, |w| {
            let t = (d - w[0].0) / (w[1].0 - w[0].0);
            w[0].1 + t * (w[1].1 - w[0].1)
        })
}

/// (distance, |γ|) averaged over elements at equal distance, sorted.
fn mean_curve(points: &[ProfilePoint]) -> Vec<(f64, f64)> {
    let mut curve: Vec<(f64, f64, usize)> = Vec::new();
    for p in points {
        match curve.last_mut() {
            Some((d, sum, n)) if (p.distance - *d).abs() <= 1e-9 * d.abs().max(1.0) => {
                *sum += p.shear_deg.abs();
                *n += 1;
            }
            _ => curve.push((p.distance, p.shear_deg.abs(), 1)),
        }
    }
    curve
        .into_iter()
        .map(|(d, s, n)| (d, s / n as f64))
        .collect()
}

const MEASURES: [Measure; 7] = [
    Measure {
        name: "max shear anywhere (°)",
        of: |o| o.max_shear_deg,
    },
    Measure {
        name: "max shear away from the springs (°)",
        of: |o| o.max_shear_away_deg,
    },
    Measure {
        name: "diagonal |γ| at d = 100 mm (°)",
        of: |o| diagonal_at(o, 100.0),
    },
    Measure {
        name: "diagonal |γ| at d = 200 mm (°)",
        of: |o| diagonal_at(o, 200.0),
    },
    Measure {
        name: "diagonal mean |γ|, |d| ≤ 200 mm (°)",
        of: |o| diagonal_mean(o, 200.0),
    },
    Measure {
        name: "DX (mm)",
        of: |o| o.draw_in.dx,
    },
    Measure {
        name: "DD (mm)",
        of: |o| o.draw_in.dd,
    },
];

/// Observed order and Richardson extrapolation from three values on meshes
/// refined by 2 (coarse, medium, fine): p = log2((f_c − f_m)/(f_m − f_f)),
/// f* = f_f + (f_f − f_m)/(2^p − 1). None when the differences do not keep
/// their sign, do not shrink (no asymptotic range) or vanish.
fn richardson(coarse: f64, medium: f64, fine: f64) -> Option<(f64, f64)> {
    let ratio = (coarse - medium) / (medium - fine);
    // Differences that do not shrink (ratio ≤ 1, order ≤ 0) are not in the
    // asymptotic range: extrapolating them runs away from the data (the
    // point springs' maximum gave −232°).
    if !(ratio.is_finite() && ratio > 1.0) {
        return None;
    }
    let p = ratio.log2();
    Some((p, fine + (fine - medium) / (2f64.powf(p) - 1.0)))
}

/// [`richardson`] for cell sizes h = [coarse, medium, fine] in any ratios:
/// f(h) = f* + C·h^p through the three values, p from
/// (f_c − f_m)/(f_m − f_f) = (h_c^p − h_m^p)/(h_m^p − h_f^p) by bisection
/// (the right side grows with p). None when the differences change sign or
/// the order falls outside (0.01, 8), where three values say nothing.
fn richardson_sizes(h: [f64; 3], f: [f64; 3]) -> Option<(f64, f64)> {
    if (h[0] / h[1] - 2.0).abs() < 1e-12 && (h[1] / h[2] - 2.0).abs() < 1e-12 {
        return richardson(f[0], f[1], f[2]);
    }
    let ratio = (f[0] - f[1]) / (f[1] - f[2]);
    if !(ratio.is_finite() && ratio > 0.0) {
        return None;
    }
    let g = |p: f64| (h[0].powf(p) - h[1].powf(p)) / (h[1].powf(p) - h[2].powf(p));
    let (mut lo, mut hi) = (0.01, 8.0);
    if !(g(lo) < ratio && ratio < g(hi)) {
        return None;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < ratio {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let p = 0.5 * (lo + hi);
    let c = (f[1] - f[2]) / (h[1].powf(p) - h[2].powf(p));
    Some((p, f[2] - c * h[2].powf(p)))
}

/// The [`MEASURES`] of `outcomes` (coarse to fine, cell sizes `sizes`)
/// as a table, with the observed order and extrapolation from the three
/// finest.
fn convergence_table(outcomes: &[Outcome], sizes: &[f64]) -> String {
    let mut text = String::from("| measure |");
    for o in outcomes {
        let _ = write!(text, " {} |", o.run.label);
    }
    text.push_str(" observed order | extrapolated |\n|---|");
    for _ in 0..outcomes.len() + 2 {
        text.push_str("--:|");
    }
    text.push('\n');
    for m in &MEASURES {
        let values: Vec<f64> = outcomes.iter().map(m.of).collect();
        let _ = write!(text, "| {} |", m.name);
        for v in &values {
            let _ = write!(text, " {v:.3} |");
        }
        let fit = match (&values[..], sizes) {
            ([.., c, md, f], [.., hc, hm, hf]) => richardson_sizes([*hc, *hm, *hf], [*c, *md, *f]),
            _ => None,
        };
        match fit {
            Some((p, x)) => {
                let _ = writeln!(text, " {p:.2} | {x:.3} |");
            }
            None => text.push_str(" — | — |\n"),
        }
    }
    text
}

/// The hemisphere (0/90, μ = 0.1, the shipped point springs) on meshes
/// refined by 2, the mass-scaling step ∝ the cell size (see
/// [`hemisphere_mesh`]).
fn mesh_convergence() -> Vec<Check> {
    // DRAPE_CONVERGENCE_MAX_CELLS caps the finest mesh of full mode: the
    // 160×160 run alone is about 2·10⁵ steps of 25 600 quads, over 20 min
    // of CPU, which a shared machine may not afford.
    let cap = std::env::var("DRAPE_CONVERGENCE_MAX_CELLS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(usize::MAX);
    let all: &[usize] = if quick_mode() {
        &[10, 20]
    } else {
        &[10, 20, 40, 80, 160]
    };
    let meshes: Vec<usize> = all.iter().copied().filter(|&n| n <= cap).collect();
    let o = Orientation::ZeroNinety;
    let runs: Vec<Run> = meshes
        .iter()
        .map(|&n| {
            Run::of(
                o.scene("hemisphere"),
                o,
                format!("{n}×{n}"),
                &hemisphere_mesh(n),
            )
        })
        .collect();
    let outcomes = execute_paper(&runs);
    let mut checks: Vec<Check> = outcomes.iter().flat_map(hemisphere_checks).collect();
    let mut text = String::from(
        "Mesh convergence of the hemisphere (0/90, μ = 0.1, 8 point springs of 1 N/mm), the \
         mass-scaling step ∝ the cell size (2e-5 s at 40×40). Order and extrapolation by \
         Richardson from the three finest meshes (refinement ratio 2).\n\n",
    );
    let sizes: Vec<f64> = meshes.iter().map(|&n| 350.0 / n as f64).collect();
    text.push_str(&convergence_table(&outcomes, &sizes));
    for m in &MEASURES {
        let values: Vec<f64> = outcomes.iter().map(m.of).collect();
        // What the shipped mesh is worth: its draw-ins within 1 mm (the
        // resolution of the paper's measured draw-ins, Table 4) of the
        // finest mesh's. Asked of the draw-ins only (smooth, global
        // measures); the maxima are reported, not asked: with point springs
        // the largest shear sits beside a point load, whose neighbourhood
        // does not converge. A ratio of successive changes is not asked
        // either: the draw-in changes by hundredths of a millimetre from
        // 20×20 on, where the state of the still-swinging skirt at the end
        // (E_kin/E_int ≈ 1e-3), not the mesh, decides the ratio.
        let shipped = meshes.iter().position(|&n| n == HEMISPHERE_CELLS);
        if let (Some(k), true) = (shipped, m.name.starts_with('D')) {
            let finest = values.len() - 1;
            if finest > k {
                checks.push(Check::abs(
                    format!(
                        "{}: {}×{} (shipped) vs {} (finest)",
                        m.name, HEMISPHERE_CELLS, HEMISPHERE_CELLS, outcomes[finest].run.label
                    ),
                    values[finest],
                    values[k],
                    1.0,
                ));
            }
        }
    }
    text.push('\n');
    text.push_str(&run_table(&outcomes));
    note(text);
    checks
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn richardson_recovers_a_known_order_and_limit() {
        // f(h) = 3 + 2·h² at h = 4, 2, 1.
        let (p, x) = richardson(35.0, 11.0, 5.0).unwrap();
        assert!((p - 2.0).abs() < 1e-12, "{p}");
        assert!((x - 3.0).abs() < 1e-12, "{x}");
        // Oscillating differences have no order.
        assert!(richardson(1.0, 2.0, 1.5).is_none());
        assert!(richardson(1.0, 1.0, 1.0).is_none());
        // Growing differences (order ≤ 0) have none either.
        assert!(richardson(18.7, 24.2, 30.9).is_none());
        assert!(richardson(1.0, 2.0, 3.0).is_none());
    }

    #[test]
    fn the_hemisphere_constants_are_the_shipped_scenes() {
        for orientation in [Orientation::ZeroNinety, Orientation::PlusMinus45] {
            let path = orientation.scene("hemisphere");
            let spec = drape_io::scene::Scene::from_file(&path, &[]).unwrap().spec;
            assert_eq!(
                spec.fabric.blank.cells,
                Some([HEMISPHERE_CELLS; 2]),
                "{}",
                path.display()
            );
            assert_eq!(
                spec.simulation.mass_scaling_dt,
                Some(HEMISPHERE_MASS_SCALING_DT),
                "{}",
                path.display()
            );
        }
    }

    #[test]
    fn richardson_with_unequal_ratios_recovers_order_and_limit() {
        // f(h) = 1 + 0.5·h^1.5 on the ring's meshes 20, 40, 60.
        let h = [350.0 / 20.0, 350.0 / 40.0, 350.0 / 60.0];
        let f = h.map(|h: f64| 1.0 + 0.5 * h.powf(1.5));
        let (p, x) = richardson_sizes(h, f).unwrap();
        assert!((p - 1.5).abs() < 1e-9, "{p}");
        assert!((x - 1.0).abs() < 1e-9, "{x}");
        // Ratio 2 is the closed form, bit for bit.
        let h2 = [4.0, 2.0, 1.0];
        assert_eq!(
            richardson_sizes(h2, [35.0, 11.0, 5.0]),
            richardson(35.0, 11.0, 5.0)
        );
        // Differences that change sign have no order.
        assert!(richardson_sizes(h, [1.0, 2.0, 1.5]).is_none());
    }

    #[test]
    fn the_ring_constants_are_the_ring_scene() {
        let path = ring_scene();
        let spec = drape_io::scene::Scene::from_file(&path, &[]).unwrap().spec;
        // hemisphere_mesh scales the shipped hemisphere's mesh and step.
        assert_eq!(spec.fabric.blank.cells, Some([HEMISPHERE_CELLS; 2]));
        assert_eq!(
            spec.simulation.mass_scaling_dt,
            Some(HEMISPHERE_MASS_SCALING_DT)
        );
        // The key the force sweep sets is the holder's force.
        let k: usize = RING_FORCE_KEY.split('.').nth(1).unwrap().parse().unwrap();
        assert_eq!(spec.tools[k].name, "holder");
        match &spec.tools[k].motion {
            drape_io::scene::MotionSpec::Force { force, .. } => assert_eq!(*force, RING_FORCE_N),
            other => panic!("{other:?}"),
        }
        assert!(RING_FORCES_N.contains(&RING_FORCE_N));
        assert!(RING_MESHES.contains(&HEMISPHERE_CELLS));
    }

    #[test]
    fn the_locking_law_equals_the_resin_at_its_onset() {
        for preset in drape_constitutive::PRESET_NAMES {
            let m = Material::preset(preset).unwrap();
            let law = locking_law(&m);
            law.validate("resin.shear_locking").unwrap();
            let onset = LOCKING_ONSET_DEG.to_radians();
            // Force per width: the law on the fabric's thickness against the
            // resin's linear shear on its own.
            let resin = m.resin.young / (2.0 * (1.0 + m.resin.poisson))
                * (1.0 - m.fibre_volume_fraction)
                * m.thickness
                * onset;
            let locking = m.thickness * law.stress(onset);
            assert!(
                (locking / resin - 1.0).abs() < 1e-12,
                "{preset}: {locking} vs {resin}"
            );
            // Negligible well below the onset, dominant beyond it.
            let at = |deg: f64| law.stress(deg.to_radians()) / law.stress(onset);
            assert!(at(20.0) < 0.07 && at(60.0) > 7.0);
        }
    }

    #[test]
    fn the_shear_law_cards_are_the_preset_changed_in_one_place() {
        let path = Orientation::PlusMinus45.scene("deep-drawing");
        let base = scene_material(&path);
        let variants = shear_law_variants(&path);
        assert_eq!(variants.len(), 3);
        for (label, (key, card)) in &variants {
            assert_eq!(*key, "fabric.material");
            // The card is what the scene then reads.
            let set = [(key.to_string(), card.clone())];
            let spec = drape_io::scene::Scene::from_file(&path, &set).unwrap().spec;
            let MaterialSpec::Inline(m) = spec.fabric.material else {
                panic!("{label}: not an inline card");
            };
            let mut expected = base.clone();
            if label.starts_with("locking") {
                expected.resin.shear_locking = Some(locking_law(&base));
            } else {
                let factor: f64 = label.rsplit(' ').next().unwrap().parse().unwrap();
                expected.resin.young = base.resin.young * factor;
            }
            assert_eq!(m, expected, "{label}");
        }
    }

    #[test]
    fn the_paper_error_bands_are_the_largest_paper_errors() {
        assert!((paper_error_band(&TABLE_2[0].2, TABLE_2[0].1) - 5.753).abs() < 1e-12);
        assert!((paper_error_band(&TABLE_2[1].2, TABLE_2[1].1) - 4.499).abs() < 1e-12);
    }
}
