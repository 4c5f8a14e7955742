//! Kinematic draping through the facade: [`kinematic_scene`] drapes a
//! scene's blank as a pin-jointed net (drape-fishnet) and writes the same
//! results folder as a forming run; [`compare_scene`] runs both on the same
//! scene and writes them side by side with their difference.
//!
//! The net is built in the mould's own coordinates and moved with the
//! mould's displacement at the scene's end time, so that it lies where the
//! formed part of a run lies.

use std::fmt::Write as _;
use std::path::Path;

use drape_fishnet::{Net, NetResults, NetStats};
use drape_io::results::{
    DrawInMm, EnergySummary, FrameData, MapPanel, Peaks, ResultsDir, ResultsError, RunInfo,
    Summary, ToolMeshes, write_flat_maps,
};
use drape_io::scene::{KinematicSetup, Scene};
use drape_model::measures::{ProfileLine, profile_elements};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::{RunControl, RunProgress, RunReport, run_scene};

/// What stops a kinematic drape or a comparison.
#[derive(Debug, thiserror::Error)]
pub enum KinematicError {
    /// The scene cannot be draped as it is (bad input: nothing written).
    #[error("{0}")]
    Input(String),
    /// The output folder cannot be used (a file, unwritable, or held by a
    /// running run): nothing was written.
    #[error(transparent)]
    Output(ResultsError),
    /// Writing results failed.
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// The work ran and did not give what it claims (a net with no cell
    /// draped, a comparison of no element); the folder's summary (or
    /// `comparison.json`) says so with this reason.
    #[error("{0}")]
    Failed(String),
    /// The forming run of a comparison was stopped (by the caller's
    /// progress callback): nothing was compared.
    #[error("{0}")]
    Stopped(String),
}

/// What a kinematic drape leaves.
#[derive(Debug, Clone)]
pub struct KinematicReport {
    /// The summary written to `summary.json` (`run.solver = "kinematic"`).
    pub summary: Summary,
    /// The draped net (in the mould's own coordinates).
    pub net: Net,
    /// The net as model, state, fields and measures (moved with the mould).
    pub results: NetResults,
    /// The net's counts.
    pub stats: NetStats,
    /// Index of the mould among the scene's tools.
    pub mould: usize,
    /// The laminate's ply the net is of (index into the model's plies;
    /// None for one ply).
    pub ply: Option<usize>,
}

