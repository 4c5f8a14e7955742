//! `drape export RUN --onto MESH`: a run's draped orientations carried onto
//! a structural mesh of the user's.
//!
//! The run's `orientations.inp` (written by every run) gives the formed
//! mesh and its values; the structural mesh is read like a blank mesh
//! (Gmsh `.msh` 4.1 or Abaqus `.inp`: triangles and quads, shells or
//! membranes); [`drape_io::results::mapping::map_onto`] carries the values
//! onto it by closest point. The mesh must be in the formed part's
//! coordinates, in mm or in the unit given ([`MeshUnits`]: a structural
//! model in metres is read as one); the distance of each of its elements
//! to the formed surface is reported in mm, and a large one means the two
//! do not describe the same part or are not placed alike.
//!
//! The include written is in the mesh's own unit (its thickness
//! distribution in metres for a mesh in metres: it goes into that model,
//! and Abaqus has no units of its own); the CSV table stays in mm, as its
//! column names say. An Abaqus/CAE file is read with its parts and
//! instances; as the include names elements by the part's labels, which
//! repeat between instances, the mesh must have one instance at most.
//!
//! Nothing that cannot be computed is written as a number: a mesh beyond
//! reach (a coordinate not finite or past 10¹² mm) is refused, an element
//! edge-on to the fibres is listed as missing with the reason
//! ([`drape_io::results::export::Orientations::missing`]), and a source
//! run that did not complete is named in the include's header
//! ([`MappedReport::source_not_completed`]; the command exits 1 on it).

use std::path::{Path, PathBuf};

use drape_io::mesh_import::read_mesh;
use drape_io::results::ResultsError;
use drape_io::results::export::Orientations;
use drape_io::results::mapping::map_onto;

use crate::compare::CompareError;

/// The length unit of a structural mesh's coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshUnits {
    /// Its name, as the include's header gives it.
    pub name: String,
    /// Millimetres per unit.
    pub millimetres: f64,
}

impl MeshUnits {
    /// drape's own: millimetres.
    pub fn mm() -> Self {
        Self {
            name: "mm".into(),
            millimetres: 1.0,
        }
    }
}

/// What a mapping leaves.
#[derive(Debug, Clone)]
pub struct MappedReport {
    /// The mapped orientations (the structural mesh's labels).
    pub mapped: Orientations,
    /// The Abaqus include written.
    pub inp: PathBuf,
    /// The CSV table written.
    pub csv: PathBuf,
    /// The largest distance of an element's centroid to the formed
    /// surface (mm) and that element's label.
    pub max_distance: (f64, i64),
    /// The mean distance (mm).
    pub mean_distance: f64,
    /// Elements farther from the formed surface than its nominal thickness.
    pub beyond_thickness: usize,
    /// The nominal thickness (mm); a laminate's, all plies together
    /// (each is mapped from its own surface, at most that far from the
    /// laminate's other side).
    pub thickness: f64,
    /// The structural mesh's size (the diagonal of its bounding box, mm,
    /// after its unit): less than 1 mm or more than 10 m is most likely a
    /// mesh in another unit than the one given.
    pub mesh_across_mm: f64,
    /// Why the source run is not a finished drape (its summary says it
    /// failed or was stopped), or None. The include's header says it too.
    pub source_not_completed: Option<String>,
    /// Why the source run's state is unknown (no readable summary: orientations
    /// written by hand or by another tool), or None. In the header too.
    pub source_unknown: Option<String>,
    /// Elements written without values (label, why): a direction that
    /// cannot be computed. Listed in the include's `DRAPE_NO_ORIENTATION`
    /// (a laminate's: in each ply's `P_NO_ORIENTATION`, the why naming it).
    pub missing: Vec<(i64, String)>,
}

/// The state of the run in `run`: (why it is not a finished drape, why its
/// state is unknown); both None when its summary says `completed`.
fn source_state(run: &Path) -> (Option<String>, Option<String>) {
    match drape_io::results::read::read_summary(run) {
        Ok(s) if s.status == "completed" => (None, None),
        Ok(s) => (
            Some(format!(
                "the source run {} {} at t = {} s{}: these are the orientations of its last frame, \
             not of a finished drape",
                run.display(),
                s.status,
                s.time,
                s.reason.map(|r| format!(" ({r})")).unwrap_or_default()
            )),
            None,
        ),
        Err(e) => (
            None,
            Some(format!("whether the source run finished is unknown ({e})")),
        ),
    }
}

