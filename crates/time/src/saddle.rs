//! The saddle-point system of `contact_solver = "active_set"`
//! ([`drape_contact::SystemRow`] says what its rows are and which are held):
//!
//! ```text
//! [K̂  0   Cᵀ ] [ Δx]   [ r  ]
//! [0  k_d C_dᵀ] [ Δd] = [ r_d]
//! [C  C_d −D ] [−λ ]   [ −g ]
//! ```
//!
//! over the nodes' 3·N components, one unknown per tool (a force-driven
//! tool's displacement along its axis with its inertia k_d; an identity for
//! a prescribed tool) and [`drape_contact::SLOTS_PER_PAIR`] slots per
//! contact candidate. A slot not held is a decoupled −1. With K̂ positive
//! definite and D > 0 the matrix is quasi-definite, so faer's sparse LDLᵀ
//! without pivoting factorises it in any symmetric order: the symbolic
//! analysis (AMD over the whole pattern) is built when the candidates
//! change and reused by every numeric factorisation until then. One
//! numeric factorisation per Newton iteration replaces the condensed
//! solver's factorisation of K̂ and its ~30 solves with the factors.
//!
//! D holds the rows' compliance plus, on rigid rows, a regularisation
//! ([`drape_contact::REGULARISATION`]·A_kk) that keeps the pivots of
//! dependent rows (nodes pinched between two tools) away from zero; its
//! bias is removed by iterative refinement against the unregularised
//! matrix (each step one solve with the factors).
//!
//! Inertia: the factorisation has exactly one negative pivot per slot when
//! K̂ is positive definite on the held rows' null space; more means the
//! linearised problem is not convex there (compressed resin), which the
//! driver treats as the condensed solver treats negative curvature.
//!
//! Not here: which rows are held (the contact pass), assembly of K̂
//! ([`crate::tangent`]).

use std::time::Instant;

use drape_contact::{ImplicitContact, SystemRow};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::tangent::SparseTangent;

/// Refinement steps at most per solve: the regularisation's bias shrinks
/// by about [`drape_contact::REGULARISATION`] times the row's share per
/// step, so two reach round-off; more means the rows are dependent in a
/// way the tolerance cannot see (a pinched node), where the refinement
/// only moves the indeterminate share.
const MAX_REFINEMENTS: usize = 4;

/// The pattern, values and factors of the saddle-point system.
pub struct SaddleSystem {
    /// 3·N.
    dofs: usize,
    tools: usize,
    slots: usize,
    /// The contact pass's candidate generation the pattern was built for.
    generation: Option<u64>,
    symbolic_matrix: Option<SymbolicSparseColMat<usize>>,
    values: Vec<f64>,
    /// K̂'s value k is the system's value `tangent_map[k]`.
    tangent_map: Vec<usize>,
    /// Each tool's diagonal value.
    tool_diagonal: Vec<usize>,
    /// Each slot's first value: its node's three components, its tool,
    /// its diagonal.
    slot_start: Vec<usize>,
    symbolic: Option<SymbolicCholesky<usize>>,
    factor_values: Vec<f64>,
    stack: MemBuffer,
    rhs: Vec<f64>,
    z: Vec<f64>,
    residual: Vec<f64>,
    /// Numeric factorisations done.
    pub factorisations: u64,
    /// Symbolic analyses done (one per change of the candidates).
    pub analyses: u64,
    /// Seconds in numeric factorisations (and analyses).
    pub factor_seconds: f64,
    /// Solves with the factors (the refinement's included).
    pub solves: u64,
}

impl Default for SaddleSystem {
    fn default() -> Self {
        Self::new()
    }
}

/// Why the saddle-point system could not be used.
#[derive(Debug, Clone, PartialEq)]
pub enum SaddleError {
    /// A zero pivot at this unknown of the system.
    ZeroPivot(usize),
    /// More negative pivots than slots: the tangent is not positive
    /// definite on the held rows' null space.
    Indefinite {
        /// Negative pivots beyond the slots'.
        extra: usize,
    },
    /// The symbolic analysis failed.
    Symbolic(String),
}

impl std::fmt::Display for SaddleError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SaddleError::ZeroPivot(i) => {
                write!(
                    f,
                    "the contact saddle-point system has a zero pivot at unknown {i}"
                )
            }
            SaddleError::Indefinite { extra } => write!(
                f,
                "the contact saddle-point system has {extra} negative pivot(s) beyond its \
                 constraints (tangent indefinite on the contact's null space)"
            ),
            SaddleError::Symbolic(e) => write!(f, "symbolic analysis of the contact system: {e}"),
        }
    }
}

