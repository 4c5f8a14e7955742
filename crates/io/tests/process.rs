//! What a forming engineer carries on from a results folder: the fibre
//! directions, the trusses and the tools in ParaView (read back by meshio
//! through `tests/check_vtu.py`), the oblique picture and a sweep's
//! picture, and the draped orientations exported for structural analysis,
//! re-read and mapped onto a different mesh of the same part.

use std::path::{Path, PathBuf};
use std::process::Command;

use drape_constitutive::Material;
use drape_contact::{Amplitude, Surface, Tool, ToolMotion};
use drape_io::mesh_import::{ImportedMesh, parse_abaqus, read_abaqus};
use drape_io::results::export::Orientations;
use drape_io::results::mapping::map_onto;
use drape_io::results::read::read_vtu;
use drape_io::results::{
    FrameData, ResultsDir, SweepAxis, SweepRun, ToolMeshes, write_sweep_picture,
};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{ElementFields, Model, State};
use nalgebra::Vector3;

fn model(element: ElementKind, cells: usize, fibres: FibreRepresentation) -> Model {
    let blank = RectangleBlank {
        width: 200.0,
        height: 200.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element,
        meshing: Meshing::Cells([cells, cells]),
        fibres,
    };
    Model::from_blank(&blank, &Material::preset("glass-serge-4x3").unwrap()).unwrap()
}

/// The blank laid on a sphere of radius `r` by the azimuthal equidistant
/// map (radial lengths kept, hoops shortened), then stretched 2 % along x:
/// the shear varies over the part, most along the diagonals, and the warp
/// is in tension.
fn draped(model: &Model, r: f64, time: f64) -> State {
    let mut state = model.initial_state();
    state.time = time;
    for x in &mut state.x {
        let rho = x.x.hypot(x.y);
        let s = if rho > 0.0 {
            r * (rho / r).sin() / rho
        } else {
            1.0
        };
        *x = Vector3::new(1.02 * x.x * s, x.y * s, r * (rho / r).cos() - r);
    }
    state
}

fn frame<'a>(model: &'a Model, state: &'a State, fields: &'a ElementFields) -> FrameData<'a> {
    FrameData {
        model,
        state,
        fields,
        contact_force: None,
        contact_status: None,
        plies: None,
    }
}

/// (width, height, distinct colours, fraction of pixels that are not white).
fn png_stats(path: &Path) -> (u32, u32, usize, f64) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let pixels: Vec<&[u8]> = buf[..info.buffer_size()].chunks_exact(3).collect();
    let inked = pixels.iter().filter(|p| **p != [255, 255, 255]).count();
    let mut colours = pixels.clone();
    colours.sort_unstable();
    colours.dedup();
    (
        info.width,
        info.height,
        colours.len(),
        inked as f64 / pixels.len() as f64,
    )
}

fn has_meshio() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import meshio"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!(
            "note: python3 with meshio not found; skipping tests/check_vtu.py (pip install meshio)"
        );
    }
    ok
}

/// `tests/check_vtu.py` with `args`: (passed, its output).
fn check_vtu(args: &[&str]) -> (bool, String) {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/check_vtu.py");
    let o = Command::new("python3")
        .arg(script)
        .args(args)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.success(), text)
}

fn punch() -> Tool {
    Tool {
        name: "punch".into(),
        surface: Surface::hemispherical_punch(Vector3::new(0.0, 0.0, -1.0), 120.0, 50.0).unwrap(),
        motion: ToolMotion::Displacement {
            direction: Vector3::z(),
            distance: 25.0,
            amplitude: Amplitude::Ramp { duration: 1.0 },
        },
        friction: 0.1,
    }
}

