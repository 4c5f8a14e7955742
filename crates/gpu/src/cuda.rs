//! The step on an NVIDIA GPU through cudarc: the model's arrays uploaded
//! once, the kernels compiled by NVRTC, a block of equal steps captured
//! once as a CUDA graph and replayed, the state downloaded only when the
//! host asks for it.

use std::sync::Arc;

use cudarc::driver::{
    CudaContext, CudaEvent, CudaFunction, CudaGraph, CudaSlice, CudaStream, DeviceRepr,
    LaunchConfig, PushKernelArg, ValidAsZeroBits, sys,
};
use cudarc::nvrtc::{CompileOptions, Ptx, compile_ptx_with_opts};
use drape_model::{Model, State};
use drape_time::Explicit;

use crate::GpuError;
use crate::layout::{Flat, SUMS, history_from_device, join, split};
use crate::schedule::{BatchSteps, Snapshot};
use crate::schedule::{Engine, StepParams};

/// Threads per block of every kernel unless set otherwise (the results do
/// not depend on it).
const BLOCK: u32 = 256;
/// Steps in the captured graph (even, so the position buffers it swaps
/// end where they started).
const GRAPH_STEPS: u64 = 20;
/// "No fault" in a kernel's fault word.
const NO_FAULT: i32 = i32::MAX;
/// Fault words: truss, quad, contact, bending.
const FAULTS: [i32; 4] = [NO_FAULT; 4];
/// Doubles of one step's params (`DRAPE_PARAMS`).
const PARAMS: usize = 10;

/// The CUDA source NVRTC compiles: `step.h` then `cuda.cu`.
pub fn kernel_source() -> String {
    format!(
        "{}\n{}",
        include_str!("../kernels/step.h"),
        include_str!("../kernels/cuda.cu")
    )
}

/// Whether the CUDA driver library and NVRTC can be opened, and how many
/// GPUs the driver sees: `Err` with what is missing. cudarc panics on first
/// use of a library it cannot open, so this runs before any other call.
pub fn probe() -> Result<usize, GpuError> {
    // SAFETY: opening a shared library by name runs its initialisers; these
    // are the CUDA libraries cudarc opens itself.
    if !unsafe { cudarc::driver::sys::is_culib_present() } {
        return Err(GpuError::NoDevice(
            "the CUDA driver library (libcuda.so.1) was not found: is an NVIDIA driver installed?"
                .into(),
        ));
    }
    // SAFETY: as above.
    if !unsafe { cudarc::nvrtc::sys::is_culib_present() } {
        return Err(GpuError::NoDevice(
            "NVRTC (libnvrtc.so) was not found: add the CUDA toolkit's lib64 folder to \
             LD_LIBRARY_PATH"
                .into(),
        ));
    }
    let count = CudaContext::device_count().map_err(|e| GpuError::NoDevice(e.to_string()))?;
    if count < 1 {
        return Err(GpuError::NoDevice("the CUDA driver sees no GPU".into()));
    }
    Ok(count as usize)
}

/// Compiles the kernels to PTX for `arch` (e.g. "compute_90"; None: NVRTC's
/// default) without fused multiply-adds. Needs NVRTC only, not a GPU: CI
/// checks with it that the kernels compile.
pub fn compile_kernels(arch: Option<&str>) -> Result<Ptx, GpuError> {
    // SAFETY: see `probe`.
    if !unsafe { cudarc::nvrtc::sys::is_culib_present() } {
        return Err(GpuError::NoDevice(
            "NVRTC (libnvrtc.so) was not found".into(),
        ));
    }
    let mut options = vec!["--std=c++17".to_owned()];
    if let Some(a) = arch {
        options.push(format!("--gpu-architecture={a}"));
    }
    compile_ptx_with_opts(
        kernel_source(),
        CompileOptions {
            fmad: Some(false),
            prec_div: Some(true),
            prec_sqrt: Some(true),
            ftz: Some(false),
            options,
            ..Default::default()
        },
    )
    .map_err(|e| GpuError::Cuda(format!("the kernels do not compile: {e}")))
}

fn cuda(e: impl std::fmt::Display) -> GpuError {
    GpuError::Cuda(e.to_string())
}

fn upload<T: DeviceRepr + Copy + Default>(
    stream: &Arc<CudaStream>,
    v: &[T],
) -> Result<CudaSlice<T>, GpuError> {
    // (A zero-length allocation is refused.)
    if v.is_empty() {
        return stream.clone_htod(&[T::default()]).map_err(cuda);
    }
    stream.clone_htod(v).map_err(cuda)
}

fn zeros<T: DeviceRepr + ValidAsZeroBits>(
    stream: &Arc<CudaStream>,
    len: usize,
) -> Result<CudaSlice<T>, GpuError> {
    stream.alloc_zeros(len.max(1)).map_err(cuda)
}