impl SaddleSystem {
    /// An empty system; the pattern is built at the first factorisation.
    pub fn new() -> Self {
        Self {
            dofs: 0,
            tools: 0,
            slots: 0,
            generation: None,
            symbolic_matrix: None,
            values: Vec::new(),
            tangent_map: Vec::new(),
            tool_diagonal: Vec::new(),
            slot_start: Vec::new(),
            symbolic: None,
            factor_values: Vec::new(),
            stack: MemBuffer::new(StackReq::EMPTY),
            rhs: Vec::new(),
            z: Vec::new(),
            residual: Vec::new(),
            factorisations: 0,
            analyses: 0,
            factor_seconds: 0.0,
            solves: 0,
        }
    }

    /// Unknowns of the system.
    pub fn size(&self) -> usize {
        self.dofs + self.tools + self.slots
    }

    /// The pattern and its symbolic analysis for `tangent`'s pattern and
    /// `contact`'s candidates.
    fn analyse(
        &mut self,
        tangent: &SparseTangent,
        contact: &ImplicitContact,
    ) -> Result<(), SaddleError> {
        let k = tangent.matrix();
        let dofs = k.ncols();
        let tools = contact.tools.len();
        let slot_list: Vec<(u32, u32)> = contact.slots().collect();
        let slots = slot_list.len();
        let n = dofs + tools + slots;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(k.compute_nnz() + tools + 5 * slots);
        let mut tangent_map = Vec::with_capacity(k.compute_nnz());
        col_ptr.push(0);
        for j in 0..dofs {
            for &i in k.row_idx_of_col_raw(j) {
                tangent_map.push(row_idx.len());
                row_idx.push(i);
            }
            col_ptr.push(row_idx.len());
        }
        let mut tool_diagonal = Vec::with_capacity(tools);
        for t in 0..tools {
            tool_diagonal.push(row_idx.len());
            row_idx.push(dofs + t);
            col_ptr.push(row_idx.len());
        }
        let mut slot_start = Vec::with_capacity(slots);
        for (s, &(node, tool)) in slot_list.iter().enumerate() {
            slot_start.push(row_idx.len());
            let i = 3 * node as usize;
            row_idx.extend([i, i + 1, i + 2, dofs + tool as usize, dofs + tools + s]);
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        let started = Instant::now();
        let matrix = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            matrix.as_ref(),
            Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| SaddleError::Symbolic(format!("{e:?}")))?;
        self.factor_seconds += started.elapsed().as_secs_f64();
        self.analyses += 1;
        self.stack = MemBuffer::new(StackReq::any_of(&[
            symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]));
        self.factor_values = vec![0.0; symbolic.len_val()];
        self.values = vec![0.0; nnz];
        self.rhs = vec![0.0; n];
        self.z = vec![0.0; n];
        self.residual = vec![0.0; n];
        self.symbolic = Some(symbolic);
        self.symbolic_matrix = Some(matrix);
        self.tangent_map = tangent_map;
        self.tool_diagonal = tool_diagonal;
        self.slot_start = slot_start;
        self.dofs = dofs;
        self.tools = tools;
        self.slots = slots;
        self.generation = Some(contact.candidate_generation());
        Ok(())
    }