/// Drapes `scene`'s blank on its mould as a pin-jointed net (the scene's
/// `[kinematic]` table, or its defaults) and writes into `out` what a
/// forming run writes: a VTU frame with a `series.pvd`, `profiles.csv`,
/// `summary.json`, `shear_map.png`, `profiles.png`, and an `energy.csv`
/// holding only its header (a net has no energy history).
///
/// The summary says `completed`; when cells of the blank could not be
/// draped (the net left the mould or folded) its `warnings` say how many.
/// A net of which no cell could be draped writes only its summary, with
/// status `failed` and the reason. A spacing that leaves no cell on the
/// blank, or a net whose estimated memory ([`crate::memory::net_bytes`])
/// exceeds what the machine has, is bad input: nothing is written.
pub fn kinematic_scene(scene: &Scene, out: &Path) -> Result<KinematicReport, KinematicError> {
    let file = scene.file.display();
    let setup = scene
        .kinematic
        .clone()
        .map_err(|e| KinematicError::Input(e.to_string()))?;
    let model = &scene.model;
    let tool = &model.tools[setup.mould];
    let material = model
        .membranes
        .first()
        .map(|b| b.section.material.clone())
        .ok_or_else(|| KinematicError::Input(format!("{file}: the blank has no elements")))?;
    let need = crate::memory::net_bytes(&setup.net);
    let available = crate::memory::available_memory();
    if need > available.bytes {
        return Err(KinematicError::Input(format!(
            "{file}: kinematic.spacing {:?} mm on a {} × {} mm blank: a net of {} crossings \
             needs about {} (1.7 kB a cell), more than the {} this machine has ({}): give a \
             larger kinematic.spacing",
            setup.net.spacing,
            setup.net.outline.width,
            setup.net.outline.height,
            setup.net.lattice_crossings(),
            crate::memory::bytes_text(need),
            crate::memory::bytes_text(available.bytes),
            available.source
        )));
    }
    let started = std::time::Instant::now();
    let net = Net::drape(&tool.surface, &setup.net)
        .map_err(|e| KinematicError::Input(format!("{file}: kinematic: {e}")))?;
    if net.stats().outline_cells == 0 {
        return Err(KinematicError::Input(format!(
            "{file}: kinematic.spacing {:?} mm on a {} × {} mm blank: no cell of the net has its \
             centre on the blank, so there is nothing to drape: give a kinematic.spacing smaller \
             than the blank",
            setup.net.spacing, setup.net.outline.width, setup.net.outline.height
        )));
    }
    let wall_s = started.elapsed().as_secs_f64();
    let shift = tool.motion.direction() * setup.mould_displacement;
    let locking = scene.spec.output.locking_angle_deg;
    let results = net
        .results(&material, shift, locking)
        .map_err(|e| KinematicError::Input(format!("{file}: kinematic: {e}")))?;
    let stats = net.stats();

    let mut dir = ResultsDir::create(out).map_err(KinematicError::Output)?;
    dir.set_shear_range(scene.spec.output.shear_range_deg);
    if stats.draped_cells == 0 {
        // Nothing to write but why: every other file would describe a net
        // that is not there (an empty frame, a NaN thickness).
        let summary = undraped_summary(scene, &stats, tool, &setup, wall_s);
        dir.write_summary(&summary)?;
        return Ok(KinematicReport {
            summary,
            net,
            results,
            stats,
            mould: setup.mould,
            ply: setup.ply,
        });
    }
    if scene.spec.output.vtu {
        dir.write_frame(
            0,
            0.0,
            &FrameData {
                model: &results.model,
                state: &results.state,
                fields: &results.fields,
                contact_force: None,
                contact_status: None,
                plies: None,
            },
        )?;
    }
    // The tools where the net lies: the mould moved as the net was, the
    // others where the run's end time puts them.
    let tools = ToolMeshes::new(&model.tools, &model.x0);
    let moved: Vec<f64> = model
        .tools
        .iter()
        .enumerate()
        .map(|(k, t)| {
            if k == setup.mould {
                setup.mould_displacement
            } else {
                t.prescribed_displacement(scene.settings.end_time)
                    .unwrap_or(0.0)
            }
        })
        .collect();
    if scene.spec.output.vtu {
        dir.write_tools(0, 0.0, &tools, &moved)?;
    }
    dir.write_energy(&[])?;
    dir.write_profiles(&results.measures)?;
    dir.write_orientations(
        &results.model,
        &results.state,
        &results.fields,
        &format!("{file}, kinematic net"),
    )?;
    if scene.spec.output.pictures {
        dir.write_pictures(
            &results.model,
            &results.state,
            &results.fields,
            &results.measures,
        )?;
        dir.write_view(
            &results.model,
            &results.state,
            &results.fields,
            &tools,
            &moved,
        )?;
    }
    let m = &results.measures;
    let draw_in = m.draw_in.unwrap_or(drape_model::measures::DrawIn {
        dx: f64::NAN,
        dy: f64::NAN,
        dd: f64::NAN,
    });
    let undraped = stats.outline_cells - stats.draped_cells;
    let summary = Summary {
        status: "completed".to_owned(),
        reason: None,
        scene: file.to_string(),
        time: 0.0,
        max_shear_deg: m.max_shear_deg,
        max_shear_at: m.max_shear_at,
        draw_in_mm: DrawInMm {
            dx: draw_in.dx,
            dy: draw_in.dy,
            dd: draw_in.dd,
        },
        draw_in_note: net_draw_in_note(&draw_in),
        // A net carries no load: no truss force (null), no yarn tension.
        max_fibre_tension_n: f64::NAN,
        max_fibre_tension_n_per_mm: 0.0,
        area_above_locking_mm2: m.area_above_locking,
        peak: {
            let mut peak = Peaks::default();
            peak.observe(&results.model, &results.state, &results.fields);
            peak
        },
        max_waviness_deg: m.max_waviness_deg,
        wrinkle_area_mm2: m.wrinkle_area,
        fold: None,
        energy: EnergySummary::default(),
        setup: None,
        run: RunInfo {
            device: None,
            wall_s,
            steps: 0,
            threads: 1,
            solver: "kinematic".to_owned(),
            implicit: None,
            mould: Some(tool.name.clone()),
            mould_reason: Some(setup.mould_reason.clone()),
            ply: ply_name(scene, &setup),
        },
        // A net that stops short is a result, not a failure: the engineer
        // reads where it could not go.
        warnings: (undraped > 0)
            .then(|| {
                format!(
                    "{undraped} of the blank's {} cells are not draped: the net left the mould's edge or folded (sheared to 90°) there",
                    stats.outline_cells
                )
            })
            .into_iter()
            .collect(),
        plies: Vec::new(),
        tools: Vec::new(),
    };
    dir.write_summary(&summary)?;
    Ok(KinematicReport {
        summary,
        net,
        results,
        stats,
        mould: setup.mould,
        ply: setup.ply,
    })
}