/// While profiling (`timing` is Some), an event on `stream` after the
/// kernels of kind `kind`.
fn mark(
    timing: &mut Option<Vec<(usize, CudaEvent)>>,
    stream: &Arc<CudaStream>,
    kind: usize,
) -> Result<(), GpuError> {
    if let Some(t) = timing {
        let event = stream
            .context()
            .new_event(Some(sys::CUevent_flags::CU_EVENT_DEFAULT))
            .map_err(cuda)?;
        event.record(stream).map_err(cuda)?;
        t.push((kind, event));
    }
    Ok(())
}

fn grid(count: usize, block: u32) -> LaunchConfig {
    LaunchConfig {
        grid_dim: ((count as u32).div_ceil(block).max(1), 1, 1),
        block_dim: (block, 1, 1),
        shared_mem_bytes: 0,
    }
}

struct DevTrusses {
    count: i64,
    law: [f64; 4],
    nodes: CudaSlice<u32>,
    length: CudaSlice<f64>,
    section: CudaSlice<f64>,
    has_dashpot: i32,
    dashpot: CudaSlice<f64>,
    first: i64,
    wave_modulus: f64,
    share: CudaSlice<f64>,
}

struct DevQuads {
    triangles: bool,
    count: i64,
    resin: CudaSlice<f64>,
    nodes: CudaSlice<u32>,
    grad: CudaSlice<f64>,
    area: CudaSlice<f64>,
    history: CudaSlice<f64>,
    stride: i64,
    first: i64,
    nodal_area: CudaSlice<f64>,
    scale: CudaSlice<f64>,
    kappa: f64,
    rho_h: f64,
}

struct DevSprings {
    count: i64,
    nodes: CudaSlice<u32>,
    anchor: CudaSlice<f64>,
    rest: CudaSlice<f64>,
    table_start: CudaSlice<i64>,
    table_len: CudaSlice<i64>,
    extension: CudaSlice<f64>,
    force: CudaSlice<f64>,
    first: i64,
    max_stiffness: f64,
}

struct DevBending {
    count: i64,
    nodes: CudaSlice<u32>,
    stiffness: CudaSlice<f64>,
    first: i64,
    share: CudaSlice<f64>,
}

struct Kernels {
    truss: CudaFunction,
    quad: CudaFunction,
    triangle: CudaFunction,
    spring: CudaFunction,
    gather: CudaFunction,
    gather_node_step: CudaFunction,
    bending: CudaFunction,
    truss_steps: CudaFunction,
    membrane_steps: CudaFunction,
    spring_steps: CudaFunction,
    bending_steps: CudaFunction,
}

/// The step of a model on a GPU.
pub struct CudaStep<'m> {
    model: &'m Model,
    flat: Flat,
    stream: Arc<CudaStream>,
    kernels: Kernels,
    trusses: Vec<DevTrusses>,
    quads: Vec<DevQuads>,
    springs: Vec<DevSprings>,
    bending: Vec<DevBending>,
    ptr: CudaSlice<i64>,
    node_slots: CudaSlice<u32>,
    mass: CudaSlice<f64>,
    fixed: CudaSlice<u8>,
    /// step.h's `drape_held`: per node, its first moving component's
    /// index in a step's prescribed coordinates.
    moving: CudaSlice<i32>,
    x0: CudaSlice<f64>,
    weight: CudaSlice<f64>,
    /// Node i's nodal loads, `load_of[load_ptr[i]..load_ptr[i + 1]]`.
    load_ptr: CudaSlice<i64>,
    load_of: CudaSlice<u32>,
    has_loads: i32,
    /// Node i's pressure slots and their elements (`Flat`'s `p_*`).
    p_ptr: CudaSlice<i64>,
    p_slot: CudaSlice<u32>,
    p_nodes: CudaSlice<u32>,
    p_count: CudaSlice<u8>,
    p_load: CudaSlice<u32>,
    has_pressure: i32,
    /// Positions and velocities: [0] current, [1] the other buffer
    /// (swapped by `parity`).
    x: [CudaSlice<f64>; 2],
    v: [CudaSlice<f64>; 2],
    f_int: CudaSlice<f64>,
    slots: CudaSlice<f64>,
    /// The tool (`DRAPE_TOOL_*`), when `has_tool`.
    tool: CudaSlice<f64>,
    has_tool: i32,
    /// Streams the element kinds run on beside the main one (each truss
    /// batch, the springs, bending), forked from it after the node step
    /// and joined before the next.
    side: Vec<Arc<CudaStream>>,
    contact_force: CudaSlice<f64>,
    status: CudaSlice<u8>,
    /// Each node's running sums (`DRAPE_SUMS`).
    sums: CudaSlice<f64>,
    /// The smallest stable step of each batch: trusses, membranes,
    /// springs, bending; and its host copy (+∞ to reset it).
    batch_steps: CudaSlice<f64>,
    batch_steps_host: Vec<f64>,
    /// Each step's `StepParams` of a block of up to `GRAPH_STEPS`.
    params: CudaSlice<f64>,
    /// ... and its values (`Engine::steps`' `values`, `Flat::step_width`
    /// a step, and one unread value, so that a step's prescribed
    /// coordinates and loads are each a slice of at least one).
    values: CudaSlice<f64>,
    block: u32,
    fault: CudaSlice<i32>,
    /// Whether the current state is in buffer 1.
    parity: usize,
    /// The captured block of `GRAPH_STEPS` steps from parity 0.
    graph: Option<CudaGraph>,
    /// While profiling: every kind on the main stream, and an event after
    /// each kind's kernels (with the kind's index).
    timing: Option<Vec<(usize, CudaEvent)>>,
    /// The GPU's name.
    pub device: String,
}