/// A run of two frames (flat, then draped) of a quad blank with trusses
/// and of a triangle blank, with a moving punch, read back by meshio: the
/// fibre vectors against the shear angle (acos(n_w·n_f) = 90° − γ), the
/// trusses as lines whose stretch is their length ratio, the tool moved
/// rigidly by its displacement.
#[test]
fn fibres_trusses_and_tools_read_back_by_meshio() {
    let tmp = tempfile::tempdir().unwrap();
    let tools_of = |m: &Model| ToolMeshes::new(&[punch()], &m.x0);
    let mut dirs = Vec::new();
    for (name, element) in [
        ("quads", ElementKind::Quad),
        ("triangles", ElementKind::Triangle),
    ] {
        let dir = tmp.path().join(name);
        let mut out = ResultsDir::create(&dir).unwrap();
        let m = model(element, 12, FibreRepresentation::Trusses);
        let tools = tools_of(&m);
        for (index, state, displacement) in [
            (0, m.initial_state(), 0.0),
            (1, draped(&m, 140.0, 0.5), 12.5),
        ] {
            let fields = m.element_fields(&state).unwrap();
            out.write_frame(index, state.time, &frame(&m, &state, &fields))
                .unwrap();
            out.write_tools(index, state.time, &tools, &[displacement])
                .unwrap();
        }
        // Our own reader agrees with the writer, bit for bit.
        let back = read_vtu(&dir.join("frames/frame_00001.vtu")).unwrap();
        let state = draped(&m, 140.0, 0.5);
        assert_eq!(back.points, state.x);
        assert_eq!(back.time, Some(0.5));
        let fields = m.element_fields(&state).unwrap();
        let shear: Vec<f64> = fields.shear.iter().map(|g| g.to_degrees()).collect();
        assert_eq!(
            back.cell_scalars("shear_angle_deg").unwrap(),
            shear.as_slice()
        );
        dirs.push((dir, m));
    }
    let (quads, m) = &dirs[0];
    let truss_count: usize = m.trusses.iter().map(|b| b.len()).sum();
    assert!(quads.join("trusses.pvd").is_file() && quads.join("tools.pvd").is_file());
    let trusses = read_vtu(&quads.join("frames/trusses_00001.vtu")).unwrap();
    assert_eq!(trusses.cells.len(), truss_count);
    // The yarn tension per width is the force over the strip width: a
    // boundary truss (half a strip) carries half the force for the same
    // tension per width.
    let (_, tension) = &trusses.cell_data["tension"];
    let (_, per_width) = &trusses.cell_data["tension_per_width"];
    let t_f = Material::preset("glass-serge-4x3")
        .unwrap()
        .family_thickness();
    let sections: Vec<f64> = m.trusses.iter().flat_map(|b| b.section.clone()).collect();
    for ((n, w), a) in tension.iter().zip(per_width).zip(&sections) {
        assert!((w - n * t_f / a).abs() <= 1e-12 * n.abs().max(1e-30) / a * t_f + 1e-300);
    }
    assert!(
        tension.iter().any(|&n| n > 0.0),
        "the draped blank stretches some yarns"
    );

    if !has_meshio() {
        return;
    }
    for (dir, m) in &dirs {
        let series = dir.join("series.pvd");
        let cells = m.membrane_count().to_string();
        let cell_type = if m.membranes[0].shape() == drape_elements::MembraneShape::Quad {
            "quad"
        } else {
            // A 0/90 triangle blank: triangles only.
            "triangle"
        };
        let (ok, text) = check_vtu(&[
            series.to_str().unwrap(),
            "--cells",
            &cells,
            "--cell-type",
            cell_type,
            "--fibres-vs-shear",
            "1e-9",
            "--frames",
            "2",
        ]);
        assert!(ok, "{text}");
        eprintln!("{text}");
        if cell_type == "triangle" {
            // Its trusses and tools are written as the quads' are.
            continue;
        }
        let (ok, text) = check_vtu(&[
            dir.join("trusses.pvd").to_str().unwrap(),
            "--cell-type",
            "line",
            "--cell-data",
            "family,tension,tension_per_width,stretch",
            "--truss-stretch",
            "--frames",
            "2",
        ]);
        assert!(ok, "{text}");
        let (ok, text) = check_vtu(&[
            dir.join("tools.pvd").to_str().unwrap(),
            "--cell-type",
            "triangle",
            "--cell-data",
            "tool",
            "--shift",
            "0,0,12.5",
        ]);
        assert!(ok, "{text}");
    }
    // The checks do check: a weft turned by 0.01° in one element fails the
    // fibre check, a wrong shift fails the tool check.
    let (dir, m) = &dirs[0];
    let state = draped(m, 140.0, 0.5);
    let mut fields = m.element_fields(&state).unwrap();
    let [w, f] = fields.fibre_direction[7];
    let axis = w.cross(&f).normalize();
    fields.fibre_direction[7][1] = nalgebra::Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(axis),
        0.01f64.to_radians(),
    ) * f;
    let bad = tempfile::tempdir().unwrap();
    let mut out = ResultsDir::create(bad.path()).unwrap();
    out.write_frame(0, 0.5, &frame(m, &state, &fields)).unwrap();
    let (ok, text) = check_vtu(&[
        bad.path().join("series.pvd").to_str().unwrap(),
        "--fibres-vs-shear",
        "1e-9",
    ]);
    assert!(!ok && text.contains("cell 7"), "{text}");
    let (ok, _) = check_vtu(&[dir.join("tools.pvd").to_str().unwrap(), "--shift", "0,0,12"]);
    assert!(!ok);
}

