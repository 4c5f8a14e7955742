//! `cargo xtask mould`: a generated open female mould, a double-curved
//! tray, written as a binary STL or an OBJ, with a matched punch beside it
//! if asked. It stands in for a user's own CAD export (no one's real
//! part): open at its outer rim, its normals pointing away from the cavity
//! as an Abaqus rigid-surface export of a female mould has them, so a
//! scene must find the fabric's side itself.
//!
//! The tray (mm, z up): a 600 × 400 flange outline, the open rim; a
//! 500 × 300 cavity opening, a rectangle with 90 mm corner radii, 80 mm
//! deep; walls at 60° from the horizontal between a 15 mm fillet at the
//! flange and a 25 mm fillet at the bottom; the whole tray bent into a
//! bowl, z += x²/(2·4000) + y²/(2·3000), so flange and bottom are double
//! curved. It is a height field z = h(x, y) over the flange outline,
//! triangulated on a grid refined where the walls are, the cells' diagonals
//! mirrored between quadrants so the mesh has the tray's two mirror
//! planes. The punch is the same surface moved `--offset` along its
//! normals (the ply's thickness), with the same winding.
//!
//! `--depth` and `--corner` change the cavity's depth and the opening's
//! corner radius (the defaults above: the shipped `tray-mould.stl`): the
//! shallower trays against which `xtask/src/validate/tray.rs` measured
//! whether the shipped tray's disagreement with the kinematic net is its
//! depth's.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// What to write.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    out: PathBuf,
    triangles: usize,
    punch: Option<PathBuf>,
    offset: f64,
    shape: Shape,
}

/// The tray's free dimensions (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shape {
    /// The cavity's depth below the flange (before the bowl's curvature).
    pub depth: f64,
    /// The cavity opening's corner radius in plan.
    pub corner: f64,
}

impl Default for Shape {
    fn default() -> Self {
        Self {
            depth: DEPTH,
            corner: CORNER,
        }
    }
}

/// The flange's outline, half sizes (mm): the open rim.
const OUTLINE: [f64; 2] = [300.0, 200.0];
/// The cavity opening, half sizes, and its corner radius (mm).
const OPENING: [f64; 2] = [250.0, 150.0];
const CORNER: f64 = 90.0;
/// Depth, wall angle from the horizontal (degrees), fillet radii (mm).
const DEPTH: f64 = 80.0;
const WALL_DEG: f64 = 60.0;
const TOP_FILLET: f64 = 15.0;
const BOTTOM_FILLET: f64 = 25.0;
/// The bowl's radii of curvature along x and y (mm).
const BOWL: [f64; 2] = [4000.0, 3000.0];

impl Options {
    /// Parses `OUT [--triangles N] [--punch FILE] [--offset MM]`.
    pub fn parse(args: &[String]) -> Result<Self, String> {
        let mut out = None;
        let mut triangles = 3000;
        let mut punch = None;
        let mut offset = 0.57;
        let mut shape = Shape::default();
        let mut it = args.iter();
        while let Some(a) = it.next() {
            let mut value = |name: &str| {
                it.next()
                    .cloned()
                    .ok_or_else(|| format!("`{name}` needs a value"))
            };
            match a.as_str() {
                "--triangles" => {
                    let v = value("--triangles")?;
                    triangles = v
                        .parse()
                        .ok()
                        .filter(|&n: &usize| (200..=10_000_000).contains(&n))
                        .ok_or_else(|| {
                            format!(
                                "--triangles `{v}`: expected a whole number from 200 to 10000000"
                            )
                        })?;
                }
                "--punch" => punch = Some(PathBuf::from(value("--punch")?)),
                "--offset" => {
                    let v = value("--offset")?;
                    offset = v
                        .parse()
                        .ok()
                        .filter(|o: &f64| o.is_finite() && *o >= 0.0 && *o < 10.0)
                        .ok_or_else(|| {
                            format!("--offset `{v}`: expected a distance in mm from 0 to 10")
                        })?;
                }
                "--depth" => {
                    let v = value("--depth")?;
                    shape.depth = v
                        .parse()
                        .ok()
                        .filter(|d: &f64| (2.0 * TOP_FILLET..=150.0).contains(d))
                        .ok_or_else(|| {
                            format!(
                                "--depth `{v}`: expected a depth in mm from {} (the fillets) to 150",
                                2.0 * TOP_FILLET
                            )
                        })?;
                }
                "--corner" => {
                    let v = value("--corner")?;
                    shape.corner = v
                        .parse()
                        .ok()
                        .filter(|r: &f64| *r > 0.0 && *r <= OPENING[1])
                        .ok_or_else(|| {
                            format!(
                                "--corner `{v}`: expected a radius in mm above 0 and at most {} \
                                 (the opening's half width)",
                                OPENING[1]
                            )
                        })?;
                }
                other if other.starts_with("--") => {
                    return Err(format!("mould: unknown option `{other}`"));
                }
                path if out.is_none() => out = Some(PathBuf::from(path)),
                extra => return Err(format!("mould: one output file, got a second `{extra}`")),
            }
        }
        let out = out.ok_or("mould: give the output file (.stl or .obj)")?;
        for p in std::iter::once(&out).chain(&punch) {
            format_of(p)?;
        }
        if shape.corner <= wall_width(&shape) {
            return Err(format!(
                "--corner {}: at most the walls' width in plan ({:.1} mm at depth {}) leaves \
                 the cavity's bottom a sharp corner; give a larger radius or a smaller depth",
                shape.corner,
                wall_width(&shape),
                shape.depth
            ));
        }
        Ok(Self {
            out,
            triangles,
            punch,
            offset,
            shape,
        })
    }
}

