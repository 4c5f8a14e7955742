//! A model flattened into the arrays the kernels read: 3-vectors
//! node-major, reference gradients and histories element-minor (see
//! `kernels/step.h`).

use drape_constitutive::ResinLaw;
use drape_contact::{ContactSettings, ProfileSegment, Surface, Tool};
use drape_elements::{MembraneBatch, MembraneShape};
use drape_model::{Model, State};
use drape_time::{Explicit, PrescribedMotions, PressurePass};
use nalgebra::Vector3;

use crate::GpuError;

/// The most Prony terms the kernels carry (`DRAPE_MAX_PRONY`).
pub(crate) const MAX_PRONY: usize = 8;
/// The most shear-locking coefficients they carry (`DRAPE_MAX_LOCKING`).
pub(crate) const MAX_LOCKING: usize = 8;
/// Doubles of a `DrapeResinStep` ([`Quads::step`]).
pub(crate) const RESIN_STEP: usize = 42;
/// Running sums per node (`DRAPE_SUMS`).
pub(crate) const SUMS: usize = 8;

/// What `model` uses that the GPU step does not do yet, named as a scene
/// names it; empty when the GPU can step it.
pub fn unsupported(model: &Model) -> Vec<String> {
    let f = model.features();
    let mut out = Vec::new();
    let mut no = |used: bool, what: &str| {
        if used {
            out.push(what.to_owned());
        }
    };
    no(
        model.tools.len() > 1,
        "more than one tool (the coupled contact solve of a node between two tools)",
    );
    no(
        f.force_driven_tools,
        "a force-driven tool (motion.kind = \"force\")",
    );
    no(
        model
            .tools
            .iter()
            .any(|t| matches!(t.surface, Surface::Mesh(_))),
        "a triangle-mesh tool (geometry from an STL or OBJ file)",
    );
    no(model.plies.len() > 1, "a stack of plies ([[plies]])");
    no(
        model.membranes.iter().any(|b| {
            b.section
                .material
                .resin
                .shear_locking
                .as_ref()
                .is_some_and(|l| l.coefficients.len() > MAX_LOCKING)
        }),
        "a shear-locking law of more than 8 coefficients",
    );
    no(
        model
            .membranes
            .iter()
            .any(|b| b.section.material.resin.prony.len() > MAX_PRONY),
        "a resin of more than 8 Prony terms",
    );
    out
}

/// A truss batch.
pub(crate) struct Trusses {
    /// [E_f, ε_sh, c_c, σ_b].
    pub law: [f64; 4],
    pub nodes: Vec<u32>,
    pub length: Vec<f64>,
    pub section: Vec<f64>,
    /// Empty for a batch without dashpots.
    pub dashpot: Vec<f64>,
    pub first: usize,
    /// The stable step's: the law's wave modulus and the nodes' mass
    /// shares (2 per truss).
    pub wave_modulus: f64,
    pub share: Vec<f64>,
}

/// A membrane batch (quads or triangles; resin only, or with embedded
/// fibres).
pub(crate) struct Quads {
    /// Whether its elements are triangles (3 nodes, 1 point), else quads.
    pub triangles: bool,
    pub resin: ResinLaw,
    pub constants: [f64; 5],
    /// Embedded fibres (1 or 0), each family's thickness t_f and the
    /// fibres' law [E_f, ε_sh, c_c, σ_b]: zeros without.
    pub fibres: [f64; 6],
    /// The shear-locking law as `DrapeResinStep` holds it (1 or 0, the
    /// fabric's thickness, the number of coefficients, the coefficients,
    /// whether a friction term, its τ_f and γ_f): zeros without.
    pub locking: [f64; 6 + MAX_LOCKING],
    pub nodes: Vec<u32>,
    /// ∂N/∂X, value (point, node, component) of element e at [v·count + e].
    pub grad: Vec<f64>,
    /// Point p's area at [p·count + e].
    pub area: Vec<f64>,
    pub stride: usize,
    pub first: usize,
    /// The stable step's: the nodes' reference areas (node a's at
    /// [a·count + e]),
    /// each element's mass-scaling factor, the stiffness bound κ and ρh.
    pub nodal_area: Vec<f64>,
    pub scale: Vec<f64>,
    pub kappa: f64,
    pub rho_h: f64,
}

