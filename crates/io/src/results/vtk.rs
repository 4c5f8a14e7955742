//! VTK XML files written by hand: one `UnstructuredGrid` (`.vtu`) per
//! frame and the `Collection` (`.pvd`) that lists the frames with their
//! times.
//!
//! # Encoding
//!
//! Data arrays are inline `format="binary"`: the raw little-endian bytes of
//! the array, preceded by a `UInt64` byte count (`header_type="UInt64"`),
//! base64-encoded as one stream. That is what VTK and meshio write for
//! uncompressed inline data, and it was chosen over `ascii` because it keeps
//! every `f64` bit for bit (restart-grade positions, exact comparisons in
//! tests) at about half the size of shortest round-trip decimal text and
//! with no float formatting in the loop. It was chosen over the `appended`
//! raw encoding because the file stays valid XML (a raw appended block is
//! not), so any XML tool can read the structure. No zlib compression: it
//! would need a compressor dependency and block bookkeeping for a gain
//! that matters only for very large meshes.
//!
//! The grid's `FieldData` holds `TimeValue` (in ascii, one number a person
//! can read), the array name ParaView uses for the time of a single file.
//!
//! Why not vtkio: 0.6.3 is from 2021, 0.7 is a release candidate, and it
//! has no `.pvd`; the format here is small enough to own.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use drape_elements::MembraneShape;

use super::{FrameData, fmt_f64};

/// VTK cell type of a linear triangle.
const VTK_TRIANGLE: u8 = 5;
/// VTK cell type of a bilinear quad (nodes counter-clockwise).
const VTK_QUAD: u8 = 9;

/// A frame whose arrays do not fit its model.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct SizeMismatch {
    /// Which array.
    pub what: &'static str,
    /// Its length.
    pub len: usize,
    /// The length the model needs.
    pub expected: usize,
}

impl std::fmt::Display for SizeMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} has {} entries, the model needs {}",
            self.what, self.len, self.expected
        )
    }
}

/// Checks that every array of `frame` has the model's node or element count,
/// so that a writer never indexes out of bounds on a caller's mistake.
fn check_sizes(frame: &FrameData<'_>) -> Result<(), SizeMismatch> {
    let nodes = frame.model.node_count();
    let cells = frame.model.membrane_count();
    let f = frame.fields;
    let checks = [
        ("state.x", frame.state.x.len(), nodes),
        ("state.v", frame.state.v.len(), nodes),
        (
            "contact_force",
            frame.contact_force.map_or(nodes, <[_]>::len),
            nodes,
        ),
        (
            "contact_status",
            frame.contact_status.map_or(nodes, <[_]>::len),
            nodes,
        ),
        ("fields.shear", f.shear.len(), cells),
        ("fields.fibre_stretch", f.fibre_stretch.len(), cells),
        ("fields.fibre_direction", f.fibre_direction.len(), cells),
        ("fields.fibre_tension", f.fibre_tension.len(), cells),
        ("fields.resin_stress", f.resin_stress.len(), cells),
        ("fields.thickness", f.thickness.len(), cells),
        ("fields.waviness", f.waviness.len(), cells),
    ];
    for (what, len, expected) in checks {
        if len != expected {
            return Err(SizeMismatch {
                what,
                len,
                expected,
            });
        }
    }
    Ok(())
}

