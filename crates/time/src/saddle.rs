//! The saddle-point system of `contact_solver = "active_set"`
//! ([`drape_contact::SystemRow`] says what its rows are and which are held):
//!
//! ```text
//! [K̂  0   Cᵀ ] [ Δx]   [ r  ]
//! [0  k_d C_dᵀ] [ Δd] = [ r_d]
//! [C  C_d −D ] [−λ ]   [ −g ]
//! ```
//!
//! over the nodes' 3·N components, one unknown per force-driven tool (its
//! displacement along its axis, with its inertia k_d; a prescribed tool's
//! step is zero) and one row per held contact row. With K̂ positive
//! definite and D > 0 the matrix is quasi-definite; it is solved by
//! eliminating the rows first, which is what an LDLᵀ with the rows
//! pivoted first does:
//!
//! ```text
//! A = K̂ + Cᵀ·D⁻¹·C,  B = Cᵀ·D⁻¹·C_d,  S = k_d + C_dᵀ·D⁻¹·C_d − Bᵀ·A⁻¹·B
//! ```
//!
//! A has K̂'s pattern (a row acts on one node, so C's part lands in that
//! node's diagonal block): its symbolic analysis is made once for the run
//! and every Newton iteration is one numeric Cholesky of it (LDLᵀ where it
//! is indefinite), plus one solve per force-driven tool for S (a dense
//! matrix of the tools' size); from 900 nodes on, in two halves of the
//! nodes on two threads. On the shipped hemisphere (40 × 40,
//! implicit) the run's 2 391 factorisations took 29.7 s where the LDLᵀ of
//! the whole saddle-point system over every candidate's slots took 37.7 s
//! for 2 380 (the summary's `factor_s`, one machine and day), and the
//! analysis when the candidates change is gone.
//!
//! D holds the rows' compliance plus, on rigid rows, a regularisation
//! ([`drape_contact::REGULARISATION`]·A_kk) that keeps the pivots of
//! dependent rows (nodes pinched between two tools) away from zero; its
//! bias is removed by iterative refinement against the unregularised
//! matrix (each step one more solve with the factors).
//!
//! Inertia: the system has one negative pivot per held row (−D) plus the
//! negative pivots of [A B; Bᵀ k_d + C_dᵀD⁻¹C_d] (Haynsworth), so the
//! linearised problem is convex on the held rows' null space exactly when
//! A is positive definite and S > 0. Where they are not (compressed resin)
//! A is factorised by LDLᵀ and the negative pivots are reported; the
//! driver treats them as the condensed solver treats negative curvature.
//!
//! Not here: which rows are held (the contact pass), assembly of K̂
//! ([`crate::tangent`]).

use std::time::Instant;

use drape_contact::{ImplicitContact, SystemRow};
use faer::Par;
use faer::dyn_stack::{MemBuffer, StackReq};
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

use crate::ordering::{FactorOrder, NumericFailure};
use crate::split::SplitCholesky;
use crate::tangent::{SparseTangent, add_symmetric_product_columns};

/// Refinement steps at most per solve: the regularisation's bias shrinks
/// by about [`drape_contact::REGULARISATION`] times the row's share per
/// step, so two reach round-off; more means the rows are dependent in a
/// way the tolerance cannot see (a pinched node), where the refinement
/// only moves the indeterminate share.
const MAX_REFINEMENTS: usize = 4;