impl Quads {
    pub fn count(&self) -> usize {
        self.area.len() / self.points()
    }

    /// Integration points per element.
    pub fn points(&self) -> usize {
        if self.triangles { 1 } else { 4 }
    }

    /// The kernels' `DrapeResinStep` for a step `dt`, as its doubles (the
    /// prony count in the low bytes of the sixth).
    pub fn step(&self, dt: f64) -> [f64; RESIN_STEP] {
        let mut factors = [(0.0, 0.0); MAX_PRONY];
        let terms = self.resin.prony.len();
        self.resin.prony_factors(dt, &mut factors[..terms]);
        let mut out = [0.0; RESIN_STEP];
        out[..5].copy_from_slice(&self.constants);
        out[6 + 2 * MAX_PRONY..12 + 2 * MAX_PRONY].copy_from_slice(&self.fibres);
        out[12 + 2 * MAX_PRONY..].copy_from_slice(&self.locking);
        out[5] = f64::from_bits(terms as u64);
        for (q, (decay, weight)) in factors.iter().enumerate() {
            out[6 + q] = *decay;
            out[6 + MAX_PRONY + q] = *weight;
        }
        out
    }
}

/// `Quads::locking` of a resin.
fn locking(resin: &ResinLaw, thickness: f64) -> [f64; 6 + MAX_LOCKING] {
    let mut out = [0.0; 6 + MAX_LOCKING];
    if let Some(law) = &resin.shear_locking {
        out[0] = 1.0;
        out[1] = thickness;
        out[2] = law.coefficients.len() as f64;
        out[3..3 + law.coefficients.len()].copy_from_slice(&law.coefficients);
        if let Some([tau, gamma]) = law.friction {
            out[3 + MAX_LOCKING..].copy_from_slice(&[1.0, tau, gamma]);
        }
    }
    out
}

/// A bending batch.
pub(crate) struct Bending {
    pub nodes: Vec<u32>,
    pub stiffness: Vec<f64>,
    pub first: usize,
    /// The nodes' mass shares (3 per triplet), for the stable step.
    pub share: Vec<f64>,
}

/// A spring batch.
pub(crate) struct Springs {
    pub nodes: Vec<u32>,
    /// Node-major, as every 3-vector.
    pub anchor: Vec<f64>,
    pub rest: Vec<f64>,
    pub table_start: Vec<i64>,
    pub table_len: Vec<i64>,
    pub extension: Vec<f64>,
    pub force: Vec<f64>,
    pub first: usize,
    /// The table's largest slope, for the stable step.
    pub max_stiffness: f64,
}

/// The model as the kernels read it.
pub(crate) struct Flat {
    pub nodes: usize,
    pub slot_count: usize,
    pub trusses: Vec<Trusses>,
    pub quads: Vec<Quads>,
    pub springs: Vec<Springs>,
    pub bending: Vec<Bending>,
    pub ptr: Vec<i64>,
    pub node_slots: Vec<u32>,
    pub mass: Vec<f64>,
    /// Bit k: component k constrained; bit 3 + k: moved by a boundary
    /// motion (step.h's `drape_held`).
    pub fixed: Vec<u8>,
    /// Per node with a moving component, its first one's index in
    /// `prescribed` (0 for the others, which never read it).
    pub moving: Vec<i32>,
    /// The moving components, whose coordinates each step is handed.
    pub prescribed: PrescribedMotions,
    /// Node i's nodal loads `load_of[load_ptr[i]..load_ptr[i + 1]]`, in the
    /// model's order (each step is handed their forces).
    pub load_ptr: Vec<i64>,
    pub load_of: Vec<u32>,
    /// How many nodal loads the model has.
    pub loads: usize,
    /// Node i's pressure slots `p_slot[p_ptr[i]..p_ptr[i + 1]]`
    /// (`drape_time::PressurePass`'s order); per slot its element's nodes
    /// (4, the last unused for a triangle), their count and its load.
    pub p_ptr: Vec<i64>,
    pub p_slot: Vec<u32>,
    pub p_nodes: Vec<u32>,
    pub p_count: Vec<u8>,
    pub p_load: Vec<u32>,
    /// How many pressure loads the model has.
    pub pressures: usize,
    pub x0: Vec<f64>,
    /// Each node's weight (the external force without the loads and
    /// pressures).
    pub weight: Vec<f64>,
    /// The tool as `kernels/step.h` reads it (`DRAPE_TOOL_*`); empty for a
    /// model without one.
    pub tool: Vec<f64>,
}