/// The summary of a net of which no cell could be draped: `failed`, why,
/// and no measure (there is no net to measure).
fn undraped_summary(
    scene: &Scene,
    stats: &NetStats,
    tool: &drape_contact::Tool,
    setup: &KinematicSetup,
    wall_s: f64,
) -> Summary {
    Summary {
        status: "failed".to_owned(),
        reason: Some(format!(
            "no cell of the net could be draped: none of the blank's {} cells has its four \
             crossings on the mould `{}` ({} crossings placed): the net leaves the mould's edge \
             or folds at once; check kinematic.seed, kinematic.spacing and the blank's cells",
            stats.outline_cells, tool.name, stats.placed
        )),
        scene: scene.file.display().to_string(),
        draw_in_mm: DrawInMm {
            dx: f64::NAN,
            dy: f64::NAN,
            dd: f64::NAN,
        },
        draw_in_note: Some("no net was draped".to_owned()),
        max_fibre_tension_n: f64::NAN,
        run: RunInfo {
            device: None,
            wall_s,
            steps: 0,
            threads: 1,
            solver: "kinematic".to_owned(),
            implicit: None,
            mould: Some(tool.name.clone()),
            mould_reason: Some(setup.mould_reason.clone()),
            ply: ply_name(scene, setup),
        },
        ..Summary::default()
    }
}

/// The name of the laminate's ply the net is of (None for one ply).
fn ply_name(scene: &Scene, setup: &KinematicSetup) -> Option<String> {
    setup.ply.map(|p| scene.model.plies[p].name.clone())
}

/// Why a net's draw-in lacks a value: the net reads it at the flat
/// blank's edge midpoints (DX, DY) and corners (DD), and a point it did
/// not reach has none.
fn net_draw_in_note(d: &drape_model::measures::DrawIn) -> Option<String> {
    let missing: Vec<&str> = [
        (d.dx, "DX (a midpoint of an edge normal to x)"),
        (d.dy, "DY (a midpoint of an edge normal to y)"),
        (d.dd, "DD (a corner)"),
    ]
    .iter()
    .filter(|(v, _)| v.is_nan())
    .map(|(_, what)| *what)
    .collect();
    (!missing.is_empty()).then(|| {
        format!(
            "{}: not on the draped net (it left the mould's edge or folded before reaching \
             that point of the blank)",
            missing.join(", ")
        )
    })
}

/// The difference of two shear profiles along one line of the blank.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ProfileDifference {
    /// Elements on the line with a value from both.
    pub points: usize,
    /// Of those, elements lying on the mould in the forming run.
    pub points_on_mould: usize,
    /// Largest |γ_mechanical − γ_kinematic| (degrees).
    pub max_abs_deg: f64,
    /// Root mean square of the difference (degrees).
    pub rms_deg: f64,
    /// Largest |difference| over the elements on the mould (degrees).
    pub max_abs_on_mould_deg: f64,
    /// Root mean square over the elements on the mould (degrees).
    pub rms_on_mould_deg: f64,
}

