//! The draped fibre orientations for the structural analysis that follows
//! forming: per element of the formed mesh, the warp and weft directions,
//! the shear angle and the thickness.
//!
//! Every run writes two files into its results folder (at its last frame):
//!
//! - `orientations.inp`, an Abaqus include: the formed mesh (`*NODE`,
//!   `*ELEMENT` as S4R/S3 shells in the element sets `DRAPE_QUADS`,
//!   `DRAPE_TRIANGLES` and `DRAPE_PLY`), element distributions and two
//!   orientations (below);
//! - `orientations.csv`: the same numbers as a table.
//!
//! [`crate::results::mapping::map_onto`] carries them onto a structural
//! mesh of the user's by closest point.
//!
//! # Conventions
//!
//! - Units mm; directions are unit vectors in the global axes.
//! - Element `k` (1-based label) is drape's element `k − 1`: cell `k − 1`
//!   of the VTU frames. Node `k` is the VTU's point `k − 1`.
//! - The warp and weft directions are the element's current yarn
//!   directions (the VTU's `fibre_direction_*`; for a quad, the
//!   area-weighted mean of its four integration points', normalised and
//!   turned symmetrically about their bisector to the element's yarn
//!   angle).
//! - γ is the element's shear angle (the VTU's `shear_angle_deg`; a quad's
//!   is the mean of its points'), positive when the angle between the
//!   yarns closes: the yarn angle is 90° − γ, and it is the angle between
//!   the two directions written, for every element.
//! - The thickness is the element's current thickness (the VTU's
//!   `thickness`).
//!
//! In `orientations.inp`:
//!
//! | name | what |
//! |---|---|
//! | `DRAPE_AXES` | `*DISTRIBUTION` (table `COORD3D, COORD3D`): point a = the warp, point b = the weft (origin at 0) |
//! | `DRAPE_YARN_ANGLE` | `*DISTRIBUTION` (table `ANGLE`): 90° − γ, degrees |
//! | `DRAPE_THICKNESS` | `*DISTRIBUTION` (table `LENGTH`): the thickness, mm, for a `*SHELL SECTION` or `*MEMBRANE SECTION` |
//! | `DRAPE_WARP` | `*ORIENTATION` from `DRAPE_AXES`: local 1 along the warp, local 2 in the ply towards the weft, local 3 = warp × weft (the ply's normal) |
//! | `DRAPE_WEFT` | `DRAPE_WARP` turned about local 3 by `DRAPE_YARN_ANGLE`: local 1 along the weft |
//!
//! A woven ply modelled as two unidirectional layers takes `DRAPE_WARP` for
//! one and `DRAPE_WEFT` for the other. Each distribution's first data line
//! (no element label) is its default, as Abaqus requires: the global axes,
//! 90° and the blank's nominal thickness. The file follows the Abaqus 2024
//! keyword reference; it has not been run through Abaqus here.
//!
//! Numbers are written as the shortest text that reads back as the same
//! `f64` (the results module's `fmt_f64`), so re-reading reproduces every value.
//!
//! A laminate (a model with plies) is written as a layup instead: one set
//! of these names per ply, prefixed by the ply's name (the `layup` module).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use drape_model::{ElementFields, Model, State};
use nalgebra::Vector3;

use super::fmt_f64;

mod layup;
pub use layup::PlyPart;

/// Per element of a mesh: the draped fibre orientation, the shear angle
/// and the thickness.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Orientations {
    /// A comment line naming where the numbers come from.
    pub title: String,
    /// The mesh's nodes (mm); empty for orientations mapped onto a mesh of
    /// the user's, which only names its elements.
    pub nodes: Vec<Vector3<f64>>,
    /// The mesh's elements (0-based node indices, 3 or 4); empty with
    /// `nodes`.
    pub elements: Vec<Vec<u32>>,
    /// Element labels.
    pub labels: Vec<i64>,
    /// Element centroids (mm).
    pub centroid: Vec<Vector3<f64>>,
    /// Warp directions (unit).
    pub warp: Vec<Vector3<f64>>,
    /// Weft directions (unit).
    pub weft: Vec<Vector3<f64>>,
    /// Shear angle γ (degrees).
    pub shear_deg: Vec<f64>,
    /// Thickness (mm).
    pub thickness: Vec<f64>,
    /// The default thickness of the distributions (mm): the nominal one.
    pub nominal_thickness: f64,
    /// For mapped orientations: each element's distance to the surface the
    /// values were taken from (mm).
    pub distance: Option<Vec<f64>>,
    /// Elements whose fibre directions could not be computed (index, why):
    /// written without distribution values and listed in the element set
    /// `DRAPE_NO_ORIENTATION` of the include, with empty fields in the
    /// table. Elements with a value that is not finite join them
    /// ([`Self::incomplete`]).
    pub missing: Vec<(usize, String)>,
    /// Lines the include's header carries for its reader (the source
    /// run's state, when it did not complete).
    pub notes: Vec<String>,
    /// A laminate's plies, bottom to top, each a range of the elements
    /// above; empty for one ply (`[fabric]`), whose files are written as
    /// they always were. With plies, `nominal_thickness` is the laminate's.
    pub plies: Vec<PlyPart>,
}

