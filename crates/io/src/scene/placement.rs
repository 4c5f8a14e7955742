//! Units and placement of the meshes a scene reads from files (a blank's
//! `mesh`, a tool's `mesh` geometry), and the repairs a tool mesh may ask
//! for.
//!
//! A file's coordinates x become `offset + R·(s·x)`: first the scale s
//! (`scale`, or the factor of `units` to millimetres), then the rotation R
//! (`rotate = [rx, ry, rz]`, degrees, about the global x, then y, then z
//! axis through the origin), then the translation `offset` (mm). CAD files
//! are often in metres or inches and placed for a press, not for drape's
//! blank at the origin.

use std::path::Path;

use drape_contact::{RepairOptions, Surface};
use nalgebra::{Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use super::SceneError;
use super::limits::{MAX_COORDINATE_MM, MIN_MESH_SIZE_MM};
use super::locate::Locator;

/// The length unit of a mesh file's coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LengthUnit {
    /// Millimetres (drape's unit).
    Mm,
    /// Centimetres.
    Cm,
    /// Metres.
    M,
    /// Inches.
    In,
}

impl LengthUnit {
    /// Millimetres per unit.
    pub fn millimetres(self) -> f64 {
        match self {
            Self::Mm => 1.0,
            Self::Cm => 10.0,
            Self::M => 1000.0,
            Self::In => 25.4,
        }
    }
}

/// Scale, rotation and translation of a mesh read from a file.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Placement {
    scale: f64,
    /// The key that gave the scale, for errors (`units`, `scale`, or none).
    scale_key: Option<&'static str>,
    rotation: Rotation3<f64>,
    offset: Vector3<f64>,
}

impl Placement {
    /// The placement of the keys `units`, `scale`, `rotate` and `offset`
    /// of the table at `table` (for errors): `units` and `scale` exclude
    /// each other.
    pub(super) fn new(
        at: &Locator<'_>,
        table: &str,
        units: Option<LengthUnit>,
        scale: Option<f64>,
        rotate: Option<[f64; 3]>,
        offset: Option<[f64; 3]>,
    ) -> Result<Self, SceneError> {
        let scale = match (units, scale) {
            (Some(_), Some(_)) => {
                return Err(at.error(
                    &format!("{table}.scale"),
                    "give `units` or `scale`, not both (`units = \"m\"` is `scale = 1000`)",
                ));
            }
            (Some(u), None) => u.millimetres(),
            (None, Some(s)) if s.is_finite() && s > 0.0 => s,
            (None, Some(s)) => {
                return Err(at.error(
                    &format!("{table}.scale"),
                    format!("{s} is not allowed: expected a positive factor"),
                ));
            }
            (None, None) => 1.0,
        };
        let finite = |key: &str, v: [f64; 3]| {
            if v.iter().all(|c| c.is_finite()) {
                Ok(Vector3::from(v))
            } else {
                Err(at.error(
                    &format!("{table}.{key}"),
                    "every component must be a finite number",
                ))
            }
        };
        let r = finite("rotate", rotate.unwrap_or_default())?.map(f64::to_radians);
        let offset =
            super::limits::position(at, &format!("{table}.offset"), offset.unwrap_or_default())?;
        Ok(Self {
            scale,
            scale_key: match (units, scale) {
                (Some(_), _) => Some("units"),
                (None, 1.0) => None,
                (None, _) => Some("scale"),
            },
            // nalgebra's roll, pitch, yaw: about x, then y, then z (fixed axes).
            rotation: Rotation3::from_euler_angles(r.x, r.y, r.z),
            offset,
        })
    }

    /// Refuses a placement that takes the file's `points` (of the mesh
    /// `key` of `table`) past ±[`MAX_COORDINATE_MM`] or makes the mesh
    /// less than [`MIN_MESH_SIZE_MM`] across, naming the key that does:
    /// the scale (`units` or `scale`), else the offset, else the file.
    pub(super) fn check(
        &self,
        at: &Locator<'_>,
        table: &str,
        key: &str,
        points: &[Vector3<f64>],
    ) -> Result<(), SceneError> {
        let blame = |k: Option<&str>| format!("{table}.{}", k.unwrap_or(key));
        let reach = points.iter().fold(0.0, |m: f64, x| m.max(x.amax()));
        let scaled = reach * self.scale;
        if scaled > MAX_COORDINATE_MM {
            let why = match self.scale_key {
                Some(k) => format!("`{k}` scales the file's coordinates by {:e}", self.scale),
                None => "the file's coordinates".to_owned(),
            };
            return Err(at.error(
                &blame(self.scale_key),
                format!(
                    "{why}: its points reach {scaled:.3e} mm from the origin, past ±{MAX_COORDINATE_MM:e} mm \
                     (drape's lengths are in mm)"
                ),
            ));
        }
        let size = across(points) * self.scale;
        if !points.is_empty() && size < MIN_MESH_SIZE_MM {
            let why = match self.scale_key {
                Some(k) => format!("`{k}` scales the file's coordinates by {:e}", self.scale),
                None => "the file's coordinates".to_owned(),
            };
            return Err(at.error(
                &blame(self.scale_key),
                format!(
                    "{why}: the mesh is {size:.3e} mm across, less than {MIN_MESH_SIZE_MM:e} mm \
                     (drape's lengths are in mm)"
                ),
            ));
        }
        // Scaled within range, placed past it: the offset's doing.
        let placed = scaled * 3f64.sqrt() + self.offset.amax();
        if placed > MAX_COORDINATE_MM {
            return Err(at.error(
                &blame(Some("offset")),
                format!(
                    "moves the mesh to {placed:.3e} mm from the origin, past ±{MAX_COORDINATE_MM:e} mm"
                ),
            ));
        }
        Ok(())
    }

