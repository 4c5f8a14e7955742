//! A user's own files in their own units, end to end: `drape export
//! --onto` an Abaqus/CAE structural mesh in metres (`--units m`), and a
//! mould mesh that the blank never comes near (a mesh in metres read as
//! millimetres) named in a warning at the end of the run, beside the
//! units warning of its size.

use std::path::Path;

mod common;
use common::*;

/// A run's `orientations.inp` as drape writes it: a flat 20 × 10 mm ply of
/// two quads at z = 0, warp along x, weft along y, no shear, 0.5 mm thick
/// (0.4 mm in element 2).
const ORIENTATIONS: &str = "\
** drape: draped fibre orientations, a hand-made ply
*NODE, NSET=DRAPE_NODES
1, 0, 0, 0
2, 10, 0, 0
3, 20, 0, 0
4, 0, 10, 0
5, 10, 10, 0
6, 20, 10, 0
*ELEMENT, TYPE=S4R, ELSET=DRAPE_QUADS
1, 1, 2, 5, 4
2, 2, 3, 6, 5
*ELSET, ELSET=DRAPE_PLY
DRAPE_QUADS
*DISTRIBUTION TABLE, NAME=DRAPE_AXES_TABLE
COORD3D, COORD3D
*DISTRIBUTION, NAME=DRAPE_AXES, LOCATION=ELEMENT, TABLE=DRAPE_AXES_TABLE
, 1, 0, 0, 0, 1, 0
1, 1, 0, 0, 0, 1, 0
2, 1, 0, 0, 0, 1, 0
*DISTRIBUTION TABLE, NAME=DRAPE_YARN_ANGLE_TABLE
ANGLE
*DISTRIBUTION, NAME=DRAPE_YARN_ANGLE, LOCATION=ELEMENT, TABLE=DRAPE_YARN_ANGLE_TABLE
, 90
1, 90
2, 90
*DISTRIBUTION TABLE, NAME=DRAPE_THICKNESS_TABLE
LENGTH
*DISTRIBUTION, NAME=DRAPE_THICKNESS, LOCATION=ELEMENT, TABLE=DRAPE_THICKNESS_TABLE
, 0.5
1, 0.5
2, 0.4
*ORIENTATION, NAME=DRAPE_WARP, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR
DRAPE_AXES
3, 0
*ORIENTATION, NAME=DRAPE_WEFT, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR
DRAPE_AXES
3, DRAPE_YARN_ANGLE
";

/// The same ply as an Abaqus/CAE structural model in metres: a shell part
/// of two S4R elements 0.1 m below, its instance translated 0.1 m up (onto
/// the formed ply), a reference point at the assembly level whose label 1
/// is also the part's first node's, a section and a step.
const SKIN_IN_METRES: &str = "\
*Heading
** Job name: skin Model name: Model-1
*Part, name=Skin
*Node
      1,           0.,           0.,        -0.1
      2,         0.01,           0.,        -0.1
      3,         0.02,           0.,        -0.1
      4,           0.,         0.01,        -0.1
      5,         0.01,         0.01,        -0.1
      6,         0.02,         0.01,        -0.1
*Element, type=S4R
101, 1, 2, 5, 4
102, 2, 3, 6, 5
*Elset, elset=skin
 101, 102
*Shell Section, elset=skin, material=cfrp
0.0005, 5
*End Part
*Assembly, name=Assembly
*Instance, name=Skin-1, part=Skin
          0.,           0.,         0.1
*End Instance
*Node
      1,           0.,           0.,           1.
*Nset, nset=Skin-RefPt_, internal
1,
*End Assembly
*Material, name=cfrp
*Elastic
70e9, 0.1
";

fn setup(dir: &Path) {
    let run = dir.join("run");
    std::fs::create_dir_all(&run).unwrap();
    std::fs::write(run.join("orientations.inp"), ORIENTATIONS).unwrap();
    std::fs::write(dir.join("skin.inp"), SKIN_IN_METRES).unwrap();
}

