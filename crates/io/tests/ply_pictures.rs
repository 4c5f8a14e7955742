//! The pictures of a laminate, one per ply, and of one ply, as before:
//! a two-ply model draped on a sphere writes `shear_3d_<ply>.png`,
//! `waviness_map_<ply>.png` and `profiles_<ply>.png` in place of the
//! overlaid `shear_3d.png`, `waviness_map.png` and `profiles.png` (and
//! `shear_map_<ply>.png` beside `shear_map.png`), and each ply's own rows
//! in `profiles.csv`;
//! a one-ply model writes the one-ply files, byte for byte those drape
//! wrote before laminates had their own pictures.

use std::path::Path;

use drape_constitutive::Material;
use drape_io::results::{PlyPicture, ResultsDir, ToolMeshes, ply_picture_of};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::stack::PlyModel;
use drape_model::{Model, State};
use nalgebra::Vector3;

/// A 100 mm square of glass, `cells` × `cells` quads.
fn blank(cells: usize) -> RectangleBlank {
    RectangleBlank {
        width: 100.0,
        height: 100.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([cells, cells]),
        fibres: FibreRepresentation::Embedded,
    }
}

fn glass() -> Material {
    Material::preset("glass-serge-4x3").unwrap()
}

/// Every node laid on a sphere of radius 80 mm under the blank's centre by
/// the azimuthal equidistant map: shear grows towards the diagonals.
fn draped(model: &Model) -> State {
    let r = 80.0;
    let mut state = model.initial_state();
    state.time = 1.0;
    for x in &mut state.x {
        let rho = x.x.hypot(x.y);
        let phi = rho / r;
        let s = if rho > 0.0 { r * phi.sin() / rho } else { 1.0 };
        *x = Vector3::new(x.x * s, x.y * s, r * phi.cos() - r + x.z);
    }
    state
}

/// Writes every picture of `model` at `state` into `dir`; the names of the
/// PNG files there, sorted.
fn pictures(dir: &Path, model: &Model, state: &State) -> Vec<String> {
    let out = ResultsDir::create(dir).unwrap();
    let fields = model.element_fields(state).unwrap();
    let measures = model.measures(state, 50.0).unwrap();
    out.write_pictures(model, state, &fields, &measures)
        .unwrap();
    let tools = ToolMeshes::new(&[], &model.x0);
    out.write_view(model, state, &fields, &tools, &[]).unwrap();
    png_names(dir)
}

fn png_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".png"))
        .collect();
    names.sort();
    names
}

/// FNV-1a, 64 bits: a fingerprint of a file that no library update
/// changes.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

#[test]
fn one_ply_pictures_are_byte_identical_to_those_before_per_ply_pictures() {
    let tmp = tempfile::tempdir().unwrap();
    let model = Model::from_blank(&blank(8), &glass()).unwrap();
    let names = pictures(tmp.path(), &model, &draped(&model));
    assert_eq!(
        names,
        [
            "profiles.png",
            "shear_3d.png",
            "shear_map.png",
            "waviness_map.png"
        ]
    );
    // Written by commit 308f8fe (before the plies had pictures of their
    // own) from this model and state.
    let print = |name: &str| fnv1a(&std::fs::read(tmp.path().join(name)).unwrap());
    let prints: Vec<(&str, u64)> = names.iter().map(|n| (n.as_str(), print(n))).collect();
    assert_eq!(
        prints,
        [
            ("profiles.png", 0x4143_a423_2342_45f7),
            ("shear_3d.png", 0x7e74_ec5e_3805_6f3d),
            ("shear_map.png", 0x4093_c2af_98f6_9937),
            ("waviness_map.png", 0x54b9_375d_72e4_2842)
        ],
        "{prints:x?}"
    );
}

#[test]
fn a_laminate_writes_one_oblique_view_and_one_waviness_map_per_ply() {
    let tmp = tempfile::tempdir().unwrap();
    let material = glass();
    let ply = |name: &str, cells: usize| PlyModel {
        model: Model::from_blank(&blank(cells), &material).unwrap(),
        name: name.into(),
        thickness: material.thickness,
        orientation_deg: 0.0,
        friction_below: 0.0,
    };
    let model = Model::stack(vec![ply("low", 8), ply("high", 6)]).unwrap();
    let names = pictures(tmp.path(), &model, &draped(&model));
    assert_eq!(
        names,
        [
            "profiles_high.png",
            "profiles_low.png",
            "shear_3d_high.png",
            "shear_3d_low.png",
            "shear_map.png",
            "shear_map_high.png",
            "shear_map_low.png",
            "waviness_map_high.png",
            "waviness_map_low.png"
        ]
    );
    assert_eq!(
        ply_picture_of(PlyPicture::Shear3d, "low"),
        "shear_3d_low.png"
    );
    let bytes = |name: &str| std::fs::read(tmp.path().join(name)).unwrap();
    for picture in ["shear_3d", "waviness_map", "profiles"] {
        let [low, high] = ["low", "high"].map(|p| bytes(&format!("{picture}_{p}.png")));
        assert_ne!(low, high, "{picture}");
    }
    // The next run into the folder starts without them.
    let _again = ResultsDir::create(tmp.path()).unwrap();
    assert_eq!(png_names(tmp.path()), Vec::<String>::new());
}