    /// Where the file's point `x` goes.
    pub(super) fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.offset + self.rotation * (x * self.scale)
    }
}

/// The diagonal of the points' bounding box (0 for none).
pub(super) fn across(points: &[Vector3<f64>]) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let (low, high) = points.iter().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(l, h), x| (l.inf(x), h.sup(x)),
    );
    (high - low).norm()
}

/// The surface of a tool's mesh file `file` (STL, OBJ or Abaqus `.inp`,
/// relative to the scene; of an `.inp`, only `instance` if given), placed
/// by `placement` and repaired as `options` ask; `g` is the geometry's field path for errors and warnings. A
/// surface less than 1 mm or more than 10 m across (after `units` and
/// `scale`) is most likely a file in another unit, and is warned about
/// as a blank mesh is.
pub(super) fn tool_mesh(
    at: &Locator<'_>,
    g: &str,
    file: &str,
    placement: &Placement,
    options: RepairOptions,
    instance: Option<&str>,
) -> Result<Surface, SceneError> {
    let path = at.file.parent().unwrap_or(Path::new(".")).join(file);
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if instance.is_some() && extension.as_deref() != Some("inp") {
        return Err(at.error(
            &format!("{g}.instance"),
            format!("`{file}`: `instance` picks an instance of an Abaqus .inp file"),
        ));
    }
    let read = match extension.as_deref() {
        Some("stl") => drape_contact::read_stl(&path).map_err(|e| e.to_string()),
        Some("obj") => drape_contact::read_obj(&path).map_err(|e| e.to_string()),
        // Rigid-surface and shell elements, Abaqus/CAE parts and instances.
        Some("inp") => crate::mesh_import::read_abaqus_surface(&path, instance)
            .map(|m| (m.vertices, m.triangles))
            .map_err(|e| e.to_string()),
        _ => {
            return Err(at.error(
                &format!("{g}.file"),
                format!("`{file}`: expected an .stl, .obj or Abaqus .inp file"),
            ));
        }
    };
    let (vertices, triangles) = read.map_err(|e| at.error(&format!("{g}.file"), e))?;
    placement.check(at, g, "file", &vertices)?;
    super::limits::mesh_size(
        at,
        &format!("{g}.file"),
        triangles.len(),
        "triangle",
        super::limits::TOOL_BYTES_PER_TRIANGLE,
        None,
    )?;
    let vertices: Vec<Vector3<f64>> = vertices.iter().map(|v| placement.apply(v)).collect();
    // drape works in mm: a mould of less than a millimetre or more than ten
    // metres across is most likely a file in another unit (a mould in
    // metres otherwise sits untouched, a speck far below the blank).
    let size = across(&vertices);
    if !(1.0..=10_000.0).contains(&size) {
        at.warn(
            &format!("{g}.units"),
            format!(
                "{}: the tool is {size:.3e} mm across, after `units`/`scale`: drape's lengths are \
                 in mm; if the file is in another unit, give `units = \"m\"` (or \"cm\", \"in\") \
                 or `scale` in [{g}]",
                path.display()
            ),
        );
    }
    let file_error = |e: String| at.error(&format!("{g}.file"), format!("{}: {e}", path.display()));
    let (triangles, report) = drape_contact::repair(&vertices, &triangles, options)
        .map_err(|e| file_error(e.to_string()))?;
    if !report.dropped.is_empty() {
        let first: Vec<String> = report
            .dropped
            .iter()
            .take(5)
            .map(usize::to_string)
            .collect();
        at.warn(
            &format!("{g}.drop_degenerate"),
            format!(
                "{}: dropped {} degenerate triangle{} (a repeated vertex, two vertices at one \
                 place or three on a line): triangle {}{}",
                path.display(),
                report.dropped.len(),
                if report.dropped.len() == 1 { "" } else { "s" },
                first.join(", "),
                if report.dropped.len() > 5 {
                    ", …"
                } else {
                    ""
                }
            ),
        );
    }
    if report.flipped > 0 {
        let (closed, open) = report.pieces;
        at.warn(
            &format!("{g}.reorient"),
            format!(
                "{}: turned {} triangle{} over to wind the mesh consistently ({closed} closed \
                 piece{} wound outward, {open} open piece{} kept on the side most of its area \
                 faced)",
                path.display(),
                report.flipped,
                if report.flipped == 1 { "" } else { "s" },
                if closed == 1 { "" } else { "s" },
                if open == 1 { "" } else { "s" },
            ),
        );
    }
    // The file's geometry (a degenerate triangle, a winding that flips) is
    // the file's fault: name it, and the keys that would repair it.
    Surface::triangle_mesh(vertices, triangles).map_err(|e| {
        let hint = match &e {
            drape_contact::SurfaceError::Mesh(drape_contact::MeshError::Degenerate { .. }) => {
                " (give `drop_degenerate = true` to drop such triangles)"
            }
            drape_contact::SurfaceError::Mesh(drape_contact::MeshError::Winding { .. }) => {
                " (give `reorient = true` to have drape wind the triangles consistently)"
            }
            _ => "",
        };
        file_error(format!("{e}{hint}"))
    })
}