impl<'m> CudaStep<'m> {
    /// The step of the model `explicit` runs on GPU 0, with its (scaled)
    /// masses, truss dashpots and contact settings.
    pub fn new(explicit: &Explicit<'m>) -> Result<Self, GpuError> {
        let model = explicit.model();
        let flat = Flat::new(explicit)?;
        probe()?;
        let ctx = CudaContext::new(0).map_err(|e| GpuError::NoDevice(e.to_string()))?;
        // One stream, ordered by itself: cudarc's per-buffer events are not
        // needed, and they cannot be waited on inside a graph capture.
        // SAFETY: no buffer is used from another stream.
        unsafe { ctx.disable_event_tracking() };
        let device = ctx.name().map_err(cuda)?;
        let (major, minor) = ctx.compute_capability().map_err(cuda)?;
        let ptx = compile_kernels(Some(&format!("compute_{major}{minor}")))?;
        let module = ctx.load_module(ptx).map_err(cuda)?;
        let load = |name: &str| module.load_function(name).map_err(cuda);
        let kernels = Kernels {
            truss: load("truss_forces")?,
            quad: load("quad_point_forces")?,
            triangle: load("triangle_forces")?,
            spring: load("spring_forces")?,
            gather: load("gather")?,
            gather_node_step: load("gather_node_step")?,
            bending: load("bending_forces")?,
            truss_steps: load("truss_steps")?,
            membrane_steps: load("membrane_steps")?,
            spring_steps: load("spring_steps")?,
            bending_steps: load("bending_steps")?,
        };
        // A stream of its own: the legacy default stream cannot be captured
        // into a graph.
        let stream = ctx.new_stream().map_err(cuda)?;
        let s = &stream;
        let trusses = flat
            .trusses
            .iter()
            .map(|t| {
                Ok(DevTrusses {
                    count: t.length.len() as i64,
                    law: t.law,
                    nodes: upload(s, &t.nodes)?,
                    length: upload(s, &t.length)?,
                    section: upload(s, &t.section)?,
                    has_dashpot: i32::from(!t.dashpot.is_empty()),
                    dashpot: upload(s, &t.dashpot)?,
                    first: t.first as i64,
                    wave_modulus: t.wave_modulus,
                    share: upload(s, &t.share)?,
                })
            })
            .collect::<Result<_, GpuError>>()?;
        let quads = flat
            .quads
            .iter()
            .map(|q| {
                Ok(DevQuads {
                    triangles: q.triangles,
                    count: q.count() as i64,
                    resin: upload(s, &q.step(0.0))?,
                    nodes: upload(s, &q.nodes)?,
                    grad: upload(s, &q.grad)?,
                    area: upload(s, &q.area)?,
                    history: zeros(s, q.count() * q.points() * q.stride)?,
                    stride: q.stride as i64,
                    first: q.first as i64,
                    nodal_area: upload(s, &q.nodal_area)?,
                    scale: upload(s, &q.scale)?,
                    kappa: q.kappa,
                    rho_h: q.rho_h,
                })
            })
            .collect::<Result<_, GpuError>>()?;
        let springs = flat
            .springs
            .iter()
            .map(|p| {
                Ok(DevSprings {
                    count: p.nodes.len() as i64,
                    nodes: upload(s, &p.nodes)?,
                    anchor: upload(s, &p.anchor)?,
                    rest: upload(s, &p.rest)?,
                    table_start: upload(s, &p.table_start)?,
                    table_len: upload(s, &p.table_len)?,
                    extension: upload(s, &p.extension)?,
                    force: upload(s, &p.force)?,
                    first: p.first as i64,
                    max_stiffness: p.max_stiffness,
                })
            })
            .collect::<Result<_, GpuError>>()?;
        let bending = flat
            .bending
            .iter()
            .map(|b| {
                Ok(DevBending {
                    count: b.stiffness.len() as i64,
                    nodes: upload(s, &b.nodes)?,
                    stiffness: upload(s, &b.stiffness)?,
                    first: b.first as i64,
                    share: upload(s, &b.share)?,
                })
            })
            .collect::<Result<_, GpuError>>()?;
        let n = flat.nodes;
        Ok(Self {
            model,
            ptr: upload(s, &flat.ptr)?,
            node_slots: upload(s, &flat.node_slots)?,
            mass: upload(s, &flat.mass)?,
            fixed: upload(s, &flat.fixed)?,
            moving: upload(s, &flat.moving)?,
            x0: upload(s, &flat.x0)?,
            weight: upload(s, &flat.weight)?,
            load_ptr: upload(s, &flat.load_ptr)?,
            load_of: upload(s, &flat.load_of)?,
            has_loads: i32::from(flat.loads > 0),
            p_ptr: upload(s, &flat.p_ptr)?,
            p_slot: upload(s, &flat.p_slot)?,
            p_nodes: upload(s, &flat.p_nodes)?,
            p_count: upload(s, &flat.p_count)?,
            p_load: upload(s, &flat.p_load)?,
            has_pressure: i32::from(flat.pressures > 0),
            x: [zeros(s, 3 * n)?, zeros(s, 3 * n)?],
            v: [zeros(s, 3 * n)?, zeros(s, 3 * n)?],
            f_int: zeros(s, 3 * n)?,
            slots: zeros(s, 3 * flat.slot_count)?,
            tool: upload(s, &flat.tool)?,
            has_tool: i32::from(!flat.tool.is_empty()),
            // One per truss batch, one for the springs, one for bending.
            side: (0..flat.trusses.len() + 2)
                .map(|_| ctx.new_stream().map_err(cuda))
                .collect::<Result<_, _>>()?,
            contact_force: zeros(s, 3 * n)?,
            status: zeros(s, n)?,
            sums: zeros(s, SUMS * n)?,
            batch_steps: zeros(
                s,
                flat.trusses.len() + flat.quads.len() + flat.springs.len() + flat.bending.len(),
            )?,
            batch_steps_host: vec![
                f64::INFINITY;
                (flat.trusses.len()
                    + flat.quads.len()
                    + flat.springs.len()
                    + flat.bending.len())
                .max(1)
            ],
            params: zeros(s, PARAMS * GRAPH_STEPS as usize)?,
            values: zeros(s, flat.step_width() * GRAPH_STEPS as usize + 1)?,
            block: BLOCK,
            fault: upload(s, &FAULTS)?,
            parity: 0,
            graph: None,
            timing: None,
            device,
            trusses,
            quads,
            springs,
            bending,
            kernels,
            stream,
            flat,
        })
    }