/// A two-ply stack, `low` (8 × 8 cells) under `high` (6 × 6).
fn two_plies(material: &Material) -> Model {
    let ply = |name: &str, cells: usize| PlyModel {
        model: Model::from_blank(&blank(cells), material).unwrap(),
        name: name.into(),
        thickness: material.thickness,
        orientation_deg: 0.0,
        friction_below: 0.0,
    };
    Model::stack(vec![ply("low", 8), ply("high", 6)]).unwrap()
}

/// `profiles.csv` of `model` at `state` written into `dir`.
fn profiles_csv(dir: &Path, model: &Model, state: &State) -> String {
    let out = ResultsDir::create(dir).unwrap();
    out.write_profiles(&model.measures(state, 50.0).unwrap())
        .unwrap();
    std::fs::read_to_string(dir.join("profiles.csv")).unwrap()
}

#[test]
fn one_ply_profiles_csv_is_byte_identical_to_the_one_before_per_ply_profiles() {
    let tmp = tempfile::tempdir().unwrap();
    let model = Model::from_blank(&blank(8), &glass()).unwrap();
    let csv = profiles_csv(tmp.path(), &model, &draped(&model));
    assert!(
        csv.starts_with("line,distance_mm,shear_deg\ndiagonal,"),
        "{csv}"
    );
    // Written by commit 4891f49 (before a laminate's profiles were per
    // ply) from this model and state.
    assert_eq!(
        fnv1a(csv.as_bytes()),
        0xea18_02b2_8935_83f5,
        "{:x}",
        fnv1a(csv.as_bytes())
    );
}

/// Each ply of a laminate has its own rows in `profiles.csv`, under a
/// `ply` column: the rows of that ply formed alone (the draped map moves
/// a ply's nodes as it moves the ply alone, lifted by its height), not
/// the elements of every ply near the bottom ply's lines.
#[test]
fn a_laminate_writes_each_plys_own_profiles_under_a_ply_column() {
    let material = glass();
    let model = two_plies(&material);
    let tmp = tempfile::tempdir().unwrap();
    let csv = profiles_csv(tmp.path(), &model, &draped(&model));
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("ply,line,distance_mm,shear_deg"));
    let rows: Vec<(String, String, f64, f64)> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 4, "{l}");
            (
                f[0].into(),
                f[1].into(),
                f[2].parse().unwrap(),
                f[3].parse().unwrap(),
            )
        })
        .collect();
    for (name, cells) in [("low", 8), ("high", 6)] {
        let alone = Model::from_blank(&blank(cells), &material).unwrap();
        let m = alone.measures(&draped(&alone), 50.0).unwrap();
        let expected: Vec<(&str, f64, f64)> = [
            ("diagonal", &m.profile_diagonal),
            ("median", &m.profile_median),
        ]
        .into_iter()
        .flat_map(|(line, points)| points.iter().map(move |p| (line, p.distance, p.shear_deg)))
        .collect();
        let got: Vec<&(String, String, f64, f64)> = rows.iter().filter(|r| r.0 == name).collect();
        assert_eq!(got.len(), expected.len(), "{name}: {csv}");
        assert!(
            expected.iter().any(|e| e.2.abs() > 1.0),
            "{name}: no shear to compare"
        );
        for (g, e) in got.iter().zip(&expected) {
            assert_eq!((g.1.as_str(), g.2), (e.0, e.1), "{name}");
            // The lifted ply's edges differ from the ply's alone in the
            // last bits of z only.
            assert!((g.3 - e.2).abs() <= 1e-9, "{name}: {g:?} against {e:?}");
        }
    }
    // Bottom to top, nothing else.
    let names: Vec<&str> = rows.iter().map(|r| r.0.as_str()).collect();
    let switch = names.iter().position(|n| *n == "high").unwrap();
    assert!(
        names[..switch].iter().all(|n| *n == "low") && names[switch..].iter().all(|n| *n == "high")
    );
    // The model's own profile is the bottom ply's, not both plies mixed.
    let m = model.measures(&draped(&model), 50.0).unwrap();
    assert_eq!(m.profile_diagonal, m.ply_profiles[0].diagonal);
    assert_eq!(m.profile_median, m.ply_profiles[0].median);
}
