//! The "your own part" example: `scenes/tray.toml`, a glass ply formed
//! into the generated open female tray mould (as a CAD export gives it:
//! open rim, normals away from the cavity) by a matched punch, run on the
//! defaults. A forming run of a user's part is right when it completes
//! without a fold, lies on the mould and agrees with the kinematic net
//! where it lies there; this case checks those three things on the
//! shipped example (and reports its wall time).
//!
//! - **No fold**: the run's own fold check (`summary.json`'s `fold`).
//! - **Conforms**: the ply's lower face within one ply thickness of the
//!   mould over ≥ 95 % of the mould area it covers. An element covers the
//!   mould when its centroid's closest point on the mould is on the user's
//!   own triangles, not on the rim extension drape adds (the ply's overhang
//!   beyond the rim is not on the part); it conforms when every node's gap,
//!   less the half thickness the contact keeps, is at most the thickness.
//! - **Agrees with the net**: the RMS of γ_run − γ_net over the elements
//!   lying on the mould (`drape compare SCENE`'s measure) within 2°: where
//!   the fabric lies on the mould both describe the same surface, and what
//!   is left is friction and the yarns' bending and stretch, which the
//!   pin-jointed net does not have.
//!
//! The first and last checks fail (2026-11-28, second session; numbers
//! release, one thread): 7.96° rms over 816 elements (8.40° while the
//! preset's yarns buckled at no cost), the median profile agreeing to
//! 0.26° and the diagonals differing by 8.80°. In the tray's corners the
//! run's yarns end up to 17 % shorter (truss stretch 0.831; 17.5 % of the
//! yarns' length below 0.95, which the fold check reports as gathering),
//! and the blank's corners are drawn in along the diagonal by DD 31.0 mm
//! where the net's move 9.6 mm: the ply lies on the mould there by
//! shortening its yarns, where a pin-jointed net must shear (45° against
//! the run's 23.8°).
//!
//! Why, measured: the yarns' compression law decides it. The presets'
//! yarn now carries its Euler load as it buckles between interlacings
//! (`FibreLaw::buckling_stress`, 1.56 MPa for the glass, from its assumed
//! bending rigidity); shortening both families by 17 % then stores
//! 0.05 mJ/mm², where shearing the corner from 24° to the net's 45°
//! against the glass preset's elastic resin (G·h_m = 3.0 N/mm) stores
//! 0.67 mJ/mm², so the model gathers. A linear compression factor that no
//! source supports shows the mechanism: c_c = 0.01 gives 3.54° rms, 0.1
//! gives 1.84° with DD 10.8 mm (the net's 9.6). μ = 0 gives 8.53° (with
//! c_c = 0), so friction is not it. What the model lacks for this part is
//! the ply's thickness: 17 % shorter yarns in both families put 45 % more
//! fibre under the punch, which closes to 0.1 mm over the ply's thickness
//! (V_f 0.5 → 0.72), and a membrane has no compaction to resist it.
//!
//! Third session: the yarns now feel the tools' gap
//! (`FibreLaw::confined_stress_and_tangent`: between two tools a buckled
//! yarn's bow stops at the free space, and it shortens further only by
//! going to higher modes, at its Euler load per (π·a_m/2L)² of
//! shortening). Measured (release, one thread, machine loaded by other
//! builds: 9.1 s CPU, 66 s wall, 12 923 steps): 6.28° rms over 816
//! elements (was 7.96°), max shear 27.8° (net 44.8°), DD 25.6 mm (was
//! 31.0; the net's 9.6), the fold check still reports gathering (16.4 %
//! of the yarns' length below 0.95, down to 0.862), so both checks still
//! fail. That is the law's ceiling, not its clearance estimate: with
//! every truss held at c = 0 from the first step (the stiffest the law
//! can be, k = 1/(ε_sh/σ_b + 1/E_f) = 129 MPa, an experiment, not
//! shipped) the run gives 5.96° and DD 24.5 mm; at c = 0.1 mm everywhere
//! 6.74°. A walled column's envelope stiffness σ_b/ε_a cannot exceed
//! σ_b/ε_sh (the crimp's own bow already uses ε_sh of the arc), a sixth
//! of the unsourced c_c = 0.01 (750 MPa, 3.54°) and a sixtieth of
//! c_c = 0.1 (1.84°).
//!
//! Nor is it the tray's depth. Shallower trays from the same generator
//! (`cargo xtask mould --depth D --corner R`, the same blank, ply and
//! punch closing to 0.1 mm over the thickness, measured the same way, not
//! shipped): 40 mm deep with 140 mm corners, net 32.7° (well below the
//! scene's 50° locking angle), run 12.7°, 4.21° rms, DD 10.4 mm (net
//! 2.6), 1.2 % of the yarns' length gathered; 30 mm deep with 150 mm
//! corners, net 24.7°, run 8.5°, 3.52° rms, DD 7.3 mm, 0.2 % gathered.
//! The run shears about a third of what the net does at every depth and
//! draws its corners in further, gathering or not: the disagreement is
//! not a locking angle the deep tray passes. Not measured here: how much
//! of it is the crimped yarns' cheap stretch (ε_sh = 1.2 %) against the
//! resin's shear (G·h_m = 3.0 N/mm). So no shallower example was added:
//! one shallow enough to pass would be chosen to pass. Both checks are left failing: the fault is the
//! model's answer, not the checks'.

