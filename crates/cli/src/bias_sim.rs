//! drape's own bias-extension test: a ±45° specimen H long between the
//! grips and W wide, one grip fixed and the other pulled, run as a scene
//! (the same model `drape run` builds, yarn bending included) and read
//! as the clamp force against the crosshead displacement. It is the
//! forward model of the inverse fit (`drape fit bias-extension --method
//! inverse`) and of the `cao2008` validation cases.
//!
//! Why the implicit driver, quasi-statically: the specimen weighs 20 g
//! and its stiff yarns put the explicit stable step at 2 µs, so a pull
//! slow enough to be quasi-static (0.5 s) takes 2.3e5 explicit steps
//! (about a minute) where Newton increments take about 50 (about a
//! second) for the same answer (28.85° and a largest yarn force of
//! 5.5595/5.5596 N at 25 mm on 20 × 10 cells). The pull is a linear ramp
//! over 1 s with a frame at every output displacement; the mass is the
//! physical one, so inertia is some 1e-9 of the strain energy.
//!
//! What it is not: a model of the grips (the clamped nodes are held
//! rigidly, with no slip), of yarn slip through the crossovers, or of the
//! specimen's out-of-plane wrinkles beyond what the membrane and bending
//! carry.

use drape_constitutive::Material;
use drape_io::scene::Scene;
use drape_time::{Frame, Implicit, Observer};

use crate::fit_bias::Specimen;

/// A virtual bias-extension test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VirtualTest {
    /// The specimen.
    pub specimen: Specimen,
    /// Cell diagonals across the width W (the length gets H/W times as
    /// many, rounded): the mesh's cells must be square.
    pub cells: usize,
    /// Largest crosshead displacement (mm).
    pub u_max: f64,
    /// Output every this many mm.
    pub step: f64,
}

/// A simulated curve: clamp force at equally spaced displacements.
#[derive(Debug, Clone, PartialEq)]
pub struct SimCurve {
    /// Crosshead displacement (mm), from 0.
    pub u: Vec<f64>,
    /// Force on the pulled grip (N).
    pub force: Vec<f64>,
    /// Force on the fixed grip (N, positive when it holds the pull).
    pub held: Vec<f64>,
    /// Newton increments taken.
    pub increments: u64,
}

impl SimCurve {
    /// The force at `u` (linear between outputs; NaN outside).
    pub fn at(&self, u: f64) -> f64 {
        let n = self.u.len();
        if n < 2 || !(u >= self.u[0] && u <= self.u[n - 1]) {
            return f64::NAN;
        }
        let k = self.u.partition_point(|&x| x <= u).clamp(1, n - 1);
        let (u0, u1) = (self.u[k - 1], self.u[k]);
        let s = (u - u0) / (u1 - u0);
        self.force[k - 1] + s * (self.force[k] - self.force[k - 1])
    }
}

impl VirtualTest {
    fn frames(&self) -> usize {
        (self.u_max / self.step).ceil().max(1.0) as usize
    }

    /// Cells along the length and across the width.
    pub fn mesh(&self) -> [usize; 2] {
        let s = self.specimen;
        let along = (s.height / s.width * self.cells as f64).round() as usize;
        [along.max(1), self.cells.max(1)]
    }

    /// The scene of the test with `material` (a file `drape run` reads).
    pub fn scene_text(&self, material: &Material) -> Result<String, String> {
        let s = self.specimen;
        let [nx, ny] = self.mesh();
        if ((s.height / nx as f64) - (s.width / ny as f64)).abs() > 1e-9 * s.height {
            return Err(format!(
                "a {} × {} mm specimen has no square ±45° cells with {} across its width: \
                 the mesh needs H/W·cells to be whole",
                s.height, s.width, self.cells
            ));
        }
        let card = toml::to_string(material).map_err(|e| e.to_string())?;
        let frames = self.frames();
        // Each table of the card goes under fabric.material.
        let mut body = String::new();
        for line in card.lines() {
            if let Some(rest) = line.strip_prefix('[') {
                body.push_str(&format!("[fabric.material.{rest}\n"));
            } else {
                body.push_str(line);
                body.push('\n');
            }
        }
        Ok(format!(
            "# drape's virtual bias-extension test ({h} × {w} mm, ±45°), written by `drape fit \
             bias-extension --method inverse`.\n\
             [simulation]\nsolver = \"implicit\"\nend_time = 1.0\nframes = {frames}\n\
             max_increment = {inc}\nquasi_static = true\n\n\
             [fabric]\norientation_deg = 45\nfibres = \"trusses\"\n\
             blank = {{ width = {h}, height = {w}, cells = [{nx}, {ny}] }}\n\n\
             [[boundary]]\nnodes = \"left\"\nmotion = {{ kind = \"fixed\" }}\n\n\
             [[boundary]]\nnodes = \"right\"\nmotion = {{ kind = \"displacement\", value = \
             [{u}, 0, 0], amplitude = {{ kind = \"ramp\", duration = 1.0 }} }}\n\n\
             [fabric.material]\n{body}",
            h = s.height,
            w = s.width,
            inc = 1.0 / frames as f64,
            u = self.u_max,
        ))
    }

    /// Runs the test with `material`.
    pub fn run(&self, material: &Material) -> Result<SimCurve, String> {
        let text = self.scene_text(material)?;
        let scene = Scene::parse(&text, "virtual-bias-extension.toml".as_ref(), &[])
            .map_err(|e| e.to_string())?;
        let model = &scene.model;
        let right = model.node_set("right").map_err(|e| e.to_string())?.to_vec();
        let left = model.node_set("left").map_err(|e| e.to_string())?.to_vec();
        struct Clamp<'a> {
            right: &'a [u32],
            left: &'a [u32],
            curve: SimCurve,
            u_max: f64,
        }
        impl Observer for Clamp<'_> {
            fn frame(&mut self, f: &Frame<'_>) {
                let sum = |set: &[u32]| set.iter().map(|&n| f.reactions[n as usize].x).sum::<f64>();
                self.curve.u.push(self.u_max * f.state.time.min(1.0));
                self.curve.force.push(sum(self.right));
                self.curve.held.push(-sum(self.left));
            }
        }
        let mut clamp = Clamp {
            right: &right,
            left: &left,
            curve: SimCurve {
                u: Vec::new(),
                force: Vec::new(),
                held: Vec::new(),
                increments: 0,
            },
            u_max: self.u_max,
        };
        let mut state = model.initial_state();
        let summary = Implicit::new(model, scene.implicit.clone())
            .and_then(|mut d| d.run(&mut state, &mut clamp))
            .map_err(|e| format!("the virtual bias extension failed: {e}"))?;
        clamp.curve.increments = summary.steps;
        Ok(clamp.curve)
    }
}
