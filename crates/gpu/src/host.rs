//! The kernels' CPU build (`kernels/host.c` over `kernels/step.h`): the
//! GPU's arithmetic, one element after another, to test it against the
//! CPU driver without a GPU. Not a fast path: the CPU driver is that.

use drape_model::{Model, State};
use drape_time::Explicit;

use crate::GpuError;
use crate::layout::{Flat, RESIN_STEP, SUMS, history_from_device, join, split};
use crate::schedule::{BatchSteps, Snapshot};
use crate::schedule::{Engine, StepParams};

#[repr(C)]
#[derive(Clone, Copy)]
struct FibreLaw {
    modulus: f64,
    crimp_strain: f64,
    compression_factor: f64,
    buckling_stress: f64,
}

unsafe extern "C" {
    fn drape_host_truss_steps(
        count: i64,
        wave_modulus: f64,
        nodes: *const u32,
        section: *const f64,
        share: *const f64,
        x: *const f64,
        n: i64,
    ) -> f64;
    fn drape_host_bending_steps(
        count: i64,
        nodes: *const u32,
        stiffness: *const f64,
        share: *const f64,
        x: *const f64,
        n: i64,
    ) -> f64;
    fn drape_host_spring_steps(
        count: i64,
        nodes: *const u32,
        anchor: *const f64,
        rest: *const f64,
        table_start: *const i64,
        table_len: *const i64,
        extension: *const f64,
        table_force: *const f64,
        max_stiffness: f64,
        mass: *const f64,
        x: *const f64,
        n: i64,
    ) -> f64;
    fn drape_host_membrane_steps(
        count: i64,
        nodes_per: i32,
        points: i32,
        nodes: *const u32,
        nodal_area: *const f64,
        resin: *const f64,
        grad: *const f64,
        scale: *const f64,
        kappa: f64,
        rho_h: f64,
        x: *const f64,
        n: i64,
    ) -> f64;
    fn drape_host_resin_step_size() -> i64;
    fn drape_host_node_step(
        n: i64,
        params: *const f64,
        x: *const f64,
        v: *const f64,
        weight: *const f64,
        load_ptr: *const i64,
        load_of: *const u32,
        loads: *const f64,
        p_ptr: *const i64,
        p_slot: *const u32,
        p_nodes: *const u32,
        p_count: *const u8,
        p_load: *const u32,
        scales: *const f64,
        f_int: *const f64,
        mass: *const f64,
        fixed: *const u8,
        x0: *const f64,
        moving: *const i32,
        held: *const f64,
        tool: *const f64,
        x_new: *mut f64,
        v_new: *mut f64,
        contact_force: *mut f64,
        status: *mut u8,
        sums: *mut f64,
    ) -> i64;
    fn drape_host_truss_forces(
        count: i64,
        law: FibreLaw,
        nodes: *const u32,
        length: *const f64,
        section: *const f64,
        dashpot: *const f64,
        x: *const f64,
        v: *const f64,
        n: i64,
        slots: *mut f64,
        slot_count: i64,
        first: i64,
    ) -> i64;
    fn drape_host_quad_forces(
        count: i64,
        resin: *const f64,
        nodes: *const u32,
        grad: *const f64,
        area: *const f64,
        history: *mut f64,
        stride: i64,
        commit: i32,
        x: *const f64,
        n: i64,
        slots: *mut f64,
        slot_count: i64,
        first: i64,
    ) -> i64;
    fn drape_host_triangle_forces(
        count: i64,
        resin: *const f64,
        nodes: *const u32,
        grad: *const f64,
        area: *const f64,
        history: *mut f64,
        stride: i64,
        commit: i32,
        x: *const f64,
        n: i64,
        slots: *mut f64,
        slot_count: i64,
        first: i64,
    ) -> i64;
    fn drape_host_bending_forces(
        count: i64,
        nodes: *const u32,
        stiffness: *const f64,
        x: *const f64,
        n: i64,
        slots: *mut f64,
        slot_count: i64,
        first: i64,
    ) -> i64;
    fn drape_host_spring_forces(
        count: i64,
        nodes: *const u32,
        anchor: *const f64,
        rest: *const f64,
        table_start: *const i64,
        table_len: *const i64,
        extension: *const f64,
        table_force: *const f64,
        x: *const f64,
        n: i64,
        slots: *mut f64,
        slot_count: i64,
        first: i64,
    );
    fn drape_host_gather(
        n: i64,
        ptr: *const i64,
        node_slots: *const u32,
        slots: *const f64,
        slot_count: i64,
        f_int: *mut f64,
    );
}

