//! Criterion benches of kinematic draping (drape-fishnet): a 40 × 40-cell
//! net (the paper's 350 mm blank, 8.75 mm cells, 1681 crossings) on the
//! hemisphere of the laying-up scene (radius 120 mm on a shank, a surface
//! of revolution), and on the same mould as a triangle mesh read from an
//! STL file (the way a CAD mould arrives): 96 rings of latitude to the
//! equator and 384 meridians, facets of about 2 mm, and the shank, 110 592
//! triangles. One call of `Net::drape` each: the seed search, the
//! generators, every cell, the shear.
//!
//! The goal of issue 16 is ≤ 10 ms for each on one core. The net is
//! sequential; `DRAPE_BENCH_CLOCK=thread-cpu` times it by the thread's CPU
//! time on a shared machine.
//!
//! `cargo bench -p drape-benches --bench fishnet -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use drape_benches::{Clock, time_iters};
use drape_contact::Surface;
use drape_fishnet::{Net, NetSpec};
use drape_model::blank::BlankFrame;
use nalgebra::Vector3;

const RADIUS: f64 = 120.0;
const SHANK: f64 = 320.0;

/// The laying-up scene's blank and net: 350 mm, 40 × 40 cells, 0/90, the
/// seed at the centre above the pole.
fn spec() -> NetSpec {
    NetSpec {
        outline: BlankFrame {
            center: Vector3::zeros(),
            width: 350.0,
            height: 350.0,
        },
        seed: [0.0, 0.0],
        orientation_deg: 0.0,
        spacing: [8.75, 8.75],
        direction: -Vector3::z(),
        warp_curve: None,
        weft_curve: None,
    }
}

/// The hemisphere on its shank, pole at z = −0.2 as in the scene, as
/// triangles counter-clockwise from outside: `rings` rings of latitude to
/// the equator, `around` meridians, the shank in rings of the same height.
fn punch_triangles(rings: usize, around: usize) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
    let centre = Vector3::new(0.0, 0.0, -0.2 - RADIUS);
    let mut v = vec![centre + Vector3::z() * RADIUS];
    let point = |theta: f64, phi: f64, z: f64| {
        centre
            + Vector3::new(
                RADIUS * theta.sin() * phi.cos(),
                RADIUS * theta.sin() * phi.sin(),
                z,
            )
    };
    let dtheta = std::f64::consts::FRAC_PI_2 / rings as f64;
    let shank_rings = (SHANK / (RADIUS * dtheta)).ceil() as usize;
    for k in 1..=rings + shank_rings {
        for m in 0..around {
            let phi = std::f64::consts::TAU * m as f64 / around as f64;
            v.push(if k <= rings {
                let theta = dtheta * k as f64;
                point(theta, phi, RADIUS * theta.cos())
            } else {
                point(
                    std::f64::consts::FRAC_PI_2,
                    phi,
                    -SHANK * (k - rings) as f64 / shank_rings as f64,
                )
            });
        }
    }
    let ring = |k: usize| 1 + (k - 1) * around;
    let mut t = Vec::new();
    for m in 0..around {
        t.push([0, (ring(1) + m) as u32, (ring(1) + (m + 1) % around) as u32]);
    }
    for k in 1..rings + shank_rings {
        for m in 0..around {
            let n = (m + 1) % around;
            let (a, b, c, d) = (ring(k) + m, ring(k + 1) + m, ring(k + 1) + n, ring(k) + n);
            t.push([a as u32, b as u32, c as u32]);
            t.push([a as u32, c as u32, d as u32]);
        }
    }
    (v, t)
}

/// The punch written as a binary STL file and read back as drape reads a
/// tool's file.
fn punch_from_stl() -> Surface {
    let (v, t) = punch_triangles(96, 384);
    let triangles: Vec<stl_io::Triangle> = t
        .iter()
        .map(|tri| {
            let [a, b, c] = tri.map(|i| v[i as usize]);
            let n = (b - a).cross(&(c - a)).normalize();
            let vertex =
                |p: Vector3<f64>| stl_io::Vertex::new([p.x as f32, p.y as f32, p.z as f32]);
            stl_io::Triangle {
                normal: stl_io::Normal::new([n.x as f32, n.y as f32, n.z as f32]),
                vertices: [vertex(a), vertex(b), vertex(c)],
            }
        })
        .collect();
    let path = std::env::temp_dir().join(format!("drape-bench-punch-{}.stl", std::process::id()));
    let mut file = std::fs::File::create(&path).expect("a temporary STL file");
    stl_io::write_stl(&mut file, triangles.iter()).expect("STL written");
    drop(file);
    let read = drape_contact::read_stl(&path);
    let _ = std::fs::remove_file(&path);
    let (vertices, triangles) = read.expect("the STL reads back");
    Surface::triangle_mesh(vertices, triangles).expect("a valid mesh")
}

fn nets(c: &mut Criterion) {
    let clock = Clock::from_env();
    let spec = spec();
    let revolution =
        Surface::hemispherical_punch(Vector3::new(0.0, 0.0, -0.2), RADIUS, SHANK).expect("punch");
    let mesh = punch_from_stl();
    let mut group = c.benchmark_group("fishnet/40x40");
    for (name, surface) in [("hemisphere", &revolution), ("stl_mesh", &mesh)] {
        let net = Net::drape(surface, &spec).expect("the net drapes");
        assert_eq!(net.stats().draped_cells, 1600, "{name}: {:?}", net.stats());
        eprintln!(
            "{name}: {} crossings, {} surface queries ({:.2} per crossing), max shear {:.2}°",
            net.stats().placed,
            net.stats().queries,
            net.stats().queries as f64 / net.stats().placed as f64,
            net.cells()
                .iter()
                .map(|c| c.shear.abs())
                .fold(0.0, f64::max)
                .to_degrees()
        );
        group.throughput(Throughput::Elements(net.stats().placed as u64));
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                time_iters(clock, iters, || {
                    black_box(Net::drape(black_box(surface), black_box(&spec)).expect("net"));
                })
            })
        });
    }
    group.finish();
}

criterion_group!(benches, nets);
criterion_main!(benches);