    /// Sets every quad batch's resin step for a step `dt`.
    fn set_resin(&mut self, dt: f64) -> Result<(), GpuError> {
        for (q, d) in self.flat.quads.iter().zip(&mut self.quads) {
            self.stream
                .memcpy_htod(&q.step(dt), &mut d.resin)
                .map_err(cuda)?;
        }
        Ok(())
    }

    /// Threads per block of every kernel from now on (the results are the
    /// same bits whatever it is: each thread writes its own slots).
    /// Brought down to what every kernel can launch with its registers.
    pub fn set_block_threads(&mut self, threads: u32) -> Result<u32, GpuError> {
        let k = &self.kernels;
        let mut most = 1024;
        for f in [
            &k.truss,
            &k.quad,
            &k.triangle,
            &k.spring,
            &k.gather,
            &k.gather_node_step,
            &k.bending,
        ] {
            most = most.min(f.max_threads_per_block().map_err(cuda)? as u32);
        }
        // Whole warps: the quads' four points are lanes of one warp.
        self.block = threads.clamp(32, most) / 32 * 32;
        self.graph = None;
        Ok(self.block)
    }

    /// The GPU time of each kind of kernel over `count` steps with
    /// `params`, launched one after another on one stream (no graph, no
    /// kinds side by side): µs per step of [gather and node step (update,
    /// contact, works), trusses, membranes, springs, bending, a separate
    /// gather (none: the step's is fused)]. Small models include the
    /// launches' gaps.
    pub fn profile(&mut self, count: u64, params: StepParams) -> Result<[f64; 6], GpuError> {
        self.set_resin(params.h)?;
        let values = self.values_at_rest(1);
        self.write_block(&[params], &values)?;
        self.timing = Some(Vec::with_capacity(7 * count as usize + 1));
        mark(&mut self.timing, &self.stream, 0)?;
        let mut result = Ok(());
        for _ in 0..count {
            result = result.and_then(|()| {
                self.launch_step(self.parity, 0)?;
                self.parity = 1 - self.parity;
                Ok(())
            });
        }
        let events = self.timing.take().unwrap_or_default();
        result?;
        self.stream.synchronize().map_err(cuda)?;
        let mut out = [0.0; 6];
        for pair in events.windows(2) {
            let ms = pair[0].1.elapsed_ms(&pair[1].1).map_err(cuda)?;
            out[pair[1].0] += f64::from(ms) * 1e3 / count as f64;
        }
        self.check_faults(0)?;
        Ok(out)
    }

