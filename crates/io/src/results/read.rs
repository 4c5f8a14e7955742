//! Reading a results folder back: the summary, the series and a frame, for
//! `drape compare RUN_A RUN_B` and `drape inspect`.
//!
//! The VTU reader reads what [`super::ResultsDir`] writes (inline binary
//! arrays with a `UInt64` header, little-endian; Float64, Int64, UInt8 and
//! UInt32 arrays), not VTU files in general: it is how drape reads its own
//! results, while the tests check the writer with independent readers.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

use super::Summary;

/// One `.vtu` file as drape writes it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VtuFrame {
    /// The `TimeValue` of its field data, when present.
    pub time: Option<f64>,
    /// Points (mm).
    pub points: Vec<Vector3<f64>>,
    /// Cells as point indices.
    pub cells: Vec<Vec<u32>>,
    /// Point arrays: name → (components, values flattened).
    pub point_data: BTreeMap<String, (usize, Vec<f64>)>,
    /// Cell arrays: name → (components, values flattened).
    pub cell_data: BTreeMap<String, (usize, Vec<f64>)>,
}

impl VtuFrame {
    /// The one-component cell array `name`.
    pub fn cell_scalars(&self, name: &str) -> Option<&[f64]> {
        self.cell_data
            .get(name)
            .filter(|(c, _)| *c == 1)
            .map(|(_, v)| v.as_slice())
    }

    /// The reference positions: the points less the point array
    /// `displacement` (the points themselves without it).
    pub fn reference_points(&self) -> Vec<Vector3<f64>> {
        match self.point_data.get("displacement") {
            Some((3, u)) if u.len() == 3 * self.points.len() => self
                .points
                .iter()
                .enumerate()
                .map(|(i, p)| p - Vector3::new(u[3 * i], u[3 * i + 1], u[3 * i + 2]))
                .collect(),
            _ => self.points.clone(),
        }
    }
}

/// Standard base64 with padding, whitespace ignored.
fn base64_decode(text: &str) -> Result<Vec<u8>, String> {
    let value = |c: u8| -> Result<u32, String> {
        Ok(u32::from(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            b'=' => 0,
            _ => return Err(format!("`{}` is not base64", c as char)),
        }))
    };
    let clean: Vec<u8> = text.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
    if !clean.len().is_multiple_of(4) {
        return Err("base64 text of a length that is not a multiple of 4".into());
    }
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    for quad in clean.chunks(4) {
        let pads = quad.iter().rev().take_while(|&&c| c == b'=').count();
        let mut n = 0u32;
        for &c in quad {
            n = (n << 6) | value(c)?;
        }
        out.extend(&n.to_be_bytes()[1..4 - pads.min(2)]);
    }
    Ok(out)
}

/// The values of one `<DataArray>` as `f64`, with its component count.
fn array_values(node: roxmltree::Node<'_, '_>) -> Result<(usize, Vec<f64>), String> {
    let name = node.attribute("Name").unwrap_or("?");
    let components: usize = node
        .attribute("NumberOfComponents")
        .unwrap_or("1")
        .parse()
        .map_err(|_| format!("array {name}: bad NumberOfComponents"))?;
    let kind = node.attribute("type").unwrap_or("");
    let text = node.text().unwrap_or("");
    if node.attribute("format") == Some("ascii") {
        let values = text
            .split_whitespace()
            .map(|t| t.parse::<f64>().map_err(|_| format!("array {name}: `{t}`")))
            .collect::<Result<_, _>>()?;
        return Ok((components, values));
    }
    if node.attribute("format") != Some("binary") {
        return Err(format!(
            "array {name}: only inline binary or ascii arrays are read"
        ));
    }
    let bytes = base64_decode(text).map_err(|e| format!("array {name}: {e}"))?;
    if bytes.len() < 8 {
        return Err(format!("array {name}: no header"));
    }
    let len = u64::from_le_bytes(bytes[..8].try_into().unwrap_or_default()) as usize;
    let data = bytes
        .get(8..8 + len)
        .ok_or_else(|| format!("array {name}: {len} bytes announced, fewer given"))?;
    let values = match kind {
        "Float64" => data
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect(),
        "Int64" => data
            .chunks_exact(8)
            .map(|c| i64::from_le_bytes(c.try_into().unwrap_or_default()) as f64)
            .collect(),
        // A laminate's `ply` cell array.
        "Int32" => data
            .chunks_exact(4)
            .map(|c| f64::from(i32::from_le_bytes(c.try_into().unwrap_or_default())))
            .collect(),
        "UInt32" => data
            .chunks_exact(4)
            .map(|c| f64::from(u32::from_le_bytes(c.try_into().unwrap_or_default())))
            .collect(),
        "UInt8" => data.iter().map(|&b| f64::from(b)).collect(),
        other => return Err(format!("array {name}: type {other} is not read")),
    };
    Ok((components, values))
}

