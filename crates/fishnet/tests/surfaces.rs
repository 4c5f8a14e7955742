//! The net on every kind of tool surface: planes (flat and tilted: an
//! unsheared grid), a surface of revolution and a triangle mesh against the
//! sphere they approximate, the mould's edge, generator curves, the
//! orientation, and the errors.

use drape_contact::{ProfileSegment, Surface};
use drape_fishnet::{FishnetError, Net, NetSpec, NodeStatus};
use drape_model::blank::BlankFrame;
use nalgebra::Vector3;
use proptest::prelude::*;

const R: f64 = 100.0;

fn spec(size: f64, d: f64) -> NetSpec {
    NetSpec {
        outline: BlankFrame {
            center: Vector3::new(0.0, 0.0, 5.0),
            width: size,
            height: size,
        },
        seed: [0.0, 0.0],
        orientation_deg: 0.0,
        spacing: [d, d],
        direction: -Vector3::z(),
        warp_curve: None,
        weft_curve: None,
    }
}

fn sphere() -> Surface {
    Surface::sphere(Vector3::new(0.0, 0.0, -R), R).unwrap()
}

/// A dome of radius `r` (pole at the origin, centre below it) meshed by
/// `rings` rings of latitude down to the polar angle `cap` and `around`
/// meridians, with a cylindrical skirt of height `skirt` below the equator
/// when `cap` is 90°; triangles counter-clockwise seen from outside.
fn dome(r: f64, rings: usize, around: usize, cap: f64, skirt: f64) -> Surface {
    let centre = Vector3::new(0.0, 0.0, -r);
    let mut v = vec![centre + Vector3::new(0.0, 0.0, r)];
    let ring = |k: usize| 1 + (k - 1) * around;
    for k in 1..=rings {
        let theta = cap * k as f64 / rings as f64;
        for m in 0..around {
            let phi = std::f64::consts::TAU * m as f64 / around as f64;
            v.push(
                centre
                    + Vector3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    ) * r,
            );
        }
    }
    let mut rows = rings;
    if skirt > 0.0 {
        let levels = (skirt / (r * cap / rings as f64)).ceil() as usize;
        for k in 1..=levels {
            let z = -skirt * k as f64 / levels as f64;
            for m in 0..around {
                let phi = std::f64::consts::TAU * m as f64 / around as f64;
                v.push(centre + Vector3::new(r * phi.cos(), r * phi.sin(), z));
            }
        }
        rows += levels;
    }
    let mut t = Vec::new();
    for m in 0..around {
        let n = (m + 1) % around;
        t.push([0, (ring(1) + m) as u32, (ring(1) + n) as u32]);
    }
    for k in 1..rows {
        for m in 0..around {
            let n = (m + 1) % around;
            let (a, b, c, d) = (ring(k) + m, ring(k + 1) + m, ring(k + 1) + n, ring(k) + n);
            t.push([a as u32, b as u32, c as u32]);
            t.push([a as u32, c as u32, d as u32]);
        }
    }
    Surface::triangle_mesh(v, t).unwrap()
}

#[test]
fn on_a_plane_the_net_is_the_flat_grid() {
    for tilt in [0.0f64, 0.3] {
        let normal = Vector3::new(0.0, tilt.sin(), tilt.cos());
        let plane = Surface::plane(Vector3::new(0.0, 0.0, -3.0), normal).unwrap();
        let net = Net::drape(&plane, &spec(100.0, 5.0)).unwrap();
        assert_eq!(net.stats().draped_cells, 400);
        for c in net.cells() {
            assert!(c.shear.abs() < 1e-12, "{tilt}: {c:?}");
            assert!((c.area - 25.0).abs() < 1e-9);
        }
        // The warp along x stays along x; the weft runs up the slope.
        let seed = net.node(0, 0).unwrap();
        let p = net.node(7, -3).unwrap();
        let expect =
            seed + Vector3::x() * 35.0 + Vector3::new(0.0, tilt.cos(), -tilt.sin()) * -15.0;
        assert!((p - expect).norm() < 1e-9, "{p:?} vs {expect:?}");
    }
}