/// The `.vtu` text of one frame at `time`.
///
/// Points are the current positions; cells are the membrane elements in
/// batch order, so that cell `i` is entry `i` of [`drape_model::ElementFields`].
pub(super) fn frame_vtu(time: f64, frame: &FrameData<'_>) -> Result<String, SizeMismatch> {
    check_sizes(frame)?;
    let model = frame.model;
    let state = frame.state;
    let fields = frame.fields;
    let n_points = model.node_count();
    let n_cells = model.membrane_count();

    let mut connectivity = Vec::with_capacity(4 * n_cells);
    let mut offsets = Vec::with_capacity(n_cells);
    let mut types = Vec::with_capacity(n_cells);
    for batch in &model.membranes {
        let kind = match batch.shape() {
            MembraneShape::Triangle => VTK_TRIANGLE,
            MembraneShape::Quad => VTK_QUAD,
        };
        for e in 0..batch.len() {
            connectivity.extend(batch.element_nodes(e).iter().map(|&n| i64::from(n)));
            offsets.push(connectivity.len() as i64);
            types.push(kind);
        }
    }

    // About 4/3 of the binary size (some 120 bytes a point and a cell)
    // plus the markup.
    let mut xml = String::with_capacity(170 * (n_points + n_cells) + 4096);
    vtu_head(&mut xml, time, n_points, n_cells);

    xml.push_str("      <PointData Vectors=\"displacement\" Scalars=\"contact_status\">\n");
    let displacement = state.x.iter().zip(&model.x0).map(|(x, x0)| x - x0);
    vectors(&mut xml, "displacement", displacement);
    vectors(&mut xml, "velocity", state.v.iter().copied());
    match frame.contact_force {
        Some(force) => vectors(&mut xml, "contact_force", force.iter().copied()),
        None => vectors(
            &mut xml,
            "contact_force",
            std::iter::repeat_n(nalgebra::Vector3::zeros(), n_points),
        ),
    }
    let status: Vec<u8> = match frame.contact_status {
        Some(status) => status.iter().map(|&s| s as u8).collect(),
        None => vec![0; n_points],
    };
    data_array(
        &mut xml,
        "UInt8",
        "contact_status",
        ONE,
        &status,
        |b, &s| b.push(s),
    );
    if model.plies.len() > 1 {
        // A laminate's inter-ply slip and pressure (only then, so a
        // one-ply frame keeps its bytes).
        let zeros = vec![0.0; n_points];
        let (slip, pressure) = frame
            .plies
            .map_or((&zeros[..], &zeros[..]), |p| (&p.slip[..], &p.pressure[..]));
        scalars(&mut xml, "ply_slip", slip);
        scalars(&mut xml, "ply_pressure", pressure);
    }
    xml.push_str("      </PointData>\n");

    xml.push_str("      <CellData Scalars=\"shear_angle_deg\">\n");
    let shear_deg: Vec<f64> = fields.shear.iter().map(|g| g.to_degrees()).collect();
    scalars(&mut xml, "shear_angle_deg", &shear_deg);
    let family =
        |values: &[[f64; 2]], k: usize| -> Vec<f64> { values.iter().map(|v| v[k]).collect() };
    scalars(
        &mut xml,
        "fibre_stretch_warp",
        &family(&fields.fibre_stretch, 0),
    );
    scalars(
        &mut xml,
        "fibre_stretch_weft",
        &family(&fields.fibre_stretch, 1),
    );
    for (k, name) in ["fibre_direction_warp", "fibre_direction_weft"]
        .iter()
        .enumerate()
    {
        vectors(&mut xml, name, fields.fibre_direction.iter().map(|d| d[k]));
    }
    scalars(
        &mut xml,
        "fibre_tension_warp",
        &family(&fields.fibre_tension, 0),
    );
    scalars(
        &mut xml,
        "fibre_tension_weft",
        &family(&fields.fibre_tension, 1),
    );
    let resin: Vec<f64> = fields.resin_stress.iter().flatten().copied().collect();
    // Three plain components [11, 22, 12] in fibre axes: not a VTK tensor
    // (that would be 6 or 9 components in global axes).
    data_array(
        &mut xml,
        "Float64",
        "resin_stress",
        &["11", "22", "12"],
        &resin,
        push_f64,
    );
    scalars(&mut xml, "thickness", &fields.thickness);
    scalars(&mut xml, "waviness", &fields.waviness);
    if model.plies.len() > 1 {
        // Which ply each cell is: ParaView's Threshold on it shows one ply.
        let ply: Vec<i32> = model.element_plies().iter().map(|&p| p as i32).collect();
        data_array(&mut xml, "Int32", "ply", ONE, &ply, |b, p| {
            b.extend(p.to_le_bytes())
        });
    }
    xml.push_str("      </CellData>\n");

    xml.push_str("      <Points>\n");
    let points: Vec<f64> = state.x.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    data_array(&mut xml, "Float64", "Points", XYZ, &points, push_f64);
    xml.push_str("      </Points>\n");

    xml.push_str("      <Cells>\n");
    data_array(
        &mut xml,
        "Int64",
        "connectivity",
        ONE,
        &connectivity,
        |b, v| b.extend(v.to_le_bytes()),
    );
    data_array(&mut xml, "Int64", "offsets", ONE, &offsets, |b, v| {
        b.extend(v.to_le_bytes())
    });
    data_array(&mut xml, "UInt8", "types", ONE, &types, |b, &t| b.push(t));
    xml.push_str("      </Cells>\n");

    xml.push_str("    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    Ok(xml)
}

/// VTK cell type of a line.
const VTK_LINE: u8 = 3;

/// The opening of a `.vtu` file at `time` with one piece of `n_points`
/// points and `n_cells` cells.
fn vtu_head(xml: &mut String, time: f64, n_points: usize, n_cells: usize) {
    xml.push_str(concat!(
        "<?xml version=\"1.0\"?>\n",
        "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
        "  <UnstructuredGrid>\n",
        "    <FieldData>\n",
    ));
    let _ = writeln!(
        xml,
        "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>",
        fmt_f64(time)
    );
    xml.push_str("    </FieldData>\n");
    let _ = writeln!(
        xml,
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
    );
}

/// The points and cells of a piece whose cells all have `nodes_per_cell`
/// nodes and VTK type `kind`, and the closing tags.
fn vtu_tail(
    xml: &mut String,
    points: impl Iterator<Item = nalgebra::Vector3<f64>>,
    connectivity: &[i64],
    nodes_per_cell: usize,
    kind: u8,
) {
    let n_cells = connectivity.len() / nodes_per_cell;
    xml.push_str("      <Points>\n");
    let points: Vec<f64> = points.flat_map(|p| [p.x, p.y, p.z]).collect();
    data_array(xml, "Float64", "Points", XYZ, &points, push_f64);
    xml.push_str("      </Points>\n      <Cells>\n");
    data_array(xml, "Int64", "connectivity", ONE, connectivity, |b, v| {
        b.extend(v.to_le_bytes())
    });
    let offsets: Vec<i64> = (1..=n_cells).map(|c| (c * nodes_per_cell) as i64).collect();
    data_array(xml, "Int64", "offsets", ONE, &offsets, |b, v| {
        b.extend(v.to_le_bytes())
    });
    data_array(xml, "UInt8", "types", ONE, &vec![kind; n_cells], |b, &t| {
        b.push(t)
    });
    xml.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
}

/// The `.vtu` text of the trusses of `model` at positions `x` (every node
/// of the model a point, every truss a line cell), or None without
/// trusses. Cell data: `family` (0 warp, 1 weft: the model's truss
/// batches in order), `tension` (axial force N = A₀·τ/λ, N),
/// `tension_per_width` (N over the width of fabric the truss carries,
/// N/mm: the membranes' `fibre_tension_*` measure), `stretch` (λ = l/L₀).
/// A truss whose length vanished has NaN values.
pub(super) fn trusses_vtu(
    time: f64,
    model: &drape_model::Model,
    x: &[nalgebra::Vector3<f64>],
) -> Option<String> {
    let count: usize = model.trusses.iter().map(|b| b.len()).sum();
    if count == 0 {
        return None;
    }
    // t_f, the thickness of one yarn family: A₀ = t_f·(strip width).
    let family_thickness = model
        .membranes
        .first()
        .map_or(f64::NAN, |b| b.section.material.family_thickness());
    let mut connectivity = Vec::with_capacity(2 * count);
    let (mut family, mut tension, mut per_width, mut stretch) = (
        Vec::with_capacity(count),
        Vec::with_capacity(count),
        Vec::with_capacity(count),
        Vec::with_capacity(count),
    );
    for (k, batch) in model.trusses.iter().enumerate() {
        for e in 0..batch.len() {
            connectivity.extend(batch.nodes[e].map(i64::from));
            family.push(k.min(255) as u8);
            let out = batch.element_output(e, x).ok();
            let n = out.map_or(f64::NAN, |o| o.tension);
            tension.push(n);
            per_width.push(n * family_thickness / batch.section[e]);
            stretch.push(out.map_or(f64::NAN, |o| o.stretch));
        }
    }
    let mut xml = String::with_capacity(80 * (x.len() + count) + 4096);
    vtu_head(&mut xml, time, x.len(), count);
    xml.push_str("      <CellData Scalars=\"tension\">\n");
    data_array(&mut xml, "UInt8", "family", ONE, &family, |b, &f| b.push(f));
    scalars(&mut xml, "tension", &tension);
    scalars(&mut xml, "tension_per_width", &per_width);
    scalars(&mut xml, "stretch", &stretch);
    xml.push_str("      </CellData>\n");
    vtu_tail(&mut xml, x.iter().copied(), &connectivity, 2, VTK_LINE);
    Some(xml)
}

/// The `.vtu` text of triangle surfaces: `points` and `triangles` (indices
/// into `points`), with the cell data `tool` (the index of each triangle's
/// tool in the scene's `[[tools]]`).
pub(super) fn surfaces_vtu(
    time: f64,
    points: &[nalgebra::Vector3<f64>],
    triangles: &[[u32; 3]],
    tool: &[u32],
) -> String {
    let connectivity: Vec<i64> = triangles.iter().flatten().map(|&i| i64::from(i)).collect();
    let mut xml = String::with_capacity(80 * (points.len() + triangles.len()) + 4096);
    vtu_head(&mut xml, time, points.len(), triangles.len());
    xml.push_str("      <CellData Scalars=\"tool\">\n");
    data_array(&mut xml, "UInt32", "tool", ONE, tool, |b, v| {
        b.extend(v.to_le_bytes())
    });
    xml.push_str("      </CellData>\n");
    vtu_tail(
        &mut xml,
        points.iter().copied(),
        &connectivity,
        3,
        VTK_TRIANGLE,
    );
    xml
}

/// The `.pvd` text listing `frames` (index → (time, file relative to the
/// `.pvd`)) in index order.
pub(super) fn series_pvd(frames: &BTreeMap<usize, (f64, String)>) -> String {
    let mut xml = String::from(concat!(
        "<?xml version=\"1.0\"?>\n",
        "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n",
        "  <Collection>\n",
    ));
    for (time, file) in frames.values() {
        let _ = writeln!(
            xml,
            "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
            fmt_f64(*time),
            xml_escape(file)
        );
    }
    xml.push_str("  </Collection>\n</VTKFile>\n");
    xml
}

fn push_f64(bytes: &mut Vec<u8>, v: &f64) {
    bytes.extend(v.to_le_bytes());
}

fn scalars(xml: &mut String, name: &str, values: &[f64]) {
    data_array(xml, "Float64", name, ONE, values, push_f64);
}

fn vectors(xml: &mut String, name: &str, values: impl Iterator<Item = nalgebra::Vector3<f64>>) {
    let flat: Vec<f64> = values.flat_map(|v| [v.x, v.y, v.z]).collect();
    data_array(xml, "Float64", name, XYZ, &flat, push_f64);
}

/// A one-component array's component names (none).
const ONE: &[&str] = &[""];
/// A three-component vector's component names (none: readers call them X, Y, Z).
const XYZ: &[&str] = &["", "", ""];

/// One `<DataArray>` in inline binary: base64 of (u64 byte count ‖ data).
/// `components` has one entry per component: its name, or "" for none
/// (`ComponentNameK` attributes, which ParaView shows instead of 0, 1, 2).
fn data_array<T>(
    xml: &mut String,
    vtk_type: &str,
    name: &str,
    components: &[&str],
    values: &[T],
    push: impl Fn(&mut Vec<u8>, &T),
) {
    let mut bytes = Vec::with_capacity(8 + std::mem::size_of_val(values));
    bytes.extend(0u64.to_le_bytes());
    for v in values {
        push(&mut bytes, v);
    }
    let len = (bytes.len() - 8) as u64;
    bytes[..8].copy_from_slice(&len.to_le_bytes());
    let _ = write!(
        xml,
        "        <DataArray type=\"{vtk_type}\" Name=\"{}\" NumberOfComponents=\"{}\"",
        xml_escape(name),
        components.len()
    );
    for (k, component) in components.iter().enumerate().filter(|(_, c)| !c.is_empty()) {
        let _ = write!(xml, " ComponentName{k}=\"{}\"", xml_escape(component));
    }
    xml.push_str(" format=\"binary\">\n          ");
    base64_encode_into(&bytes, xml);
    xml.push_str("\n        </DataArray>\n");
}

/// Escapes the five XML special characters (file names may hold `&`).
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Standard base64 (RFC 4648, with padding), appended to `out`. Twenty
/// lines are cheaper than a dependency, and the tests pin the RFC vectors.
pub(super) fn base64_encode_into(bytes: &[u8], out: &mut String) {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    out.reserve(bytes.len().div_ceil(3) * 4);
    let mut chunks = bytes.chunks_exact(3);
    for c in &mut chunks {
        let n = (u32::from(c[0]) << 16) | (u32::from(c[1]) << 8) | u32::from(c[2]);
        for shift in [18, 12, 6, 0] {
            out.push(ALPHABET[(n >> shift) as usize & 63] as char);
        }
    }
    match *chunks.remainder() {
        [a] => {
            let n = u32::from(a) << 16;
            out.push(ALPHABET[(n >> 18) as usize & 63] as char);
            out.push(ALPHABET[(n >> 12) as usize & 63] as char);
            out.push_str("==");
        }
        [a, b] => {
            let n = (u32::from(a) << 16) | (u32::from(b) << 8);
            out.push(ALPHABET[(n >> 18) as usize & 63] as char);
            out.push(ALPHABET[(n >> 12) as usize & 63] as char);
            out.push(ALPHABET[(n >> 6) as usize & 63] as char);
            out.push('=');
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b64(s: &str) -> String {
        let mut out = String::new();
        base64_encode_into(s.as_bytes(), &mut out);
        out
    }

    #[test]
    fn base64_matches_rfc4648_vectors() {
        let vectors = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, encoded) in vectors {
            assert_eq!(b64(plain), encoded, "{plain:?}");
        }
        let mut high = String::new();
        base64_encode_into(&[0xff, 0xfe, 0xfd, 0xfc], &mut high);
        assert_eq!(high, "//79/A==");
    }

    #[test]
    fn pvd_lists_frames_in_index_order_and_escapes_names() {
        let mut frames = BTreeMap::new();
        frames.insert(1, (0.5, "frames/b&c.vtu".to_owned()));
        frames.insert(0, (0.0, "frames/a.vtu".to_owned()));
        let pvd = series_pvd(&frames);
        let a = pvd.find("file=\"frames/a.vtu\"").unwrap();
        let b = pvd.find("file=\"frames/b&amp;c.vtu\"").unwrap();
        assert!(a < b, "{pvd}");
        assert!(pvd.contains("timestep=\"0.5\""), "{pvd}");
    }
}