use std::path::Path;
use std::time::Instant;

use drape_contact::Surface;
use nalgebra::Vector3;

use super::{Case, Check};

/// The cases of this module.
pub const CASES: &[Case] = &[Case {
    name: "scenes/tray",
    quick: false,
    run: tray,
}];

fn tray() -> Vec<Check> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives inside the workspace");
    let scene = drape_io::scene::Scene::from_file(&root.join("scenes/tray.toml"), &[])
        .expect("the scene loads");
    let out = super::target_dir(root).join("validation").join("tray");
    let start = Instant::now();
    let report = drape::compare_scene(&scene, &out, &mut |_| drape::RunControl::Continue)
        .expect("both runs write their results");
    let wall = start.elapsed().as_secs_f64();
    let run = &report.mechanical.summary;
    let s = &report.comparison.summary;
    let model = &scene.model;
    let mould = &model.tools[report.kinematic.mould];
    let Surface::Mesh(mesh) = &mould.surface else {
        panic!("the tray's mould is a mesh");
    };
    let state = &report.mechanical.state;
    let displacement = mould.prescribed_displacement(state.time).unwrap_or(0.0);
    let h = 2.0 * model.contact_offset;
    let gap: Vec<f64> = state
        .x
        .iter()
        .map(|x| mould.project(x, displacement).gap - model.contact_offset)
        .collect();
    let (mut covered, mut conforming) = (0.0, 0.0);
    for batch in &model.membranes {
        for e in 0..batch.len() {
            let nodes = batch.element_nodes(e);
            let p: Vec<Vector3<f64>> = nodes.iter().map(|&n| state.x[n as usize]).collect();
            let centroid = p.iter().sum::<Vector3<f64>>() / p.len() as f64;
            if mesh.on_rim_extension(&centroid) {
                continue;
            }
            // A quad's area from its diagonals, a triangle's from two sides.
            let area = if p.len() == 4 {
                0.5 * (p[2] - p[0]).cross(&(p[3] - p[1])).norm()
            } else {
                0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm()
            };
            covered += area;
            if nodes.iter().all(|&n| gap[n as usize] <= h) {
                conforming += area;
            }
        }
    }
    let fraction = conforming / covered;
    let folded = run.fold.as_ref().is_some_and(|f| f.folded);
    super::note(format!(
        "tray: {} in {wall:.1} s wall (kinematic net and forming run, dev profile), \
         largest shear {:.2}° (net {:.2}°), {:.0} of {:.0} mm² of the covered mould \
         within a thickness ({:.1} %), rms γ_run − γ_net on the mould {:.2}° over {} elements",
        run.status,
        s.mechanical_max_shear_deg,
        s.kinematic_max_shear_deg,
        conforming,
        covered,
        100.0 * fraction,
        s.all.rms_on_mould_deg,
        s.all.points_on_mould,
    ));
    vec![
        Check::abs(
            format!("run completed ({}) without a fold (fold check)", run.status),
            0.0,
            if run.status == "completed" {
                f64::from(u8::from(folded))
            } else {
                f64::NAN
            },
            0.0,
        ),
        Check::abs(
            format!(
                "share of the covered mould ({covered:.0} mm²) with the ply within a thickness ({h:.2} mm), ≥ 0.95"
            ),
            1.0,
            fraction,
            0.05,
        ),
        Check::abs(
            format!(
                "rms of γ_run − γ_net on the mould ({} elements) (°)",
                s.all.points_on_mould
            ),
            0.0,
            if s.all.points_on_mould > 0 {
                s.all.rms_on_mould_deg
            } else {
                f64::NAN
            },
            2.0,
        ),
    ]
}