/// `tool` as `kernels/step.h` reads it, with the contact pass's `offset`
/// (half the thickness), fault tolerance `slack` and largest travel.
pub(crate) fn encode_tool(tool: &Tool, offset: f64, slack: f64, max_travel: f64) -> Vec<f64> {
    let mut t = vec![0.0; 18];
    let put3 = |t: &mut Vec<f64>, at: usize, v: &Vector3<f64>| {
        t[at..at + 3].copy_from_slice(v.as_slice());
    };
    match &tool.surface {
        Surface::Plane { point, normal } => {
            t[0] = 0.0;
            put3(&mut t, 1, point);
            put3(&mut t, 4, normal);
        }
        Surface::Sphere { center, radius } => {
            t[0] = 1.0;
            put3(&mut t, 1, center);
            t[7] = *radius;
        }
        Surface::Revolution {
            origin,
            profile,
            free_ends,
        } => {
            t[0] = 2.0;
            put3(&mut t, 1, origin);
            t[8] = f64::from(u8::from(free_ends[0]));
            t[9] = f64::from(u8::from(free_ends[1]));
            t[17] = profile.len() as f64;
            for s in profile {
                t.extend(match *s {
                    ProfileSegment::Line { from, to } => [0.0, from[0], from[1], to[0], to[1], 0.0],
                    ProfileSegment::Arc {
                        center,
                        radius,
                        from_deg,
                        to_deg,
                    } => [1.0, center[0], center[1], radius, from_deg, to_deg],
                });
            }
        }
        Surface::Mesh(_) => unreachable!("refused by `unsupported`"),
    }
    put3(&mut t, 10, &tool.motion.direction());
    t[13] = tool.friction;
    t[14] = offset;
    t[15] = slack;
    t[16] = max_travel;
    t
}

/// `v` as the kernels read 3-vectors: node-major, [3i + k].
pub(crate) fn split(v: &[Vector3<f64>]) -> Vec<f64> {
    v.iter().flat_map(|p| [p.x, p.y, p.z]).collect()
}

/// The 3-vectors of a node-major array.
pub(crate) fn join(a: &[f64]) -> Vec<Vector3<f64>> {
    a.chunks_exact(3)
        .map(|p| Vector3::new(p[0], p[1], p[2]))
        .collect()
}

/// Batch `b`'s history, value-major, from the CPU's layout.
pub(crate) fn history_to_device(b: &MembraneBatch, h: &[f64]) -> Vec<f64> {
    let (count, eh) = (b.len(), b.element_history_len());
    let mut out = vec![0.0; h.len()];
    for e in 0..count {
        for (j, v) in b.element_history(h, e).iter().enumerate() {
            out[j * count + e] = *v;
        }
    }
    debug_assert_eq!(out.len(), count * eh);
    out
}

/// Batch `b`'s history in the CPU's layout, from the value-major one.
pub(crate) fn history_from_device(b: &MembraneBatch, d: &[f64]) -> Vec<f64> {
    let (count, eh) = (b.len(), b.element_history_len());
    let mut out = vec![0.0; d.len()];
    let mut values = vec![0.0; eh];
    for e in 0..count {
        for (j, v) in values.iter_mut().enumerate() {
            *v = d[j * count + e];
        }
        b.set_element_history(&mut out, e, &values);
    }
    out
}

