//! The results directory end to end: a small blank model in a deformed
//! state written as two frames, the CSV files, the JSON summary and the
//! pictures; the VTU checked by parsing its XML and decoding its arrays,
//! and, when Python's meshio is installed, by `tests/check_vtu.py`.

use std::path::{Path, PathBuf};
use std::process::Command;

use drape_constitutive::Material;
use drape_contact::ContactStatus;
use drape_io::results::{
    DrawInMm, EnergyRow, EnergySummary, FrameData, Peaks, ResultsDir, RunInfo, RunSetup, Summary,
};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Model, State};
use drape_time::Energies;
use nalgebra::Vector3;

const POINT_ARRAYS: [&str; 4] = [
    "displacement",
    "velocity",
    "contact_force",
    "contact_status",
];
const CELL_ARRAYS: [&str; 10] = [
    "shear_angle_deg",
    "fibre_stretch_warp",
    "fibre_stretch_weft",
    "fibre_direction_warp",
    "fibre_direction_weft",
    "fibre_tension_warp",
    "fibre_tension_weft",
    "resin_stress",
    "thickness",
    "waviness",
];

fn blank(element: ElementKind, cells: usize) -> RectangleBlank {
    RectangleBlank {
        width: 200.0,
        height: 200.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element,
        meshing: Meshing::Cells([cells, cells]),
        fibres: FibreRepresentation::Trusses,
    }
}

fn model(element: ElementKind, cells: usize) -> Model {
    let glass = Material::preset("glass-serge-4x3").unwrap();
    Model::from_blank(&blank(element, cells), &glass).unwrap()
}

/// The blank laid on a sphere of radius `r` by the azimuthal equidistant
/// map (radial lengths kept, hoops shortened): a 0/90 fabric shears most
/// along the diagonals, as on the paper's hemisphere.
fn draped(model: &Model, r: f64, time: f64) -> State {
    let mut state = model.initial_state();
    state.time = time;
    state.step = 1000;
    for (x, v) in state.x.iter_mut().zip(&mut state.v) {
        let rho = x.x.hypot(x.y);
        let phi = rho / r;
        let s = if rho > 0.0 { r * phi.sin() / rho } else { 1.0 };
        *x = Vector3::new(x.x * s, x.y * s, r * phi.cos() - r);
        *v = Vector3::new(0.0, 0.0, -10.0 * phi);
    }
    state
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Standard base64 with padding; independent of the writer's encoder.
fn base64_decode(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {:?}", c as char),
    };
    let clean: Vec<u8> = text.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    for quad in clean.chunks(4) {
        let pads = quad.iter().filter(|&&c| c == b'=').count();
        let mut n = 0u32;
        for &c in quad {
            n = (n << 6) | if c == b'=' { 0 } else { u32::from(value(c)) };
        }
        out.extend(&n.to_be_bytes()[1..4 - pads]);
    }
    out
}

/// The payload of an inline binary array with a UInt64 header.
fn payload(array: roxmltree::Node<'_, '_>) -> Vec<u8> {
    assert_eq!(array.attribute("format"), Some("binary"));
    let bytes = base64_decode(array.text().unwrap_or(""));
    let len = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    assert_eq!(bytes.len() - 8, len, "header byte count");
    bytes[8..].to_vec()
}