/// The GPU step's kernels run on the CPU, one element after another.
pub struct HostStep<'m> {
    model: &'m Model,
    flat: Flat,
    x: Vec<f64>,
    v: Vec<f64>,
    x_new: Vec<f64>,
    v_new: Vec<f64>,
    f_int: Vec<f64>,
    slots: Vec<f64>,
    contact_force: Vec<f64>,
    status: Vec<u8>,
    sums: Vec<f64>,
    history: Vec<Vec<f64>>,
}

impl<'m> HostStep<'m> {
    /// The step of the model `explicit` runs, with its (scaled) masses,
    /// truss dashpots and contact settings.
    pub fn new(explicit: &Explicit<'m>) -> Result<Self, GpuError> {
        let model = explicit.model();
        let flat = Flat::new(explicit)?;
        let n = flat.nodes;
        // SAFETY: no arguments; the C struct the resin steps are read as.
        let bytes = unsafe { drape_host_resin_step_size() } as usize;
        assert_eq!(bytes, RESIN_STEP * std::mem::size_of::<f64>());
        Ok(Self {
            model,
            x: vec![0.0; 3 * n],
            v: vec![0.0; 3 * n],
            x_new: vec![0.0; 3 * n],
            v_new: vec![0.0; 3 * n],
            f_int: vec![0.0; 3 * n],
            contact_force: vec![0.0; 3 * n],
            status: vec![0; n],
            sums: vec![0.0; SUMS * n],
            slots: vec![0.0; 3 * flat.slot_count],
            history: Vec::new(),
            flat,
        })
    }