#[test]
fn export_onto_a_cae_file_in_metres() {
    let dir = temp("export-m");
    setup(&dir);
    let (run, skin, out) = (dir.join("run"), dir.join("skin.inp"), dir.join("mapped"));
    let export = |units: &[&str]| {
        let mut args = vec![
            "export",
            run.to_str().unwrap(),
            "--onto",
            skin.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(units);
        drape(&args)
    };
    let o = export(&["--units", "m"]);
    let said = text(&o);
    assert!(o.status.success(), "{said}");
    assert!(said.contains("mapped            2 elements"), "{said}");
    // On the part: both centroids lie in the formed ply (distances in mm).
    assert!(
        said.contains("distance          largest 0.0000 mm"),
        "{said}"
    );
    assert!(!said.contains("warning"), "{said}");
    assert!(said.contains("(lengths in m)"), "{said}");
    let inp = std::fs::read_to_string(out.join("orientations_skin.inp")).unwrap();
    assert!(inp.contains("** Units m."), "{inp}");
    // The thickness in metres, for a model in metres: the structural
    // elements' centroids are the formed ones', which take the formed
    // elements' own values (0.5 and 0.4 mm).
    let thickness: Vec<f64> = inp
        .split("TABLE=DRAPE_THICKNESS_TABLE\n")
        .nth(1)
        .unwrap()
        .lines()
        .take(3)
        .map(|l| l.rsplit(", ").next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(thickness.len(), 3, "{inp}");
    for (got, want) in thickness.iter().zip([0.0005, 0.0005, 0.0004]) {
        assert!((got - want).abs() < 1e-15, "{got} != {want}\n{inp}");
    }
    assert!(
        inp.contains("101, 1, 0, 0, 0, 1, 0\n102, 1, 0, 0, 0, 1, 0\n"),
        "{inp}"
    );
    // The CSV stays in mm: centroids at x = 5 and 15 mm, z = 0.
    let csv = std::fs::read_to_string(out.join("orientations_skin.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 2, "{csv}");
    for (row, (label, x)) in rows.iter().zip([(101.0, 5.0), (102.0, 15.0)]) {
        assert_eq!(row[0], label, "{csv}");
        assert!(
            (row[1] - x).abs() < 1e-12 && (row[2] - 5.0).abs() < 1e-12,
            "{csv}"
        );
        assert!(row[3].abs() < 1e-12, "{csv}");
        assert!(row.last().unwrap().abs() < 1e-12, "{csv}");
    }

    // The same with --scale 1000 (mm per unit).
    let o = export(&["--scale", "1000"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        std::fs::read_to_string(out.join("orientations_skin.inp"))
            .unwrap()
            .contains("** Units mesh units (1 = 1000 mm).")
    );

    // Without --units the mesh is 0.02 mm across: a warning says so.
    let o = export(&[]);
    let said = text(&o);
    assert!(o.status.success(), "{said}");
    assert!(
        said.contains("mm across in mm: is it in another unit? give --units"),
        "{said}"
    );

    // Bad units and a file with two instances are bad input.
    let o = export(&["--units", "ft"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = export(&["--scale=0"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("--scale 0: expected a positive"),
        "{}",
        text(&o)
    );
    std::fs::write(
        &skin,
        SKIN_IN_METRES.replace(
            "*End Instance\n",
            "*End Instance\n*Instance, name=Skin-2, part=Skin\n*End Instance\n",
        ),
    )
    .unwrap();
    let o = export(&["--units", "m"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("2 instances (Skin-1, Skin-2)"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A 10 × 10 mm blank of 2 × 2 cells at rest, and one fixed mesh tool
/// (`geometry`), for a run of 1 ms.
fn scene(geometry: &str) -> String {
    format!(
        "[simulation]\nend_time = 0.001\nframes = 2\n\n[fabric]\nmaterial = \"glass-serge-4x3\"\n\
         fibres = \"trusses\"\nblank = {{ width = 10, height = 10, cells = [2, 2] }}\n\n\
         [[tools]]\nname = \"mould\"\ngeometry = {geometry}\n"
    )
}

#[test]
fn a_mould_the_blank_never_nears_is_named_at_the_end() {
    let dir = temp("untouched");
    // A 0.5 m square plate written in metres at x, y = 20…20.5 m: read
    // as mm it is a 0.5 mm speck 20 mm from the blank's corner.
    std::fs::write(
        dir.join("plate.stl"),
        "solid plate\n facet normal 0 0 1\n  outer loop\n   vertex 20 20 0\n   vertex 20.5 20 0\n   \
         vertex 20.5 20.5 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n   \
         vertex 20 20 0\n   vertex 20.5 20.5 0\n   vertex 20 20.5 0\n  endloop\n endfacet\n\
         endsolid plate\n",
    )
    .unwrap();
    let run = |name: &str, geometry: &str| {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, scene(geometry)).unwrap();
        let out = dir.join(name);
        let o = drape(&[
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", text(&o));
        (text(&o), json(&out.join("summary.json")))
    };
    // No node lies over the speck, so the side of this open mesh cannot be
    // detected from the blank: it is given; and the speck lies in the
    // blank's plane, where a rim extension would reach the blank's corner.
    let (said, summary) = run(
        "speck",
        r#"{ kind = "mesh", file = "plate.stl", flip_normals = false, rim_extension = 0 }"#,
    );
    let warnings: Vec<String> = summary["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap().to_owned())
        .collect();
    let size = warnings
        .iter()
        .find(|w| w.contains("mm across"))
        .unwrap_or_else(|| panic!("{warnings:?}"));
    assert!(size.contains("tools[0].geometry.units"), "{size}");
    let near = warnings
        .iter()
        .find(|w| w.contains("never came near the blank"))
        .unwrap_or_else(|| panic!("{warnings:?}"));
    assert!(
        near.contains("tool `mould` (tools[0])")
            && near.contains("contact margin (5 mm)")
            && near.contains("units = \"m\""),
        "{near}"
    );
    assert!(said.contains("never came near the blank"), "{said}");

    // In metres and moved under the blank (1 mm below it): near from the
    // start, no warning.
    let (said, summary) = run(
        "under",
        r#"{ kind = "mesh", file = "plate.stl", units = "m", offset = [-20250, -20250, -1] }"#,
    );
    // (An empty list is left out of the summary.)
    assert_eq!(
        summary["warnings"].as_array().map_or(0, Vec::len),
        0,
        "{said}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