    /// Launches the forces at buffer `at` (positions and velocities), the
    /// histories advanced when `commit`, and the gather: the element kinds
    /// side by side (trusses, springs and bending on streams of their own,
    /// the quads on the main one), each into its own slots, joined before
    /// the gather.
    fn launch_forces(&mut self, at: usize, commit: bool, gather: bool) -> Result<(), GpuError> {
        let n = self.flat.nodes as i64;
        let sc = self.flat.slot_count as i64;
        let commit = i32::from(commit);
        let (x, v) = (&self.x[at], &self.v[at]);
        // Every kind on the main stream while profiling.
        let serial = self.timing.is_some();
        let lane = |k: usize| if serial { &self.stream } else { &self.side[k] };
        if !serial {
            for side in &self.side {
                side.join(&self.stream).map_err(cuda)?;
            }
        }
        let nt = self.trusses.len();
        for (k, t) in self.trusses.iter().enumerate() {
            let mut b = lane(k).launch_builder(&self.kernels.truss);
            b.arg(&t.count)
                .arg(&t.law[0])
                .arg(&t.law[1])
                .arg(&t.law[2])
                .arg(&t.law[3])
                .arg(&t.nodes)
                .arg(&t.length)
                .arg(&t.section)
                .arg(&t.has_dashpot)
                .arg(&t.dashpot)
                .arg(x)
                .arg(v)
                .arg(&n)
                .arg(&mut self.slots)
                .arg(&sc)
                .arg(&t.first)
                .arg(&mut self.fault);
            // SAFETY: the arguments match `truss_forces` in cuda.cu.
            unsafe { b.launch(grid(t.count as usize, self.block)) }.map_err(cuda)?;
        }
        mark(&mut self.timing, &self.stream, 1)?;
        for q in &mut self.quads {
            // A quad's four points on four threads; a triangle's one.
            let (kernel, threads) = if q.triangles {
                (&self.kernels.triangle, q.count as usize)
            } else {
                (&self.kernels.quad, 4 * q.count as usize)
            };
            let mut b = self.stream.launch_builder(kernel);
            b.arg(&q.count)
                .arg(&q.resin)
                .arg(&q.nodes)
                .arg(&q.grad)
                .arg(&q.area)
                .arg(&mut q.history)
                .arg(&q.stride)
                .arg(&commit)
                .arg(x)
                .arg(&n)
                .arg(&mut self.slots)
                .arg(&sc)
                .arg(&q.first)
                .arg(&mut self.fault);
            // SAFETY: the arguments match `quad_point_forces` and
            // `triangle_forces` in cuda.cu; the blocks are whole warps.
            unsafe { b.launch(grid(threads, self.block)) }.map_err(cuda)?;
        }
        mark(&mut self.timing, &self.stream, 2)?;
        for p in &self.springs {
            let mut b = lane(nt).launch_builder(&self.kernels.spring);
            b.arg(&p.count)
                .arg(&p.nodes)
                .arg(&p.anchor)
                .arg(&p.rest)
                .arg(&p.table_start)
                .arg(&p.table_len)
                .arg(&p.extension)
                .arg(&p.force)
                .arg(x)
                .arg(&n)
                .arg(&mut self.slots)
                .arg(&sc)
                .arg(&p.first);
            // SAFETY: the arguments match `spring_forces` in cuda.cu.
            unsafe { b.launch(grid(p.count as usize, self.block)) }.map_err(cuda)?;
        }
        mark(&mut self.timing, &self.stream, 3)?;
        for t in &self.bending {
            let mut b = lane(nt + 1).launch_builder(&self.kernels.bending);
            b.arg(&t.count)
                .arg(&t.nodes)
                .arg(&t.stiffness)
                .arg(x)
                .arg(&n)
                .arg(&mut self.slots)
                .arg(&sc)
                .arg(&t.first)
                .arg(&mut self.fault);
            // SAFETY: the arguments match `bending_forces` in cuda.cu.
            unsafe { b.launch(grid(t.count as usize, self.block)) }.map_err(cuda)?;
        }
        mark(&mut self.timing, &self.stream, 4)?;
        if !serial {
            for side in &self.side {
                self.stream.join(side).map_err(cuda)?;
            }
        }
        if gather {
            self.launch_gather()?;
        }
        Ok(())
    }

