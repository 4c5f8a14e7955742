//! A draped net as drape's model types, and reading it at flat points.

use drape_constitutive::Material;
use drape_contact::Surface;
use drape_fishnet::{Net, NetSpec};
use drape_model::blank::BlankFrame;
use nalgebra::Vector3;

fn spec(width: f64, height: f64, d: f64) -> NetSpec {
    NetSpec {
        outline: BlankFrame {
            center: Vector3::new(0.0, 0.0, 2.0),
            width,
            height,
        },
        seed: [0.0, 0.0],
        orientation_deg: 0.0,
        spacing: [d, d],
        direction: -Vector3::z(),
        warp_curve: None,
        weft_curve: None,
    }
}

fn carbon() -> Material {
    Material::preset("carbon-prepreg-2x2").unwrap()
}

#[test]
fn a_net_on_a_plane_is_an_undeformed_blank_moved_down() {
    let plane = Surface::plane(Vector3::new(0.0, 0.0, -1.0), Vector3::z()).unwrap();
    let net = Net::drape(&plane, &spec(60.0, 40.0, 5.0)).unwrap();
    let shift = Vector3::new(0.0, 0.0, 7.0);
    let r = net.results(&carbon(), shift, 50.0).unwrap();
    assert_eq!(r.model.membrane_count(), 12 * 8);
    assert_eq!(r.model.node_count(), 13 * 9);
    for (x, x0) in r.state.x.iter().zip(&r.model.x0) {
        assert!((x - x0 - Vector3::new(0.0, 0.0, -3.0 + 7.0)).norm() < 1e-12);
    }
    let f = &r.fields;
    assert!(f.shear.iter().all(|g| g.abs() < 1e-12));
    assert!(f.thickness.iter().all(|h| (h - 0.3).abs() < 1e-12));
    assert!(
        f.fibre_direction
            .iter()
            .all(|[w, t]| (w - Vector3::x()).norm() < 1e-12 && (t - Vector3::y()).norm() < 1e-12)
    );
    let m = &r.measures;
    let d = m.draw_in.unwrap();
    assert!(
        d.dx.abs() < 1e-12 && d.dy.abs() < 1e-12 && d.dd.abs() < 1e-12,
        "{d:?}"
    );
    assert_eq!(m.area_above_locking, 0.0);
    // Half a cell either side of the median: the two middle rows.
    assert_eq!(m.profile_median.len(), 24);
    assert!(m.profile_diagonal.len() >= 8);
}

#[test]
fn fields_and_measures_of_a_net_on_a_sphere_are_the_cells() {
    let r0 = 80.0;
    let sphere = Surface::sphere(Vector3::new(0.0, 0.0, -r0), r0).unwrap();
    let net = Net::drape(&sphere, &spec(120.0, 120.0, 4.0)).unwrap();
    let r = net.results(&carbon(), Vector3::zeros(), 20.0).unwrap();
    let f = &r.fields;
    for (k, cell) in net.cells().iter().enumerate() {
        assert_eq!(f.shear[k], cell.shear);
        let [w, t] = f.fibre_direction[k];
        // The angle between the fibres closes by the shear.
        let angle = w.cross(&t).norm().atan2(w.dot(&t));
        assert!((std::f64::consts::FRAC_PI_2 - angle - cell.shear).abs() < 1e-12);
        // The fabric's volume kept: thicker where the cell's area shrank.
        assert!((f.thickness[k] * cell.area - 0.3 * 16.0).abs() < 1e-12);
        assert!(f.thickness[k] >= 0.3 * (1.0 - 1e-12));
    }
    let m = &r.measures;
    let largest = f.shear.iter().fold(0.0f64, |a, g| a.max(g.abs()));
    assert_eq!(m.max_shear_deg, largest.to_degrees());
    // The wrinkle indicator is the cells' largest waviness, as a run's:
    // on a smooth sphere, above 0 and below the 5° threshold.
    let wavy = f.waviness.iter().fold(0.0f64, |a, &w| a.max(w));
    assert_eq!(m.max_waviness_deg, wavy);
    assert!(wavy > 0.0 && wavy < 5.0 && m.wrinkle_area == 0.0, "{wavy}");
    let above: f64 = f
        .shear
        .iter()
        .filter(|g| g.abs() > 20f64.to_radians())
        .count() as f64
        * 16.0;
    assert_eq!(m.area_above_locking, above);
    assert!(above > 0.0);
    // The blank is pulled in everywhere: the corners most.
    let d = m.draw_in.unwrap();
    assert!(
        d.dx > 0.0 && (d.dx - d.dy).abs() < 1e-9 && d.dd > d.dx,
        "{d:?}"
    );
    // The edge midpoints are crossings of the generators (great circles),
    // 15 chords of 4 mm from the pole: DX = 60 − R·sin(15·2·asin(2/R)).
    let step = 2.0 * (2.0 / r0).asin();
    let expect = 60.0 - r0 * (15.0 * step).sin();
    assert!((d.dx - expect).abs() < 1e-9, "{} vs {expect}", d.dx);
}