/// `comparison.json`: a forming run against the kinematic net.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ComparisonSummary {
    /// `completed`, or `failed` when nothing could be compared (the
    /// reason says why; the other numbers are then meaningless).
    #[serde(default)]
    pub status: String,
    /// Why it failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The scene file.
    pub scene: String,
    /// The forming run's status.
    pub mechanical_status: String,
    /// Largest |γ| of the forming run (degrees).
    pub mechanical_max_shear_deg: f64,
    /// Largest |γ| of the net (degrees).
    pub kinematic_max_shear_deg: f64,
    /// Elements of the forming run.
    pub elements: usize,
    /// Of those, elements whose reference centroid lies on the draped net.
    pub compared: usize,
    /// Of those, elements lying on the mould at the end of the run (every
    /// node within half a thickness of its contact position).
    pub on_mould: usize,
    /// Over every compared element.
    pub all: ProfileDifference,
    /// Along the blank's diagonal.
    pub diagonal: ProfileDifference,
    /// Along the median parallel to x.
    pub median: ProfileDifference,
}

/// Per element of a forming run, the two shears at its material point.
#[derive(Debug, Clone, Default)]
pub struct Comparison {
    /// The summary.
    pub summary: ComparisonSummary,
    /// γ of the forming run per element (degrees).
    pub mechanical_deg: Vec<f64>,
    /// γ of the net at the element's reference centroid (degrees; NaN off
    /// the draped net).
    pub kinematic_deg: Vec<f64>,
    /// Whether the element lies on the mould at the end of the run.
    pub on_mould: Vec<bool>,
    /// Reference centroids.
    pub centroid0: Vec<Vector3<f64>>,
    /// The elements compared: every one, or a laminate's ply's (the
    /// others' values are NaN).
    pub elements: std::ops::Range<usize>,
}

fn differences(indices: impl Iterator<Item = usize>, c: &Comparison) -> ProfileDifference {
    let mut d = ProfileDifference::default();
    let (mut sum, mut sum_on) = (0.0, 0.0);
    for e in indices {
        let diff = c.mechanical_deg[e] - c.kinematic_deg[e];
        if !diff.is_finite() {
            continue;
        }
        d.points += 1;
        sum += diff * diff;
        d.max_abs_deg = d.max_abs_deg.max(diff.abs());
        if c.on_mould[e] {
            d.points_on_mould += 1;
            sum_on += diff * diff;
            d.max_abs_on_mould_deg = d.max_abs_on_mould_deg.max(diff.abs());
        }
    }
    d.rms_deg = (sum / d.points.max(1) as f64).sqrt();
    d.rms_on_mould_deg = (sum_on / d.points_on_mould.max(1) as f64).sqrt();
    d
}

/// The forming run `mechanical` of `scene` against its kinematic net: the
/// net's shear read at each element's reference centroid
/// ([`Net::shear_at`]: bilinear between cell centres), element by element
/// and along the diagonal and median. Empty when the run's element fields
/// cannot be evaluated (a collapsed element) or `kinematic` was draped on a
/// tool `scene` does not have.
pub fn compare(scene: &Scene, kinematic: &KinematicReport, mechanical: &RunReport) -> Comparison {
    let model = &scene.model;
    let Ok(fields) = model.element_fields(&mechanical.state) else {
        return Comparison::default();
    };
    let Some(tool) = model.tools.get(kinematic.mould) else {
        return Comparison::default();
    };
    let displacement = tool
        .prescribed_displacement(mechanical.state.time)
        .unwrap_or(0.0);
    // A laminate's net is of one ply: only that ply's elements are
    // compared. A node lies on the mould within half a thickness of its
    // contact position: a ply's own thickness over the plies below it
    // (and, as those plies' flat faces sag inside the mould's curve, down
    // to the mould itself).
    let (elements, reach) = match kinematic.ply {
        Some(p) => {
            let ply = &model.plies[p];
            let below: f64 = model.plies[..p].iter().map(|q| q.thickness).sum();
            (ply.elements.clone(), below + ply.thickness)
        }
        None => (0..fields.shear.len(), 2.0 * model.contact_offset),
    };
    let touching: Vec<bool> = mechanical
        .state
        .x
        .iter()
        .map(|x| (0.0..=reach).contains(&tool.project(x, displacement).gap))
        .collect();
    let mut c = Comparison {
        centroid0: fields.centroid0.clone(),
        mechanical_deg: fields
            .shear
            .iter()
            .enumerate()
            .map(|(e, g)| {
                if elements.contains(&e) {
                    g.to_degrees()
                } else {
                    f64::NAN
                }
            })
            .collect(),
        elements: elements.clone(),
        ..Comparison::default()
    };
    for batch in &model.membranes {
        for e in 0..batch.len() {
            c.on_mould
                .push(batch.element_nodes(e).iter().all(|&n| touching[n as usize]));
        }
    }
    c.kinematic_deg = fields
        .centroid0
        .iter()
        .enumerate()
        .map(|(e, p)| match elements.contains(&e) {
            true => kinematic.net.shear_at(p).map_or(f64::NAN, f64::to_degrees),
            false => f64::NAN,
        })
        .collect();
    let s = &mut c.summary;
    s.scene = scene.file.display().to_string();
    s.mechanical_status = mechanical.summary.status.clone();
    s.mechanical_max_shear_deg = match kinematic.ply {
        Some(p) => mechanical
            .summary
            .plies
            .get(p)
            .map_or(f64::NAN, |ply| ply.max_shear_deg),
        None => mechanical.measures.max_shear_deg,
    };
    s.kinematic_max_shear_deg = kinematic.results.measures.max_shear_deg;
    s.elements = elements.len();
    s.compared = c.kinematic_deg.iter().filter(|v| v.is_finite()).count();
    s.on_mould = elements
        .clone()
        .filter(|&e| c.kinematic_deg[e].is_finite() && c.on_mould[e])
        .count();
    let all = differences(elements.clone(), &c);
    let (diagonal, median) = match profile_frame(model, kinematic.ply) {
        Some(info) => {
            let line = |l| differences(profile(info, &c, l).into_iter().map(|(e, _)| e), &c);
            (line(ProfileLine::Diagonal), line(ProfileLine::MedianX))
        }
        None => Default::default(),
    };
    c.summary.all = all;
    c.summary.diagonal = diagonal;
    c.summary.median = median;
    c
}

