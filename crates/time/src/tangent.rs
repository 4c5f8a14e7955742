//! The implicit driver's sparse tangent: K̂ = c·M + sym(∂f_int/∂x) over all
//! 3·N degrees of freedom, assembled from the elements' exact tangents and
//! factorised with faer's sparse Cholesky.
//!
//! Built once per topology: the upper-triangle CSC pattern of the node
//! adjacency, each element's slots (one per entry of its upper local
//! triangle) and, per matrix value, the slots that sum into it (CSR, in
//! ascending order, so the assembly is lock-free and independent of the
//! thread count, like the force gather), and the symbolic factorisation
//! (AMD ordering, simplicial or supernodal by faer's flop ratio), reused
//! by every numeric factorisation of the run.
//!
//! The membranes' tangent is the exact derivative of the hypo-elastic
//! update, which is not symmetric (its τ̄ depends on the path through
//! Uₙ); the factorised matrix is its symmetric part, as the paper's
//! condensed contact solve needs a symmetric K (C·K⁻¹·Cᵀ s.p.d.). Newton
//! then converges at the rate of the skew part relative to the whole
//! (measured in the implicit driver's tests), quadratically for trusses,
//! springs and embedded fibres, whose tangents are symmetric.
//!
//! A follower pressure's load stiffness −∂f_p/∂x is not symmetric either
//! (its blocks are cross-product matrices, [`drape_model::pressure`]): K̂
//! takes its symmetric part ([`SparseTangent::add_pressure_stiffness`]),
//! the residual the exact follower load, so the converged state is exact
//! and only Newton's rate depends on the skew part left out (for a
//! consistent pressure load, which the triangles' is, that part is the
//! loaded surface's free edges'; measured in the implicit driver's tests).
//!
//! Where the resin is compressed, its exact tangent can make K̂
//! indefinite; the driver may then factorise a positive one instead
//! ([`MembraneTangentChoice`]). The residual is always exact.
//!
//! Constrained components get an identity row and column: the driver keeps
//! them at their prescribed values and their residual at zero.
//!
//! Not here: no dense matrix beyond one element's, no residual, no contact.

use std::time::Instant;

use drape_elements::{ElementError, MembraneTangent};
use drape_model::Model;
use faer::Par;
use faer::dyn_stack::{MemBuffer, StackReq};
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use nalgebra::{DMatrix, Matrix3, Vector3};
use rayon::prelude::*;

use crate::ordering::{FactorOrder, NumericFailure};
use crate::split::SplitCholesky;

/// Elements per assembly task, each with its own element-matrix buffer.
const CHUNK: usize = 128;

/// Which factorisation holds the current values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Factorisation {
    /// LLᵀ: the matrix was positive definite.
    Cholesky,
    /// LDLᵀ without pivoting: Cholesky met a non-positive pivot.
    Ldlt,
}

/// Which resin membrane tangent the implicit driver factorises (see
/// [`MembraneTangent`] for the tension field and why).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MembraneTangentChoice {
    /// Always the exact tangent (Newton quadratic; K̂ indefinite where the
    /// resin is compressed more than the yarns, bending and inertia hold
    /// it, and the increment is then cut).
    Exact,
    /// Always the tension field (K̂ positive definite as far as the resin
    /// goes; Newton linear wherever the resin is compressed).
    TensionField,
    /// The exact tangent while Cholesky accepts it; when it finds K̂
    /// indefinite, the resin's compressive stress terms are scaled down by
    /// [`COMPRESSION_KEPT`] until it does, and the attempt keeps the scale
    /// it reached (see [`SparseTangent::begin_attempt`]).
    TensionFieldWhenIndefinite,
}

/// The fractions of the resin's compressive stress terms tried, in turn,
/// when the exact K̂ is indefinite (0: the tension field).
///
/// Why a ladder and not the tension field at once: the less of the exact
/// tangent is dropped, the faster Newton converges. Measured on the ±45
/// hemisphere 10 × 10 with the physical mass and bending (one core, user
/// CPU; the exact tangent: 233 increments, 1 410 + 16 Newton iterations,
/// 32 cutbacks, all "contact indefinite", 4.3 s): the tension field
/// always, 656 increments and 5 927 Newton, 18.4 s; the tension field
/// when indefinite, 177 and 1 491 + 250, 10 Newton-limit cutbacks, 5.5 s;
/// with this ladder, 145 and 1 295 + 52, 3 cutbacks, 4.5 s; ladders
/// (0.5, 0), (0.9, 0.75, 0.5, 0) and (0.8, 0.6, 0.3, 0) in between. The
/// answers agree to 1e-5°.
pub const COMPRESSION_KEPT: [f64; 3] = [0.75, 0.5, 0.0];

/// Why the tangent could not be assembled or factorised.
#[derive(Debug, Clone)]
pub enum TangentError {
    /// An element's tangent failed (the batch named).
    Element(String, ElementError),
    /// The factorisation met a zero pivot.
    ZeroPivot(FactorError),
}

impl std::fmt::Display for TangentError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TangentError::Element(batch, e) => write!(f, "tangent of {batch}: {e}"),
            TangentError::ZeroPivot(e) => write!(
                f,
                "the tangent has a zero pivot at node {} (component {})",
                e.dof / 3,
                e.dof % 3
            ),
        }
    }
}

/// Why a factorisation failed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FactorError {
    /// The degree of freedom (3·node + component) of the zero pivot.
    pub dof: usize,
}

/// One batch's elements: node lists and where their slots start.
#[derive(Debug, Clone)]
struct BatchSlots {
    /// First slot of the batch.
    start: usize,
    /// Local dofs per element (3 × nodes).
    dofs: usize,
}