/// A flat disc of radius 70 mm under a 120 mm square: the edge midpoints
/// (60 mm out) are on it, the corners (85 mm) are not. The draw-in that
/// can be read is (zero on a plane), the corners' is NaN: not a missing
/// draw-in for the whole blank, as if it were not a rectangle.
#[test]
fn a_net_short_of_the_corners_still_has_the_edge_draw_in() {
    let disc = Surface::revolution(
        Vector3::new(0.0, 0.0, -1.0),
        vec![drape_contact::ProfileSegment::Line {
            from: [0.0, 0.0],
            to: [70.0, 0.0],
        }],
    )
    .unwrap();
    let net = Net::drape(&disc, &spec(120.0, 120.0, 4.0)).unwrap();
    let r = net.results(&carbon(), Vector3::zeros(), 50.0).unwrap();
    let d = r.measures.draw_in.unwrap();
    assert!(d.dx.abs() < 1e-12 && d.dy.abs() < 1e-12, "{d:?}");
    assert!(d.dd.is_nan(), "{d:?}");
}

#[test]
fn the_net_reads_at_flat_points() {
    let r0 = 80.0;
    let sphere = Surface::sphere(Vector3::new(0.0, 0.0, -r0), r0).unwrap();
    let net = Net::drape(&sphere, &spec(120.0, 120.0, 4.0)).unwrap();
    // At a crossing: the crossing; at a cell's centre: the cell's shear.
    let flat = net.flat(3, -5);
    assert!((net.position_at(&flat).unwrap() - net.node(3, -5).unwrap()).norm() < 1e-12);
    let centre = (net.flat(3, -5) + net.flat(4, -4)) / 2.0;
    assert!((net.shear_at(&centre).unwrap() - net.cell(3, -5).unwrap().shear).abs() < 1e-12);
    // Between four centres: their bilinear mean.
    let mid = net.flat(4, -4);
    let mean = [(3, -5), (4, -5), (3, -4), (4, -4)]
        .iter()
        .map(|&(i, j)| net.cell(i, j).unwrap().shear)
        .sum::<f64>()
        / 4.0;
    assert!((net.shear_at(&mid).unwrap() - mean).abs() < 1e-12);
    // Within the edge cells' outer halves: the edge cell's value; off the
    // blank: nothing.
    let edge = net.flat(-15, 0) + Vector3::new(0.5, 1.0, 0.0);
    assert_eq!(net.shear_at(&edge), Some(net.cell(-15, 0).unwrap().shear));
    assert_eq!(net.shear_at(&Vector3::new(70.0, 0.0, 2.0)), None);
    assert_eq!(net.position_at(&Vector3::new(70.0, 0.0, 2.0)), None);
}