    /// Each node's internal force from the element slots (the step's
    /// fused kernel gathers before its update; this one is for the start
    /// and for the host to read the forces).
    fn launch_gather(&mut self) -> Result<(), GpuError> {
        let n = self.flat.nodes as i64;
        let sc = self.flat.slot_count as i64;
        let mut b = self.stream.launch_builder(&self.kernels.gather);
        b.arg(&n)
            .arg(&self.ptr)
            .arg(&self.node_slots)
            .arg(&self.slots)
            .arg(&sc)
            .arg(&mut self.f_int);
        // SAFETY: the arguments match `gather` in cuda.cu.
        unsafe { b.launch(grid(n as usize, self.block)) }.map_err(cuda)?;
        mark(&mut self.timing, &self.stream, 5)
    }

    /// One step from buffer `from` into the other, with the params of step
    /// `k` of the block in device memory: the node step (update, contact,
    /// works), then the forces.
    fn launch_step(&mut self, from: usize, k: usize) -> Result<(), GpuError> {
        let n = self.flat.nodes as i64;
        let to = 1 - from;
        let [x0, x1] = &mut self.x;
        let [v0, v1] = &mut self.v;
        let (x, x_new, v, v_new) = if from == 0 {
            (&*x0, x1, &*v0, v1)
        } else {
            (&*x1, x0, &*v1, v0)
        };
        let params = self.params.slice(PARAMS * k..PARAMS * (k + 1));
        let (m, w) = (self.flat.prescribed.len(), self.flat.step_width());
        let held = self.values.slice(w * k..w * k + 1.max(m));
        let loads = self.values.slice(w * k + m..w * (k + 1) + 1);
        let l3 = 3 * self.flat.loads;
        let scales = self.values.slice(w * k + m + l3..w * (k + 1) + 1);
        let sc = self.flat.slot_count as i64;
        let mut b = self.stream.launch_builder(&self.kernels.gather_node_step);
        b.arg(&n)
            .arg(&self.ptr)
            .arg(&self.node_slots)
            .arg(&self.slots)
            .arg(&sc)
            .arg(&params)
            .arg(x)
            .arg(v)
            .arg(&self.weight)
            .arg(&self.load_ptr)
            .arg(&self.load_of)
            .arg(&self.has_loads)
            .arg(&loads)
            .arg(&self.p_ptr)
            .arg(&self.p_slot)
            .arg(&self.p_nodes)
            .arg(&self.p_count)
            .arg(&self.p_load)
            .arg(&self.has_pressure)
            .arg(&scales)
            .arg(&mut self.f_int)
            .arg(&self.mass)
            .arg(&self.fixed)
            .arg(&self.x0)
            .arg(&self.moving)
            .arg(&held)
            .arg(&self.has_tool)
            .arg(&self.tool)
            .arg(x_new)
            .arg(v_new)
            .arg(&mut self.contact_force)
            .arg(&mut self.status)
            .arg(&mut self.sums)
            .arg(&mut self.fault);
        // SAFETY: the arguments match `gather_node_step` in cuda.cu.
        unsafe { b.launch(grid(n as usize, self.block)) }.map_err(cuda)?;
        mark(&mut self.timing, &self.stream, 0)?;
        self.launch_forces(to, true, false)
    }

    /// The fault words, reset; an element error if one is set.
    fn check_faults(&mut self, step: u64) -> Result<(), GpuError> {
        let fault = self.stream.clone_dtoh(&self.fault).map_err(cuda)?;
        if fault.iter().any(|&f| f != NO_FAULT) {
            self.stream
                .memcpy_htod(&FAULTS, &mut self.fault)
                .map_err(cuda)?;
            if fault[2] != NO_FAULT {
                return Err(GpuError::contact_fault(fault[2] as u64, step));
            }
            let (kind, index) = if fault[0] != NO_FAULT {
                ("truss", fault[0])
            } else if fault[1] != NO_FAULT {
                ("membrane element", fault[1])
            } else {
                ("bending triplet", fault[3])
            };
            return Err(GpuError::Element {
                kind,
                index: index as usize,
                step,
            });
        }
        Ok(())
    }

    /// `count` steps with `params` and their resin step (the moving
    /// components held at their reference coordinates, no loads), none of them
    /// checked until the end: for timing the step alone. Returns the
    /// seconds the GPU took (the stream synchronised before and after).
    pub fn time_steps(&mut self, count: u64, params: StepParams) -> Result<f64, GpuError> {
        self.set_resin(params.h)?;
        let block = vec![params; count as usize];
        let values = self.values_at_rest(block.len());
        self.stream.synchronize().map_err(cuda)?;
        let started = std::time::Instant::now();
        self.run_block(&block, &values)?;
        self.stream.synchronize().map_err(cuda)?;
        let seconds = started.elapsed().as_secs_f64();
        self.check_faults(0)?;
        Ok(seconds)
    }

