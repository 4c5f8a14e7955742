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

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use drape_model::{ElementFields, Model, State};
use nalgebra::Vector3;

use super::fmt_f64;

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
    /// The orientations of `model` at `state` from its element `fields`
    /// (the formed mesh: current positions, labels = element index + 1).
    pub fn of_frame(model: &Model, state: &State, fields: &ElementFields, title: &str) -> Self {
        let mut elements = Vec::with_capacity(model.membrane_count());
        for batch in &model.membranes {
            for e in 0..batch.len() {
                elements.push(batch.element_nodes(e).to_vec());
            }
        }
        let nominal = model
            .membranes
            .first()
            .map_or(f64::NAN, |b| b.section.material.thickness);
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
        let skip: std::collections::BTreeSet<usize> =
            self.incomplete().into_iter().map(|(e, _)| e).collect();
        let mut s = String::with_capacity(240 * (self.len() + 1));
        s.push_str(
            "element,x_mm,y_mm,z_mm,warp_x,warp_y,warp_z,weft_x,weft_y,weft_z,shear_deg,\
             yarn_angle_deg,thickness_mm",
        );
        if self.distance.is_some() {
            s.push_str(",distance_mm");
        }
        s.push('\n');
        for e in 0..self.len() {
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
        s
    }

    /// Reads an include written by [`Self::to_inp`] (drape's own format:
    /// `*NODE`, `*ELEMENT` and the `DRAPE_*` distributions; other keywords
    /// are skipped). `path` names the file in errors.
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
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let line = raw.trim();
            if line.is_empty() || line.starts_with("**") {
                if let Some(title) = line.strip_prefix("** drape: draped fibre orientations, ") {
                    title.clone_into(&mut out.title);
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
                        Block::Distribution(name.trim().to_owned())
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
        let axes = table(names::AXES, 6)?;
        let angle = table(names::YARN_ANGLE, 1)?;
        let thickness = table(names::THICKNESS, 1)?;
        out.nominal_thickness = defaults
            .get(names::THICKNESS)
            .and_then(|v| v.first().copied())
            .unwrap_or(f64::NAN);
        let by_label: BTreeMap<i64, &Vec<i64>> = elements.iter().map(|(l, n)| (*l, n)).collect();
        for (&label, v) in axes {
            let missing = |what: &str| format!("{}: element {label} has no {what}", path.display());
            out.labels.push(label);
            out.warp.push(Vector3::new(v[0], v[1], v[2]));
            out.weft.push(Vector3::new(v[3], v[4], v[5]));
            out.shear_deg.push(
                90.0 - angle
                    .get(&label)
                    .ok_or_else(|| missing(names::YARN_ANGLE))?[0],
            );
            out.thickness.push(
                thickness
                    .get(&label)
                    .ok_or_else(|| missing(names::THICKNESS))?[0],
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
}