fn f64s(bytes: &[u8]) -> Vec<f64> {
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn child<'a, 'i>(node: roxmltree::Node<'a, 'i>, tag: &str) -> roxmltree::Node<'a, 'i> {
    node.children()
        .find(|n| n.has_tag_name(tag))
        .unwrap_or_else(|| panic!("no <{tag}> in <{}>", node.tag_name().name()))
}

fn array_names(node: roxmltree::Node<'_, '_>) -> Vec<String> {
    node.children()
        .filter(|n| n.has_tag_name("DataArray"))
        .map(|n| n.attribute("Name").unwrap().to_owned())
        .collect()
}

fn named<'a, 'i>(node: roxmltree::Node<'a, 'i>, name: &str) -> roxmltree::Node<'a, 'i> {
    node.children()
        .find(|n| n.attribute("Name") == Some(name))
        .unwrap_or_else(|| panic!("no array {name}"))
}

/// Checks one VTU against the model and state it was written from.
fn check_vtu(path: &Path, model: &Model, state: &State, time: f64, cell_type: u8) {
    let text = read(path);
    let doc = roxmltree::Document::parse(&text).unwrap();
    let root = doc.root_element();
    assert_eq!(root.attribute("type"), Some("UnstructuredGrid"));
    assert_eq!(root.attribute("header_type"), Some("UInt64"));
    assert_eq!(root.attribute("byte_order"), Some("LittleEndian"));
    let grid = child(root, "UnstructuredGrid");
    let time_value = named(child(grid, "FieldData"), "TimeValue");
    assert_eq!(
        time_value.text().unwrap().trim().parse::<f64>().unwrap(),
        time
    );
    let piece = child(grid, "Piece");
    let n_points: usize = piece.attribute("NumberOfPoints").unwrap().parse().unwrap();
    let n_cells: usize = piece.attribute("NumberOfCells").unwrap().parse().unwrap();
    assert_eq!(n_points, model.node_count());
    assert_eq!(n_cells, model.membrane_count());
    assert_eq!(array_names(child(piece, "PointData")), POINT_ARRAYS);
    assert_eq!(array_names(child(piece, "CellData")), CELL_ARRAYS);

    // Positions are bit-exact current positions.
    let points = f64s(&payload(child(child(piece, "Points"), "DataArray")));
    let expected: Vec<f64> = state.x.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    assert_eq!(points, expected);
    let displacement = f64s(&payload(named(child(piece, "PointData"), "displacement")));
    let u: Vec<f64> = state
        .x
        .iter()
        .zip(&model.x0)
        .flat_map(|(x, x0)| [x.x - x0.x, x.y - x0.y, x.z - x0.z])
        .collect();
    assert_eq!(displacement, u);
    for name in ["fibre_direction_warp", "fibre_direction_weft"] {
        let a = named(child(piece, "CellData"), name);
        assert_eq!(a.attribute("NumberOfComponents"), Some("3"));
        let v = f64s(&payload(a));
        assert_eq!(v.len(), 3 * n_cells);
        for d in v.chunks_exact(3) {
            assert!(
                (d[0].hypot(d[1]).hypot(d[2]) - 1.0).abs() < 1e-12,
                "{name}: {d:?}"
            );
        }
    }
    let resin = named(child(piece, "CellData"), "resin_stress");
    assert_eq!(resin.attribute("NumberOfComponents"), Some("3"));
    assert_eq!(f64s(&payload(resin)).len(), 3 * n_cells);

    let cells = child(piece, "Cells");
    let types = payload(named(cells, "types"));
    assert_eq!(types.len(), n_cells);
    assert!(types.iter().all(|&t| t == cell_type), "{types:?}");
    let offsets = payload(named(cells, "offsets"));
    let nodes_per_cell = if cell_type == 9 { 4 } else { 3 };
    let last = i64::from_le_bytes(offsets[offsets.len() - 8..].try_into().unwrap());
    assert_eq!(last as usize, nodes_per_cell * n_cells);
    let connectivity = payload(named(cells, "connectivity"));
    let first: Vec<i64> = connectivity[..8 * nodes_per_cell]
        .chunks_exact(8)
        .map(|c| i64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let batch_first: Vec<i64> = model.membranes[0]
        .element_nodes(0)
        .iter()
        .map(|&n| i64::from(n))
        .collect();
    assert_eq!(first, batch_first);
}

/// Runs `tests/check_vtu.py` on `series` when Python has meshio; prints a
/// note and returns otherwise.
fn check_with_meshio(series: &Path, points: usize, cells: usize, frames: usize) {
    let has_meshio = Command::new("python3")
        .args(["-c", "import meshio"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_meshio {
        eprintln!(
            "note: python3 with meshio not found; skipping tests/check_vtu.py (pip install meshio)"
        );
        return;
    }
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/check_vtu.py");
    let output = Command::new("python3")
        .arg(&script)
        .arg(series)
        .args([
            "--points",
            &points.to_string(),
            "--cells",
            &cells.to_string(),
        ])
        .args([
            "--point-data",
            &POINT_ARRAYS.join(","),
            "--cell-data",
            &CELL_ARRAYS.join(","),
        ])
        .args(["--frames", &frames.to_string()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "check_vtu.py failed:\n{stdout}\n{stderr}"
    );
    eprintln!("{stdout}");
    // And the checker does check: a wrong count fails.
    let wrong = Command::new("python3")
        .arg(&script)
        .arg(series)
        .args(["--points", &(points + 1).to_string()])
        .output()
        .unwrap();
    assert_eq!(wrong.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&wrong.stdout).contains("FAIL"));
}

fn frame<'a>(
    model: &'a Model,
    state: &'a State,
    fields: &'a drape_model::ElementFields,
    contact: Option<(&'a [Vector3<f64>], &'a [ContactStatus])>,
) -> FrameData<'a> {
    FrameData {
        model,
        state,
        fields,
        contact_force: contact.map(|c| c.0),
        contact_status: contact.map(|c| c.1),
        plies: None,
    }
}

/// Every file under `dir`, recursively.
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(walk(&path));
        } else {
            files.push(path);
        }
    }
    files
}