#[test]
fn a_hemispherical_punch_drapes_as_the_sphere_on_its_cap() {
    let punch = Surface::hemispherical_punch(Vector3::zeros(), R, 200.0).unwrap();
    let (a, b) = (
        Net::drape(&punch, &spec(240.0, 6.0)).unwrap(),
        Net::drape(&sphere(), &spec(240.0, 6.0)).unwrap(),
    );
    let mut compared = 0;
    for c in a.cells() {
        let [i, j] = c.index;
        let on_cap = [(i, j), (i + 1, j + 1), (i + 1, j), (i, j + 1)]
            .iter()
            .all(|&(p, q)| a.node(p, q).unwrap().z > -R);
        if on_cap {
            let s = b.cell(i, j).unwrap();
            assert!((c.shear - s.shear).abs() < 1e-9, "{:?}", c.index);
            compared += 1;
        }
    }
    assert!(compared > 1000, "{compared}");
    // Below the equator the punch's shank carries the net on: no cell is
    // lost, while the whole sphere's net runs round under the equator.
    assert_eq!(a.stats().draped_cells, 1600);
}

#[test]
fn a_meshed_dome_drapes_as_the_sphere_within_its_faceting() {
    // 60 rings to the equator: facets of 2.6 mm, a chordal error of
    // r(1 − cos(Δθ/2)) = 8.6e-3 mm. On facets the yarns turn at the edges
    // instead of smoothly, which perturbs each crossing by a fraction of
    // that error; the shear, a difference of directions over a 6 mm cell,
    // moves by up to about 8.6e-3/6 rad ≈ 0.1°.
    let mesh = dome(R, 60, 240, std::f64::consts::FRAC_PI_2, 0.0);
    let (a, b) = (
        Net::drape(&mesh, &spec(160.0, 6.0)).unwrap(),
        Net::drape(&sphere(), &spec(160.0, 6.0)).unwrap(),
    );
    assert_eq!(a.stats().draped_cells, b.stats().draped_cells);
    let worst = a
        .cells()
        .iter()
        .map(|c| (c.shear - b.cell(c.index[0], c.index[1]).unwrap().shear).abs())
        .fold(0.0, f64::max);
    assert!(worst.to_degrees() < 0.1, "{}°", worst.to_degrees());
    // The crossings are on the facets.
    for c in a.cells() {
        let [i, j] = c.index;
        let x = a.node(i, j).unwrap();
        assert!(mesh.project(&x).gap.abs() < 1e-9);
    }
}

#[test]
fn the_net_stops_at_the_mould_edge() {
    // An open spherical cap to 40° from the pole: 70 mm of arc from it.
    let cap = dome(R, 30, 120, 40f64.to_radians(), 0.0);
    let net = Net::drape(&cap, &spec(200.0, 5.0)).unwrap();
    let stats = net.stats();
    assert!(
        stats.draped_cells > 0 && stats.draped_cells < stats.outline_cells,
        "{stats:?}"
    );
    assert!(stats.missed > 0);
    // Draped cells lie on the cap; the generators reach about 70 mm.
    for c in net.cells() {
        assert!(c.centroid.z > -R + R * 40f64.to_radians().cos() - 1.0);
    }
    let reach = (1..40).take_while(|&k| net.node(k, 0).is_some()).count();
    assert!((13..=14).contains(&reach), "{reach}");
    assert_eq!(net.status(reach as i32 + 1, 0), Some(NodeStatus::OffMould));
    assert_eq!(net.status(reach as i32 + 2, 0), Some(NodeStatus::Blocked));
}