#[test]
fn the_oblique_view_and_the_sweep_picture_are_drawn() {
    let tmp = tempfile::tempdir().unwrap();
    let out = ResultsDir::create(tmp.path()).unwrap();
    let m = model(ElementKind::Quad, 20, FibreRepresentation::Embedded);
    let state = draped(&m, 140.0, 1.0);
    let fields = m.element_fields(&state).unwrap();
    let tools = ToolMeshes::new(&[punch()], &m.x0);
    out.write_view(&m, &state, &fields, &tools, &[25.0])
        .unwrap();
    let (w, h, colours, inked) = png_stats(&tmp.path().join("shear_3d.png"));
    assert_eq!((w, h), (1000, 820));
    assert!(
        colours > 50,
        "a colour map uses many colours, got {colours}"
    );
    // The part (about a third of the map area) and the colour bar.
    assert!(
        inked > 0.15,
        "only {:.1} % of the picture is drawn",
        100.0 * inked
    );

    let axes = [
        SweepAxis {
            key: "tools.0.friction".into(),
            values: vec!["0".into(), "0.1".into(), "0.2".into()],
        },
        SweepAxis {
            key: "fabric.orientation_deg".into(),
            values: vec!["0".into(), "45".into()],
        },
    ];
    let mut runs = Vec::new();
    for (i, mu) in ["0", "0.1", "0.2"].iter().enumerate() {
        for (j, theta) in ["0", "45"].iter().enumerate() {
            runs.push(SweepRun {
                values: vec![(*mu).into(), (*theta).into()],
                max_shear_deg: 30.0 - i as f64 + j as f64,
                draw_in_dx_mm: 50.0 - 2.0 * i as f64,
                draw_in_dd_mm: f64::NAN,
            });
        }
    }
    let path = tmp.path().join("sweep.png");
    write_sweep_picture(&path, &axes, &runs).unwrap();
    let (w, h, colours, inked) = png_stats(&path);
    // Two keys across, max shear and DX down (no DD: none is finite).
    assert_eq!((w, h), (2 * 560, 2 * 400));
    assert!(
        colours > 10 && inked > 0.03,
        "{colours} colours, {inked} inked"
    );
}

/// Orientations of `m` at `state`, written and read back.
fn round_trip(
    m: &Model,
    state: &State,
) -> (Orientations, Orientations, PathBuf, tempfile::TempDir) {
    let tmp = tempfile::tempdir().unwrap();
    let out = ResultsDir::create(tmp.path()).unwrap();
    let fields = m.element_fields(state).unwrap();
    out.write_orientations(m, state, &fields, "test at t = 1 s")
        .unwrap();
    let path = tmp.path().join("orientations.inp");
    let back = Orientations::read_inp(&path).unwrap();
    (
        Orientations::of_frame(m, state, &fields, "test at t = 1 s"),
        back,
        path,
        tmp,
    )
}