/// Whether `path` is an STL (true) or an OBJ (false).
fn format_of(path: &Path) -> Result<bool, String> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("stl") => Ok(true),
        Some("obj") => Ok(false),
        _ => Err(format!(
            "{}: expected an .stl or .obj file name",
            path.display()
        )),
    }
}

/// The tray's depth profile: height at the inward distance `d` from the
/// cavity's opening (≤ 0 on the flange).
fn profile(shape: &Shape, d: f64) -> f64 {
    let theta = WALL_DEG.to_radians();
    let (r1, r2) = (TOP_FILLET, BOTTOM_FILLET);
    let d1 = r1 * theta.sin();
    let z1 = -r1 + r1 * theta.cos();
    let z2 = -shape.depth + r2 * (1.0 - theta.cos());
    let d2 = d1 + (z1 - z2) / theta.tan();
    let dc = d2 + r2 * theta.sin();
    if d <= 0.0 {
        0.0
    } else if d <= d1 {
        -r1 + (r1 * r1 - d * d).sqrt()
    } else if d <= d2 {
        z1 - (d - d1) * theta.tan()
    } else if d <= dc {
        -shape.depth + r2 - (r2 * r2 - (d - dc) * (d - dc)).max(0.0).sqrt()
    } else {
        -shape.depth
    }
}

/// Where the bottom fillet ends, inward from the opening (mm).
fn wall_width(shape: &Shape) -> f64 {
    let theta = WALL_DEG.to_radians();
    let d1 = TOP_FILLET * theta.sin();
    let z1 = -TOP_FILLET + TOP_FILLET * theta.cos();
    let z2 = -shape.depth + BOTTOM_FILLET * (1.0 - theta.cos());
    d1 + (z1 - z2) / theta.tan() + BOTTOM_FILLET * theta.sin()
}

/// The mould's height at (x, y).
fn height(shape: &Shape, x: f64, y: f64) -> f64 {
    // Signed distance to the rounded rectangle of the opening, < 0 inside.
    let corner = shape.corner;
    let q = [
        x.abs() - (OPENING[0] - corner),
        y.abs() - (OPENING[1] - corner),
    ];
    let outside = q[0].max(0.0).hypot(q[1].max(0.0));
    let s = outside + q[0].max(q[1]).min(0.0) - corner;
    profile(shape, -s) + x * x / (2.0 * BOWL[0]) + y * y / (2.0 * BOWL[1])
}

/// The unit normal of the height field pointing up (into the cavity).
fn up_normal(shape: &Shape, x: f64, y: f64) -> [f64; 3] {
    let h = 1e-4;
    let hx = (height(shape, x + h, y) - height(shape, x - h, y)) / (2.0 * h);
    let hy = (height(shape, x, y + h) - height(shape, x, y - h)) / (2.0 * h);
    let n = (hx * hx + hy * hy + 1.0).sqrt();
    [-hx / n, -hy / n, 1.0 / n]
}