fn is_png(path: &Path) -> (u32, u32, usize) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let mut colours: Vec<&[u8]> = buf[..info.buffer_size()].chunks_exact(3).collect();
    colours.sort_unstable();
    colours.dedup();
    (info.width, info.height, colours.len())
}

#[test]
fn writes_a_complete_results_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let mut out = ResultsDir::create(&dir).unwrap();
    assert_eq!(out.path(), dir);
    assert!(dir.join("frames").is_dir());

    let model = model(ElementKind::Quad, 20);
    let start = model.initial_state();
    let start_fields = model.element_fields(&start).unwrap();
    out.write_frame(0, 0.0, &frame(&model, &start, &start_fields, None))
        .unwrap();
    // A run that stopped here still has a valid one-frame series.
    let series = read(&dir.join("series.pvd"));
    assert_eq!(series.matches("<DataSet ").count(), 1, "{series}");

    let state = draped(&model, 160.0, 0.025);
    let fields = model.element_fields(&state).unwrap();
    let force: Vec<Vector3<f64>> = state
        .x
        .iter()
        .map(|x| Vector3::new(0.0, 0.0, -(x.z + 1.0).min(0.0)))
        .collect();
    let status: Vec<ContactStatus> = state
        .x
        .iter()
        .map(|x| match x.x.hypot(x.y) {
            r if r < 40.0 => ContactStatus::Stick,
            r if r < 70.0 => ContactStatus::Slip,
            _ => ContactStatus::Open,
        })
        .collect();
    out.write_frame(
        1,
        0.025,
        &frame(&model, &state, &fields, Some((&force, &status))),
    )
    .unwrap();

    check_vtu(&dir.join("frames/frame_00000.vtu"), &model, &start, 0.0, 9);
    check_vtu(
        &dir.join("frames/frame_00001.vtu"),
        &model,
        &state,
        0.025,
        9,
    );
    let series_text = read(&dir.join("series.pvd"));
    let pvd = roxmltree::Document::parse(&series_text).unwrap();
    let sets: Vec<(String, String)> = pvd
        .descendants()
        .filter(|n| n.has_tag_name("DataSet"))
        .map(|n| {
            (
                n.attribute("timestep").unwrap().into(),
                n.attribute("file").unwrap().into(),
            )
        })
        .collect();
    assert_eq!(
        sets,
        [
            ("0".into(), "frames/frame_00000.vtu".into()),
            ("0.025".into(), "frames/frame_00001.vtu".into())
        ]
    );

    let energy = |t: f64| Energies {
        kinetic: 1.0 + t,
        strain: 2.0,
        internal_work: 2.5,
        viscous: 0.5,
        damping: 1e-12,
        external_work: 0.0,
        boundary_work: 3.5,
        contact_work: -0.25,
        friction_dissipation: 0.125,
        numerical_dissipation: 0.0625,
        confinement_work: 0.03125,
        balance_error: -1e-9,
        residual_work: 0.0,
    };
    let rows: Vec<EnergyRow> = (0..3)
        .map(|k| EnergyRow {
            time: 0.01 * k as f64,
            step: 100 * k,
            energy: energy(k as f64),
        })
        .collect();
    out.write_energy(&rows).unwrap();
    let csv = read(&dir.join("energy.csv"));
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "time,step,kinetic,strain,internal_work,viscous,damping,external_work,boundary_work,contact_work,friction_dissipation,numerical_dissipation,confinement_work,balance_error"
    );
    assert_eq!(lines.len(), 4);
    assert_eq!(
        lines[2],
        "0.01,100,2,2,2.5,0.5,1e-12,0,3.5,-0.25,0.125,0.0625,0.03125,-1e-9"
    );

    let measures = model.measures(&state, 45.0).unwrap();
    assert!(!measures.profile_diagonal.is_empty() && !measures.profile_median.is_empty());
    out.write_profiles(&measures).unwrap();
    let csv = read(&dir.join("profiles.csv"));
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("line,distance_mm,shear_deg"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let count = |line: &str| rows.iter().filter(|r| r[0] == line).count();
    assert_eq!(count("diagonal"), measures.profile_diagonal.len());
    assert_eq!(count("median"), measures.profile_median.len());
    assert_eq!(rows.len(), count("diagonal") + count("median"));
    let first: f64 = rows[0][2].parse().unwrap();
    assert_eq!(first, measures.profile_diagonal[0].shear_deg);

    let draw_in = measures.draw_in.unwrap();
    let summary = Summary {
        status: "completed".into(),
        reason: None,
        scene: "scenes/test.toml".into(),
        time: state.time,
        max_shear_deg: measures.max_shear_deg,
        max_shear_at: measures.max_shear_at,
        draw_in_mm: DrawInMm {
            dx: draw_in.dx,
            dy: draw_in.dy,
            dd: draw_in.dd,
        },
        max_fibre_tension_n: measures.max_fibre_tension_n,
        max_fibre_tension_n_per_mm: 0.25,
        area_above_locking_mm2: measures.area_above_locking,
        peak: Peaks {
            max_shear_deg: 31.25,
            max_shear_time_s: 0.02,
            ..Peaks::default()
        },
        max_waviness_deg: measures.max_waviness_deg,
        wrinkle_area_mm2: measures.wrinkle_area,
        fold: Some(drape_model::folds::FoldCheck {
            folded: true,
            turned_back_elements: 2,
            turned_back_area_mm2: 12.5,
            wavy_area_mm2: 40.0,
            wavy_area_limit_mm2: 200.0,
            worst: Some(drape_model::folds::FoldSite {
                element: 7,
                at: [1.0, -2.5, 3.0],
                turn_deg: 170.0,
                waviness_deg: 12.0,
            }),
            gathered: Some(drape_model::folds::Gathering {
                share: 0.03,
                shortest_stretch: 0.875,
                at: [-59.5, -56.25, -4.0],
            }),
        }),
        energy: EnergySummary {
            balance_error: 1e-4,
            kinetic_to_internal: 0.01,
            ..EnergySummary::default()
        },
        setup: Some(RunSetup {
            nodes: model.node_count(),
            fibres: "trusses".into(),
            mass_scaling_dt_s: Some(2e-5),
            ..RunSetup::default()
        }),
        run: RunInfo {
            device: None,
            wall_s: 1.5,
            steps: 1000,
            threads: 2,
            solver: "explicit".into(),
            ..RunInfo::default()
        },
        warnings: Vec::new(),
        ..Summary::default()
    };
    out.write_summary(&summary).unwrap();
    let json = read(&dir.join("summary.json"));
    assert!(json.starts_with("{\n  \"status\": \"completed\""), "{json}");
    assert!(!json.contains("reason"));
    assert!(!json.contains("warnings"), "no warnings, no field: {json}");
    let back: Summary = serde_json::from_str(&json).unwrap();
    assert_eq!(back, summary);

    out.write_pictures(&model, &state, &fields, &measures)
        .unwrap();
    let (w, h, colours) = is_png(&dir.join("shear_map.png"));
    assert_eq!((w, h), (1000, 820));
    assert!(
        colours > 50,
        "a colour map uses many colours, got {colours}"
    );
    let (w, h, colours) = is_png(&dir.join("profiles.png"));
    assert_eq!((w, h), (1000, 600));
    assert!(colours > 4, "{colours}");
    // One flat-blank panel with its colour bar.
    let (w, h, colours) = is_png(&dir.join("waviness_map.png"));
    assert_eq!((w, h), (620, 720));
    assert!(colours > 50, "{colours}");

    // Keep the directory for a person (or another reader) to look at.
    if let Some(keep) = std::env::var_os("DRAPE_KEEP_RESULTS") {
        let keep = PathBuf::from(keep);
        std::fs::create_dir_all(keep.join("frames")).unwrap();
        for entry in walk(&dir) {
            let relative = entry.strip_prefix(&dir).unwrap();
            std::fs::copy(&entry, keep.join(relative)).unwrap();
        }
    }

    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert!(
        !names.iter().any(|n| n.contains(".tmp")),
        "temporary left: {names:?}"
    );

    check_with_meshio(
        &dir.join("series.pvd"),
        model.node_count(),
        model.membrane_count(),
        2,
    );

    // Reusing the directory (once the first run has let it go) starts a
    // new run: no frame of the old one stays.
    drop(out);
    let mut again = ResultsDir::create(&dir).unwrap();
    assert!(!dir.join("series.pvd").exists());
    assert!(!dir.join("frames/frame_00001.vtu").exists());
    assert!(!dir.join("summary.json").exists());
    again
        .write_frame(0, 0.0, &frame(&model, &start, &start_fields, None))
        .unwrap();
    assert_eq!(
        read(&dir.join("series.pvd")).matches("<DataSet ").count(),
        1
    );
}