/// The sparse tangent of a model with its pattern, assembly maps, symbolic
/// and numeric factors.
pub struct SparseTangent {
    n: usize,
    symbolic_matrix: SymbolicSparseColMat<usize>,
    /// Matrix values (upper triangle, CSC).
    pub values: Vec<f64>,
    /// Value index of each dof's diagonal.
    diagonal: Vec<usize>,
    /// Value indices of each node's diagonal block, upper triangle:
    /// (0,0), (0,1), (1,1), (0,2), (1,2), (2,2) (a node's block is read
    /// and added to for every contact row, where a search of the column
    /// per entry cost ~2 % of an implicit deep drawing).
    node_block_at: Vec<[usize; 6]>,
    /// Value indices zeroed for constrained dofs (their rows and columns).
    constrained_entries: Vec<usize>,
    /// Whether each dof is constrained.
    constrained: Vec<bool>,
    /// Per-element slots.
    slots: Vec<f64>,
    /// CSR value → slots.
    value_ptr: Vec<usize>,
    value_slots: Vec<u32>,
    trusses: Vec<BatchSlots>,
    membranes: Vec<BatchSlots>,
    springs: Vec<BatchSlots>,
    bending: Vec<BatchSlots>,
    /// Element-matrix buffers, one per assembly chunk of each batch.
    truss_scratch: Vec<Vec<DMatrix<f64>>>,
    membrane_scratch: Vec<Vec<DMatrix<f64>>>,
    bending_scratch: Vec<Vec<DMatrix<f64>>>,
    /// The pattern in its factor's order ([`FactorOrder`]), and the values
    /// there at the last factorisation.
    factor: FactorOrder,
    ordered_values: Vec<f64>,
    factor_values: Vec<f64>,
    /// The factorisation in two halves on two threads
    /// ([`SplitCholesky`]) where the model is large enough and cuts well;
    /// else faer's of the whole, in `factor_values`. Analysed at the first
    /// factorisation (the active-set solver factorises its own matrix).
    split: Option<SplitCholesky>,
    split_analysed: bool,
    kind: Factorisation,
    stack: MemBuffer,
    /// Seconds spent in numeric factorisations.
    pub factor_seconds: f64,
    /// Numeric factorisations done.
    pub factorisations: u64,
    /// Factorisations that fell back to LDLᵀ.
    pub indefinite: u64,
    /// The largest diagonal entry of the stiffness (without the mass term)
    /// at the last assembly, over the free dofs (N/mm).
    pub max_stiffness: f64,
    /// The resin membranes' tangent (exact unless set).
    pub membrane_tangent: MembraneTangentChoice,
    /// Factorisations with the resin's compressive stress terms scaled
    /// down ([`MembraneTangentChoice::TensionFieldWhenIndefinite`]).
    pub compression_scaled: u64,
    /// How far down [`COMPRESSION_KEPT`] the attempt went (0: exact).
    kept_level: usize,
    /// The fraction of the resin's compressive stress terms the next
    /// assembly keeps.
    kept: f64,
}

/// The entries (row, column) of a 3 × 3 block's upper triangle, in the
/// order of [`SparseTangent`]'s `node_block_at`.
const UPPER_BLOCK: [(usize, usize); 6] = [(0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2)];

/// Upper-local-triangle pairs (p ≤ q) of an element with `dofs` dofs.
fn local_pairs(dofs: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..dofs).flat_map(move |q| (0..=q).map(move |p| (p, q)))
}

/// The slots of a batch of `len` elements.
fn batch_slots<'s>(slots: &'s mut [f64], bs: &BatchSlots, len: usize) -> &'s mut [f64] {
    let m = bs.dofs * (bs.dofs + 1) / 2;
    &mut slots[bs.start..bs.start + m * len]
}

/// Fills a batch's slots in parallel chunks: `tangent(e, k)` writes element
/// `e`'s matrix into `k`, whose symmetrised upper triangle goes to the
/// element's slots. The failure of the lowest element is reported, whatever
/// the thread count.
fn assemble_batch(
    slots: &mut [f64],
    scratch: &mut [DMatrix<f64>],
    tangent: impl Fn(usize, &mut DMatrix<f64>) -> Result<(), ElementError> + Sync,
) -> Result<(), ElementError> {
    fn write(k: &DMatrix<f64>, out: &mut [f64]) {
        let d = k.nrows();
        let mut s = 0;
        for q in 0..d {
            for p in 0..=q {
                out[s] = if p == q {
                    k[(p, p)]
                } else {
                    0.5 * (k[(p, q)] + k[(q, p)])
                };
                s += 1;
            }
        }
    }
    let lowest = |a: ElementError, acc: Option<ElementError>| match acc {
        Some(b) if b.element < a.element => Some(b),
        _ => Some(a),
    };
    let Some(d) = scratch.first().map(DMatrix::nrows) else {
        return Ok(());
    };
    let m = d * (d + 1) / 2;
    let failed = slots
        .par_chunks_mut(m * CHUNK)
        .zip(scratch.par_iter_mut())
        .enumerate()
        .map(|(c, (out, k))| {
            for (j, o) in out.chunks_mut(m).enumerate() {
                tangent(c * CHUNK + j, k)?;
                write(k, o);
            }
            Ok(())
        })
        .fold(
            || None,
            |acc, r: Result<(), ElementError>| match r {
                Err(e) => lowest(e, acc),
                Ok(()) => acc,
            },
        )
        .reduce(
            || None,
            |a, b| match b {
                Some(b) => lowest(b, a),
                None => a,
            },
        );
    failed.map_or(Ok(()), Err)
}

/// y += `scale`·K·x for the symmetric K stored as its upper triangle
/// (`scale` ±1 keeps every product exact, so the sums are those of
/// adding or subtracting K·x term by term).
pub(crate) fn add_symmetric_product(
    k: SparseColMatRef<'_, usize, f64>,
    x: &[f64],
    y: &mut [f64],
    scale: f64,
) {
    add_symmetric_product_columns(k, 0..k.ncols(), x, y, scale);
}

/// [`add_symmetric_product`]'s terms of the upper triangle's `columns`.
pub(crate) fn add_symmetric_product_columns(
    k: SparseColMatRef<'_, usize, f64>,
    columns: std::ops::Range<usize>,
    x: &[f64],
    y: &mut [f64],
    scale: f64,
) {
    let (ptr, rows, values) = (k.col_ptr(), k.row_idx(), k.val());
    for j in columns {
        let range = ptr[j]..ptr[j + 1];
        for (&i, &v) in rows[range.clone()].iter().zip(&values[range]) {
            let v = scale * v;
            y[i] += v * x[j];
            if i != j {
                y[j] += v * x[i];
            }
        }
    }
}