impl Flat {
    /// The model `explicit` runs, with its (scaled) masses, truss dashpots,
    /// contact settings and what its stable step reads.
    pub fn new(explicit: &Explicit<'_>) -> Result<Self, GpuError> {
        let model = explicit.model();
        let (mass, dashpots) = (explicit.mass(), explicit.fibre_dashpots());
        let contact: Option<&ContactSettings> = explicit.contact().map(|c| &c.settings);
        let inputs = explicit.step_inputs();
        let missing = unsupported(model);
        if !missing.is_empty() {
            return Err(GpuError::Unsupported(missing));
        }
        let layout = model.slot_layout();
        let n = model.node_count();
        let trusses = model
            .trusses
            .iter()
            .zip(&layout.truss_offsets)
            .enumerate()
            .map(|(b, (t, &first))| Trusses {
                law: [
                    t.law.modulus,
                    t.law.crimp_strain,
                    t.law.compression_factor,
                    t.law.buckling_stress,
                ],
                nodes: t.nodes.iter().flatten().copied().collect(),
                length: t.length.clone(),
                section: t.section.clone(),
                dashpot: dashpots.get(b).cloned().unwrap_or_default(),
                first,
                wave_modulus: t.law.wave_modulus(),
                share: inputs.truss_mass[b].iter().flatten().copied().collect(),
            })
            .collect();
        let quads = model
            .membranes
            .iter()
            .zip(&layout.membrane_offsets)
            .zip(inputs.membrane_scale)
            .map(|((m, &first), scale)| {
                let count = m.len();
                let shape = m.shape();
                let (nn, np) = (shape.nodes(), shape.points());
                // Element-minor: value v of element e at [v·count + e].
                let mut grad = vec![0.0; count * 2 * nn * np];
                let mut area = vec![0.0; count * np];
                let mut nodes = Vec::with_capacity(count * nn);
                for e in 0..count {
                    nodes.extend_from_slice(m.element_nodes(e));
                    for p in 0..np {
                        for (a, g) in m.point_gradients(e, p).iter().enumerate() {
                            grad[((p * nn + a) * 2) * count + e] = g.x;
                            grad[((p * nn + a) * 2 + 1) * count + e] = g.y;
                        }
                        area[p * count + e] = m.point_weight(e, p);
                    }
                }
                let material = &m.section.material;
                let resin = material.resin.clone();
                // Summed as the CPU pass sums it (quad_lanes' ResinStep).
                let mut long_term = 1.0;
                for p in &resin.prony {
                    long_term -= p.g;
                }
                Quads {
                    triangles: shape == MembraneShape::Triangle,
                    constants: [
                        resin.wave_modulus(),
                        resin.poisson,
                        resin.shear_modulus(),
                        long_term,
                        material.resin_thickness(),
                    ],
                    resin,
                    fibres: if m.section.embedded_fibres {
                        let law = &material.fibre;
                        [
                            1.0,
                            material.family_thickness(),
                            law.modulus,
                            law.crimp_strain,
                            law.compression_factor,
                            law.buckling_stress,
                        ]
                    } else {
                        [0.0; 6]
                    },
                    locking: locking(&material.resin, material.thickness),
                    nodes,
                    grad,
                    area,
                    stride: m.history_stride(),
                    first,
                    nodal_area: (0..nn)
                        .flat_map(|a| (0..count).map(move |e| m.nodal_areas(e)[a]))
                        .collect(),
                    scale: scale.clone(),
                    kappa: m.stiffness_bound(),
                    rho_h: material.areal_density(),
                }
            })
            .collect();
        let springs = model
            .springs
            .iter()
            .zip(&layout.spring_offsets)
            .map(|(s, &first)| {
                let points: Vec<[f64; 2]> = s.table.clone().into();
                let count = s.len();
                Springs {
                    nodes: s.nodes.clone(),
                    anchor: split(&s.anchors),
                    rest: s.rest_length.clone(),
                    table_start: vec![0; count],
                    table_len: vec![points.len() as i64; count],
                    extension: points.iter().map(|p| p[0]).collect(),
                    force: points.iter().map(|p| p[1]).collect(),
                    first,
                    max_stiffness: s.table.max_stiffness(),
                }
            })
            .collect();
        let bending = model
            .bending
            .iter()
            .zip(&layout.bending_offsets)
            .zip(inputs.bending_mass)
            .map(|((b, &first), share)| Bending {
                nodes: b.nodes.iter().flatten().copied().collect(),
                stiffness: b.stiffnesses().to_vec(),
                first,
                share: share.iter().flatten().copied().collect(),
            })
            .collect();
        let (ptr, node_slots) = layout.node_slot_lists();
        let mut fixed: Vec<u8> = drape_time::constrained_components(model)
            .iter()
            .map(|c| (0..3).filter(|&k| c[k]).fold(0, |bits, k| bits | 1 << k))
            .collect();
        // step.h's drape_held: bit 3 + k for a moving component, the node's
        // first in the step's list of prescribed coordinates.
        let mut moving = vec![0i32; n];
        let prescribed = PrescribedMotions::new(model);
        for (j, (i, k)) in prescribed.components().enumerate() {
            if fixed[i] >> 3 == 0 {
                moving[i] = j as i32;
            }
            fixed[i] |= 8 << k;
        }
        let owners = model
            .loads
            .iter()
            .enumerate()
            .flat_map(|(l, load)| load.nodes.iter().map(move |&i| (i, l as u32)));
        let (load_ptr, load_of) = drape_model::node_slots(n, owners);
        let pass = PressurePass::new(model);
        let (p_ptr, p_slot) = if pass.is_empty() {
            (&[0usize][..], &[][..])
        } else {
            pass.node_slot_lists()
        };
        let (mut p_nodes, mut p_count, mut p_load) = (Vec::new(), Vec::new(), Vec::new());
        for &(l, e) in pass.slots() {
            let nodes = model.pressure[l as usize].element(e as usize);
            p_nodes.extend((0..4).map(|a| nodes.get(a).copied().unwrap_or(0)));
            p_count.push(nodes.len() as u8);
            p_load.push(l);
        }
        // Weight from the physical mass (drape-time's external forces).
        let weight: Vec<Vector3<f64>> = model.mass.iter().map(|m| model.gravity * *m).collect();
        Ok(Self {
            nodes: n,
            slot_count: layout.len,
            trusses,
            quads,
            springs,
            bending,
            ptr: ptr.iter().map(|&p| p as i64).collect(),
            node_slots: node_slots.to_vec(),
            mass: mass.to_vec(),
            fixed,
            moving,
            prescribed,
            load_ptr: load_ptr.iter().map(|&p| p as i64).collect(),
            load_of,
            loads: model.loads.len(),
            p_ptr: p_ptr.iter().map(|&p| p as i64).collect(),
            p_slot: p_slot.to_vec(),
            p_nodes,
            p_count,
            p_load,
            pressures: model.pressure.len(),
            x0: split(&model.x0),
            weight: split(&weight),
            tool: match (model.tools.first(), contact) {
                (Some(tool), Some(c)) => {
                    encode_tool(tool, c.offset, c.fault_tolerance, c.max_travel)
                }
                (Some(_), None) => {
                    return Err(GpuError::Unsupported(vec![
                        "a tool without the driver's contact settings".into(),
                    ]));
                }
                (None, _) => Vec::new(),
            },
        })
    }

    /// Values handed per step (`Engine::steps`' `values`): each moving
    /// component's coordinate, each nodal load's force, then each
    /// pressure's p·a(t).
    pub fn step_width(&self) -> usize {
        self.prescribed.len() + 3 * self.loads + self.pressures
    }

    /// Every membrane batch's history, value-major, from `state`.
    pub fn histories(model: &Model, state: &State) -> Vec<Vec<f64>> {
        model
            .membranes
            .iter()
            .zip(&state.history)
            .map(|(b, h)| history_to_device(b, h))
            .collect()
    }
}