#[test]
fn triangles_are_vtk_triangles() {
    let tmp = tempfile::tempdir().unwrap();
    let mut out = ResultsDir::create(tmp.path()).unwrap();
    let model = model(ElementKind::Triangle, 6);
    let state = draped(&model, 150.0, 1.0);
    let fields = model.element_fields(&state).unwrap();
    out.write_frame(3, 1.0, &frame(&model, &state, &fields, None))
        .unwrap();
    check_vtu(
        &tmp.path().join("frames/frame_00003.vtu"),
        &model,
        &state,
        1.0,
        5,
    );
    check_with_meshio(
        &tmp.path().join("series.pvd"),
        model.node_count(),
        model.membrane_count(),
        1,
    );
    // A model that is not a blank has no profiles: the plot says so.
    let measures = drape_model::Measures::default();
    out.write_pictures(&model, &state, &fields, &measures)
        .unwrap();
}

#[test]
fn errors_name_the_path_instead_of_panicking() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("not-a-directory");
    std::fs::write(&file, b"x").unwrap();
    let error = ResultsDir::create(&file.join("run")).err().unwrap();
    assert!(error.path.starts_with(&file), "{error}");
    assert!(error.to_string().contains("not-a-directory"), "{error}");

    // Arrays that do not fit the model: an error naming the frame file,
    // and nothing written.
    let mut out = ResultsDir::create(&tmp.path().join("run")).unwrap();
    let model = model(ElementKind::Quad, 4);
    let state = model.initial_state();
    let mut fields = model.element_fields(&state).unwrap();
    fields.shear.pop();
    let error = out
        .write_frame(0, 0.0, &frame(&model, &state, &fields, None))
        .unwrap_err();
    assert_eq!(error.source.kind(), std::io::ErrorKind::InvalidInput);
    assert!(error.path.ends_with("frames/frame_00000.vtu"), "{error}");
    assert!(error.to_string().contains("fields.shear"), "{error}");
    assert!(!error.path.exists());
    assert!(!tmp.path().join("run/series.pvd").exists());

    // The directory vanished under a running writer.
    std::fs::remove_dir_all(tmp.path().join("run")).unwrap();
    let error = out
        .write_profiles(&drape_model::Measures::default())
        .unwrap_err();
    assert!(error.path.ends_with("profiles.csv"), "{error}");
}