/// The names the include defines.
pub mod names {
    /// The orientation along the warp.
    pub const WARP: &str = "DRAPE_WARP";
    /// The orientation along the weft.
    pub const WEFT: &str = "DRAPE_WEFT";
    /// The distribution of points a (warp) and b (weft).
    pub const AXES: &str = "DRAPE_AXES";
    /// The distribution of the yarn angle 90° − γ.
    pub const YARN_ANGLE: &str = "DRAPE_YARN_ANGLE";
    /// The distribution of the thickness.
    pub const THICKNESS: &str = "DRAPE_THICKNESS";
    /// The element set of the elements without values.
    pub const NO_ORIENTATION: &str = "DRAPE_NO_ORIENTATION";
    /// The element set of every element.
    pub const PLY: &str = "DRAPE_PLY";
}

impl Orientations {
    /// The formed mesh's `*NODE` and `*ELEMENT` blocks (coordinates by
    /// `length`), one element set per kind; returns the sets written.
    fn write_mesh(&self, s: &mut String, length: &dyn Fn(f64) -> String) -> Vec<&'static str> {
        s.push_str("*NODE, NSET=DRAPE_NODES\n");
        for (i, p) in self.nodes.iter().enumerate() {
            let _ = writeln!(
                s,
                "{}, {}, {}, {}",
                i + 1,
                length(p.x),
                length(p.y),
                length(p.z)
            );
        }
        let mut sets = Vec::new();
        for (kind, set, corners) in [("S4R", "DRAPE_QUADS", 4), ("S3", "DRAPE_TRIANGLES", 3)] {
            let of_kind: Vec<usize> = (0..self.elements.len())
                .filter(|&e| self.elements[e].len() == corners)
                .collect();
            if of_kind.is_empty() {
                continue;
            }
            sets.push(set);
            let _ = writeln!(s, "*ELEMENT, TYPE={kind}, ELSET={set}");
            for e in of_kind {
                let _ = write!(s, "{}", self.labels[e]);
                for &n in &self.elements[e] {
                    let _ = write!(s, ", {}", n + 1);
                }
                s.push('\n');
            }
        }
        sets
    }

    /// Element `e`'s row of an axes distribution: its label, then its
    /// warp and weft directions (the layup writes the same rows per ply).
    fn axes_row(&self, s: &mut String, e: usize) {
        let (a, b) = (self.warp[e], self.weft[e]);
        let _ = writeln!(
            s,
            "{}, {}, {}, {}, {}, {}, {}",
            self.labels[e],
            fmt_f64(a.x),
            fmt_f64(a.y),
            fmt_f64(a.z),
            fmt_f64(b.x),
            fmt_f64(b.y),
            fmt_f64(b.z)
        );
    }

    /// The orientations of `model` at `state` from its element `fields`
    /// (the formed mesh: current positions, labels = element index + 1).
    pub fn of_frame(model: &Model, state: &State, fields: &ElementFields, title: &str) -> Self {
        let mut elements = Vec::with_capacity(model.membrane_count());
        for batch in &model.membranes {
            for e in 0..batch.len() {
                elements.push(batch.element_nodes(e).to_vec());
            }
        }
        // A stack of one ply is written as `[fabric]` is (as its VTU
        // frames are): a layup only from two plies on.
        let layup = if model.plies.len() > 1 {
            &model.plies[..]
        } else {
            &[]
        };
        let nominal = if layup.is_empty() {
            model
                .membranes
                .first()
                .map_or(f64::NAN, |b| b.section.material.thickness)
        } else {
            layup.iter().map(|p| p.thickness).sum()
        };
        let plies = layup
            .iter()
            .map(|p| PlyPart {
                name: p.name.clone(),
                elements: p.elements.clone(),
                nominal_thickness: p.thickness,
            })
            .collect();
        Self {
            title: title.to_owned(),
            nodes: state.x.clone(),
            labels: (1..=elements.len() as i64).collect(),
            elements,
            centroid: fields.centroid.clone(),
            warp: fields.fibre_direction.iter().map(|d| d[0]).collect(),
            weft: fields.fibre_direction.iter().map(|d| d[1]).collect(),
            shear_deg: fields.shear.iter().map(|g| g.to_degrees()).collect(),
            thickness: fields.thickness.clone(),
            nominal_thickness: nominal,
            distance: None,
            missing: Vec::new(),
            notes: Vec::new(),
            plies,
        }
    }

    /// The elements written without values (index, why): those in
    /// [`Self::missing`], then those with a direction, shear angle or
    /// thickness that is not finite.
    pub fn incomplete(&self) -> Vec<(usize, String)> {
        let mut out = self.missing.clone();
        for e in 0..self.len() {
            if out.iter().any(|(m, _)| *m == e) {
                continue;
            }
            let values = self.warp[e]
                .iter()
                .chain(self.weft[e].iter())
                .copied()
                .chain([self.shear_deg[e], self.thickness[e]]);
            if crate::finite::first_non_finite(values).is_some() {
                out.push((
                    e,
                    "a direction, shear angle or thickness that is not a finite number".into(),
                ));
            }
        }
        out.sort_by_key(|(e, _)| *e);
        out
    }

    /// Checks what must be finite for the files to mean anything: the
    /// nodes, the centroids, the nominal thickness and the distances.
    /// (Per-element values that are not finite are written as missing,
    /// [`Self::incomplete`].)
    pub fn check_finite(&self) -> Result<(), String> {
        use crate::finite::check;
        check(
            "node coordinates",
            self.nodes.iter().flat_map(|p| p.iter().copied()),
        )?;
        check(
            "element centroids",
            self.centroid.iter().flat_map(|p| p.iter().copied()),
        )?;
        check("the nominal thickness", [self.nominal_thickness])?;
        check("distances", self.distance.iter().flatten().copied())
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// Whether there is no element.
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    /// The text of the Abaqus include (see the module's docs), in mm.
    pub fn to_inp(&self) -> String {
        self.to_inp_in("mm", 1.0)
    }

    /// [`Self::to_inp`] with its lengths (node coordinates, thicknesses) in
    /// the unit `unit` of `millimetres` mm: an include for a model in
    /// metres must give its thickness in metres (Abaqus has no units, the
    /// model's are the include's). Directions and angles are unchanged.
    pub fn to_inp_in(&self, unit: &str, millimetres: f64) -> String {
        if !self.plies.is_empty() {
            return layup::to_inp_in(self, unit, millimetres);
        }
        let length = |v: f64| fmt_f64(v / millimetres);
        let mut s = String::with_capacity(200 * (self.nodes.len() + 3 * self.len()) + 4096);
        let _ = writeln!(s, "** drape: draped fibre orientations, {}", self.title);
        let _ = writeln!(
            s,
            "** Units {unit}. Conventions: docs/scene-reference.md, \"Orientations for structural analysis\"."
        );
        s.push_str(concat!(
            "**   DRAPE_WARP   local 1 = warp, local 2 in the ply towards the weft, local 3 = warp x weft\n",
            "**   DRAPE_WEFT   DRAPE_WARP turned about local 3 by DRAPE_YARN_ANGLE (90 - shear): local 1 = weft\n",
        ));
        let _ = writeln!(s, "**   DRAPE_THICKNESS  the formed thickness ({unit})");
        s.push_str(concat!(
            "** For example:\n",
            "** *SHELL SECTION, ELSET=DRAPE_PLY, MATERIAL=FABRIC, ORIENTATION=DRAPE_WARP\n",
            "** DRAPE_THICKNESS, 5\n",
        ));
        for note in &self.notes {
            let _ = writeln!(s, "** NOTE: {note}");
        }
        let incomplete = self.incomplete();
        let skip: std::collections::BTreeSet<usize> = incomplete.iter().map(|(e, _)| *e).collect();
        if !incomplete.is_empty() {
            let _ = writeln!(
                s,
                "** {} elements have no values (listed in {}): they take the distributions' \
                 defaults (the global axes, 90 degrees, the nominal thickness); give them an \
                 orientation of your own. Why:",
                incomplete.len(),
                names::NO_ORIENTATION
            );
            for (e, why) in &incomplete {
                let _ = writeln!(s, "**   element {}: {why}", self.labels[*e]);
            }
        }
        if !self.nodes.is_empty() {
            let sets = self.write_mesh(&mut s, &length);
            let _ = writeln!(s, "*ELSET, ELSET={}\n{}", names::PLY, sets.join(", "));
        }
        if !incomplete.is_empty() {
            let _ = writeln!(s, "*ELSET, ELSET={}", names::NO_ORIENTATION);
            for chunk in incomplete.chunks(16) {
                let labels: Vec<String> = chunk
                    .iter()
                    .map(|(e, _)| self.labels[*e].to_string())
                    .collect();
                let _ = writeln!(s, "{}", labels.join(", "));
            }
        }
        let _ = writeln!(
            s,
            "*DISTRIBUTION TABLE, NAME={0}_TABLE\nCOORD3D, COORD3D\n\
             *DISTRIBUTION, NAME={0}, LOCATION=ELEMENT, TABLE={0}_TABLE\n, 1, 0, 0, 0, 1, 0",
            names::AXES
        );
        for e in (0..self.len()).filter(|e| !skip.contains(e)) {
            self.axes_row(&mut s, e);
        }
        let _ = writeln!(
            s,
            "*DISTRIBUTION TABLE, NAME={0}_TABLE\nANGLE\n\
             *DISTRIBUTION, NAME={0}, LOCATION=ELEMENT, TABLE={0}_TABLE\n, 90",
            names::YARN_ANGLE
        );
        for e in (0..self.len()).filter(|e| !skip.contains(e)) {
            let _ = writeln!(
                s,
                "{}, {}",
                self.labels[e],
                fmt_f64(90.0 - self.shear_deg[e])
            );
        }
        let _ = writeln!(
            s,
            "*DISTRIBUTION TABLE, NAME={0}_TABLE\nLENGTH\n\
             *DISTRIBUTION, NAME={0}, LOCATION=ELEMENT, TABLE={0}_TABLE\n, {1}",
            names::THICKNESS,
            length(self.nominal_thickness)
        );
        for e in (0..self.len()).filter(|e| !skip.contains(e)) {
            let _ = writeln!(s, "{}, {}", self.labels[e], length(self.thickness[e]));
        }
        let _ = writeln!(
            s,
            "*ORIENTATION, NAME={}, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR\n{}\n3, 0",
            names::WARP,
            names::AXES
        );
        let _ = writeln!(
            s,
            "*ORIENTATION, NAME={}, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR\n{}\n3, {}",
            names::WEFT,
            names::AXES,
            names::YARN_ANGLE
        );
        s
    }

    /// The text of the CSV table: header
    /// `element,x_mm,y_mm,z_mm,warp_x,warp_y,warp_z,weft_x,weft_y,weft_z,shear_deg,yarn_angle_deg,thickness_mm`
    /// (and `,distance_mm` for mapped orientations), one row per element;
    /// x, y, z are the element's centroid. An element of
    /// [`Self::incomplete`] has empty fields for its directions, angles and
    /// thickness (never `NaN`): a value that could not be computed.
    pub fn to_csv(&self) -> String {
        if !self.plies.is_empty() {
            return layup::to_csv(self);
        }
        let skip: std::collections::BTreeSet<usize> =
            self.incomplete().into_iter().map(|(e, _)| e).collect();
        let mut s = String::with_capacity(240 * (self.len() + 1));
        self.csv_header(&mut s);
        for e in 0..self.len() {
            self.csv_row(&mut s, e, &skip);
        }
        s
    }

    /// The CSV's header line of [`Self::to_csv`].
    fn csv_header(&self, s: &mut String) {
        s.push_str(
            "element,x_mm,y_mm,z_mm,warp_x,warp_y,warp_z,weft_x,weft_y,weft_z,shear_deg,\
             yarn_angle_deg,thickness_mm",
        );
        if self.distance.is_some() {
            s.push_str(",distance_mm");
        }
        s.push('\n');
    }

    /// Element `e`'s line of [`Self::to_csv`] (its values withheld when it
    /// is in `skip`, the incomplete ones).
    fn csv_row(&self, s: &mut String, e: usize, skip: &std::collections::BTreeSet<usize>) {
        let _ = write!(s, "{}", self.labels[e]);
        let c = self
            .centroid
            .get(e)
            .copied()
            .unwrap_or(Vector3::repeat(f64::NAN));
        for (k, v) in [
            c.x,
            c.y,
            c.z,
            self.warp[e].x,
            self.warp[e].y,
            self.warp[e].z,
            self.weft[e].x,
            self.weft[e].y,
            self.weft[e].z,
            self.shear_deg[e],
            90.0 - self.shear_deg[e],
            self.thickness[e],
        ]
        .into_iter()
        .chain(self.distance.as_ref().map(|d| d[e]))
        .enumerate()
        {
            s.push(',');
            // The centroid (0..3) and the distance are always written;
            // an incomplete element's values are not.
            let withheld = (3..12).contains(&k) && skip.contains(&e);
            if !withheld {
                s.push_str(&crate::finite::or_empty(v, fmt_f64));
            }
        }
        s.push('\n');
    }

    /// Reads an include written by [`Self::to_inp`] (drape's own format:
    /// `*NODE`, `*ELEMENT` and the `DRAPE_*` distributions, or a layup's
    /// per-ply ones when its header names plies; other keywords are
    /// skipped). `path` names the file in errors.
    pub fn parse_inp(text: &str, path: &Path) -> Result<Self, String> {
        let err = |line: usize, what: &str| format!("{}:{line}: {what}", path.display());
        let mut out = Self::default();
        let mut node_index: BTreeMap<i64, u32> = BTreeMap::new();
        let mut elements: Vec<(i64, Vec<i64>)> = Vec::new();
        // Distribution name → (label → values).
        let mut distributions: BTreeMap<String, BTreeMap<i64, Vec<f64>>> = BTreeMap::new();
        let mut defaults: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        enum Block {
            None,
            Node,
            Element,
            Distribution(String),
        }
        let mut block = Block::None;
        let mut ply_names: Vec<String> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let line = raw.trim();
            if line.is_empty() || line.starts_with("**") {
                if let Some(title) = line.strip_prefix("** drape: draped fibre orientations, ") {
                    title.clone_into(&mut out.title);
                }
                if let Some(list) = line.strip_prefix(layup::PLIES_LINE) {
                    ply_names = list.split(',').map(|n| n.trim().to_owned()).collect();
                }
                continue;
            }
            if let Some(keyword) = line.strip_prefix('*') {
                let upper = keyword.to_ascii_uppercase();
                let mut parts = upper.split(',').map(str::trim);
                let name = parts.next().unwrap_or("");
                block = match name {
                    "NODE" => Block::Node,
                    "ELEMENT" => Block::Element,
                    "DISTRIBUTION" => {
                        let name = parts
                            .find_map(|p| p.strip_prefix("NAME="))
                            .ok_or_else(|| err(line_no, "a *DISTRIBUTION without NAME="))?;
                        Block::Distribution(name.trim().trim_matches('"').to_owned())
                    }
                    _ => Block::None,
                };
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let numbers = |from: usize| -> Result<Vec<f64>, String> {
                fields[from..]
                    .iter()
                    .map(|f| {
                        f.parse::<f64>()
                            .map_err(|_| err(line_no, &format!("`{f}` is not a number")))
                    })
                    .collect()
            };
            let label = || -> Result<i64, String> {
                fields[0]
                    .parse::<i64>()
                    .map_err(|_| err(line_no, &format!("`{}` is not a label", fields[0])))
            };
            match &block {
                Block::None => {}
                Block::Node => {
                    let v = numbers(1)?;
                    if v.len() != 3 {
                        return Err(err(line_no, "a node needs x, y and z"));
                    }
                    node_index.insert(label()?, out.nodes.len() as u32);
                    out.nodes.push(Vector3::new(v[0], v[1], v[2]));
                }
                Block::Element => {
                    let nodes = fields[1..]
                        .iter()
                        .map(|f| f.parse::<i64>().map_err(|_| err(line_no, "a node label")))
                        .collect::<Result<Vec<_>, _>>()?;
                    if !(3..=4).contains(&nodes.len()) {
                        return Err(err(line_no, "an element needs 3 or 4 nodes"));
                    }
                    elements.push((label()?, nodes));
                }
                Block::Distribution(name) => {
                    if fields[0].is_empty() {
                        defaults.insert(name.clone(), numbers(1)?);
                    } else {
                        distributions
                            .entry(name.clone())
                            .or_default()
                            .insert(label()?, numbers(1)?);
                    }
                }
            }
        }
        let table = |name: &str, width: usize| -> Result<&BTreeMap<i64, Vec<f64>>, String> {
            let t = distributions
                .get(name)
                .ok_or_else(|| format!("{}: no *DISTRIBUTION {name}", path.display()))?;
            if let Some((label, v)) = t.iter().find(|(_, v)| v.len() != width) {
                return Err(format!(
                    "{}: {name}: element {label} has {} values, expected {width}",
                    path.display(),
                    v.len()
                ));
            }
            Ok(t)
        };
        let by_label: BTreeMap<i64, &Vec<i64>> = elements.iter().map(|(l, n)| (*l, n)).collect();
        // One ply's distributions are named DRAPE_*; a layup's, after each
        // ply (Abaqus names are case-blind: the keys were upper-cased).
        let prefixes: Vec<String> = if ply_names.is_empty() {
            vec!["DRAPE".into()]
        } else {
            ply_names.iter().map(|n| n.to_ascii_uppercase()).collect()
        };
        for (p, prefix) in prefixes.iter().enumerate() {
            let axes = table(&format!("{prefix}_AXES"), 6)?;
            let angle_name = format!("{prefix}_YARN_ANGLE");
            let angle = table(&angle_name, 1)?;
            let thickness_name = format!("{prefix}_THICKNESS");
            let thickness = table(&thickness_name, 1)?;
            let nominal = defaults
                .get(&thickness_name)
                .and_then(|v| v.first().copied())
                .unwrap_or(f64::NAN);
            let first = out.labels.len();
            for (&label, v) in axes {
                let missing =
                    |what: &str| format!("{}: element {label} has no {what}", path.display());
                out.labels.push(label);
                out.warp.push(Vector3::new(v[0], v[1], v[2]));
                out.weft.push(Vector3::new(v[3], v[4], v[5]));
                out.shear_deg
                    .push(90.0 - angle.get(&label).ok_or_else(|| missing(&angle_name))?[0]);
                out.thickness.push(
                    thickness
                        .get(&label)
                        .ok_or_else(|| missing(&thickness_name))?[0],
                );
                if !out.nodes.is_empty() {
                    let nodes = by_label
                        .get(&label)
                        .ok_or_else(|| missing("*ELEMENT line"))?
                        .iter()
                        .map(|n| {
                            node_index.get(n).copied().ok_or_else(|| {
                                format!("{}: element {label}: no node {n}", path.display())
                            })
                        })
                        .collect::<Result<Vec<u32>, String>>()?;
                    let c = nodes
                        .iter()
                        .map(|&n| out.nodes[n as usize])
                        .sum::<Vector3<f64>>()
                        / nodes.len() as f64;
                    out.centroid.push(c);
                    out.elements.push(nodes);
                }
            }
            if ply_names.is_empty() {
                out.nominal_thickness = nominal;
            } else {
                out.plies.push(PlyPart {
                    name: ply_names[p].clone(),
                    elements: first..out.labels.len(),
                    nominal_thickness: nominal,
                });
            }
        }
        if !out.plies.is_empty() {
            out.nominal_thickness = out.plies.iter().map(|p| p.nominal_thickness).sum();
        }
        Ok(out)
    }

    /// Reads `path` ([`Self::parse_inp`]).
    pub fn read_inp(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Self::parse_inp(&text, path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three flat triangles: the first whole, the second without a
    /// direction (edge-on), the third with a thickness that is not finite.
    fn three() -> Orientations {
        let x = Vector3::x();
        let y = Vector3::y();
        Orientations {
            title: "three".into(),
            nodes: vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.0, 1.0, 0.0),
                Vector3::new(1.0, 1.0, 0.0),
            ],
            elements: vec![vec![0, 1, 2], vec![1, 3, 2], vec![0, 1, 3]],
            labels: vec![1, 2, 3],
            centroid: vec![Vector3::repeat(0.3); 3],
            warp: vec![x, Vector3::repeat(f64::NAN), x],
            weft: vec![y, y, y],
            shear_deg: vec![0.0, 1.0, 2.0],
            thickness: vec![0.5, 0.5, f64::INFINITY],
            nominal_thickness: 0.5,
            distance: None,
            missing: vec![(1, "edge-on".into())],
            notes: vec!["the source run stopped".into()],
            plies: Vec::new(),
        }
    }

    #[test]
    fn values_that_cannot_be_written_are_listed_as_missing_never_as_nan() {
        let o = three();
        assert_eq!(
            o.incomplete().iter().map(|(e, _)| *e).collect::<Vec<_>>(),
            [1, 2]
        );
        assert!(o.check_finite().is_ok());
        let inp = o.to_inp();
        let csv = o.to_csv();
        for text in [&inp, &csv] {
            let lower = text.to_ascii_lowercase();
            assert!(!lower.contains("nan") && !lower.contains("inf"), "{text}");
        }
        assert!(inp.contains("** NOTE: the source run stopped\n"), "{inp}");
        assert!(
            inp.contains("*ELSET, ELSET=DRAPE_NO_ORIENTATION\n2, 3\n"),
            "{inp}"
        );
        assert!(inp.contains("**   element 2: edge-on\n"), "{inp}");
        // Read back: only the whole element has values.
        let back = Orientations::parse_inp(&inp, Path::new("three.inp")).unwrap();
        assert_eq!(back.labels, [1]);
        assert_eq!(back.thickness, [0.5]);
        // The table: the centroid always, the values only where whole.
        let rows: Vec<&str> = csv.lines().skip(1).collect();
        assert_eq!(rows[0], "1,0.3,0.3,0.3,1,0,0,0,1,0,0,90,0.5");
        assert_eq!(rows[1], "2,0.3,0.3,0.3,,,,,,,,,");
        assert_eq!(rows[2], "3,0.3,0.3,0.3,,,,,,,,,");
    }

    #[test]
    fn a_node_or_a_nominal_thickness_that_is_not_finite_is_an_error() {
        let mut o = three();
        o.nodes[3].z = f64::NAN;
        let e = o.check_finite().unwrap_err();
        assert!(e.contains("node coordinates: value 12 is NaN"), "{e}");
        let mut o = three();
        o.nominal_thickness = f64::NAN;
        assert!(o.check_finite().unwrap_err().contains("nominal thickness"));
    }

    /// A quad and a triangle with values that need every digit; written
    /// in metres, as `drape export --units m` does.
    fn golden() -> Orientations {
        Orientations {
            title: "golden".into(),
            nodes: vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.5, 0.0, 0.1),
                Vector3::new(0.0, 1.25, 0.0),
                Vector3::new(1.5, 1.25, -0.2),
                Vector3::new(3.0, 0.0, 0.0),
            ],
            elements: vec![vec![0, 1, 3, 2], vec![1, 4, 3]],
            labels: vec![1, 2],
            centroid: vec![
                Vector3::new(0.75, 0.625, -0.025),
                Vector3::new(2.0, 0.4166666666666667, -0.03333333333333333),
            ],
            warp: vec![Vector3::new(0.6, 0.8, 0.0), Vector3::new(1.0, 0.0, 0.0)],
            weft: vec![Vector3::new(-0.6, 0.8, 0.0), Vector3::new(0.0, 1.0, 0.0)],
            shear_deg: vec![16.26020470831196, -0.1],
            thickness: vec![0.31, 0.2999999999999999],
            nominal_thickness: 0.3,
            ..Orientations::default()
        }
    }

    /// The files of one ply (no plies: `[fabric]`) are, byte for byte,
    /// what drape wrote before laminates existed: the expected texts were
    /// written by that version (commit 5f63977) from these numbers.
    #[test]
    fn one_ply_files_are_byte_identical_to_those_before_laminates() {
        let o = golden();
        let data = |name: &str| {
            std::fs::read_to_string(
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("tests/data/orientations")
                    .join(name),
            )
            .unwrap()
        };
        assert_eq!(o.to_inp_in("m", 1000.0), data("one_ply_m.inp"));
        assert_eq!(o.to_csv(), data("one_ply.csv"));
        let mut m = o;
        m.nodes.clear();
        m.elements.clear();
        m.distance = Some(vec![0.0, 0.125]);
        m.missing = vec![(1, "edge-on".into())];
        m.notes = vec!["stopped".into()];
        assert_eq!(m.to_inp(), data("one_ply_mapped.inp"));
        assert_eq!(m.to_csv(), data("one_ply_mapped.csv"));
    }

    /// `golden` as ply `name`, turned by `deg` about z and raised by `dz`
    /// (its labels from `first`).
    fn ply_of(deg: f64, dz: f64, first: i64) -> Orientations {
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), deg.to_radians());
        let mut o = golden();
        o.nodes.iter_mut().for_each(|x| x.z += dz);
        o.centroid.iter_mut().for_each(|x| x.z += dz);
        o.warp.iter_mut().for_each(|d| *d = r * *d);
        o.weft.iter_mut().for_each(|d| *d = r * *d);
        o.labels.iter_mut().for_each(|l| *l += first - 1);
        o
    }

    /// Two plies (the second with a name Abaqus must read quoted) written
    /// as a layup and read back: each ply's elements, directions, angles
    /// and nominal thickness as that ply's, under its own names; the
    /// table has a `ply` column.
    #[test]
    fn a_layup_reads_back_ply_by_ply_under_the_plies_names() {
        let mut top = ply_of(45.0, 0.3, 3);
        top.nominal_thickness = 0.25;
        top.missing = vec![(1, "edge-on".into())];
        let o = Orientations::layup(vec![
            ("p0".into(), ply_of(0.0, 0.0, 1)),
            ("+45".into(), top),
        ]);
        assert_eq!(o.plies[1].elements, 2..4);
        assert_eq!(o.elements[2], [5, 6, 8, 7]);
        assert!((o.nominal_thickness - 0.55).abs() < 1e-15);
        let inp = o.to_inp();
        for line in [
            "** plies, bottom to top: p0, +45\n",
            "*ELSET, ELSET=p0\n1, 2\n",
            "*ELSET, ELSET=\"+45\"\n3, 4\n",
            "*ELSET, ELSET=\"+45_NO_ORIENTATION\"\n4\n",
            "*DISTRIBUTION, NAME=p0_AXES, LOCATION=ELEMENT, TABLE=p0_AXES_TABLE\n",
            "*ORIENTATION, NAME=\"+45_WEFT\", DEFINITION=COORDINATES, SYSTEM=RECTANGULAR\n\"+45_AXES\"\n3, \"+45_YARN_ANGLE\"\n",
            "*DISTRIBUTION, NAME=\"+45_THICKNESS\", LOCATION=ELEMENT, TABLE=\"+45_THICKNESS_TABLE\"\n, 0.25\n",
            "**   ply +45, element 4: edge-on\n",
        ] {
            assert!(inp.contains(line), "{line}\n{inp}");
        }
        assert!(
            !inp.contains("DRAPE_AXES") && !inp.contains("DRAPE_PLY"),
            "{inp}"
        );
        let back = Orientations::parse_inp(&inp, Path::new("layup.inp")).unwrap();
        let names: Vec<&str> = back.plies.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["p0", "+45"]);
        assert_eq!(back.plies[0].elements, 0..2);
        // Element 4 has no values: only element 3 of the top ply.
        assert_eq!(back.plies[1].elements, 2..3);
        assert_eq!(back.labels, [1, 2, 3]);
        assert_eq!(back.plies[1].nominal_thickness, 0.25);
        for (e, want) in [(0, &o.warp[0]), (1, &o.warp[1]), (2, &o.warp[2])] {
            assert_eq!(&back.warp[e], want, "element {e}");
        }
        assert_eq!(back.weft[2], o.weft[2]);
        // γ goes through the yarn angle 90° − γ: exact to its last bits.
        for e in 0..3 {
            assert!(
                (back.shear_deg[e] - o.shear_deg[e]).abs() < 1e-12,
                "element {e}"
            );
        }
        assert_eq!(back.elements[2], o.elements[2]);
        let csv = o.to_csv();
        let rows: Vec<&str> = csv.lines().collect();
        assert!(rows[0].starts_with("ply,element,x_mm,"), "{csv}");
        assert!(rows[3].starts_with("+45,3,"), "{csv}");
        assert_eq!(
            rows[4],
            "+45,4,2,0.4166666666666667,0.26666666666666666,,,,,,,,,"
        );
    }

    /// A ply's orientations taken out of a layup are the ply's own.
    #[test]
    fn a_ply_taken_from_a_layup_is_that_ply() {
        let top = ply_of(-45.0, 0.3, 3);
        let o = Orientations::layup(vec![
            ("a".into(), ply_of(0.0, 0.0, 1)),
            ("b".into(), top.clone()),
        ]);
        let b = o.ply(&o.plies[1]);
        assert_eq!(b.labels, top.labels);
        assert_eq!(b.warp, top.warp);
        assert_eq!(b.shear_deg, top.shear_deg);
        assert!(b.plies.is_empty());
        // Its elements name the layup's nodes (the second ply's).
        assert_eq!(b.nodes[b.elements[0][0] as usize], top.nodes[0]);
    }
}