#[test]
fn generator_curves_on_great_circles_give_the_geodesic_net() {
    let d = 5.0;
    let centre = Vector3::new(0.0, 0.0, -R);
    let circle = |along: Vector3<f64>| -> Vec<Vector3<f64>> {
        (-200..=200)
            .map(|k| {
                let a = f64::from(k) * 0.006;
                centre + (along * a.sin() + Vector3::z() * a.cos()) * R
            })
            .collect()
    };
    let mut curved = spec(100.0, d);
    curved.warp_curve = Some(circle(Vector3::x()));
    curved.weft_curve = Some(circle(Vector3::y()));
    let a = Net::drape(&sphere(), &curved).unwrap();
    let b = Net::drape(&sphere(), &spec(100.0, d)).unwrap();
    for c in a.cells() {
        let s = b.cell(c.index[0], c.index[1]).unwrap();
        assert!((c.shear - s.shear).abs() < 1e-9);
    }
    // A generator along a small circle (latitude 20° below the pole) is no
    // geodesic: the warp follows it, within the sagitta of the polyline's
    // segments (7e-5 mm, 7e-7 rad of polar angle).
    let lat = 20f64.to_radians();
    let small: Vec<Vector3<f64>> = (-750..=750)
        .map(|k| {
            let phi = f64::from(k) * 0.004;
            centre + Vector3::new(lat.sin() * phi.sin(), -lat.sin() * phi.cos(), lat.cos()) * R
        })
        .collect();
    let mut along = spec(100.0, d);
    along.seed = [0.0, -R * lat.sin()];
    along.outline.center = Vector3::new(0.0, -R * lat.sin(), 5.0);
    along.warp_curve = Some(small);
    let net = Net::drape(&sphere(), &along).unwrap();
    for k in -10..=10 {
        let x = net.node(k, 0).unwrap() - centre;
        // On the latitude circle: the polar angle of the crossing.
        let polar = (x.z / x.norm()).acos();
        assert!((polar - lat).abs() < 1e-6, "{k}: {}", polar.to_degrees());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    /// On a sphere seeded at its pole, the net does not depend on the warp's
    /// angle: cell (i, j) shears the same.
    #[test]
    fn on_a_sphere_the_net_is_the_same_at_any_orientation(theta in 0.0f64..360.0) {
        let base = Net::drape(&sphere(), &spec(160.0, 8.0)).unwrap();
        let mut turned = spec(160.0, 8.0);
        turned.orientation_deg = theta;
        let net = Net::drape(&sphere(), &turned).unwrap();
        for i in -5..5 {
            for j in -5..5 {
                let (a, b) = (net.cell(i, j).unwrap(), base.cell(i, j).unwrap());
                prop_assert!((a.shear - b.shear).abs() < 1e-9);
            }
        }
    }
}

#[test]
fn bad_input_is_an_error_naming_it() {
    let mut s = spec(100.0, 5.0);
    s.spacing = [0.0, 5.0];
    assert!(matches!(
        Net::drape(&sphere(), &s),
        Err(FishnetError::Invalid {
            field: "spacing",
            ..
        })
    ));
    let mut s = spec(100.0, 5.0);
    s.seed = [80.0, 0.0];
    assert!(matches!(
        Net::drape(&sphere(), &s),
        Err(FishnetError::Invalid { field: "seed", .. })
    ));
    // A mould beside the blank.
    let beside = Surface::sphere(Vector3::new(500.0, 0.0, -R), R).unwrap();
    assert!(matches!(
        Net::drape(&beside, &spec(100.0, 5.0)),
        Err(FishnetError::SeedMissesMould { .. })
    ));
    // A plane the blank moves away from.
    let plane = Surface::plane(Vector3::zeros(), -Vector3::z()).unwrap();
    assert!(matches!(
        Net::drape(&plane, &spec(100.0, 5.0)),
        Err(FishnetError::SeedMissesMould { .. })
    ));
    // A ring facing down (a blank holder): met from above, its back.
    let ring = Surface::revolution(
        Vector3::zeros(),
        vec![ProfileSegment::Line {
            from: [200.0, 0.0],
            to: [1.0, 0.0],
        }],
    )
    .unwrap();
    // Seeded over the ring itself: the axis passes through its opening,
    // whose free edge is outside from every side.
    let mut over_ring = spec(100.0, 5.0);
    over_ring.outline.center = Vector3::new(100.0, 0.0, 5.0);
    over_ring.seed = [100.0, 0.0];
    let e = Net::drape(&ring, &over_ring).unwrap_err();
    assert!(matches!(e, FishnetError::SeedBehindMould { .. }), "{e}");
    let e = Net::drape(&ring, &spec(100.0, 5.0)).unwrap_err();
    assert!(matches!(e, FishnetError::SeedMissesMould { .. }), "{e}");
    // A generator curve that misses the seed.
    let mut s = spec(100.0, 5.0);
    s.warp_curve = Some(vec![
        Vector3::new(-50.0, 10.0, 0.0),
        Vector3::new(50.0, 10.0, 0.0),
    ]);
    let e = Net::drape(&sphere(), &s).unwrap_err();
    assert!(
        e.to_string().contains("warp generator curve passes 10"),
        "{e}"
    );
}