impl SparseTangent {
    /// The pattern, maps and symbolic factorisation of `model`'s elements;
    /// `constrained[3·node + component]` marks the prescribed dofs.
    pub fn new(model: &Model, constrained: Vec<bool>) -> Result<Self, String> {
        let nodes = model.node_count();
        let n = 3 * nodes;
        assert_eq!(constrained.len(), n);
        // Element node lists, in batch order.
        let mut elements: Vec<Vec<u32>> = Vec::new();
        for b in &model.trusses {
            elements.extend(b.nodes.iter().map(|e| e.to_vec()));
        }
        for b in &model.membranes {
            elements.extend((0..b.len()).map(|e| b.element_nodes(e).to_vec()));
        }
        for b in &model.springs {
            elements.extend(b.nodes.iter().map(|&i| vec![i]));
        }
        for b in &model.bending {
            elements.extend(b.nodes.iter().map(|e| e.to_vec()));
        }
        // Node adjacency (upper: neighbour ≤ node), every node its own.
        let mut adjacent: Vec<Vec<u32>> = (0..nodes as u32).map(|i| vec![i]).collect();
        for e in &elements {
            for &a in e {
                for &b in e {
                    if a < b {
                        adjacent[b as usize].push(a);
                    }
                }
            }
        }
        for a in &mut adjacent {
            a.sort_unstable();
            a.dedup();
        }
        // Dof CSC, upper triangle.
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for (j, adj) in adjacent.iter().enumerate() {
            for c in 0..3 {
                for &i in adj {
                    let i = i as usize;
                    let rows = if i < j { 3 } else { c + 1 };
                    row_idx.extend((0..rows).map(|r| 3 * i + r));
                }
                col_ptr.push(row_idx.len());
            }
        }
        let index = |i: usize, j: usize| -> usize {
            let (i, j) = if i <= j { (i, j) } else { (j, i) };
            let col = &row_idx[col_ptr[j]..col_ptr[j + 1]];
            col_ptr[j] + col.binary_search(&i).expect("entry in the pattern")
        };
        let diagonal: Vec<usize> = (0..n).map(|d| index(d, d)).collect();
        let node_block_at = (0..n / 3)
            .map(|i| {
                let d = 3 * i;
                UPPER_BLOCK.map(|(a, b)| index(d + a, d + b))
            })
            .collect();
        let mut constrained_entries = Vec::new();
        for j in 0..n {
            for k in col_ptr[j]..col_ptr[j + 1] {
                if constrained[j] || constrained[row_idx[k]] {
                    constrained_entries.push(k);
                }
            }
        }
        // Slots.
        let mut slot_value: Vec<u32> = Vec::new();
        let mut add_batch = |list: &mut Vec<BatchSlots>, elems: &[Vec<u32>]| {
            let dofs = 3 * elems.first().map_or(0, Vec::len);
            list.push(BatchSlots {
                start: slot_value.len(),
                dofs,
            });
            for e in elems {
                for (p, q) in local_pairs(dofs) {
                    let gp = 3 * e[p / 3] as usize + p % 3;
                    let gq = 3 * e[q / 3] as usize + q % 3;
                    slot_value.push(index(gp, gq) as u32);
                }
            }
        };
        let mut trusses = Vec::new();
        let mut membranes = Vec::new();
        let mut springs = Vec::new();
        let mut bending = Vec::new();
        let mut at = 0;
        for b in &model.trusses {
            add_batch(&mut trusses, &elements[at..at + b.len()]);
            at += b.len();
        }
        for b in &model.membranes {
            add_batch(&mut membranes, &elements[at..at + b.len()]);
            at += b.len();
        }
        for b in &model.springs {
            add_batch(&mut springs, &elements[at..at + b.len()]);
            at += b.len();
        }
        for b in &model.bending {
            add_batch(&mut bending, &elements[at..at + b.len()]);
            at += b.len();
        }
        let nnz = row_idx.len();
        // Counting sort by value keeps each value's slots ascending.
        let mut value_ptr = vec![0usize; nnz + 1];
        for &v in &slot_value {
            value_ptr[v as usize + 1] += 1;
        }
        for k in 0..nnz {
            value_ptr[k + 1] += value_ptr[k];
        }
        let mut fill = value_ptr.clone();
        let mut value_slots = vec![0u32; slot_value.len()];
        for (s, &v) in slot_value.iter().enumerate() {
            value_slots[fill[v as usize]] = s as u32;
            fill[v as usize] += 1;
        }
        let symbolic_matrix = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let factor = FactorOrder::analyse(symbolic_matrix.as_ref())
            .map_err(|e| format!("symbolic factorisation of the tangent: {e:?}"))?;
        let symbolic = factor.symbolic();
        let stack = MemBuffer::new(StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]));
        let chunks = |len: usize| len.div_ceil(CHUNK);
        Ok(Self {
            n,
            values: vec![0.0; nnz],
            diagonal,
            node_block_at,
            constrained_entries,
            constrained,
            slots: vec![0.0; slot_value.len()],
            value_ptr,
            value_slots,
            truss_scratch: model
                .trusses
                .iter()
                .map(|b| vec![DMatrix::zeros(6, 6); chunks(b.len())])
                .collect(),
            membrane_scratch: model
                .membranes
                .iter()
                .map(|b| {
                    let d = 3 * b.shape().nodes();
                    vec![DMatrix::zeros(d, d); chunks(b.len())]
                })
                .collect(),
            bending_scratch: model
                .bending
                .iter()
                .map(|b| vec![DMatrix::zeros(9, 9); chunks(b.len())])
                .collect(),
            trusses,
            membranes,
            springs,
            bending,
            factor_values: vec![0.0; symbolic.len_val()],
            ordered_values: vec![0.0; factor.len()],
            factor,
            split: None,
            split_analysed: false,
            symbolic_matrix,
            stack,
            kind: Factorisation::Cholesky,
            factor_seconds: 0.0,
            factorisations: 0,
            indefinite: 0,
            max_stiffness: 0.0,
            membrane_tangent: MembraneTangentChoice::Exact,
            compression_scaled: 0,
            kept_level: 0,
            kept: 1.0,
        })
    }

    /// Number of degrees of freedom (3 per node).
    pub fn dofs(&self) -> usize {
        self.n
    }

    /// Stored entries of the upper triangle.
    pub fn nonzeros(&self) -> usize {
        self.values.len()
    }

    /// The assembled upper triangle as a faer matrix (for benches and
    /// checks of other factorisations of the same values).
    pub fn matrix(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(self.symbolic_matrix.as_ref(), &self.values)
    }

    /// The symbolic factorisation every numeric one reuses (of the matrix
    /// in its factor's order).
    pub fn symbolic(&self) -> &SymbolicCholesky<usize> {
        self.factor.symbolic()
    }

    /// Assembles K̂ = diag(`mass_factor`·m) + sym(K) at positions `x`, the
    /// membranes from their committed `history` over a step `dt` (their
    /// exact tangent, or the tension field if that is the choice: see
    /// [`Self::assemble_and_factorise`] for the choice that depends on the
    /// factorisation); an identity block for the constrained dofs.
    pub fn assemble(
        &mut self,
        model: &Model,
        x: &[Vector3<f64>],
        history: &[Vec<f64>],
        dt: f64,
        mass: &[f64],
        mass_factor: f64,
    ) -> Result<(), (String, ElementError)> {
        self.assemble_from(model, x, history, None, dt, mass, mass_factor)
    }

    /// [`Self::assemble`], the membranes' stress read from `evaluated` where
    /// the forces at `x` have already advanced `history` into it
    /// ([`drape_elements::MembraneBatch::element_tangent_after_forces`]).
    #[allow(clippy::too_many_arguments)]
    fn assemble_from(
        &mut self,
        model: &Model,
        x: &[Vector3<f64>],
        history: &[Vec<f64>],
        evaluated: Option<&[Vec<f64>]>,
        dt: f64,
        mass: &[f64],
        mass_factor: f64,
    ) -> Result<(), (String, ElementError)> {
        for (i, b) in model.trusses.iter().enumerate() {
            let slots = batch_slots(&mut self.slots, &self.trusses[i], b.len());
            assemble_batch(slots, &mut self.truss_scratch[i], |e, k| {
                b.element_tangent(e, x, k)
            })
            .map_err(|e| (format!("truss batch {i}"), e))?;
        }
        for (i, b) in model.membranes.iter().enumerate() {
            let h = &history[i];
            let slots = batch_slots(&mut self.slots, &self.membranes[i], b.len());
            let kind = match self.membrane_tangent {
                MembraneTangentChoice::TensionField => MembraneTangent::TensionField,
                _ if self.kept < 1.0 => MembraneTangent::CompressionScaled(self.kept),
                _ => MembraneTangent::Exact,
            };
            let next = evaluated.map(|h| &h[i]);
            assemble_batch(slots, &mut self.membrane_scratch[i], |e, k| match next {
                Some(next) => b.element_tangent_after_forces(
                    e,
                    x,
                    &b.element_history(h, e),
                    &b.element_history(next, e),
                    dt,
                    kind,
                    k,
                ),
                None => b.element_tangent_with(e, x, &b.element_history(h, e), dt, kind, k),
            })
            .map_err(|e| (format!("membrane batch {i} ({:?})", b.shape()), e))?;
        }
        for (i, b) in model.bending.iter().enumerate() {
            let slots = batch_slots(&mut self.slots, &self.bending[i], b.len());
            assemble_batch(slots, &mut self.bending_scratch[i], |e, k| {
                b.element_tangent(e, x, k)
            })
            .map_err(|e| (format!("bending batch {i}"), e))?;
        }
        for (i, b) in model.springs.iter().enumerate() {
            let start = self.springs[i].start;
            for e in 0..b.len() {
                let k = b.element_tangent(e, x);
                let mut s = start + 6 * e;
                for q in 0..3 {
                    for p in 0..=q {
                        self.slots[s] = 0.5 * (k[(p, q)] + k[(q, p)]);
                        s += 1;
                    }
                }
            }
        }
        // Gather per value, in ascending slot order.
        let (slots, ptr, list) = (&self.slots, &self.value_ptr, &self.value_slots);
        self.values
            .par_iter_mut()
            .with_min_len(4096)
            .enumerate()
            .for_each(|(v, out)| {
                let mut sum = 0.0;
                for &s in &list[ptr[v]..ptr[v + 1]] {
                    sum += slots[s as usize];
                }
                *out = sum;
            });
        self.max_stiffness = self
            .diagonal
            .iter()
            .zip(&self.constrained)
            .filter(|(_, c)| !**c)
            .map(|(&k, _)| self.values[k].abs())
            .fold(0.0, f64::max);
        for (d, &k) in self.diagonal.iter().enumerate() {
            self.values[k] += mass_factor * mass[d / 3];
        }
        for &k in &self.constrained_entries {
            self.values[k] = 0.0;
        }
        for (d, &c) in self.constrained.iter().enumerate() {
            if c {
                self.values[self.diagonal[d]] = 1.0;
            }
        }
        Ok(())
    }

    /// [`Self::assemble`] and [`Self::factorise`]; with
    /// [`MembraneTangentChoice::TensionFieldWhenIndefinite`], a K̂ that
    /// Cholesky finds indefinite is assembled again with less of the
    /// resin's compressive stress terms ([`COMPRESSION_KEPT`]) and
    /// factorised again, until Cholesky succeeds or the tension field is
    /// reached (counted in [`Self::compression_scaled`]); the next call of the
    /// same attempt starts where this one stopped. `extra` adds to every
    /// assembly before it is factorised (the contact pass's stick springs).
    /// `evaluated`: the membranes' new history the forces at `x` wrote from
    /// `history` (the Newton loop's residual), whose stress the assembly
    /// then reads instead of updating it again; None to update it here.
    /// Returns the factorisation and the seconds spent assembling.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble_and_factorise(
        &mut self,
        model: &Model,
        x: &[Vector3<f64>],
        history: &[Vec<f64>],
        evaluated: Option<&[Vec<f64>]>,
        dt: f64,
        mass: &[f64],
        mass_factor: f64,
        extra: &mut dyn FnMut(&mut SparseTangent),
    ) -> Result<(Factorisation, f64), TangentError> {
        let mut kind = Factorisation::Cholesky;
        let (_, assembly) = self.assemble_and_factorise_with(
            model,
            x,
            history,
            evaluated,
            dt,
            mass,
            mass_factor,
            extra,
            &mut |tangent| {
                kind = tangent.factorise().map_err(TangentError::ZeroPivot)?;
                Ok(kind == Factorisation::Cholesky)
            },
        )?;
        Ok((kind, assembly))
    }

    /// [`Self::assemble_and_factorise`] with the factorisation left to
    /// `factor`, which says whether what it factorised was definite (the
    /// contact saddle-point system's inertia, see [`crate::saddle`]); an
    /// indefinite one climbs the same ladder of membrane tangents. Returns
    /// the last answer of `factor` and the seconds spent assembling.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble_and_factorise_with(
        &mut self,
        model: &Model,
        x: &[Vector3<f64>],
        history: &[Vec<f64>],
        evaluated: Option<&[Vec<f64>]>,
        dt: f64,
        mass: &[f64],
        mass_factor: f64,
        extra: &mut dyn FnMut(&mut SparseTangent),
        factor: &mut dyn FnMut(&mut SparseTangent) -> Result<bool, TangentError>,
    ) -> Result<(bool, f64), TangentError> {
        let when_indefinite =
            self.membrane_tangent == MembraneTangentChoice::TensionFieldWhenIndefinite;
        let mut assembly = 0.0;
        let mut level = if when_indefinite { self.kept_level } else { 0 };
        loop {
            self.kept = match level {
                0 => 1.0,
                l => COMPRESSION_KEPT[l - 1],
            };
            let started = Instant::now();
            let assembled = self.assemble_from(model, x, history, evaluated, dt, mass, mass_factor);
            self.kept = 1.0;
            assembled.map_err(|(batch, e)| TangentError::Element(batch, e))?;
            extra(self);
            assembly += started.elapsed().as_secs_f64();
            if level > 0 {
                self.compression_scaled += 1;
            }
            let definite = factor(self)?;
            if definite || !when_indefinite || level == COMPRESSION_KEPT.len() {
                self.kept_level = level;
                return Ok((definite, assembly));
            }
            level += 1;
        }
    }

    /// A new attempt of an increment: [`Self::assemble_and_factorise`]
    /// tries the exact tangent first again, and [`Self::max_stiffness`] is
    /// 0 until the attempt's first assembly.
    ///
    /// Why the stiffness is forgotten: it sets the driver's force scale
    /// before that assembly, and an attempt cut for divergence left it at
    /// the diverged iterate's (5.8e14 N/mm on the ±45 deep drawing at
    /// 20 × 20 under twice its holder force): the force scale was then
    /// 2.5e11 N, every later predictor passed the force test at its first
    /// iteration with a residual of 230 N, and the run drifted until the
    /// energy guard stopped it.
    pub fn begin_attempt(&mut self) {
        self.kept_level = 0;
        self.max_stiffness = 0.0;
    }

    /// Factorises the assembled values: Cholesky, or LDLᵀ when Cholesky
    /// meets a non-positive pivot (the tangent is then indefinite: the
    /// driver reports it and cuts the increment if the solve goes wrong).
    pub fn factorise(&mut self) -> Result<Factorisation, FactorError> {
        let started = Instant::now();
        self.factorisations += 1;
        let factor = &self.factor;
        factor.scatter(&self.values, &mut self.ordered_values);
        if !self.split_analysed {
            self.split_analysed = true;
            self.split = SplitCholesky::new(
                self.symbolic_matrix.as_ref(),
                |k| factor.place(k),
                &factor.ranks(),
            );
            if self.split.is_some() {
                self.factor_values = Vec::new();
            }
        }
        let result = if self.factorise_values(false).is_ok() {
            self.kind = Factorisation::Cholesky;
            Ok(self.kind)
        } else {
            self.indefinite += 1;
            self.kind = Factorisation::Ldlt;
            match self.factorise_values(true) {
                Ok(()) => Ok(self.kind),
                Err(NumericFailure::ZeroPivot(dof)) => Err(FactorError { dof }),
                Err(NumericFailure::NotPositiveDefinite) => unreachable!("LDLᵀ asks no sign"),
            }
        };
        self.factor_seconds += started.elapsed().as_secs_f64();
        result
    }

    /// Factorises the values in the factor's order, in two halves where
    /// the model is split (Cholesky, LDLᵀ where `ldlt`); a zero pivot is
    /// named by its component.
    fn factorise_values(&mut self, ldlt: bool) -> Result<(), NumericFailure> {
        if let Some(split) = &mut self.split {
            return split.factorise(&self.ordered_values, ldlt).map(|_| ());
        }
        let factor = &self.factor;
        factor
            .factorise(
                &self.ordered_values,
                &mut self.factor_values,
                ldlt,
                &mut self.stack,
            )
            .map_err(|failure| match failure {
                NumericFailure::ZeroPivot(p) => NumericFailure::ZeroPivot(factor.component(p)),
                other => other,
            })
    }

    /// Solves K̂·z = `rhs` in place with the current factors.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        if let Some(split) = &mut self.split {
            split.solve_in_place(rhs);
            return;
        }
        let ldlt = self.kind == Factorisation::Ldlt;
        self.factor
            .solve(rhs, &self.factor_values, ldlt, &mut self.stack);
    }

    /// y = K̂·x with the assembled values (symmetric, from the upper
    /// triangle): for residual checks.
    pub fn multiply(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        add_symmetric_product(self.matrix(), x, y, 1.0);
    }

    /// Adds the symmetric `block` to node `i`'s 3 × 3 diagonal block of the
    /// assembled K̂ (before [`Self::factorise`]); constrained dofs keep
    /// their identity rows.
    pub fn add_node_block(&mut self, i: usize, block: &Matrix3<f64>) {
        for (&(a, b), &k) in UPPER_BLOCK.iter().zip(&self.node_block_at[i]) {
            if !self.constrained[3 * i + a] && !self.constrained[3 * i + b] {
                self.values[k] += block[(a, b)];
            }
        }
    }

    /// Node `i`'s assembled 3 × 3 diagonal block.
    pub fn node_block(&self, i: usize) -> Matrix3<f64> {
        let at = &self.node_block_at[i];
        let mut m = Matrix3::zeros();
        for (&(a, b), &k) in UPPER_BLOCK.iter().zip(at) {
            m[(a, b)] = self.values[k];
            m[(b, a)] = self.values[k];
        }
        m
    }

    /// Adds the symmetric part of the follower pressures' load stiffness
    /// −∂f_p/∂x at positions `x` and time `t` to the assembled K̂ (before
    /// [`Self::factorise`]); constrained dofs keep their identity rows.
    ///
    /// On an element of k nodes with the pressure p·a(t), every node's
    /// force is (p·a/k)·A, so block (b, c) of −∂f/∂x is −(p·a/k)·D_c with
    /// D_c = ∂A/∂x_c skew: its symmetric part with block (c, b) is
    /// −(p·a/2k)·(D_c − D_b), zero on the diagonal blocks. Elements in the
    /// model's order, each entry added in turn: the same sums whatever the
    /// thread count. Nothing without pressure.
    pub fn add_pressure_stiffness(&mut self, model: &Model, x: &[Vector3<f64>], t: f64) {
        use drape_model::pressure::vector_area_derivative;
        for load in &model.pressure {
            let scale = load.value * load.amplitude.value(t);
            if scale == 0.0 {
                continue;
            }
            for e in 0..load.len() {
                let nodes = load.element(e);
                let k = nodes.len();
                let factor = -scale / (2.0 * k as f64);
                for b in 0..k {
                    for c in 0..k {
                        let (nb, nc) = (nodes[b] as usize, nodes[c] as usize);
                        if nb >= nc {
                            continue;
                        }
                        let block = (vector_area_derivative(nodes, x, c)
                            - vector_area_derivative(nodes, x, b))
                            * factor;
                        for r in 0..3 {
                            for q in 0..3 {
                                self.add_entry(3 * nb + r, 3 * nc + q, block[(r, q)]);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Adds `v` to the upper-triangle entry (`i`, `j`), i < j, unless either
    /// dof is constrained; the entry must be in the pattern.
    fn add_entry(&mut self, i: usize, j: usize, v: f64) {
        if self.constrained[i] || self.constrained[j] {
            return;
        }
        let (ptr, rows) = (
            self.symbolic_matrix.col_ptr(),
            self.symbolic_matrix.row_idx(),
        );
        let found = rows[ptr[j]..ptr[j + 1]].binary_search(&i);
        debug_assert!(found.is_ok(), "({i}, {j}) is in the pattern");
        if let Ok(k) = found {
            self.values[ptr[j] + k] += v;
        }
    }

    /// The assembled entry (i, j) (zero outside the pattern).
    pub fn entry(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if i <= j { (i, j) } else { (j, i) };
        let (ptr, rows) = (
            self.symbolic_matrix.col_ptr(),
            self.symbolic_matrix.row_idx(),
        );
        rows[ptr[j]..ptr[j + 1]]
            .binary_search(&i)
            .map_or(0.0, |k| self.values[ptr[j] + k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shared::ForcePass;
    use drape_constitutive::Material;
    use drape_elements::{ForceTable, SpringBatch};
    use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};

    /// A 3 × 2 carbon blank (quads, trusses or embedded fibres) with two
    /// holding springs, moved to a sheared, stretched and lifted state.
    fn model(fibres: FibreRepresentation, element: ElementKind) -> (Model, Vec<Vector3<f64>>) {
        let blank = RectangleBlank {
            width: 30.0,
            height: 20.0,
            center: Vector3::zeros(),
            orientation_deg: 0.0,
            element,
            meshing: Meshing::Cells([3, 2]),
            fibres,
        };
        let material = Material::preset("carbon-prepreg-2x2").unwrap();
        let mut model = Model::from_blank(&blank, &material).unwrap();
        model.springs.push(SpringBatch {
            table: ForceTable::linear(2.0, 0.5),
            nodes: vec![0, 5],
            anchors: vec![
                Vector3::new(-20.0, -12.0, 1.0),
                Vector3::new(18.0, 11.0, -2.0),
            ],
            rest_length: vec![1.0, 0.5],
        });
        let x = model
            .x0
            .iter()
            .map(|p| {
                Vector3::new(
                    1.004 * p.x + 0.25 * p.y,
                    0.998 * p.y + 0.01 * p.x,
                    0.002 * p.x * p.y + 0.05 * p.x,
                )
            })
            .collect();
        (model, x)
    }

    fn flat(v: &[Vector3<f64>]) -> Vec<f64> {
        v.iter().flat_map(|p| [p.x, p.y, p.z]).collect()
    }

    #[test]
    fn the_assembled_matrix_is_the_symmetric_part_of_the_force_jacobian() {
        // (fibres, element, resin only, yarn bending)
        for (fibres, element, resin_only, bending) in [
            (
                FibreRepresentation::Trusses,
                ElementKind::Quad,
                false,
                false,
            ),
            (FibreRepresentation::Trusses, ElementKind::Quad, true, false),
            (FibreRepresentation::Trusses, ElementKind::Quad, false, true),
            (
                FibreRepresentation::Embedded,
                ElementKind::Quad,
                false,
                false,
            ),
            (
                FibreRepresentation::Embedded,
                ElementKind::Triangle,
                false,
                false,
            ),
        ] {
            let (mut model, x) = model(fibres, element);
            if resin_only {
                model.trusses.clear();
            }
            if bending {
                // Rigidities large enough to weigh against the membranes.
                model
                    .add_yarn_bending(Vector3::x(), Vector3::z(), [2.0e3, 1.0e3])
                    .unwrap();
                assert!(!model.bending.is_empty());
            }
            let n = 3 * model.node_count();
            let dt = 0.01;
            // A committed history from halfway, so that Uₙ ≠ I and τ̄ₙ ≠ 0.
            let mut pass = ForcePass::new(&model);
            let half: Vec<_> = model
                .x0
                .iter()
                .zip(&x)
                .map(|(a, b)| (a + b) * 0.5)
                .collect();
            let initial = model.initial_state().history;
            pass.evaluate(&model, &half, None, &initial, dt, 0, 0.0, None)
                .unwrap();
            let history = pass.history_new.clone();
            let mut constrained = vec![false; n];
            constrained[4] = true; // node 1, y
            let mut k = SparseTangent::new(&model, constrained.clone()).unwrap();
            let (mass, factor) = (&model.mass, 3.0e4);
            k.assemble(&model, &x, &history, dt, mass, factor).unwrap();
            // Central differences of the gathered internal forces.
            let h = 1e-6;
            let mut jac = vec![vec![0.0; n]; n];
            for j in 0..n {
                let mut xp = x.clone();
                xp[j / 3][j % 3] += h;
                pass.evaluate(&model, &xp, None, &history, dt, 0, 0.0, None)
                    .unwrap();
                let fp = flat(&pass.f_int);
                let mut xm = x.clone();
                xm[j / 3][j % 3] -= h;
                pass.evaluate(&model, &xm, None, &history, dt, 0, 0.0, None)
                    .unwrap();
                let fm = flat(&pass.f_int);
                for i in 0..n {
                    jac[i][j] = (fp[i] - fm[i]) / (2.0 * h);
                }
            }
            let scale = jac.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            let (mut worst, mut skew) = (0.0f64, 0.0f64);
            for i in 0..n {
                for j in 0..n {
                    let expected = if constrained[i] || constrained[j] {
                        if i == j { 1.0 } else { 0.0 }
                    } else {
                        0.5 * (jac[i][j] + jac[j][i])
                            + if i == j { factor * mass[i / 3] } else { 0.0 }
                    };
                    worst = worst.max((k.entry(i, j) - expected).abs());
                    skew = skew.max((jac[i][j] - jac[j][i]).abs());
                }
            }
            assert!(
                worst <= 1e-6 * scale,
                "{fibres:?} {element:?} bending {bending}: {worst:e} (scale {scale:e})"
            );
            // A node's block, read or added to in one go, is its entries.
            let block = Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 5.0, 3.0, 5.0, 6.0);
            for i in 0..n / 3 {
                let before = Matrix3::from_fn(|a, b| k.entry(3 * i + a, 3 * i + b));
                assert_eq!(k.node_block(i), before, "node {i}");
                k.add_node_block(i, &block);
                let after = Matrix3::from_fn(|a, b| k.entry(3 * i + a, 3 * i + b));
                let held = |a: usize| constrained[3 * i + a];
                let added = Matrix3::from_fn(|a, b| {
                    if held(a) || held(b) {
                        0.0
                    } else {
                        block[(a, b)]
                    }
                });
                assert_eq!(after, before + added, "node {i}");
            }
            eprintln!(
                "{fibres:?} {element:?} resin only {resin_only} bending {bending}: largest |K − Kᵀ| / max|K| = {:.2e}",
                skew / scale
            );
        }
    }

    #[test]
    fn the_pressure_stiffness_is_the_symmetric_part_of_minus_the_load_jacobian() {
        use crate::shared::PressurePass;
        use drape_model::{Amplitude, PressureLoad};
        for element in [ElementKind::Quad, ElementKind::Triangle] {
            let (mut model, x) = model(FibreRepresentation::Embedded, element);
            let n = 3 * model.node_count();
            // p·a(t) = 0.3 × 0.5, pushing against the normals.
            let load = PressureLoad::on_membranes(
                &model,
                None,
                true,
                0.3,
                Amplitude::Ramp { duration: 2.0 },
            );
            model.pressure.push(load);
            let t = 1.0;
            let history = model.initial_state().history;
            let mut constrained = vec![false; n];
            constrained[4] = true; // node 1, y
            let mut without = SparseTangent::new(&model, constrained.clone()).unwrap();
            without
                .assemble(&model, &x, &history, 0.01, &model.mass, 1.0)
                .unwrap();
            let mut with = SparseTangent::new(&model, constrained.clone()).unwrap();
            with.assemble(&model, &x, &history, 0.01, &model.mass, 1.0)
                .unwrap();
            with.add_pressure_stiffness(&model, &x, t);
            // Central differences of the gathered pressure forces.
            let mut pass = PressurePass::new(&model);
            let mut forces = |x: &[Vector3<f64>]| {
                let mut f = vec![Vector3::zeros(); x.len()];
                pass.add_into(&model, x, t, &mut f);
                flat(&f)
            };
            let h = 1e-6;
            let mut jac = vec![vec![0.0; n]; n];
            for j in 0..n {
                let mut xp = x.clone();
                xp[j / 3][j % 3] += h;
                let mut xm = x.clone();
                xm[j / 3][j % 3] -= h;
                let (fp, fm) = (forces(&xp), forces(&xm));
                for i in 0..n {
                    jac[i][j] = (fp[i] - fm[i]) / (2.0 * h);
                }
            }
            let scale = jac.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            let (mut worst, mut skew) = (0.0f64, 0.0f64);
            for i in 0..n {
                for j in 0..n {
                    let expected = if constrained[i] || constrained[j] {
                        0.0
                    } else {
                        -0.5 * (jac[i][j] + jac[j][i])
                    };
                    let added = with.entry(i, j) - without.entry(i, j);
                    worst = worst.max((added - expected).abs());
                    skew = skew.max((jac[i][j] - jac[j][i]).abs());
                }
            }
            assert!(scale > 0.0);
            assert!(
                worst <= 1e-8 * scale,
                "{element:?}: {worst:e} (scale {scale:e})"
            );
            // The load stiffness is not symmetric: its skew part is what K̂
            // leaves out.
            assert!(skew > 1e-3 * scale, "{element:?}: skew {skew:e}");
            eprintln!(
                "{element:?}: pressure stiffness, largest |K − Kᵀ| / max|K| = {:.2e}",
                skew / scale
            );
        }
    }

    /// A resin-only 3 × 2 blank scaled in plane by `stretch` (a slight
    /// bulge out of plane), its history committed there, and a mass factor
    /// of 1e-6 of its stiffness: (model, x, history, mass factor).
    fn resin_blank(stretch: f64) -> (Model, Vec<Vector3<f64>>, Vec<Vec<f64>>, f64) {
        let (mut model, _) = model(FibreRepresentation::Trusses, ElementKind::Quad);
        model.trusses.clear();
        model.springs.clear();
        let x: Vec<_> = model
            .x0
            .iter()
            .map(|p| Vector3::new(stretch * p.x, stretch * p.y, 1e-3 * p.x * p.y))
            .collect();
        let dt = 0.01;
        let mut pass = ForcePass::new(&model);
        let initial = model.initial_state().history;
        pass.evaluate(&model, &x, None, &initial, dt, 0, 0.0, None)
            .unwrap();
        let history = pass.history_new.clone();
        let n = 3 * model.node_count();
        let mut k = SparseTangent::new(&model, vec![false; n]).unwrap();
        k.assemble(&model, &x, &history, dt, &model.mass, 0.0)
            .unwrap();
        let factor = 1e-6 * k.max_stiffness / model.mass[0];
        (model, x, history, factor)
    }

    /// The driver's force scale reads the stiffness before an attempt's
    /// first assembly: a new attempt must not carry the last one's (see
    /// [`SparseTangent::begin_attempt`]).
    #[test]
    fn a_new_attempt_forgets_the_last_assembly_s_stiffness() {
        let (model, x, history, _) = resin_blank(1.0);
        let n = 3 * model.node_count();
        let mut k = SparseTangent::new(&model, vec![false; n]).unwrap();
        k.assemble(&model, &x, &history, 0.01, &model.mass, 0.0)
            .unwrap();
        assert!(k.max_stiffness > 0.0);
        k.begin_attempt();
        assert_eq!(k.max_stiffness, 0.0);
    }

    #[test]
    fn a_compressed_resin_is_factorised_with_its_compression_scaled_down_when_indefinite() {
        let dt = 0.01;
        let (model, x, history, factor) = resin_blank(0.97);
        let n = 3 * model.node_count();
        let mut k = SparseTangent::new(&model, vec![false; n]).unwrap();
        let call = |k: &mut SparseTangent| {
            k.assemble_and_factorise(
                &model,
                &x,
                &history,
                None,
                dt,
                &model.mass,
                factor,
                &mut |_| {},
            )
            .unwrap()
            .0
        };
        // The exact tangent is indefinite...
        assert_eq!(call(&mut k), Factorisation::Ldlt);
        assert_eq!((k.indefinite, k.compression_scaled), (1, 0));
        // ...the choice steps down until Cholesky succeeds...
        k.membrane_tangent = MembraneTangentChoice::TensionFieldWhenIndefinite;
        k.begin_attempt();
        assert_eq!(call(&mut k), Factorisation::Cholesky);
        let (indefinite, scaled) = (k.indefinite - 1, k.compression_scaled);
        assert!(scaled >= 1 && indefinite == scaled, "{indefinite} {scaled}");
        let values = k.values.clone();
        // ...and the attempt stays where it got to: once, with no exact try.
        assert_eq!(call(&mut k), Factorisation::Cholesky);
        assert_eq!(k.compression_scaled, scaled + 1);
        assert_eq!(k.values, values);
        // A new attempt tries the exact tangent first again.
        k.begin_attempt();
        assert_eq!(call(&mut k), Factorisation::Cholesky);
        assert_eq!(k.indefinite - 1, 2 * indefinite);
        // The tension field always: positive definite at once.
        let mut field = SparseTangent::new(&model, vec![false; n]).unwrap();
        field.membrane_tangent = MembraneTangentChoice::TensionField;
        assert_eq!(call(&mut field), Factorisation::Cholesky);
        assert_eq!((field.indefinite, field.compression_scaled), (0, 0));
    }

    #[test]
    fn a_stretched_resin_gets_the_exact_tangent_whatever_the_choice() {
        let dt = 0.01;
        let (model, x, history, factor) = resin_blank(1.01);
        let n = 3 * model.node_count();
        let mut values = Vec::new();
        for choice in [
            MembraneTangentChoice::Exact,
            MembraneTangentChoice::TensionField,
            MembraneTangentChoice::TensionFieldWhenIndefinite,
        ] {
            let mut k = SparseTangent::new(&model, vec![false; n]).unwrap();
            k.membrane_tangent = choice;
            let (kind, _) = k
                .assemble_and_factorise(
                    &model,
                    &x,
                    &history,
                    None,
                    dt,
                    &model.mass,
                    factor,
                    &mut |_| {},
                )
                .unwrap();
            assert_eq!((kind, k.compression_scaled), (Factorisation::Cholesky, 0));
            values.push(k.values);
        }
        assert_eq!(values[0], values[1]);
        assert_eq!(values[0], values[2]);
    }

    #[test]
    fn solves_with_cholesky_and_with_ldlt_when_indefinite() {
        let (model, x) = model(FibreRepresentation::Trusses, ElementKind::Quad);
        let n = 3 * model.node_count();
        let history = model.initial_state().history;
        let mut k = SparseTangent::new(&model, vec![false; n]).unwrap();
        let b: Vec<f64> = (0..n).map(|i| ((i * 7 + 3) % 11) as f64 - 5.0).collect();
        // A positive mass term makes the tangent definite, a negative one
        // (larger than the softest stiffness) indefinite.
        for (factor, kind) in [
            (1.0e3, Factorisation::Cholesky),
            (-50.0, Factorisation::Ldlt),
        ] {
            k.assemble(
                &model,
                &x,
                &history,
                0.01,
                &model.mass,
                factor / model.mass[0],
            )
            .unwrap();
            assert_eq!(k.factorise().unwrap(), kind);
            let mut z = b.clone();
            k.solve(&mut z);
            let mut y = vec![0.0; n];
            k.multiply(&z, &mut y);
            let err = y
                .iter()
                .zip(&b)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            let size = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(
                err <= 1e-9 * size * k.values.iter().fold(0.0f64, |m, v| m.max(v.abs())),
                "{kind:?}: {err:e}"
            );
        }
        assert_eq!((k.factorisations, k.indefinite), (2, 1));
    }
}