/// The blank whose diagonal and median a comparison's profiles follow:
/// the laminate's ply the net is of, or the one blank.
fn profile_frame(
    model: &drape_model::Model,
    ply: Option<usize>,
) -> Option<&drape_model::BlankInfo> {
    match ply {
        Some(p) => model.plies[p].blank.as_ref(),
        None => model.blank.as_ref(),
    }
}

/// The compared elements on `line` of `info`'s blank, with their
/// distance along it.
fn profile(info: &drape_model::BlankInfo, c: &Comparison, line: ProfileLine) -> Vec<(usize, f64)> {
    profile_elements(&info.frame, &c.centroid0, line, 0.5 * info.cell_size)
        .into_iter()
        .filter(|(e, _)| c.elements.contains(e))
        .collect()
}

/// What a comparison leaves.
#[derive(Debug, Clone)]
pub struct ComparisonReport {
    /// The kinematic drape (written to `out/kinematic`).
    pub kinematic: KinematicReport,
    /// The forming run (written to `out/mechanical`).
    pub mechanical: RunReport,
    /// The comparison (written to `out`).
    pub comparison: Comparison,
}

/// Runs `scene` both ways: the kinematic net into `out/kinematic`, the
/// forming run into `out/mechanical` (each a full results folder), and
/// writes their comparison into `out`:
///
/// - `comparison.json` ([`ComparisonSummary`]);
/// - `comparison.csv`: per element of the run, its reference centroid,
///   both shears, their difference and whether it lies on the mould;
/// - `profiles.csv`: the same along the diagonal and the median;
/// - `comparison.png`: on the flat blank, the run's |γ|, the net's |γ| at
///   the same material points (one colour scale) and |γ|mech − |γ|kin.
pub fn compare_scene(
    scene: &Scene,
    out: &Path,
    progress: &mut dyn FnMut(&RunProgress) -> RunControl,
) -> Result<ComparisonReport, KinematicError> {
    let kinematic = kinematic_scene(scene, &out.join("kinematic"))?;
    crate::compare::clear_comparison(out, &["profiles.csv"])?;
    if kinematic.summary.status != "completed" {
        let reason = format!(
            "the kinematic net failed: {}",
            kinematic
                .summary
                .reason
                .as_deref()
                .unwrap_or("no reason given")
        );
        let summary = ComparisonSummary {
            status: "failed".to_owned(),
            reason: Some(reason.clone()),
            scene: scene.file.display().to_string(),
            ..ComparisonSummary::default()
        };
        crate::compare::write_json(out, &summary)?;
        return Err(KinematicError::Failed(reason));
    }
    let mechanical = run_scene(scene, &out.join("mechanical"), progress)?;
    if mechanical.summary.status == "stopped" {
        return Err(KinematicError::Stopped(format!(
            "the forming run was stopped at t = {:.6} s of {:.6} s: nothing compared (a partial \
             run against the net would compare two different things); its results so far are \
             in {}",
            mechanical.summary.time,
            scene.settings.end_time,
            out.join("mechanical").display()
        )));
    }
    let mut c = compare(scene, &kinematic, &mechanical);
    c.summary.status = "completed".to_owned();
    if c.summary.compared == 0 {
        let reason = format!(
            "no element compared: none of the forming run's {} elements has its reference \
             centroid on the draped net",
            c.summary.elements
        );
        c.summary.status = "failed".to_owned();
        c.summary.reason = Some(reason.clone());
        crate::compare::write_json(out, &c.summary)?;
        return Err(KinematicError::Failed(reason));
    }
    let at = |name: &str| {
        let path = out.join(name);
        move |source| ResultsError { path, source }
    };
    // No NaN in a table: a value that cannot be had is an empty field.
    let number = |v: f64| drape_io::finite::or_empty(v, |v| v.to_string());

    let mut csv =
        String::from("element,x0_mm,y0_mm,mechanical_deg,kinematic_deg,difference_deg,on_mould\n");
    for e in c.elements.clone() {
        let _ = writeln!(
            csv,
            "{e},{},{},{},{},{},{}",
            number(c.centroid0[e].x),
            number(c.centroid0[e].y),
            number(c.mechanical_deg[e]),
            number(c.kinematic_deg[e]),
            number(c.mechanical_deg[e] - c.kinematic_deg[e]),
            u8::from(c.on_mould[e])
        );
    }
    drape_io::atomic::write(&out.join("comparison.csv"), csv.as_bytes())
        .map_err(at("comparison.csv"))?;

    let mut profiles =
        String::from("line,distance_mm,mechanical_deg,kinematic_deg,difference_deg,on_mould\n");
    if let Some(info) = profile_frame(&scene.model, kinematic.ply) {
        for (name, line) in [
            ("diagonal", ProfileLine::Diagonal),
            ("median", ProfileLine::MedianX),
        ] {
            for (e, distance) in profile(info, &c, line) {
                let _ = writeln!(
                    profiles,
                    "{name},{},{},{},{},{}",
                    number(distance),
                    number(c.mechanical_deg[e]),
                    number(c.kinematic_deg[e]),
                    number(c.mechanical_deg[e] - c.kinematic_deg[e]),
                    u8::from(c.on_mould[e])
                );
            }
        }
    }
    drape_io::atomic::write(&out.join("profiles.csv"), profiles.as_bytes())
        .map_err(at("profiles.csv"))?;

    let magnitude = |v: &[f64]| -> Vec<f64> { v.iter().map(|g| g.abs()).collect() };
    let (mech, kin) = (magnitude(&c.mechanical_deg), magnitude(&c.kinematic_deg));
    let difference: Vec<f64> = mech.iter().zip(&kin).map(|(m, k)| m - k).collect();
    let shared = mech
        .iter()
        .chain(&kin)
        .filter(|v| v.is_finite())
        .fold(0.0f64, |a, &b| a.max(b));
    write_flat_maps(
        &out.join("comparison.png"),
        &scene.model,
        &[
            MapPanel {
                title: format!("Forming run ({}): |γ|", mechanical.summary.status),
                values: &mech,
                label: "|γ| (deg)".into(),
                signed: false,
                scale: Some(shared),
                range: scene.spec.output.shear_range_deg,
            },
            MapPanel {
                title: "Kinematic net: |γ|".into(),
                values: &kin,
                label: "|γ| (deg)".into(),
                signed: false,
                scale: Some(shared),
                range: scene.spec.output.shear_range_deg,
            },
            MapPanel {
                title: "Difference: |γ| run − |γ| net".into(),
                values: &difference,
                label: "difference (deg)".into(),
                signed: true,
                scale: None,
                range: None,
            },
        ],
    )?;
    crate::compare::write_json(out, &c.summary)?;
    Ok(ComparisonReport {
        kinematic,
        mechanical,
        comparison: c,
    })
}