    fn forces(&mut self, dt: f64, commit: bool, step: u64) -> Result<(), GpuError> {
        let f = &self.flat;
        let (n, sc) = (f.nodes as i64, f.slot_count as i64);
        let slots = self.slots.as_mut_ptr();
        for t in &f.trusses {
            let law = FibreLaw {
                modulus: t.law[0],
                crimp_strain: t.law[1],
                compression_factor: t.law[2],
                buckling_stress: t.law[3],
            };
            let dashpot = if t.dashpot.is_empty() {
                std::ptr::null()
            } else {
                t.dashpot.as_ptr()
            };
            // SAFETY: every array has the length the kernel reads (built
            // together in `Flat::new`); the slots of the batch are its own.
            let fault = unsafe {
                drape_host_truss_forces(
                    t.length.len() as i64,
                    law,
                    t.nodes.as_ptr(),
                    t.length.as_ptr(),
                    t.section.as_ptr(),
                    dashpot,
                    self.x.as_ptr(),
                    self.v.as_ptr(),
                    n,
                    slots,
                    sc,
                    t.first as i64,
                )
            };
            if fault >= 0 {
                return Err(GpuError::Element {
                    kind: "truss",
                    index: fault as usize,
                    step,
                });
            }
        }
        for (q, h) in f.quads.iter().zip(&mut self.history) {
            let resin = q.step(dt);
            // SAFETY: as above; `h` is the batch's value-major history.
            let membrane_forces = if q.triangles {
                drape_host_triangle_forces
            } else {
                drape_host_quad_forces
            };
            let fault = unsafe {
                membrane_forces(
                    q.count() as i64,
                    resin.as_ptr(),
                    q.nodes.as_ptr(),
                    q.grad.as_ptr(),
                    q.area.as_ptr(),
                    h.as_mut_ptr(),
                    q.stride as i64,
                    i32::from(commit),
                    self.x.as_ptr(),
                    n,
                    slots,
                    sc,
                    q.first as i64,
                )
            };
            if fault >= 0 {
                return Err(GpuError::Element {
                    kind: if q.triangles { "triangle" } else { "quad" },
                    index: fault as usize,
                    step,
                });
            }
        }
        for s in &f.springs {
            // SAFETY: as above.
            unsafe {
                drape_host_spring_forces(
                    s.nodes.len() as i64,
                    s.nodes.as_ptr(),
                    s.anchor.as_ptr(),
                    s.rest.as_ptr(),
                    s.table_start.as_ptr(),
                    s.table_len.as_ptr(),
                    s.extension.as_ptr(),
                    s.force.as_ptr(),
                    self.x.as_ptr(),
                    n,
                    slots,
                    sc,
                    s.first as i64,
                )
            };
        }
        for b in &f.bending {
            // SAFETY: as above.
            let fault = unsafe {
                drape_host_bending_forces(
                    b.stiffness.len() as i64,
                    b.nodes.as_ptr(),
                    b.stiffness.as_ptr(),
                    self.x.as_ptr(),
                    n,
                    slots,
                    sc,
                    b.first as i64,
                )
            };
            if fault >= 0 {
                return Err(GpuError::Element {
                    kind: "bending triplet",
                    index: fault as usize,
                    step,
                });
            }
        }
        // SAFETY: ptr has n + 1 entries indexing node_slots; f_int 3n.
        unsafe {
            drape_host_gather(
                n,
                f.ptr.as_ptr(),
                f.node_slots.as_ptr(),
                self.slots.as_ptr(),
                sc,
                self.f_int.as_mut_ptr(),
            )
        };
        Ok(())
    }

    fn update(&mut self, p: StepParams, values: &[f64], step: u64) -> Result<(), GpuError> {
        let f = &self.flat;
        let params = p.values();
        let tool = if f.tool.is_empty() {
            std::ptr::null()
        } else {
            f.tool.as_ptr()
        };
        assert_eq!(values.len(), f.step_width(), "a step's values");
        let (held, rest) = values.split_at(f.prescribed.len());
        let (loads, scales) = rest.split_at(3 * f.loads);
        let or_null = |v: &[f64]| {
            if v.is_empty() {
                std::ptr::null()
            } else {
                v.as_ptr()
            }
        };
        // SAFETY: every node array has 3n entries (fixed, moving and mass
        // n, load_ptr n + 1, the sums SUMS·n), the params 10, the tool as
        // step.h reads it, `held` one per moving component (`moving`
        // indexes it), `loads` three per load (`load_of` indexes it), the
        // pressure slots as drape_pressure reads them.
        let fault = unsafe {
            drape_host_node_step(
                f.nodes as i64,
                params.as_ptr(),
                self.x.as_ptr(),
                self.v.as_ptr(),
                f.weight.as_ptr(),
                f.load_ptr.as_ptr(),
                f.load_of.as_ptr(),
                or_null(loads),
                f.p_ptr.as_ptr(),
                f.p_slot.as_ptr(),
                f.p_nodes.as_ptr(),
                f.p_count.as_ptr(),
                f.p_load.as_ptr(),
                or_null(scales),
                self.f_int.as_ptr(),
                f.mass.as_ptr(),
                f.fixed.as_ptr(),
                f.x0.as_ptr(),
                f.moving.as_ptr(),
                held.as_ptr(),
                tool,
                self.x_new.as_mut_ptr(),
                self.v_new.as_mut_ptr(),
                self.contact_force.as_mut_ptr(),
                self.status.as_mut_ptr(),
                self.sums.as_mut_ptr(),
            )
        };
        if fault >= 0 {
            return Err(GpuError::contact_fault(fault as u64, step));
        }
        std::mem::swap(&mut self.x, &mut self.x_new);
        std::mem::swap(&mut self.v, &mut self.v_new);
        Ok(())
    }
}