/// The condensed matrix A, its factors and the tools' Schur complement.
pub struct SaddleSystem {
    /// 3·N.
    dofs: usize,
    /// K̂'s pattern (upper triangle), the same for the whole run.
    symbolic_matrix: Option<SymbolicSparseColMat<usize>>,
    /// K̂'s values at the last factorisation: the refinement's residual
    /// (A's values less the rows' CᵀD⁻¹C would cancel entries 1/D large).
    tangent_values: Vec<f64>,
    /// A's pattern in the factor's order ([`FactorOrder`]), and its values
    /// there.
    factor: Option<FactorOrder>,
    values: Vec<f64>,
    /// Each node's diagonal block in `values`: entries (0,0), (0,1),
    /// (1,1), (0,2), (1,2), (2,2).
    node_block: Vec<[usize; 6]>,
    factor_values: Vec<f64>,
    stack: MemBuffer,
    /// Whether A was factorised by Cholesky (else LDLᵀ).
    cholesky: bool,
    /// A's factorisation in two halves on two threads ([`SplitCholesky`]),
    /// where A is large enough and its nodes cut well; else `factor`'s.
    split: Option<SplitCholesky>,
    /// Whether the last system was indefinite.
    indefinite: bool,
    /// The force-driven tools, in the system's order.
    free_tools: Vec<usize>,
    /// Per free tool: B's column (3·N).
    coupling: Vec<Vec<f64>>,
    /// Per free tool: A⁻¹·B's column (3·N).
    coupled: Vec<Vec<f64>>,
    /// The free tools' Schur complement S, row-major, then its LDLᵀ in
    /// place (unit lower L below the diagonal, D on it).
    schur: Vec<f64>,
    /// Each held row's μ = −λ of the current solve, in the rows' order.
    mu: Vec<f64>,
    z: Vec<f64>,
    tool_z: Vec<f64>,
    residual: Vec<f64>,
    tool_residual: Vec<f64>,
    tool_delta: Vec<f64>,
    row_residual: Vec<f64>,
    product: Vec<f64>,
    /// The second half of the columns' share of K̂·z.
    product_half: Vec<f64>,
    /// Numeric factorisations done.
    pub factorisations: u64,
    /// Seconds in numeric factorisations (and analyses).
    pub factor_seconds: f64,
    /// Solves with the factors (the tools' and the refinement's included).
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
    /// A zero pivot at this unknown of the system (a component 3·node + k,
    /// or 3·N + the force-driven tool's place among them).
    ZeroPivot(usize),
    /// Negative pivots beyond the held rows': the tangent is not positive
    /// definite on the held rows' null space.
    Indefinite {
        /// Negative pivots beyond the rows'.
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
            symbolic_matrix: None,
            factor: None,
            tangent_values: Vec::new(),
            values: Vec::new(),
            node_block: Vec::new(),
            factor_values: Vec::new(),
            stack: MemBuffer::new(StackReq::EMPTY),
            cholesky: true,
            split: None,
            indefinite: false,
            free_tools: Vec::new(),
            coupling: Vec::new(),
            coupled: Vec::new(),
            schur: Vec::new(),
            mu: Vec::new(),
            z: Vec::new(),
            tool_z: Vec::new(),
            residual: Vec::new(),
            tool_residual: Vec::new(),
            tool_delta: Vec::new(),
            row_residual: Vec::new(),
            product: Vec::new(),
            product_half: Vec::new(),
            factorisations: 0,
            factor_seconds: 0.0,
            solves: 0,
        }
    }

    /// The symbolic analysis of `tangent`'s pattern, in the factor's
    /// order ([`FactorOrder`]).
    fn analyse(&mut self, tangent: &SparseTangent) -> Result<(), SaddleError> {
        let k = tangent.matrix();
        let dofs = k.ncols();
        let started = Instant::now();
        let symbolic_error = |e| SaddleError::Symbolic(format!("{e:?}"));
        let matrix = k.symbolic().to_owned().map_err(symbolic_error)?;
        let factor = FactorOrder::analyse(matrix.as_ref()).map_err(symbolic_error)?;
        self.factor_seconds += started.elapsed().as_secs_f64();
        let (ptr, rows) = (matrix.col_ptr(), matrix.row_idx());
        let at = |i: usize, j: usize| {
            factor.place(
                ptr[j]
                    + rows[ptr[j]..ptr[j + 1]]
                        .binary_search(&i)
                        .expect("a node's own block is in the tangent's pattern"),
            )
        };
        self.node_block = (0..dofs / 3)
            .map(|n| {
                let d = 3 * n;
                [
                    at(d, d),
                    at(d, d + 1),
                    at(d + 1, d + 1),
                    at(d, d + 2),
                    at(d + 1, d + 2),
                    at(d + 2, d + 2),
                ]
            })
            .collect();
        self.split = SplitCholesky::new(matrix.as_ref(), |k| factor.place(k), &factor.ranks());
        // The whole factor's values and workspace only where A is not split.
        let symbolic = factor.symbolic();
        (self.stack, self.factor_values) = match self.split {
            Some(_) => (MemBuffer::new(StackReq::EMPTY), Vec::new()),
            None => (
                MemBuffer::new(StackReq::any_of(&[
                    symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
                    symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
                    symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
                ])),
                vec![0.0; symbolic.len_val()],
            ),
        };
        self.values = vec![0.0; factor.len()];
        self.tangent_values = vec![0.0; factor.len()];
        for v in [
            &mut self.z,
            &mut self.residual,
            &mut self.product,
            &mut self.product_half,
        ] {
            *v = vec![0.0; dofs];
        }
        self.factor = Some(factor);
        self.symbolic_matrix = Some(matrix);
        self.dofs = dofs;
        Ok(())
    }

    /// A held row's D in the factorised matrix.
    fn factorised_compliance(row: &SystemRow) -> f64 {
        row.compliance + row.regularisation
    }

    /// The row's coefficient on its tool's unknown, and that unknown's
    /// place among the free tools (None for a prescribed tool).
    fn tool_of(&self, row: &SystemRow) -> Option<(usize, f64)> {
        self.free_tools
            .iter()
            .position(|&t| t == row.tool as usize)
            .map(|k| (k, row.tool_coefficient))
    }

    /// Row `row`'s direction on the free components of its node.
    fn direction(row: &SystemRow, fixed: &[bool]) -> [f64; 3] {
        let i = 3 * row.node as usize;
        std::array::from_fn(|c| if fixed[i + c] { 0.0 } else { row.direction[c] })
    }

    /// Fills A from the assembled `tangent` (with its springs) and the held
    /// `rows`, factorises it and forms the tools' Schur complement;
    /// `fixed` marks the prescribed components (no row acts on them).
    pub fn factorise(
        &mut self,
        tangent: &SparseTangent,
        fixed: &[bool],
        contact: &ImplicitContact,
        rows: &[SystemRow],
    ) -> Result<(), SaddleError> {
        if self.factor.is_none() || self.dofs != tangent.dofs() {
            self.analyse(tangent)?;
        }
        let started = Instant::now();
        self.factorisations += 1;
        self.tangent_values.copy_from_slice(tangent.matrix().val());
        let Some(factor) = &self.factor else {
            unreachable!("analysed above");
        };
        factor.scatter(&self.tangent_values, &mut self.values);
        self.free_tools.clear();
        self.free_tools
            .extend((0..contact.tools.len()).filter(|&t| contact.tool_equation(t).is_some()));
        let tools = self.free_tools.len();
        self.coupling.resize_with(tools, Vec::new);
        self.coupled.resize_with(tools, Vec::new);
        for v in self.coupling.iter_mut().chain(self.coupled.iter_mut()) {
            v.clear();
            v.resize(self.dofs, 0.0);
        }
        self.schur.clear();
        self.schur.resize(tools * tools, 0.0);
        for (k, &t) in self.free_tools.iter().enumerate() {
            self.schur[k * tools + k] = contact.tool_equation(t).map_or(1.0, |(kd, _)| kd);
        }
        for row in rows {
            let d = Self::factorised_compliance(row);
            let c = Self::direction(row, fixed);
            let block = self.node_block[row.node as usize];
            let mut at = 0;
            for b in 0..3 {
                for a in 0..=b {
                    self.values[block[at]] += c[a] * c[b] / d;
                    at += 1;
                }
            }
            if let Some((k, cd)) = self.tool_of(row) {
                let i = 3 * row.node as usize;
                for (a, &ca) in c.iter().enumerate() {
                    self.coupling[k][i + a] += ca * cd / d;
                }
                self.schur[k * tools + k] += cd * cd / d;
            }
        }
        // Cholesky, or LDLᵀ where it meets a non-positive pivot. After an
        // indefinite system LDLᵀ comes first: compressed resin stays
        // compressed over the iterations (a fifth of the deep drawings'
        // systems), and a failed Cholesky costs up to a whole
        // factorisation.
        self.cholesky = !self.indefinite && self.factorise_a(false).is_ok();
        let mut extra = 0;
        if !self.cholesky {
            match self.factorise_a(true) {
                Ok(negative) => extra = negative,
                Err(NumericFailure::ZeroPivot(component)) => {
                    self.factor_seconds += started.elapsed().as_secs_f64();
                    return Err(SaddleError::ZeroPivot(component));
                }
                Err(NumericFailure::NotPositiveDefinite) => unreachable!("LDLᵀ asks no sign"),
            }
        }
        // S = k_d + C_dᵀD⁻¹C_d − Bᵀ·A⁻¹·B.
        for k in 0..tools {
            let mut y = std::mem::take(&mut self.coupled[k]);
            y.copy_from_slice(&self.coupling[k]);
            self.solve_a(&mut y);
            for l in 0..tools {
                let dot: f64 = self.coupling[l].iter().zip(&y).map(|(b, y)| b * y).sum();
                self.schur[l * tools + k] -= dot;
            }
            self.coupled[k] = y;
        }
        let negative = small_ldlt(&mut self.schur, tools)
            .map_err(|k| SaddleError::ZeroPivot(self.dofs + k))?;
        extra += negative;
        self.indefinite = extra > 0;
        self.factor_seconds += started.elapsed().as_secs_f64();
        if extra > 0 {
            return Err(SaddleError::Indefinite { extra });
        }
        Ok(())
    }

    /// Factorises A's `values`, in two halves where it is split (Cholesky,
    /// LDLᵀ where `ldlt`): the negative pivots, or why it failed (a zero
    /// pivot's component).
    fn factorise_a(&mut self, ldlt: bool) -> Result<usize, NumericFailure> {
        if let Some(split) = &mut self.split {
            return split.factorise(&self.values, ldlt);
        }
        let factor = self.factor.as_ref().expect("analysed");
        factor
            .factorise(&self.values, &mut self.factor_values, ldlt, &mut self.stack)
            .map_err(|failure| match failure {
                NumericFailure::ZeroPivot(p) => NumericFailure::ZeroPivot(factor.component(p)),
                other => other,
            })?;
        Ok(if ldlt { self.negative_pivots() } else { 0 })
    }

    /// Negative entries of D in the last LDLᵀ of A (faer keeps D on the
    /// factor's diagonal, in both layouts).
    fn negative_pivots(&self) -> usize {
        let Some(factor) = &self.factor else {
            return 0;
        };
        let symbolic = factor.symbolic();
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

    /// v ← A⁻¹·v with the factors.
    fn solve_a(&mut self, v: &mut [f64]) {
        if let Some(split) = &mut self.split {
            split.solve_in_place(v);
            self.solves += 1;
            return;
        }
        let factor = self.factor.as_mut().expect("factorised");
        factor.solve(v, &self.factor_values, !self.cholesky, &mut self.stack);
        self.solves += 1;
    }

    /// Solves the regularised system for the right-hand sides in
    /// `residual` (components), `tool_residual` (free tools) and
    /// `row_residual` (held rows), and adds the answer to `z`, `tool_z` and
    /// `mu`.
    fn solve_regularised(&mut self, rows: &[SystemRow], fixed: &[bool]) {
        let tools = self.free_tools.len();
        // f₁ = h₁ + Cᵀ·D⁻¹·h₃ and f₂ = h₂ + C_dᵀ·D⁻¹·h₃.
        let mut f1 = std::mem::take(&mut self.product);
        f1.copy_from_slice(&self.residual);
        for (row, &h3) in rows.iter().zip(&self.row_residual) {
            let d = Self::factorised_compliance(row);
            let c = Self::direction(row, fixed);
            let i = 3 * row.node as usize;
            for (f, ca) in f1[i..i + 3].iter_mut().zip(c) {
                *f += ca * h3 / d;
            }
            if let Some((k, cd)) = self.tool_of(row) {
                self.tool_residual[k] += cd * h3 / d;
            }
        }
        self.solve_a(&mut f1);
        // Δd = S⁻¹·(f₂ − Bᵀ·A⁻¹f₁); Δx = A⁻¹f₁ − A⁻¹B·Δd.
        let mut step = std::mem::take(&mut self.tool_delta);
        step.clear();
        step.resize(tools, 0.0);
        for (k, s) in step.iter_mut().enumerate() {
            let dot: f64 = self.coupling[k].iter().zip(&f1).map(|(b, z)| b * z).sum();
            *s = self.tool_residual[k] - dot;
        }
        small_ldlt_solve(&self.schur, tools, &mut step);
        for (k, &s) in step.iter().enumerate() {
            for (x, &y) in f1.iter_mut().zip(&self.coupled[k]) {
                *x -= y * s;
            }
            self.tool_z[k] += s;
        }
        for (x, &f) in f1.iter_mut().zip(fixed) {
            if f {
                *x = 0.0;
            }
        }
        // μ = (C·Δx + C_d·Δd − h₃)/D.
        for (r, row) in rows.iter().enumerate() {
            let d = Self::factorised_compliance(row);
            let c = Self::direction(row, fixed);
            let i = 3 * row.node as usize;
            let mut v = c[0] * f1[i] + c[1] * f1[i + 1] + c[2] * f1[i + 2] - self.row_residual[r];
            if let Some((k, cd)) = self.tool_of(row) {
                v += cd * step[k];
            }
            self.mu[r] += v / d;
        }
        for (z, &x) in self.z.iter_mut().zip(&f1) {
            *z += x;
        }
        self.product = f1;
        self.tool_delta = step;
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
        let tools = self.free_tools.len();
        self.z.fill(0.0);
        self.tool_z.clear();
        self.tool_z.resize(tools, 0.0);
        self.mu.clear();
        self.mu.resize(rows.len(), 0.0);
        self.tool_residual.resize(tools, 0.0);
        self.row_residual.resize(rows.len(), 0.0);
        let mut left = f64::INFINITY;
        for step in 0..=MAX_REFINEMENTS + 1 {
            // residual = rhs − M₀·(z, Δd, μ), M₀ without the
            // regularisation (zero before the first solve).
            for ((res, &ri), &f) in self.residual.iter_mut().zip(r).zip(fixed) {
                *res = if f { 0.0 } else { ri };
            }
            for (k, &t) in self.free_tools.iter().enumerate() {
                self.tool_residual[k] = contact
                    .tool_equation(t)
                    .map_or(0.0, |(kd, res)| res - kd * self.tool_z[k]);
            }
            if step > 0 {
                self.subtract_tangent_product();
            }
            for (r, row) in rows.iter().enumerate() {
                let c = Self::direction(row, fixed);
                let i = 3 * row.node as usize;
                let mu = self.mu[r];
                for (res, ca) in self.residual[i..i + 3].iter_mut().zip(c) {
                    *res -= ca * mu;
                }
                let mut v = c[0] * self.z[i] + c[1] * self.z[i + 1] + c[2] * self.z[i + 2]
                    - row.compliance * mu;
                if let Some((k, cd)) = self.tool_of(row) {
                    self.tool_residual[k] -= cd * mu;
                    v += cd * self.tool_z[k];
                }
                self.row_residual[r] = -row.target - v;
            }
            if step > 0 {
                left = self.row_residual.iter().fold(0.0, |m, v| m.max(v.abs()));
                if left <= tolerance || step == MAX_REFINEMENTS + 1 {
                    break;
                }
            }
            self.solve_regularised(rows, fixed);
        }
        for ((d, &z), &f) in dx.iter_mut().zip(&self.z).zip(fixed) {
            *d = if f { 0.0 } else { z };
        }
        tool_step.clear();
        tool_step.extend((0..contact.tools.len()).map(|t| {
            self.free_tools
                .iter()
                .position(|&f| f == t)
                .map_or(0.0, |k| self.tool_z[k])
        }));
        lambda.clear();
        lambda.extend(self.mu.iter().map(|mu| -mu));
        left
    }

    /// residual −= K̂·z (K̂ from its upper triangle), the columns in two
    /// halves of equal entries on two threads: the second half's terms
    /// summed apart and added last, whatever the thread count.
    fn subtract_tangent_product(&mut self) {
        let matrix = self.symbolic_matrix.as_ref().expect("analysed");
        let (ptr, n) = (matrix.col_ptr(), matrix.ncols());
        let middle = ptr.partition_point(|&p| p < ptr[n] / 2).min(n);
        let (first, second) = (
            SparseColMatRef::new(matrix.as_ref(), &self.tangent_values),
            &mut self.product_half,
        );
        second.fill(0.0);
        let (z, residual) = (&self.z, &mut self.residual);
        rayon::join(
            || add_symmetric_product_columns(first, 0..middle, z, residual, -1.0),
            || add_symmetric_product_columns(first, middle..n, z, second, -1.0),
        );
        for (r, s) in residual.iter_mut().zip(second.iter()) {
            *r += s;
        }
    }
}

