//! The orientations of a laminate: an Abaqus layup with one set of names
//! per ply, and a table with a `ply` column.
//!
//! For a ply named `P`, the include defines what one ply's defines with
//! `DRAPE` replaced by `P`: the distributions `P_AXES`, `P_YARN_ANGLE` and
//! `P_THICKNESS` (its default the ply's nominal thickness), the
//! orientations `P_WARP` and `P_WEFT`, and `P_NO_ORIENTATION` for its
//! elements without values. The formed mesh's elements of each ply are the
//! element set `P`. A name that is not a plain Abaqus label (a letter, then
//! letters, digits or `_`) is written in double quotes, as Abaqus reads
//! such names. The header line [`PLIES_LINE`] lists the plies bottom to
//! top, and is what marks a layup when the file is read back.
//!
//! Orientations mapped onto a mesh of the user's (`drape export --onto`)
//! are a layup too: each ply is mapped on its own onto the same target
//! elements (a structural mesh is one surface, usually the laminate's
//! mould side or mid-surface), so every ply has a distribution over every
//! target element, and the mesh's element set is the user's own: a
//! composite shell section takes one layer per ply with its `P_WARP`.
//!
//! What this is not: the one-ply format (the parent module; a `[fabric]`
//! run's files do not change).

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::ops::Range;

use super::{Orientations, fmt_f64};

/// The header line that lists a layup's plies (bottom to top, `, `
/// between names: a ply's name holds no comma or space).
pub(super) const PLIES_LINE: &str = "** plies, bottom to top: ";

/// One ply of a laminate in [`Orientations`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlyPart {
    /// Its name (the scene's `[[stack.ply]] name`).
    pub name: String,
    /// Its elements: indices into the orientations' per-element vectors.
    pub elements: Range<usize>,
    /// Its nominal thickness (mm): its thickness distribution's default.
    pub nominal_thickness: f64,
}

/// `name` as Abaqus reads it: as it is when a plain label, else quoted.
pub fn abaqus_name(name: &str) -> String {
    let mut chars = name.chars();
    let plain = chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if plain {
        name.to_owned()
    } else {
        format!("\"{name}\"")
    }
}

impl PlyPart {
    /// The Abaqus name of this ply's `what` (`AXES`, `WARP`...).
    pub fn name_of(&self, what: &str) -> String {
        abaqus_name(&format!("{}_{what}", self.name))
    }
}

impl Orientations {
    /// The orientations of ply `part` alone: its elements (the mesh's
    /// nodes all kept), with the ply's nominal thickness; no plies.
    pub fn ply(&self, part: &PlyPart) -> Orientations {
        let r = part.elements.clone();
        Orientations {
            title: self.title.clone(),
            nodes: self.nodes.clone(),
            elements: self.elements.get(r.clone()).unwrap_or_default().to_vec(),
            labels: self.labels[r.clone()].to_vec(),
            centroid: self.centroid.get(r.clone()).unwrap_or_default().to_vec(),
            warp: self.warp[r.clone()].to_vec(),
            weft: self.weft[r.clone()].to_vec(),
            shear_deg: self.shear_deg[r.clone()].to_vec(),
            thickness: self.thickness[r.clone()].to_vec(),
            nominal_thickness: part.nominal_thickness,
            distance: self.distance.as_ref().map(|d| d[r.clone()].to_vec()),
            missing: self
                .missing
                .iter()
                .filter(|(e, _)| r.contains(e))
                .map(|(e, why)| (e - r.start, why.clone()))
                .collect(),
            notes: self.notes.clone(),
            plies: Vec::new(),
        }
    }