#[test]
fn the_orientation_export_reads_back_with_its_angles() {
    for element in [ElementKind::Quad, ElementKind::Triangle] {
        let m = model(element, 10, FibreRepresentation::Embedded);
        let state = draped(&m, 140.0, 1.0);
        let (written, back, path, _tmp) = round_trip(&m, &state);
        assert_eq!(back.title, "test at t = 1 s");
        assert_eq!(
            back.labels,
            (1..=m.membrane_count() as i64).collect::<Vec<_>>()
        );
        assert_eq!(back.nodes, state.x);
        let mut worst = 0.0f64;
        for e in 0..written.len() {
            // Shortest round-trip text: directions and thickness exactly,
            // γ through 90° − (90° − γ).
            assert_eq!(back.warp[e], written.warp[e]);
            assert_eq!(back.weft[e], written.weft[e]);
            assert_eq!(back.thickness[e], written.thickness[e]);
            assert_eq!(back.centroid[e], written.centroid[e]);
            assert!((back.shear_deg[e] - written.shear_deg[e]).abs() < 1e-9);
            // The angle between the re-read yarns is the re-read yarn angle.
            let angle = back.warp[e].angle(&back.weft[e]).to_degrees();
            worst = worst.max((angle - (90.0 - back.shear_deg[e])).abs());
        }
        assert!(worst < 1e-9, "{element:?}: yarn angle off by {worst:e}°");
        assert!(
            written.shear_deg.iter().any(|g| g.abs() > 5.0),
            "a sheared part"
        );
        // The mesh of the include reads with drape's Abaqus reader, its
        // labels and nodes as written.
        let mesh = read_abaqus(&path).unwrap();
        assert_eq!(mesh.x0, state.x);
        assert_eq!(mesh.element_count(), m.membrane_count());
        // And the CSV holds the same numbers.
        let csv = std::fs::read_to_string(path.with_extension("csv")).unwrap();
        let rows: Vec<Vec<f64>> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), written.len());
        for (e, r) in rows.iter().enumerate() {
            assert_eq!(
                r[4..7],
                [written.warp[e].x, written.warp[e].y, written.warp[e].z]
            );
            assert_eq!(r[10], written.shear_deg[e]);
            assert_eq!(r[12], written.thickness[e]);
        }
    }
}

// --- Mapping onto a second, different mesh of the same part ----------------

/// The part: a spherical cap of radius R over the (x, y) plane.
const R: f64 = 150.0;

fn on_part(x: f64, y: f64) -> Vector3<f64> {
    Vector3::new(x, y, (R * R - x * x - y * y).sqrt() - R)
}

/// A smooth draped field at (x, y): warp angle α and shear γ (radians)
/// varying over the part, the thickness h₀/cos γ.
fn field(x: f64, y: f64) -> (f64, f64, f64) {
    let alpha = 0.25 * (x / 40.0).sin() + 0.15 * (y / 50.0).cos();
    let gamma = (25.0 * x * y / 3600.0 + 5.0 * ((x + y) / 30.0).sin()).to_radians();
    (alpha, gamma, 0.3 / gamma.cos())
}

/// The yarns of the field at (x, y) in the plane with unit normal `n`.
fn yarns(x: f64, y: f64, n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let (alpha, gamma, _) = field(x, y);
    let t = Vector3::new(alpha.cos(), alpha.sin(), 0.0);
    let warp = (t - n * t.dot(n)).normalize();
    let beta = std::f64::consts::FRAC_PI_2 - gamma;
    (warp, warp * beta.cos() + n.cross(&warp) * beta.sin())
}

/// The formed mesh: n × n quads over [−60, 60]², its nodes on the part,
/// each element carrying the field at its centroid's (x, y).
fn formed(n: usize) -> Orientations {
    let h = 120.0 / n as f64;
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut o = Orientations {
        title: "a spherical cap".into(),
        nominal_thickness: 0.3,
        ..Orientations::default()
    };
    for j in 0..=n {
        for i in 0..=n {
            o.nodes
                .push(on_part(-60.0 + h * i as f64, -60.0 + h * j as f64));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let nodes = vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
            let c = nodes
                .iter()
                .map(|&k| o.nodes[k as usize])
                .sum::<Vector3<f64>>()
                / 4.0;
            let normal = (o.nodes[nodes[2] as usize] - o.nodes[nodes[0] as usize])
                .cross(&(o.nodes[nodes[3] as usize] - o.nodes[nodes[1] as usize]))
                .normalize();
            let (warp, weft) = yarns(c.x, c.y, &normal);
            let (_, gamma, thickness) = field(c.x, c.y);
            o.labels.push(o.elements.len() as i64 + 1);
            o.elements.push(nodes);
            o.centroid.push(c);
            o.warp.push(warp);
            o.weft.push(weft);
            o.shear_deg.push(gamma.to_degrees());
            o.thickness.push(thickness);
        }
    }
    o
}