/// Maps the orientations of the results folder `run` onto the mesh file
/// `mesh` (coordinates in `units`) and writes `orientations_<mesh
/// name>.inp` (in the mesh's unit) and `.csv` (in mm) into `out`.
pub fn map_orientations(
    run: &Path,
    mesh: &Path,
    units: &MeshUnits,
    out: &Path,
) -> Result<MappedReport, CompareError> {
    let input = CompareError::Input;
    let source_path = run.join("orientations.inp");
    if !source_path.is_file() {
        return Err(input(format!(
            "{}: no orientations.inp: not a run's results folder, or a run written before \
             drape exported orientations (run it again)",
            run.display()
        )));
    }
    let source = Orientations::read_inp(&source_path).map_err(input)?;
    if !(units.millimetres.is_finite() && units.millimetres > 0.0) {
        return Err(input(format!(
            "a mesh unit of {} mm: expected a positive factor",
            units.millimetres
        )));
    }
    let mut target = read_mesh(mesh).map_err(|e| input(e.to_string()))?;
    if target.instances.len() > 1 {
        return Err(input(format!(
            "{}: the mesh has {} instances ({}): their element labels repeat, and the \
             orientations name elements by label — export the part to map onto in a file \
             with one instance",
            mesh.display(),
            target.instances.len(),
            target.instances.join(", ")
        )));
    }
    for x in &mut target.x0 {
        *x *= units.millimetres;
    }
    let (low, high) = target.x0.iter().fold(
        (
            nalgebra::Vector3::repeat(f64::INFINITY),
            nalgebra::Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(l, h), x| (l.inf(x), h.sup(x)),
    );
    let mesh_across_mm = (high - low).norm();
    // Coordinates past ~1e150 mm square to infinity in a distance: no
    // closest point means anything there.
    const FARTHEST_MM: f64 = 1e12;
    if let Some(p) = target
        .x0
        .iter()
        .find(|p| !p.iter().all(|v| v.is_finite() && v.abs() <= FARTHEST_MM))
    {
        return Err(input(format!(
            "{}: a node at ({:e}, {:e}, {:e}) mm (in {}): coordinates must be finite and within \
             {FARTHEST_MM:e} mm to be placed against the formed part: is the mesh in another \
             unit (give --units or --scale), or broken?",
            mesh.display(),
            p.x,
            p.y,
            p.z,
            units.name
        )));
    }
    let mut mapped =
        map_onto(&source, &target).map_err(|e| input(format!("{}: {e}", source_path.display())))?;
    let distance = mapped.distance.clone().unwrap_or_default();
    if let Some((k, d)) = drape_io::finite::first_non_finite(distance.iter().copied()) {
        return Err(input(format!(
            "{}: element {}: its distance to the formed part of {} is {d}: the mesh cannot be \
             placed against it (is it in another unit, or far from the part?)",
            mesh.display(),
            mapped.labels[k],
            run.display()
        )));
    }
    let (source_not_completed, source_unknown) = source_state(run);
    mapped
        .notes
        .extend(source_not_completed.iter().chain(&source_unknown).cloned());
    let missing: Vec<(i64, String)> = mapped
        .incomplete()
        .into_iter()
        .map(|(e, why)| {
            // A laminate's labels repeat, once per ply: say whose.
            match mapped.plies.iter().find(|p| p.elements.contains(&e)) {
                Some(p) => (mapped.labels[e], format!("ply {}: {why}", p.name)),
                None => (mapped.labels[e], why),
            }
        })
        .collect();
    mapped
        .check_finite()
        .map_err(|e| input(format!("{}: {e}", mesh.display())))?;
    let stem = mesh
        .file_stem()
        .map_or_else(|| "mesh".to_owned(), |s| s.to_string_lossy().into_owned());
    std::fs::create_dir_all(out).map_err(|source| ResultsError {
        path: out.to_owned(),
        source,
    })?;
    let inp = out.join(format!("orientations_{stem}.inp"));
    let csv = out.join(format!("orientations_{stem}.csv"));
    let include = mapped.to_inp_in(&units.name, units.millimetres);
    for (path, text) in [(&inp, include), (&csv, mapped.to_csv())] {
        drape_io::atomic::write(path, text.as_bytes()).map_err(|source| ResultsError {
            path: path.clone(),
            source,
        })?;
    }
    let max_distance =
        distance
            .iter()
            .zip(&mapped.labels)
            .fold(
                (0.0f64, 0i64),
                |(m, l), (&d, &label)| {
                    if d > m { (d, label) } else { (m, l) }
                },
            );
    let mean_distance = distance.iter().sum::<f64>() / distance.len().max(1) as f64;
    let thickness = source.nominal_thickness;
    Ok(MappedReport {
        beyond_thickness: distance.iter().filter(|&&d| d > thickness).count(),
        mapped,
        inp,
        csv,
        max_distance,
        mean_distance,
        thickness,
        mesh_across_mm,
        source_not_completed,
        source_unknown,
        missing,
    })
}