    /// The layup of `plies` (name, that ply's orientations, bottom to top),
    /// one after the other (their meshes too, if any); the title and notes
    /// are the first ply's.
    pub fn layup(plies: Vec<(String, Orientations)>) -> Orientations {
        let mut out = Orientations::default();
        for (p, (name, o)) in plies.into_iter().enumerate() {
            let first = out.labels.len();
            if p == 0 {
                out.title = o.title;
                out.notes = o.notes;
                out.distance = o.distance.as_ref().map(|_| Vec::new());
            }
            let shift = out.nodes.len() as u32;
            out.nodes.extend(o.nodes);
            out.elements.extend(
                o.elements
                    .into_iter()
                    .map(|e| e.into_iter().map(|n| n + shift).collect::<Vec<u32>>()),
            );
            out.labels.extend(o.labels);
            out.centroid.extend(o.centroid);
            out.warp.extend(o.warp);
            out.weft.extend(o.weft);
            out.shear_deg.extend(o.shear_deg);
            out.thickness.extend(o.thickness);
            if let (Some(all), Some(d)) = (&mut out.distance, o.distance) {
                all.extend(d);
            }
            out.missing
                .extend(o.missing.into_iter().map(|(e, why)| (e + first, why)));
            out.plies.push(PlyPart {
                name,
                elements: first..out.labels.len(),
                nominal_thickness: o.nominal_thickness,
            });
        }
        out.nominal_thickness = out.plies.iter().map(|p| p.nominal_thickness).sum();
        out
    }
}

/// The element labels of `elements` (indices), 16 a line.
fn label_lines(s: &mut String, o: &Orientations, elements: impl Iterator<Item = usize>) {
    let labels: Vec<String> = elements.map(|e| o.labels[e].to_string()).collect();
    for chunk in labels.chunks(16) {
        let _ = writeln!(s, "{}", chunk.join(", "));
    }
}