    /// Fills the system from the assembled `tangent` (with its springs),
    /// the tools' equations and the held `rows`, and factorises it;
    /// `fixed` marks the prescribed components (no row acts on them).
    pub fn factorise(
        &mut self,
        tangent: &SparseTangent,
        fixed: &[bool],
        contact: &ImplicitContact,
        rows: &[SystemRow],
    ) -> Result<(), SaddleError> {
        if self.generation != Some(contact.candidate_generation())
            || self.tools != contact.tools.len()
        {
            self.analyse(tangent, contact)?;
        }
        let started = Instant::now();
        for (&k, &v) in self.tangent_map.iter().zip(&tangent.values) {
            self.values[k] = v;
        }
        for (t, &d) in self.tool_diagonal.iter().enumerate() {
            self.values[d] = contact.tool_equation(t).map_or(1.0, |(k, _)| k);
        }
        for &s in &self.slot_start {
            self.values[s..s + 4].fill(0.0);
            self.values[s + 4] = -1.0;
        }
        for row in rows {
            let s = self.slot_start[row.slot];
            let i = 3 * row.node as usize;
            for c in 0..3 {
                self.values[s + c] = if fixed[i + c] { 0.0 } else { row.direction[c] };
            }
            self.values[s + 3] = if contact.tool_equation(row.tool as usize).is_some() {
                row.tool_coefficient
            } else {
                0.0
            };
            self.values[s + 4] = -(row.compliance + row.regularisation);
        }
        self.factorisations += 1;
        let (Some(symbolic), Some(matrix)) = (&self.symbolic, &self.symbolic_matrix) else {
            unreachable!("analysed above");
        };
        let a = SparseColMatRef::new(matrix.as_ref(), &self.values);
        let factored = symbolic.factorize_numeric_ldlt(
            &mut self.factor_values,
            a,
            Side::Upper,
            LdltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.stack),
            Default::default(),
        );
        self.factor_seconds += started.elapsed().as_secs_f64();
        if let Err(faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index }) = factored
        {
            let at = symbolic.perm().map_or(index, |p| p.arrays().0[index]);
            return Err(SaddleError::ZeroPivot(at));
        }
        let negative = self.negative_pivots();
        if negative > self.slots {
            return Err(SaddleError::Indefinite {
                extra: negative - self.slots,
            });
        }
        Ok(())
    }

    /// Negative entries of D in the last factorisation (faer keeps D on
    /// the factor's diagonal, in both layouts).
    fn negative_pivots(&self) -> usize {
        let Some(symbolic) = &self.symbolic else {
            return 0;
        };
        let values = &self.factor_values;
        match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let ptr = s.col_ptr();
                (0..s.ncols()).filter(|&k| values[ptr[k]] < 0.0).count()
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let begin = s.supernode_begin();
                let val_ptr = s.col_ptr_for_val();
                let mut negative = 0;
                for sn in 0..begin.len() - 1 {
                    let ncols = begin[sn + 1] - begin[sn];
                    let block = &values[val_ptr[sn]..val_ptr[sn + 1]];
                    let nrows = block.len() / ncols;
                    negative += (0..ncols).filter(|&j| block[j * nrows + j] < 0.0).count();
                }
                negative
            }
        }
    }

    fn solve_in_place(&mut self, which: Which) {
        let symbolic = self.symbolic.as_ref().expect("factorised");
        let v = match which {
            Which::Z => &mut self.z,
            Which::Residual => &mut self.residual,
        };
        let n = v.len();
        LdltRef::new(symbolic, &self.factor_values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(v, n, 1),
            Par::Seq,
            MemStack::new(&mut self.stack),
        );
        self.solves += 1;
    }

    /// Solves the factorised system for the residual `r` (3·N, every force
    /// but the multipliers', the springs' forces at the iterate in it),
    /// the tools' residuals and the held `rows`' targets, and refines it
    /// against the unregularised matrix until every row holds to
    /// `tolerance` (mm). Writes Δx into `dx`, λ of each row into `lambda`,
    /// each tool's Δd into `tool_step`; returns the largest row residual
    /// left (mm).
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        r: &[f64],
        fixed: &[bool],
        contact: &ImplicitContact,
        rows: &[SystemRow],
        tolerance: f64,
        dx: &mut [f64],
        lambda: &mut Vec<f64>,
        tool_step: &mut Vec<f64>,
    ) -> f64 {
        let (dofs, tools) = (self.dofs, self.tools);
        self.rhs.fill(0.0);
        for ((b, &ri), &f) in self.rhs.iter_mut().zip(r).zip(fixed) {
            *b = if f { 0.0 } else { ri };
        }
        for t in 0..tools {
            self.rhs[dofs + t] = contact.tool_equation(t).map_or(0.0, |(_, res)| res);
        }
        for row in rows {
            self.rhs[dofs + tools + row.slot] = -row.target;
        }
        self.z.copy_from_slice(&self.rhs);
        self.solve_in_place(Which::Z);
        let mut left = f64::INFINITY;
        for step in 0..=MAX_REFINEMENTS {
            // residual = rhs − M₀·z, M₀ without the regularisation.
            self.multiply_into_residual();
            for row in rows {
                let p = dofs + tools + row.slot;
                self.residual[p] -= row.regularisation * self.z[p];
            }
            left = rows
                .iter()
                .map(|row| self.residual[dofs + tools + row.slot].abs())
                .fold(0.0, f64::max);
            if left <= tolerance || step == MAX_REFINEMENTS {
                break;
            }
            self.solve_in_place(Which::Residual);
            for (z, d) in self.z.iter_mut().zip(&self.residual) {
                *z += d;
            }
        }
        for ((d, &z), &f) in dx.iter_mut().zip(&self.z[..dofs]).zip(fixed) {
            *d = if f { 0.0 } else { z };
        }
        tool_step.clear();
        tool_step.extend_from_slice(&self.z[dofs..dofs + tools]);
        lambda.clear();
        lambda.extend(rows.iter().map(|row| -self.z[dofs + tools + row.slot]));
        left
    }

    /// residual = rhs − M·z with the factorised (regularised) values.
    fn multiply_into_residual(&mut self) {
        let matrix = self.symbolic_matrix.as_ref().expect("analysed");
        let (ptr, idx) = (matrix.col_ptr(), matrix.row_idx());
        self.residual.copy_from_slice(&self.rhs);
        let (z, res, values) = (&self.z, &mut self.residual, &self.values);
        for j in 0..z.len() {
            for k in ptr[j]..ptr[j + 1] {
                let (i, v) = (idx[k], values[k]);
                res[i] -= v * z[j];
                if i != j {
                    res[j] -= v * z[i];
                }
            }
        }
    }
}

#[derive(Clone, Copy)]
enum Which {
    Z,
    Residual,
}