/// The structural mesh: triangles of side about 7 mm on a grid turned by
/// 20°, inside the disc of radius 40 mm, their nodes on the part, written
/// as an Abaqus file (S3 shells, labels from 101) and read by drape's
/// importer.
fn structural() -> ImportedMesh {
    let (s, c) = 20f64.to_radians().sin_cos();
    let step = 7.0;
    let k = 8i32;
    let mut text = String::from("*NODE\n");
    let mut inside = std::collections::BTreeMap::new();
    for j in -k..=k {
        for i in -k..=k {
            let (u, v) = (step * f64::from(i), step * f64::from(j));
            let (x, y) = (c * u - s * v, s * u + c * v);
            let label = (j + k) * (2 * k + 1) + (i + k) + 1;
            let p = on_part(x, y);
            text.push_str(&format!("{label}, {}, {}, {}\n", p.x, p.y, p.z));
            inside.insert(label, x.hypot(y) <= 40.0);
        }
    }
    text.push_str("*ELEMENT, TYPE=S3\n");
    let mut element = 101;
    for j in -k..k {
        for i in -k..k {
            let id = |a: i32, b: i32| (b + k) * (2 * k + 1) + (a + k) + 1;
            for t in [
                [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
            ] {
                if t.iter().all(|n| inside[n]) {
                    text.push_str(&format!("{element}, {}, {}, {}\n", t[0], t[1], t[2]));
                    element += 1;
                }
            }
        }
    }
    parse_abaqus(&text, Path::new("structural.inp")).unwrap()
}

/// The largest errors of `mapped` against the field at each structural
/// element's centroid: (γ in degrees, warp and weft directions in degrees,
/// relative thickness), and the largest distance to the formed mesh.
fn mapping_errors(mapped: &Orientations, target: &ImportedMesh) -> (f64, f64, f64, f64) {
    let mut worst = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let by_label: std::collections::BTreeMap<i64, [u32; 3]> = target
        .triangle_labels
        .iter()
        .copied()
        .zip(target.triangles.iter().copied())
        .collect();
    for e in 0..mapped.len() {
        let t = by_label[&mapped.labels[e]];
        let [a, b, c] = t.map(|n| target.x0[n as usize]);
        let normal = (b - a).cross(&(c - a)).normalize();
        let centroid = mapped.centroid[e];
        let (warp, weft) = yarns(centroid.x, centroid.y, &normal);
        let (_, gamma, thickness) = field(centroid.x, centroid.y);
        worst.0 = worst
            .0
            .max((mapped.shear_deg[e] - gamma.to_degrees()).abs());
        worst.1 = worst.1.max(mapped.warp[e].angle(&warp).to_degrees());
        worst.1 = worst.1.max(mapped.weft[e].angle(&weft).to_degrees());
        worst.2 = worst.2.max((mapped.thickness[e] / thickness - 1.0).abs());
        worst.3 = worst.3.max(mapped.distance.as_ref().unwrap()[e]);
    }
    worst
}

/// The interpolation error of the formed n × n mesh itself for γ: the
/// exact γ at its nodes interpolated linearly over its triangles (quads
/// split 0–2, as the mapping does) at the structural centroids, against
/// the exact γ there. The mapping cannot do better than this; it adds the
/// error of its nodal means (of the same order).
fn interpolation_error(n: usize, target: &ImportedMesh) -> f64 {
    let h = 120.0 / n as f64;
    let gamma = |x: f64, y: f64| field(x, y).1.to_degrees();
    let mut worst = 0.0f64;
    for t in &target.triangles {
        let c = t
            .iter()
            .map(|&k| target.x0[k as usize])
            .sum::<Vector3<f64>>()
            / 3.0;
        let (u, v) = ((c.x + 60.0) / h, (c.y + 60.0) / h);
        let (i, j) = (u.floor(), v.floor());
        let (s, r) = (u - i, v - j);
        let node = |a: f64, b: f64| gamma(-60.0 + h * a, -60.0 + h * b);
        let (g00, g10, g11, g01) = (
            node(i, j),
            node(i + 1.0, j),
            node(i + 1.0, j + 1.0),
            node(i, j + 1.0),
        );
        // Triangle (0, 1, 2) below the diagonal s = r, (0, 2, 3) above.
        let linear = if s >= r {
            g00 + s * (g10 - g00) + r * (g11 - g10)
        } else {
            g00 + r * (g01 - g00) + s * (g11 - g01)
        };
        worst = worst.max((linear - gamma(c.x, c.y)).abs());
    }
    worst
}

/// A smooth field on a formed mesh carried onto a different mesh of the
/// same part (triangles of another size, turned, labelled otherwise)
/// reproduces the field within the interpolation error of the formed mesh,
/// which falls as its element size squared.
#[test]
fn orientations_mapped_onto_another_mesh_of_the_part_keep_their_angles() {
    let target = structural();
    assert!(target.triangles.len() > 80, "{}", target.triangles.len());
    let mut errors = Vec::new();
    for n in [12, 24] {
        // Through the file, as `drape export --onto` reads it.
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("orientations.inp");
        std::fs::write(&path, formed(n).to_inp()).unwrap();
        let source = Orientations::read_inp(&path).unwrap();
        let mapped = map_onto(&source, &target).unwrap();
        assert_eq!(mapped.len(), target.triangles.len());
        assert_eq!(mapped.labels[0], 101);
        // The mapped include and table read back as written.
        let mapped_path = tmp.path().join("mapped.inp");
        std::fs::write(&mapped_path, mapped.to_inp()).unwrap();
        let back = Orientations::read_inp(&mapped_path).unwrap();
        assert_eq!(back.warp, mapped.warp);
        assert_eq!(back.labels, mapped.labels);
        assert!(
            mapped
                .to_csv()
                .lines()
                .next()
                .unwrap()
                .ends_with(",distance_mm")
        );
        let e = mapping_errors(&mapped, &target);
        let interpolation = interpolation_error(n, &target);
        eprintln!(
            "formed mesh {n} × {n} (h = {} mm): largest error γ {:.4}° (the mesh's own linear \
             interpolation: {interpolation:.4}°), yarn directions {:.4}°, thickness {:.2e}, \
             distance {:.3} mm",
            120 / n,
            e.0,
            e.1,
            e.2,
            e.3
        );
        // Within the formed mesh's interpolation error: measured 1.30 and
        // 1.35 times it (the nodal means add an error of the same order).
        assert!(e.0 < 1.5 * interpolation, "{} vs {interpolation}", e.0);
        errors.push(e);
    }
    let (coarse, fine) = (errors[0], errors[1]);
    // The numbers for the 5 mm mesh, stated: γ 0.125°, yarn directions
    // 0.166°, thickness 2.5e-4 (a field whose γ varies by up to 0.5°/mm).
    assert!(fine.0 < 0.15, "γ error {}°", fine.0);
    assert!(fine.1 < 0.2, "direction error {}°", fine.1);
    assert!(fine.2 < 5e-4, "thickness error {}", fine.2);
    // Second order: halving the element size divides the error by about 4.
    let order = (coarse.0 / fine.0).log2();
    assert!(
        order > 1.8,
        "γ error order {order} ({} → {})",
        coarse.0,
        fine.0
    );
    let order = (coarse.1 / fine.1).log2();
    assert!(order > 1.8, "direction error order {order}");
    // Both meshes lie on the part: centroids within the chord's sagitta.
    assert!(fine.3 < 0.1, "distance {}", fine.3);
}