#[test]
fn one_run_per_folder_and_a_killed_runs_temporaries_are_cleared() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    // What a run killed between writing and renaming leaves.
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    for left in [".summary.json.tmp4242", "frames/.frame_00003.vtu.tmp4242"] {
        std::fs::write(dir.join(left), b"half").unwrap();
    }
    std::fs::write(dir.join("notes.txt"), b"mine").unwrap();
    let first = ResultsDir::create(&dir).unwrap();
    assert!(!dir.join(".summary.json.tmp4242").exists());
    assert!(!dir.join("frames/.frame_00003.vtu.tmp4242").exists());
    assert!(
        dir.join("notes.txt").exists(),
        "a user's file is left alone"
    );

    // A second claim while the first holds the folder: refused, naming the
    // holder, and nothing removed.
    first.write_energy(&[]).unwrap();
    let busy = ResultsDir::create(&dir).err().unwrap();
    assert_eq!(
        busy.source.kind(),
        std::io::ErrorKind::ResourceBusy,
        "{busy}"
    );
    assert!(
        busy.to_string().contains(&format!(
            "another drape run (process {})",
            std::process::id()
        )),
        "{busy}"
    );
    assert!(ResultsDir::reopen(&dir, &[]).is_err());
    assert!(dir.join("energy.csv").exists());
    drop(first);
    // Released with its holder.
    let again = ResultsDir::create(&dir).unwrap();
    assert!(!dir.join("energy.csv").exists());
    drop(again);
}