/// LDLᵀ without pivoting of the symmetric n × n `s` (row-major, both
/// triangles), in place: L's multipliers below the diagonal, D on it.
/// Returns the negative pivots, or the index of a zero one. For the free
/// tools' Schur complement: n is the number of force-driven tools (one or
/// two), where nalgebra's decompositions would allocate every iteration.
fn small_ldlt(s: &mut [f64], n: usize) -> Result<usize, usize> {
    let mut negative = 0;
    for k in 0..n {
        let d = s[k * n + k];
        if d == 0.0 || !d.is_finite() {
            return Err(k);
        }
        if d < 0.0 {
            negative += 1;
        }
        for i in k + 1..n {
            for j in k + 1..=i {
                s[i * n + j] -= s[i * n + k] * s[j * n + k] / d;
            }
        }
        for i in k + 1..n {
            s[i * n + k] /= d;
        }
    }
    Ok(negative)
}

/// Solves L·D·Lᵀ·x = b in place with the factors of [`small_ldlt`].
fn small_ldlt_solve(s: &[f64], n: usize, x: &mut [f64]) {
    for i in 0..n {
        for j in 0..i {
            x[i] -= s[i * n + j] * x[j];
        }
    }
    for i in 0..n {
        x[i] /= s[i * n + i];
    }
    for i in (0..n).rev() {
        for j in i + 1..n {
            x[i] -= s[j * n + i] * x[j];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// The tools' small LDLᵀ solves as nalgebra's LU does and counts the
    /// negative eigenvalues (Sylvester's law of inertia).
    #[test]
    fn the_small_ldlt_solves_and_counts_negative_pivots() {
        for (entries, negative) in [
            (vec![4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0], 0),
            (vec![2.0, 1.0, 0.0, 1.0, -3.0, 1.0, 0.0, 1.0, 1.0], 1),
            (vec![-1.0, 0.5, 0.5, -2.0], 2),
        ] {
            let n = (entries.len() as f64).sqrt() as usize;
            let m = DMatrix::from_row_slice(n, n, &entries);
            let eigen = m.clone().symmetric_eigenvalues();
            assert_eq!(eigen.iter().filter(|&&e| e < 0.0).count(), negative);
            let mut s = entries.clone();
            assert_eq!(small_ldlt(&mut s, n), Ok(negative));
            let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
            let mut x = b.clone();
            small_ldlt_solve(&s, n, &mut x);
            let expected = m.lu().solve(&DVector::from_vec(b)).expect("regular");
            for (a, e) in x.iter().zip(expected.iter()) {
                assert!((a - e).abs() <= 1e-14 * e.abs().max(1.0), "{a} against {e}");
            }
        }
        let mut singular = vec![1.0, 1.0, 1.0, 1.0];
        assert_eq!(small_ldlt(&mut singular, 2), Err(1));
    }
}
