//! A female tray mould for the mesh-against-analytic step ratio of
//! `step_profile`: one round, double-curved dish (a spherical cavity, a
//! conical wall, a convex fillet and a flat flange with an open outer rim)
//! written twice, as a surface of revolution and as a ≈ 7 000-triangle OBJ
//! mesh of the same profile, with the same blank, punch and springs. The
//! two scenes differ only in the mould's representation, so the ratio of
//! their step times is what a triangle mesh costs over an analytic tool.
//!
//! The mesh is generated here (not read from the repository) so that the
//! bench depends on nothing but itself.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One segment of the profile in the (r, z) half-plane, from the axis out.
enum Segment {
    Line {
        from: [f64; 2],
        to: [f64; 2],
    },
    Arc {
        center: [f64; 2],
        radius: f64,
        from_deg: f64,
        to_deg: f64,
    },
}

impl Segment {
    fn at(&self, s: f64) -> [f64; 2] {
        match *self {
            Self::Line { from, to } => [
                from[0] + s * (to[0] - from[0]),
                from[1] + s * (to[1] - from[1]),
            ],
            Self::Arc {
                center,
                radius,
                from_deg,
                to_deg,
            } => {
                let a = (from_deg + s * (to_deg - from_deg)).to_radians();
                [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
            }
        }
    }

    fn length(&self) -> f64 {
        match *self {
            Self::Line { from, to } => (to[0] - from[0]).hypot(to[1] - from[1]),
            Self::Arc {
                radius,
                from_deg,
                to_deg,
                ..
            } => radius * (to_deg - from_deg).abs().to_radians(),
        }
    }

    fn toml(&self) -> String {
        match *self {
            Self::Line { from, to } => format!(
                "{{ kind = \"line\", from = [{:.12}, {:.12}], to = [{:.12}, {:.12}] }}",
                from[0], from[1], to[0], to[1]
            ),
            Self::Arc {
                center,
                radius,
                from_deg,
                to_deg,
            } => format!(
                "{{ kind = \"arc\", center = [{:.12}, {:.12}], radius = {radius}, from_deg = {from_deg}, to_deg = {to_deg} }}",
                center[0], center[1]
            ),
        }
    }
}

/// The dish's profile, flange at z = 0, fabric above (on the left of the
/// travel from the axis out): a cavity of radius 150 out to 30° of slope, a
/// 30° wall, a convex fillet of radius 20 into the flange (38 mm deep in
/// all), the flange out to r = 200 (its end is the open rim).
fn profile() -> Vec<Segment> {
    let (r_cavity, wall, r_fillet, r_rim) = (150.0, 30.0, 20.0, 200.0);
    let slope = 30.0f64;
    let (s, c) = slope.to_radians().sin_cos();
    // From the bottom (r = 0, z = 0 for now; shifted below).
    let a_end = [r_cavity * s, r_cavity * (1.0 - c)];
    let w_end = [a_end[0] + wall * c, a_end[1] + wall * s];
    // A clockwise arc from 90° + slope to 90°, its start at the wall's end.
    let f_center = [w_end[0] + r_fillet * s, w_end[1] - r_fillet * c];
    let top = f_center[1] + r_fillet;
    let shift = |p: [f64; 2]| [p[0], p[1] - top];
    vec![
        Segment::Arc {
            center: shift([0.0, r_cavity]),
            radius: r_cavity,
            from_deg: -90.0,
            to_deg: -90.0 + slope,
        },
        Segment::Line {
            from: shift(a_end),
            to: shift(w_end),
        },
        Segment::Arc {
            center: shift(f_center),
            radius: r_fillet,
            from_deg: 90.0 + slope,
            to_deg: 90.0,
        },
        Segment::Line {
            from: shift([f_center[0], top]),
            to: [r_rim, 0.0],
        },
    ]
}

/// The profile sampled at `rings` + 1 points spread by arc length (the
/// segments' ends among them), from the axis out.
fn sampled(profile: &[Segment], rings: usize) -> Vec<[f64; 2]> {
    let total: f64 = profile.iter().map(Segment::length).sum();
    let mut points = vec![profile[0].at(0.0)];
    for seg in profile {
        let n = ((seg.length() / total * rings as f64).round() as usize).max(1);
        points.extend((1..=n).map(|k| seg.at(k as f64 / n as f64)));
    }
    points
}

/// The dish as a triangle mesh: `sectors` around, counter-clockwise seen
/// from the fabric's side (above); a fan at the axis, two triangles per
/// cell elsewhere. Returns the OBJ text and the triangle count.
fn obj(profile: &[Segment], rings: usize, sectors: usize) -> (String, usize) {
    let points = sampled(profile, rings);
    let mut text = String::from("# drape bench: a round tray mould, open at its outer rim\n");
    writeln!(text, "v 0 0 {:.15}", points[0][1]).unwrap();
    for p in &points[1..] {
        for j in 0..sectors {
            let a = std::f64::consts::TAU * j as f64 / sectors as f64;
            writeln!(
                text,
                "v {:.15} {:.15} {:.15}",
                p[0] * a.cos(),
                p[0] * a.sin(),
                p[1]
            )
            .unwrap();
        }
    }
    // OBJ indices from 1: the centre is 1, ring i ≥ 1 sector j is
    // 2 + (i − 1)·sectors + j.
    let v = |i: usize, j: usize| 2 + (i - 1) * sectors + j % sectors;
    let mut triangles = 0;
    for j in 0..sectors {
        writeln!(text, "f 1 {} {}", v(1, j), v(1, j + 1)).unwrap();
        triangles += 1;
    }
    for i in 1..points.len() - 1 {
        for j in 0..sectors {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            writeln!(text, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
            triangles += 2;
        }
    }
    (text, triangles)
}

/// The scene text around a mould `geometry`.
fn scene(geometry: &str, end_time: f64) -> String {
    format!(
        r#"# drape bench: a 280 × 280 mm carbon blank pressed into a round tray
# mould by a hemispherical punch ({end_time} s stroke, mass-scaled).
gravity = [0, 0, -9810]

[simulation]
end_time = {end_time}
frames = 2
mass_scaling_dt = 2e-5

[fabric]
material = "carbon-prepreg-2x2"
orientation_deg = 0
fibres = "trusses"
blank = {{ width = 280, height = 280, cells = [40, 40], center = [0, 0, 0.5] }}

[[tools]]
name = "mould"
friction = 0.1
geometry = {geometry}

[[tools]]
name = "punch"
friction = 0.1
geometry = {{ kind = "hemispherical_punch", pointing = "down", pole = [0, 0, 1.0], radius = 70, shank = 60 }}
motion = {{ kind = "displacement", direction = [0, 0, -1], distance = 38, amplitude = {{ kind = "smooth_step", duration = {end_time} }} }}

[[springs]]
nodes = ["corners", "edge_midpoints"]
stiffness = 1.0
"#
    )
}

/// Writes the two scenes (and the mesh) into `dir`: (mesh scene, analytic
/// scene, triangle count).
pub fn write_scenes(dir: &Path, end_time: f64) -> (PathBuf, PathBuf, usize) {
    std::fs::create_dir_all(dir).expect("the tray bench's folder");
    let profile = profile();
    let (mesh, triangles) = obj(&profile, 55, 64);
    std::fs::write(dir.join("tray.obj"), mesh).expect("tray.obj");
    let segments: Vec<String> = profile.iter().map(Segment::toml).collect();
    let revolution = format!(
        "{{ kind = \"revolution\", origin = [0, 0, 0], profile = [{}] }}",
        segments.join(", ")
    );
    let analytic = dir.join("tray-revolution.toml");
    let meshed = dir.join("tray-mesh.toml");
    std::fs::write(&analytic, scene(&revolution, end_time)).expect("tray-revolution.toml");
    std::fs::write(
        &meshed,
        scene("{ kind = \"mesh\", file = \"tray.obj\" }", end_time),
    )
    .expect("tray-mesh.toml");
    (meshed, analytic, triangles)
}