/// The Abaqus include of a layup (see the module's docs), lengths in
/// `unit` of `millimetres` mm.
pub(super) fn to_inp_in(o: &Orientations, unit: &str, millimetres: f64) -> String {
    let length = |v: f64| fmt_f64(v / millimetres);
    let mut s = String::with_capacity(200 * (o.nodes.len() + 3 * o.len()) + 4096);
    let _ = writeln!(s, "** drape: draped fibre orientations, {}", o.title);
    let names: Vec<&str> = o.plies.iter().map(|p| p.name.as_str()).collect();
    let _ = writeln!(s, "{PLIES_LINE}{}", names.join(", "));
    let _ = writeln!(
        s,
        "** Units {unit}. Conventions: docs/scene-reference.md, \"Exporting the fibre orientations\"."
    );
    s.push_str(concat!(
        "** For each ply P:\n",
        "**   P_WARP   local 1 = warp, local 2 in the ply towards the weft, local 3 = warp x weft\n",
        "**   P_WEFT   P_WARP turned about local 3 by P_YARN_ANGLE (90 - shear): local 1 = weft\n",
    ));
    let _ = writeln!(s, "**   P_THICKNESS  the formed thickness ({unit})");
    if o.nodes.is_empty() {
        s.push_str(
            "** Every ply was mapped on its own onto the same elements (one surface): one \
             distribution per ply over all of them. For example, a composite shell with one \
             layer per ply from the bottom:\n** *SHELL SECTION, ELSET=<your set>, COMPOSITE\n",
        );
        for p in &o.plies {
            let _ = writeln!(
                s,
                "** {}, 3, FABRIC, {}, {}",
                length(p.nominal_thickness),
                p.name_of("WARP"),
                abaqus_name(&p.name)
            );
        }
    } else {
        s.push_str("** Each ply's elements are the element set of its name. For example:\n");
        for p in &o.plies {
            let _ = writeln!(
                s,
                "** *SHELL SECTION, ELSET={}, MATERIAL=FABRIC, ORIENTATION={}\n** {}, 5",
                abaqus_name(&p.name),
                p.name_of("WARP"),
                p.name_of("THICKNESS")
            );
        }
    }
    for note in &o.notes {
        let _ = writeln!(s, "** NOTE: {note}");
    }
    let incomplete = o.incomplete();
    let skip: BTreeSet<usize> = incomplete.iter().map(|(e, _)| *e).collect();
    if !incomplete.is_empty() {
        let _ = writeln!(
            s,
            "** {} elements have no values (listed in each ply's P_NO_ORIENTATION): they take \
             the distributions' defaults (the global axes, 90 degrees, the ply's nominal \
             thickness); give them an orientation of your own. Why:",
            incomplete.len()
        );
        for (e, why) in &incomplete {
            let ply = o.plies.iter().find(|p| p.elements.contains(e));
            let _ = writeln!(
                s,
                "**   ply {}, element {}: {why}",
                ply.map_or("?", |p| p.name.as_str()),
                o.labels[*e]
            );
        }
    }
    if !o.nodes.is_empty() {
        o.write_mesh(&mut s, &length);
        for p in &o.plies {
            let _ = writeln!(s, "*ELSET, ELSET={}", abaqus_name(&p.name));
            label_lines(&mut s, o, p.elements.clone());
        }
    }
    for p in &o.plies {
        let lacking: Vec<usize> = p.elements.clone().filter(|e| skip.contains(e)).collect();
        if !lacking.is_empty() {
            let _ = writeln!(s, "*ELSET, ELSET={}", p.name_of("NO_ORIENTATION"));
            label_lines(&mut s, o, lacking.into_iter());
        }
        let whole = || p.elements.clone().filter(|e| !skip.contains(e));
        let axes = p.name_of("AXES");
        let _ = writeln!(
            s,
            "*DISTRIBUTION TABLE, NAME={0}\nCOORD3D, COORD3D\n\
             *DISTRIBUTION, NAME={1}, LOCATION=ELEMENT, TABLE={0}\n, 1, 0, 0, 0, 1, 0",
            p.name_of("AXES_TABLE"),
            axes
        );
        for e in whole() {
            o.axes_row(&mut s, e);
        }
        let angle = p.name_of("YARN_ANGLE");
        let _ = writeln!(
            s,
            "*DISTRIBUTION TABLE, NAME={0}\nANGLE\n\
             *DISTRIBUTION, NAME={1}, LOCATION=ELEMENT, TABLE={0}\n, 90",
            p.name_of("YARN_ANGLE_TABLE"),
            angle
        );
        for e in whole() {
            let _ = writeln!(s, "{}, {}", o.labels[e], fmt_f64(90.0 - o.shear_deg[e]));
        }
        let _ = writeln!(
            s,
            "*DISTRIBUTION TABLE, NAME={0}\nLENGTH\n\
             *DISTRIBUTION, NAME={1}, LOCATION=ELEMENT, TABLE={0}\n, {2}",
            p.name_of("THICKNESS_TABLE"),
            p.name_of("THICKNESS"),
            length(p.nominal_thickness)
        );
        for e in whole() {
            let _ = writeln!(s, "{}, {}", o.labels[e], length(o.thickness[e]));
        }
        let _ = writeln!(
            s,
            "*ORIENTATION, NAME={}, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR\n{axes}\n3, 0",
            p.name_of("WARP"),
        );
        let _ = writeln!(
            s,
            "*ORIENTATION, NAME={}, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR\n{axes}\n3, {angle}",
            p.name_of("WEFT"),
        );
    }
    s
}

/// The CSV table of a layup: the one-ply table with a first column `ply`
/// (the ply's name), the plies one after the other, bottom to top.
pub(super) fn to_csv(o: &Orientations) -> String {
    let skip: BTreeSet<usize> = o.incomplete().into_iter().map(|(e, _)| e).collect();
    let mut s = String::with_capacity(250 * (o.len() + 1));
    s.push_str("ply,");
    o.csv_header(&mut s);
    for p in &o.plies {
        for e in p.elements.clone() {
            let _ = write!(s, "{},", p.name);
            o.csv_row(&mut s, e, &skip);
        }
    }
    s
}