impl Engine for HostStep<'_> {
    fn load(&mut self, state: &State) -> Result<(), GpuError> {
        self.x = split(&state.x);
        self.v = split(&state.v);
        self.history = Flat::histories(self.model, state);
        Ok(())
    }

    fn store(&mut self, state: &mut State) -> Result<(), GpuError> {
        state.x = join(&self.x);
        state.v = join(&self.v);
        for ((b, d), h) in self
            .model
            .membranes
            .iter()
            .zip(&self.history)
            .zip(&mut state.history)
        {
            *h = history_from_device(b, d);
        }
        Ok(())
    }

    fn batch_steps(&mut self, out: &mut BatchSteps) -> Result<(), GpuError> {
        let f = &self.flat;
        let (x, n) = (self.x.as_ptr(), f.nodes as i64);
        // SAFETY (every call): the arrays were built together in
        // `Flat::new` with the lengths the loops read.
        let steps = BatchSteps {
            trusses: f
                .trusses
                .iter()
                .map(|t| unsafe {
                    drape_host_truss_steps(
                        t.length.len() as i64,
                        t.wave_modulus,
                        t.nodes.as_ptr(),
                        t.section.as_ptr(),
                        t.share.as_ptr(),
                        x,
                        n,
                    )
                })
                .collect(),
            membranes: f
                .quads
                .iter()
                .map(|q| unsafe {
                    drape_host_membrane_steps(
                        q.count() as i64,
                        if q.triangles { 3 } else { 4 },
                        q.points() as i32,
                        q.nodes.as_ptr(),
                        q.nodal_area.as_ptr(),
                        q.step(0.0).as_ptr(),
                        q.grad.as_ptr(),
                        q.scale.as_ptr(),
                        q.kappa,
                        q.rho_h,
                        x,
                        n,
                    )
                })
                .collect(),
            springs: f
                .springs
                .iter()
                .map(|s| unsafe {
                    drape_host_spring_steps(
                        s.nodes.len() as i64,
                        s.nodes.as_ptr(),
                        s.anchor.as_ptr(),
                        s.rest.as_ptr(),
                        s.table_start.as_ptr(),
                        s.table_len.as_ptr(),
                        s.extension.as_ptr(),
                        s.force.as_ptr(),
                        s.max_stiffness,
                        f.mass.as_ptr(),
                        x,
                        n,
                    )
                })
                .collect(),
            bending: f
                .bending
                .iter()
                .map(|b| unsafe {
                    drape_host_bending_steps(
                        b.stiffness.len() as i64,
                        b.nodes.as_ptr(),
                        b.stiffness.as_ptr(),
                        b.share.as_ptr(),
                        x,
                        n,
                    )
                })
                .collect(),
        };
        // (The CPU build is a check, not a fast path: it allocates.)
        *out = steps;
        Ok(())
    }

    fn snapshot(&mut self, state: &mut State) -> Result<Snapshot, GpuError> {
        self.store(state)?;
        Ok(Snapshot {
            f_int: join(&self.f_int),
            contact_force: join(&self.contact_force),
            status: self.status.clone(),
            sums: self.sums.clone(),
        })
    }

    fn start_forces(&mut self, dt: f64) -> Result<(), GpuError> {
        self.forces(dt, false, 0)
    }

    fn steps(&mut self, params: &[StepParams], values: &[f64], step: u64) -> Result<(), GpuError> {
        let w = self.flat.step_width();
        for (k, p) in params.iter().enumerate() {
            let at = step + k as u64 + 1;
            self.update(*p, &values[k * w..(k + 1) * w], at)?;
            self.forces(p.h, true, at)?;
        }
        Ok(())
    }
}