/// Reads the `.vtu` file `path`.
pub fn read_vtu(path: &Path) -> Result<VtuFrame, String> {
    let at = |e: String| format!("{}: {e}", path.display());
    let text = std::fs::read_to_string(path).map_err(|e| at(e.to_string()))?;
    let doc = roxmltree::Document::parse(&text).map_err(|e| at(e.to_string()))?;
    let mut frame = VtuFrame::default();
    let find = |tag: &str| doc.descendants().find(|n| n.has_tag_name(tag));
    let arrays = |parent: Option<roxmltree::Node<'_, '_>>| -> Result<BTreeMap<String, (usize, Vec<f64>)>, String> {
        let mut out = BTreeMap::new();
        for a in parent.iter().flat_map(|p| p.children()).filter(|n| n.has_tag_name("DataArray")) {
            let name = a.attribute("Name").unwrap_or("").to_owned();
            out.insert(name, array_values(a).map_err(at)?);
        }
        Ok(out)
    };
    frame.time = arrays(find("FieldData"))?
        .get("TimeValue")
        .and_then(|(_, v)| v.first().copied());
    let points = arrays(find("Points"))?;
    let (_, xyz) = points
        .values()
        .next()
        .ok_or_else(|| at("no points".into()))?;
    frame.points = xyz
        .chunks_exact(3)
        .map(|c| Vector3::new(c[0], c[1], c[2]))
        .collect();
    let cells = arrays(find("Cells"))?;
    let get = |name: &str| {
        cells
            .get(name)
            .map(|(_, v)| v.as_slice())
            .ok_or_else(|| at(format!("no cell array {name}")))
    };
    let (connectivity, offsets) = (get("connectivity")?, get("offsets")?);
    let mut start = 0usize;
    for &end in offsets {
        let end = end as usize;
        let nodes = connectivity
            .get(start..end)
            .ok_or_else(|| at("cell offsets beyond the connectivity".into()))?;
        frame.cells.push(nodes.iter().map(|&n| n as u32).collect());
        start = end;
    }
    frame.point_data = arrays(find("PointData"))?;
    frame.cell_data = arrays(find("CellData"))?;
    Ok(frame)
}

/// The frames a `.pvd` series lists: (time, file), in the series' order.
pub fn read_pvd(path: &Path) -> Result<Vec<(f64, PathBuf)>, String> {
    let at = |e: String| format!("{}: {e}", path.display());
    let text = std::fs::read_to_string(path).map_err(|e| at(e.to_string()))?;
    let doc = roxmltree::Document::parse(&text).map_err(|e| at(e.to_string()))?;
    let base = path.parent().unwrap_or(Path::new("."));
    doc.descendants()
        .filter(|n| n.has_tag_name("DataSet"))
        .map(|d| {
            let time = d
                .attribute("timestep")
                .and_then(|t| t.parse().ok())
                .ok_or_else(|| at("a DataSet without a timestep".into()))?;
            let file = d
                .attribute("file")
                .ok_or_else(|| at("a DataSet without a file".into()))?;
            Ok((time, base.join(file)))
        })
        .collect()
}

/// The summary of the results folder `dir`.
pub fn read_summary(dir: &Path) -> Result<Summary, String> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            format!(
                "{}: no summary.json: not a run's results folder, or no run has finished writing \
                 there",
                dir.display()
            )
        } else {
            format!("{}: {e}", path.display())
        }
    })?;
    serde_json::from_str(&text).map_err(|e| format!("{}: not a drape summary: {e}", path.display()))
}

/// The last frame of the results folder `dir` (the last entry of its
/// `series.pvd`).
pub fn read_last_frame(dir: &Path) -> Result<VtuFrame, String> {
    let pvd = dir.join("series.pvd");
    let frames = read_pvd(&pvd)?;
    let (_, last) = frames.last().ok_or_else(|| {
        format!(
            "{}: no frame (was the run written with `output.vtu = false`?)",
            pvd.display()
        )
    })?;
    read_vtu(last)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_rfc4648_vectors() {
        for (plain, encoded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(
                base64_decode(encoded).unwrap(),
                plain.as_bytes(),
                "{encoded}"
            );
        }
        assert!(base64_decode("Zm9").is_err());
        assert!(base64_decode("Zm9*").is_err());
    }
}