    /// The moving components at their reference coordinates and no loads
    /// for `steps` steps (`values` for timing).
    fn values_at_rest(&self, steps: usize) -> Vec<f64> {
        let f = &self.flat;
        let mut rest: Vec<f64> = f
            .prescribed
            .components()
            .map(|(i, k)| f.x0[3 * i + k])
            .collect();
        rest.resize(f.step_width(), 0.0);
        rest.repeat(steps)
    }

    /// Writes a chunk's params and values to the device (in stream order,
    /// so after the chunk before has run).
    fn write_block(&mut self, part: &[StepParams], values: &[f64]) -> Result<(), GpuError> {
        let mut params = [0.0; PARAMS * GRAPH_STEPS as usize];
        for (p, s) in params.chunks_exact_mut(PARAMS).zip(part) {
            p.copy_from_slice(&s.values());
        }
        self.stream
            .memcpy_htod(&params, &mut self.params)
            .map_err(cuda)?;
        if !values.is_empty() {
            let mut to = self.values.slice_mut(0..values.len());
            self.stream.memcpy_htod(values, &mut to).map_err(cuda)?;
        }
        Ok(())
    }

    /// A step of each of `steps` (with `values`, as `Engine::steps`), in
    /// chunks of `GRAPH_STEPS`: each chunk written to the device, then the
    /// captured graph where the chunk is whole and starts at parity 0,
    /// single launches otherwise.
    fn run_block(&mut self, steps: &[StepParams], values: &[f64]) -> Result<(), GpuError> {
        let w = self.flat.step_width();
        for (c, part) in steps.chunks(GRAPH_STEPS as usize).enumerate() {
            let chunk = part.len();
            let first = c * GRAPH_STEPS as usize;
            self.write_block(part, &values[first * w..(first + chunk) * w])?;
            if self.parity == 0 && chunk == GRAPH_STEPS as usize {
                if self.graph.is_none() {
                    self.capture()?;
                }
                let graph = self.graph.as_ref().expect("captured just above");
                graph.launch().map_err(cuda)?;
            } else {
                for k in 0..chunk {
                    self.launch_step(self.parity, k)?;
                    self.parity = 1 - self.parity;
                }
            }
        }
        Ok(())
    }

    fn capture(&mut self) -> Result<(), GpuError> {
        self.stream
            .begin_capture(sys::CUstreamCaptureMode::CU_STREAM_CAPTURE_MODE_THREAD_LOCAL)
            .map_err(cuda)?;
        let mut result = Ok(());
        for k in 0..GRAPH_STEPS {
            result = result.and_then(|()| self.launch_step((k % 2) as usize, k as usize));
        }
        let graph = self
            .stream
            .end_capture(sys::CUgraphInstantiate_flags(0))
            .map_err(cuda)?;
        result?;
        self.graph = Some(graph.ok_or_else(|| GpuError::Cuda("the capture made no graph".into()))?);
        Ok(())
    }
}

