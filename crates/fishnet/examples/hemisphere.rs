//! Kinematic draping of the paper's laying-up: a 350 × 350 mm 0/90 ply of
//! 40 × 40 cells on a hemisphere of radius 120 mm on a cylindrical shank,
//! seeded at the pole. Prints the shear along the blank's diagonal and how
//! long the net took.
//!
//! `cargo run --release -p drape-fishnet --example hemisphere [ORIENTATION_DEG]`

use drape_contact::Surface;
use drape_fishnet::{Net, NetSpec};
use drape_model::blank::BlankFrame;
use nalgebra::Vector3;

fn main() {
    let orientation_deg: f64 = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("an orientation in degrees"))
        .unwrap_or(0.0);
    let mould = Surface::hemispherical_punch(Vector3::new(0.0, 0.0, -0.2), 120.0, 320.0)
        .expect("a valid punch");
    let spec = NetSpec {
        outline: BlankFrame {
            center: Vector3::zeros(),
            width: 350.0,
            height: 350.0,
        },
        seed: [0.0, 0.0],
        orientation_deg,
        spacing: [8.75, 8.75],
        direction: -Vector3::z(),
        warp_curve: None,
        weft_curve: None,
    };
    let started = std::time::Instant::now();
    let net = Net::drape(&mould, &spec).expect("the net drapes");
    let elapsed = started.elapsed();
    let stats = net.stats();
    println!(
        "{} of {} cells draped, {} crossings, {} closest-point queries, {:.2} ms",
        stats.draped_cells,
        stats.outline_cells,
        stats.placed,
        stats.queries,
        elapsed.as_secs_f64() * 1e3
    );
    println!("shear along the diagonal (flat distance from the centre, γ):");
    for k in (0..40).step_by(3) {
        let corner = Vector3::new(-175.0, -175.0, 0.0);
        let centre = corner + Vector3::new(1.0, 1.0, 0.0) * (8.75 * (k as f64 + 0.5));
        let distance = (centre.x + centre.y) / 2f64.sqrt();
        match net.shear_at(&centre) {
            Some(g) => println!("  {distance:8.1} mm  {:7.2}°", g.to_degrees()),
            None => println!("  {distance:8.1} mm  (not draped)"),
        }
    }
}