/// `n + 1` coordinates over [−half, half], denser (four times) across the
/// band of the walls, symmetric about 0.
fn coordinates(shape: &Shape, half: f64, opening: f64, n: usize) -> Vec<f64> {
    let wall = wall_width(shape);
    // The walls and their fillets in plan, with a little on either side.
    let (lo, hi) = (opening - wall - 5.0, opening + 5.0);
    let density = |x: f64| {
        if (lo..=hi).contains(&x.abs()) {
            4.0
        } else {
            1.0
        }
    };
    let samples = 20_000;
    let step = 2.0 * half / samples as f64;
    let mut cumulative = vec![0.0; samples + 1];
    for k in 0..samples {
        let x = -half + (k as f64 + 0.5) * step;
        cumulative[k + 1] = cumulative[k] + density(x) * step;
    }
    let total = cumulative[samples];
    let at = |target: f64| {
        let k = cumulative
            .partition_point(|&c| c < target)
            .clamp(1, samples);
        let (c0, c1) = (cumulative[k - 1], cumulative[k]);
        -half + (k as f64 - 1.0 + (target - c0) / (c1 - c0)) * step
    };
    let mut xs: Vec<f64> = (0..=n).map(|i| at(total * i as f64 / n as f64)).collect();
    // Exactly symmetric, and exactly on the outline.
    for i in 0..=n / 2 {
        let m = 0.5 * (xs[n - i] - xs[i]);
        xs[i] = -m;
        xs[n - i] = m;
    }
    xs[0] = -half;
    xs[n] = half;
    if n.is_multiple_of(2) {
        xs[n / 2] = 0.0;
    }
    xs
}