impl Engine for CudaStep<'_> {
    fn load(&mut self, state: &State) -> Result<(), GpuError> {
        self.parity = 0;
        self.stream
            .memcpy_htod(&split(&state.x), &mut self.x[0])
            .map_err(cuda)?;
        self.stream
            .memcpy_htod(&split(&state.v), &mut self.v[0])
            .map_err(cuda)?;
        for (h, d) in Flat::histories(self.model, state)
            .iter()
            .zip(&mut self.quads)
        {
            if !h.is_empty() {
                self.stream.memcpy_htod(h, &mut d.history).map_err(cuda)?;
            }
        }
        Ok(())
    }

    fn store(&mut self, state: &mut State) -> Result<(), GpuError> {
        let n = self.flat.nodes;
        let x = self.stream.clone_dtoh(&self.x[self.parity]).map_err(cuda)?;
        let v = self.stream.clone_dtoh(&self.v[self.parity]).map_err(cuda)?;
        state.x = join(&x[..3 * n]);
        state.v = join(&v[..3 * n]);
        for ((b, d), h) in self
            .model
            .membranes
            .iter()
            .zip(&self.quads)
            .zip(&mut state.history)
        {
            let values = self.stream.clone_dtoh(&d.history).map_err(cuda)?;
            *h = history_from_device(b, &values[..h.len()]);
        }
        Ok(())
    }

    fn batch_steps(&mut self, out: &mut BatchSteps) -> Result<(), GpuError> {
        let n = self.flat.nodes as i64;
        let x = &self.x[self.parity];
        let slots = self.trusses.len() + self.quads.len() + self.springs.len() + self.bending.len();
        self.stream
            .memcpy_htod(&self.batch_steps_host, &mut self.batch_steps)
            .map_err(cuda)?;
        let mut slot = 0;
        for t in &self.trusses {
            let out = self.batch_steps.slice(slot..slot + 1);
            let mut b = self.stream.launch_builder(&self.kernels.truss_steps);
            b.arg(&t.count)
                .arg(&t.wave_modulus)
                .arg(&t.nodes)
                .arg(&t.section)
                .arg(&t.share)
                .arg(x)
                .arg(&n)
                .arg(&out);
            // SAFETY: the arguments match `truss_steps` in cuda.cu.
            unsafe { b.launch(grid(t.count as usize, self.block)) }.map_err(cuda)?;
            slot += 1;
        }
        for q in &self.quads {
            let out = self.batch_steps.slice(slot..slot + 1);
            let (nodes_per, points) = if q.triangles { (3i32, 1i32) } else { (4, 4) };
            let mut b = self.stream.launch_builder(&self.kernels.membrane_steps);
            b.arg(&q.count)
                .arg(&nodes_per)
                .arg(&points)
                .arg(&q.nodes)
                .arg(&q.nodal_area)
                .arg(&q.resin)
                .arg(&q.grad)
                .arg(&q.scale)
                .arg(&q.kappa)
                .arg(&q.rho_h)
                .arg(x)
                .arg(&n)
                .arg(&out);
            // SAFETY: the arguments match `membrane_steps` in cuda.cu.
            unsafe { b.launch(grid(q.count as usize, self.block)) }.map_err(cuda)?;
            slot += 1;
        }
        for p in &self.springs {
            let out = self.batch_steps.slice(slot..slot + 1);
            let mut b = self.stream.launch_builder(&self.kernels.spring_steps);
            b.arg(&p.count)
                .arg(&p.nodes)
                .arg(&p.anchor)
                .arg(&p.rest)
                .arg(&p.table_start)
                .arg(&p.table_len)
                .arg(&p.extension)
                .arg(&p.force)
                .arg(&p.max_stiffness)
                .arg(&self.mass)
                .arg(x)
                .arg(&n)
                .arg(&out);
            // SAFETY: the arguments match `spring_steps` in cuda.cu.
            unsafe { b.launch(grid(p.count as usize, self.block)) }.map_err(cuda)?;
            slot += 1;
        }
        for t in &self.bending {
            let out = self.batch_steps.slice(slot..slot + 1);
            let mut b = self.stream.launch_builder(&self.kernels.bending_steps);
            b.arg(&t.count)
                .arg(&t.nodes)
                .arg(&t.stiffness)
                .arg(&t.share)
                .arg(x)
                .arg(&n)
                .arg(&out);
            // SAFETY: the arguments match `bending_steps` in cuda.cu.
            unsafe { b.launch(grid(t.count as usize, self.block)) }.map_err(cuda)?;
            slot += 1;
        }
        let mut all = std::mem::take(&mut self.batch_steps_host);
        self.stream
            .memcpy_dtoh(&self.batch_steps, &mut all)
            .map_err(cuda)?;
        let (nt, nq, ns) = (self.trusses.len(), self.quads.len(), self.springs.len());
        out.set(
            &all[..nt],
            &all[nt..nt + nq],
            &all[nt + nq..nt + nq + ns],
            &all[nt + nq + ns..slots],
        );
        all.fill(f64::INFINITY);
        self.batch_steps_host = all;
        Ok(())
    }

    fn snapshot(&mut self, state: &mut State) -> Result<Snapshot, GpuError> {
        // The last step's elements are not gathered until the next step.
        self.launch_gather()?;
        self.store(state)?;
        let n = self.flat.nodes;
        let get =
            |s: &Arc<CudaStream>, b: &CudaSlice<f64>, len: usize| -> Result<Vec<f64>, GpuError> {
                let mut v = s.clone_dtoh(b).map_err(cuda)?;
                v.truncate(len);
                Ok(v)
            };
        let mut status = self.stream.clone_dtoh(&self.status).map_err(cuda)?;
        status.truncate(n);
        Ok(Snapshot {
            f_int: join(&get(&self.stream, &self.f_int, 3 * n)?),
            contact_force: join(&get(&self.stream, &self.contact_force, 3 * n)?),
            status,
            sums: get(&self.stream, &self.sums, SUMS * n)?,
        })
    }

    fn start_forces(&mut self, dt: f64) -> Result<(), GpuError> {
        self.set_resin(dt)?;
        self.launch_forces(self.parity, false, true)?;
        self.check_faults(0)
    }

    fn steps(&mut self, params: &[StepParams], values: &[f64], step: u64) -> Result<(), GpuError> {
        // Every step of a block has the same h, so one resin step.
        self.set_resin(params[0].h)?;
        self.run_block(params, values)?;
        self.check_faults(step)
    }
}