/// The tray's vertices and triangles (normals away from the cavity: down),
/// about `triangles` of them; `offset` moves every vertex along the
/// surface's upward normal.
pub fn tray(shape: &Shape, triangles: usize, offset: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let aspect = OUTLINE[0] / OUTLINE[1];
    let cells = triangles as f64 / 2.0;
    // Even counts: a grid line on each mirror plane.
    let even = |v: f64| ((v / 2.0).round() as usize).max(2) * 2;
    let nx = even((cells * aspect).sqrt());
    let ny = even((cells / aspect).sqrt());
    let xs = coordinates(shape, OUTLINE[0], OPENING[0], nx);
    let ys = coordinates(shape, OUTLINE[1], OPENING[1], ny);
    let mut vertices = Vec::with_capacity((nx + 1) * (ny + 1));
    for &y in &ys {
        for &x in &xs {
            let n = up_normal(shape, x, y);
            vertices.push([
                x + offset * n[0],
                y + offset * n[1],
                height(shape, x, y) + offset * n[2],
            ]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut tris = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            // Clockwise seen from above: normals down. The diagonal runs
            // towards the centre in every quadrant (mirror symmetric).
            let centre_x = 0.5 * (xs[i] + xs[i + 1]);
            let centre_y = 0.5 * (ys[j] + ys[j + 1]);
            if centre_x * centre_y > 0.0 {
                tris.push([a, c, b]);
                tris.push([a, d, c]);
            } else {
                tris.push([a, d, b]);
                tris.push([b, d, c]);
            }
        }
    }
    (vertices, tris)
}

/// The bytes of a binary STL of the mesh.
pub fn binary_stl(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(84 + 50 * triangles.len());
    let mut header = [b' '; 80];
    let title = b"drape: generated open female tray mould (cargo xtask mould)";
    header[..title.len()].copy_from_slice(title);
    out.extend_from_slice(&header);
    out.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for t in triangles {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        for value in n.iter().map(|c| c / len).chain(a).chain(b).chain(c) {
            out.extend_from_slice(&(value as f32).to_le_bytes());
        }
        out.extend_from_slice(&0u16.to_le_bytes());
    }
    out
}

/// The text of an OBJ of the mesh.
fn obj(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> String {
    let mut out = String::from("# drape: generated open female tray mould (cargo xtask mould)\n");
    for v in vertices {
        out.push_str(&format!("v {} {} {}\n", v[0], v[1], v[2]));
    }
    for t in triangles {
        out.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    out
}

fn write(path: &Path, vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Result<(), String> {
    let bytes = if format_of(path)? {
        binary_stl(vertices, triangles)
    } else {
        obj(vertices, triangles).into_bytes()
    };
    // Whole or not at all: a temporary beside it, renamed over it.
    let tmp = path.with_extension("tmp-mould");
    std::fs::write(&tmp, &bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| format!("{}: {e}", path.display()))?;
    println!(
        "{}: {} triangles, {} vertices, {} bytes",
        path.display(),
        triangles.len(),
        vertices.len(),
        bytes.len()
    );
    Ok(())
}

/// Writes the mould (and the punch).
pub fn main(options: &Options) -> ExitCode {
    let (v, t) = tray(&options.shape, options.triangles, 0.0);
    let mut result = write(&options.out, &v, &t);
    if let (Ok(()), Some(punch)) = (&result, &options.punch) {
        let (v, t) = tray(&options.shape, options.triangles, options.offset);
        result = write(punch, &v, &t);
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_profile_is_continuous_with_a_continuous_slope() {
        for shape in [
            Shape::default(),
            Shape {
                depth: 40.0,
                corner: 140.0,
            },
        ] {
            let profile = |d| profile(&shape, d);
            let h = 1e-6;
            let mut d = -5.0;
            while d < 100.0 {
                let jump = (profile(d + h) - profile(d - h)).abs();
                assert!(
                    jump < 2.0 * h * 60f64.to_radians().tan() + 1e-9,
                    "jump at {d}"
                );
                d += 0.01;
            }
            assert_eq!(profile(-1.0), 0.0);
            assert_eq!(profile(wall_width(&shape) + 1.0), -shape.depth);
            // The wall's slope is the wall angle.
            let mid = 0.5 * (TOP_FILLET + wall_width(&shape) - BOTTOM_FILLET);
            let slope = (profile(mid - 0.5) - profile(mid + 0.5)) / 1.0;
            assert!((slope - 60f64.to_radians().tan()).abs() < 1e-9, "{slope}");
        }
    }

    #[test]
    fn the_tray_is_open_at_its_outline_wound_down_and_mirror_symmetric() {
        let (v, t) = tray(&Shape::default(), 3000, 0.0);
        assert!((t.len() as f64 - 3000.0).abs() < 300.0, "{}", t.len());
        // Normals down (away from the cavity).
        for tri in &t {
            let [a, b, c] = tri.map(|i| v[i as usize]);
            let nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(nz < 0.0);
        }
        // Every vertex has its mirror images about x = 0 and y = 0.
        let key = |p: [f64; 3]| [p[0], p[1]].map(|c| (c * 1e6).round() as i64);
        let set: std::collections::HashSet<_> = v.iter().map(|&p| key(p)).collect();
        for p in &v {
            assert!(set.contains(&key([-p[0], p[1], p[2]])));
            assert!(set.contains(&key([p[0], -p[1], p[2]])));
        }
        // The bottom is 80 mm below the flange at the centre.
        let shape = Shape::default();
        assert!((height(&shape, 0.0, 0.0) + DEPTH).abs() < 1e-12);
        assert_eq!(height(&shape, 300.0, 0.0), 300.0 * 300.0 / 8000.0);
    }

    #[test]
    fn the_punch_is_the_mould_moved_along_its_normals() {
        let (m, _) = tray(&Shape::default(), 1000, 0.0);
        let (p, _) = tray(&Shape::default(), 1000, 0.57);
        for (a, b) in m.iter().zip(&p) {
            let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            assert!((len - 0.57).abs() < 1e-12 && d[2] > 0.0);
        }
    }

    #[test]
    fn depth_and_corner_are_options_checked_and_named() {
        let parse = |extra: &[&str]| {
            let mut args = vec!["m.stl".to_owned()];
            args.extend(extra.iter().map(|s| (*s).to_owned()));
            Options::parse(&args)
        };
        // The defaults are the shipped mould's.
        assert_eq!(parse(&[]).unwrap().shape, Shape::default());
        let shallow = parse(&["--depth", "40", "--corner", "140"]).unwrap().shape;
        assert_eq!((shallow.depth, shallow.corner), (40.0, 140.0));
        let (v, _) = tray(&shallow, 2000, 0.0);
        let bottom = v.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
        assert!((bottom + 40.0).abs() < 1e-9, "{bottom}");
        for (args, says) in [
            (&["--depth", "5"][..], "--depth `5`"),
            (&["--depth", "x"][..], "--depth `x`"),
            (&["--corner", "0"][..], "--corner `0`"),
            (&["--corner", "151"][..], "--corner `151`"),
            // 20 mm corners under 80 mm walls: a sharp bottom corner.
            (&["--corner", "20"][..], "sharp corner"),
        ] {
            let err = parse(args).unwrap_err();
            assert!(err.contains(says), "{err}");
        }
    }
}
