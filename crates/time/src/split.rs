//! The implicit driver's sparse factorisations on two threads (the
//! active-set solver's A, the condensed solver's K̂): the nodes cut in two
//! halves by a separator, each half's factor taken on its own thread, the
//! separator's dense Schur complement after them.
//!
//! faer's supernodal factorisation walks its supernodes one after another
//! (its `Par` only splits the dense kernels, which are too small here to
//! gain: 12.9 ms against 7.2 ms on two threads), so the second core idled
//! through the largest item of an implicit iteration. In the order
//! [I₁, I₂, S] (the separator S last, no entry between I₁ and I₂) A's
//! Cholesky factor is
//!
//! ```text
//! L = [L₁₁  0    0  ]      L₁₁L₁₁ᵀ = A₁₁,  L_s1 = A_s1·L₁₁⁻ᵀ (the same for 2)
//!     [0    L₂₂  0  ]      L_ssL_ssᵀ = A_ss − L_s1L_s1ᵀ − L_s2L_s2ᵀ
//!     [L_s1 L_s2 L_ss]
//! ```
//!
//! Each half h factorises B_h = [A_hh A_hs; A_sh A_ss] (a principal block
//! of A, so positive definite when A is) with faer, the separator last:
//! its factor holds L_hh, L_sh and M_h with M_hM_hᵀ = A_ss − L_shL_shᵀ.
//! Then L_ssL_ssᵀ = M₁M₁ᵀ + M₂M₂ᵀ − A_ss, a dense matrix of the
//! separator's size, and a solve runs the halves' triangular sweeps up to
//! the separator on the two threads, the separator's between them. An
//! indefinite A goes the same way by LDLᵀ without pivoting (M_hD_hM_hᵀ),
//! and its negative pivots are those of the halves' own columns and of the
//! separator's (Sylvester's law of inertia: the order of elimination does
//! not change the count). What is computed does not depend on the thread
//! count (a one-thread pool runs both halves' arithmetic as it is). Costs
//! beyond A's own factor: each half's dense separator block and its
//! product M_hM_hᵀ, and the separator's factorisation on one thread. On
//! the shipped 41 × 41-node scenes a half takes about 57 % of the whole
//! factor's time, the separator (243 components) 4 %.
//!
//! The cut: a breadth-first search of the nodes' graph from a
//! pseudo-peripheral node (George–Liu); the level that halves the rest is
//! the separator (a level set separates the levels before it from those
//! after it, whatever the couplings' reach: yarn bending couples a node's
//! neighbours on either side of it).
//!
//! Not here: assembling the matrix, choosing between Cholesky and LDLᵀ.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::linalg::cholesky::{ldlt, llt};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_unit_lower_triangular_in_place,
    solve_unit_upper_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::{Accum, Mat, MatMut, MatRef, Par};

use crate::ordering::{FactorOrder, NumericFailure, pattern};

/// Fewer nodes than this are factorised whole: the separator's dense work
/// and two thread hand-overs per solve cost about what a half saves (the
/// shipped hemisphere implicit at 25 × 25 nodes: 4.0 s split against 3.9 s
/// whole; at 33 × 33: 7.1 s against 8.3–8.8 s).
const MIN_NODES: usize = 900;

/// The separator's nodes at most, as a share of all and in multiples of
/// √nodes: a blank's mesh is planar, so a good cut grows as √nodes
/// (Lipton–Tarjan; 2√nodes on the shipped square blanks, where yarn
/// bending makes it two grid lines wide). A longer one is a poor cut, whose
/// dense blocks (cubic in its size) would cost more than the halves save.
const MAX_SEPARATOR_SHARE: f64 = 0.1;
const MAX_SEPARATOR_ROOTS: f64 = 3.0;

/// A's Cholesky factor as two halves and their separator.
pub(crate) struct SplitCholesky {
    halves: [Half; 2],
    /// The separator's components (A's numbering), in its order.
    separator: Vec<usize>,
    /// Per entry of A's separator block: its row and column in the
    /// separator's order (row ≥ column) and its place in A's values.
    separator_entries: Vec<(usize, usize, usize)>,
    /// M₁M₁ᵀ + M₂M₂ᵀ − A_ss, then its factor (lower triangle; LDLᵀ's D
    /// on the diagonal).
    schur: Mat<f64>,
    /// Whether the last factorisation was LDLᵀ (else Cholesky).
    ldlt: bool,
    stack: MemBuffer,
    /// The separator's part of a solve.
    rhs: Vec<f64>,
}

/// One half: B_h and its factor.
struct Half {
    /// A's component at each place of B_h's order: the half's own
    /// components (in the whole matrix's fill-reducing order), then the
    /// separator's.
    components: Vec<usize>,
    /// The half's own components (B_h's leading block).
    own: usize,
    factor: FactorOrder,
    /// Per value of B_h (lower triangle, the factor's layout): its place,
    /// and the place of the same entry in A's values.
    from_a: Vec<(usize, usize)>,
    values: Vec<f64>,
    factor_values: Vec<f64>,
    stack: MemBuffer,
    /// M_h, the factor's separator block, dense (unit diagonal after
    /// LDLᵀ).
    m: Mat<f64>,
    /// M_h·D_s after LDLᵀ (D_s the separator's pivots in B_h).
    scaled: Mat<f64>,
    /// The pivots of the half's own columns after LDLᵀ.
    pivots: Vec<f64>,
    /// M_hM_hᵀ (M_hD_sM_hᵀ after LDLᵀ; lower triangle).
    gram: Mat<f64>,
    /// A right-hand side in B_h's order.
    x: Vec<f64>,
    /// A supernode's rows below its diagonal block.
    below: Vec<f64>,
}

impl SplitCholesky {
    /// The halves and separator of the symmetric pattern `upper` (its upper
    /// triangle, three components per node), whose entry k lies at
    /// `place(k)` in the values the factorisations will read; each half's
    /// components are taken in the order of their `rank` (the place of each
    /// in a fill-reducing order of the whole: AMD's order of the whole
    /// makes less work than AMD of each half alone, which does not see the
    /// separator). `None` where the matrix is too small or no balanced cut
    /// with a small separator is found.
    pub(crate) fn new(
        upper: SymbolicSparseColMatRef<'_, usize>,
        place: impl Fn(usize) -> usize,
        rank: &[usize],
    ) -> Option<Self> {
        let n = upper.ncols();
        if n % 3 != 0 || n / 3 < MIN_NODES {
            return None;
        }
        let side = cut(upper)?;
        let (ptr, rows) = (upper.col_ptr(), upper.row_idx());
        let separator: Vec<usize> = (0..n).filter(|&c| side[c / 3] == SEPARATOR).collect();
        let mut at_separator = vec![usize::MAX; n];
        for (k, &c) in separator.iter().enumerate() {
            at_separator[c] = k;
        }
        let mut separator_entries = Vec::new();
        for j in 0..n {
            for (k, &i) in rows[ptr[j]..ptr[j + 1]].iter().enumerate() {
                let (a, b) = (at_separator[i], at_separator[j]);
                if a != usize::MAX && b != usize::MAX {
                    separator_entries.push((a.max(b), a.min(b), place(ptr[j] + k)));
                }
            }
        }
        let halves = [
            Half::new(upper, &place, rank, &side, 0, &separator)?,
            Half::new(upper, &place, rank, &side, 1, &separator)?,
        ];
        let s = separator.len();
        Some(Self {
            halves,
            separator,
            separator_entries,
            schur: Mat::zeros(s, s),
            ldlt: false,
            stack: MemBuffer::new(StackReq::any_of(&[
                llt::factor::cholesky_in_place_scratch::<f64>(s, Par::Seq, Default::default()),
                ldlt::factor::cholesky_in_place_scratch::<f64>(s, Par::Seq, Default::default()),
            ])),
            rhs: vec![0.0; s],
        })
    }

    /// The separator's components.
    #[cfg(test)]
    fn separator_len(&self) -> usize {
        self.separator.len()
    }

    /// Cholesky (LDLᵀ where `ldlt`) of the matrix whose values (at the
    /// places `new` was given) are `a`; the number of negative pivots, or
    /// why it failed (a zero pivot's component in the matrix's numbering).
    pub(crate) fn factorise(&mut self, a: &[f64], ldlt: bool) -> Result<usize, NumericFailure> {
        self.ldlt = ldlt;
        let [h1, h2] = &mut self.halves;
        let (r1, r2) = rayon::join(|| h1.factorise(a, ldlt), || h2.factorise(a, ldlt));
        let negative = r1? + r2?;
        let s = self.separator.len();
        let (g1, g2) = (&self.halves[0].gram, &self.halves[1].gram);
        for j in 0..s {
            for i in j..s {
                self.schur[(i, j)] = g1[(i, j)] + g2[(i, j)];
            }
        }
        for &(i, j, p) in &self.separator_entries {
            self.schur[(i, j)] -= a[p];
        }
        let stack = MemStack::new(&mut self.stack);
        if !ldlt {
            return llt::factor::cholesky_in_place(
                self.schur.as_mut(),
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map(|_| 0)
            .map_err(|_| NumericFailure::NotPositiveDefinite);
        }
        ldlt::factor::cholesky_in_place(
            self.schur.as_mut(),
            LdltRegularization::default(),
            Par::Seq,
            stack,
            Default::default(),
        )
        .map_err(|LdltError::ZeroPivot { index }| {
            NumericFailure::ZeroPivot(self.separator[index])
        })?;
        Ok(negative + (0..s).filter(|&k| self.schur[(k, k)] < 0.0).count())
    }

    /// v ← A⁻¹·v with the last factorisation (which succeeded).
    pub(crate) fn solve_in_place(&mut self, v: &mut [f64]) {
        let [h1, h2] = &mut self.halves;
        let ldlt = self.ldlt;
        rayon::join(|| h1.forward(v, true, ldlt), || h2.forward(v, false, ldlt));
        let [h1, h2] = &self.halves;
        for (k, r) in self.rhs.iter_mut().enumerate() {
            *r = h1.x[h1.own + k] + h2.x[h2.own + k];
        }
        let s = self.rhs.len();
        let l = self.schur.as_ref();
        let mut rhs = MatMut::from_column_major_slice_mut(&mut self.rhs, s, 1);
        if self.ldlt {
            solve_unit_lower_triangular_in_place(l, rhs.rb_mut(), Par::Seq);
            for k in 0..s {
                rhs[(k, 0)] /= l[(k, k)];
            }
            solve_unit_upper_triangular_in_place(l.transpose(), rhs.rb_mut(), Par::Seq);
        } else {
            solve_lower_triangular_in_place(l, rhs.rb_mut(), Par::Seq);
            solve_upper_triangular_in_place(l.transpose(), rhs.rb_mut(), Par::Seq);
        }
        let [h1, h2] = &mut self.halves;
        let (rhs, ldlt) = (&self.rhs, self.ldlt);
        rayon::join(|| h1.backward(rhs, ldlt), || h2.backward(rhs, ldlt));
        for h in &self.halves {
            for (&c, &x) in h.components[..h.own].iter().zip(&h.x) {
                v[c] = x;
            }
        }
        for (&c, &x) in self.separator.iter().zip(&self.rhs) {
            v[c] = x;
        }
    }
}

/// `cut`'s mark of a separator node.
const SEPARATOR: u8 = 2;

/// Each node's half (0 or 1) or [`SEPARATOR`]: the breadth-first level of
/// a pseudo-peripheral start that splits the rest most evenly. Nodes the
/// search does not reach (another connected part) join the second half.
fn cut(upper: SymbolicSparseColMatRef<'_, usize>) -> Option<Vec<u8>> {
    let nodes = upper.ncols() / 3;
    let (ptr, rows) = (upper.col_ptr(), upper.row_idx());
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); nodes];
    for j in 0..upper.ncols() {
        for &i in &rows[ptr[j]..ptr[j + 1]] {
            let (a, b) = (i / 3, j / 3);
            if a != b {
                neighbours[a].push(b as u32);
                neighbours[b].push(a as u32);
            }
        }
    }
    for n in &mut neighbours {
        n.sort_unstable();
        n.dedup();
    }
    let levels = |start: usize| {
        let mut level = vec![u32::MAX; nodes];
        let mut queue = vec![start];
        level[start] = 0;
        let mut head = 0;
        while head < queue.len() {
            let a = queue[head];
            head += 1;
            for &b in &neighbours[a] {
                if level[b as usize] == u32::MAX {
                    level[b as usize] = level[a] + 1;
                    queue.push(b as usize);
                }
            }
        }
        (level, queue)
    };
    // Two sweeps: the last node reached from node 0 starts the levels.
    let (_, order) = levels(0);
    let (level, _) = levels(*order.last()?);
    let deepest = level.iter().filter(|&&l| l != u32::MAX).max().copied()? as usize;
    let mut count = vec![0usize; deepest + 1];
    for &l in &level {
        if l != u32::MAX {
            count[l as usize] += 1;
        }
    }
    let mut best: Option<(usize, usize)> = None;
    let mut before = 0;
    for (k, &c) in count.iter().enumerate() {
        let after = nodes - before - c;
        let imbalance = before.abs_diff(after);
        if k > 0 && after > 0 && best.is_none_or(|(_, b)| imbalance < b) {
            best = Some((k, imbalance));
        }
        before += c;
    }
    let (k, _) = best?;
    let separator = count[k];
    let first: usize = count[..k].iter().sum();
    let second = nodes - first - separator;
    let most =
        (MAX_SEPARATOR_SHARE * nodes as f64).min(MAX_SEPARATOR_ROOTS * (nodes as f64).sqrt());
    if separator as f64 > most || first.min(second) < nodes / 4 {
        return None;
    }
    Some(
        level
            .iter()
            .map(|&l| match l as usize {
                l if l < k => 0,
                l if l == k => SEPARATOR,
                _ => 1,
            })
            .collect(),
    )
}

impl Half {
    fn new(
        upper: SymbolicSparseColMatRef<'_, usize>,
        place: &impl Fn(usize) -> usize,
        rank: &[usize],
        side: &[u8],
        half: u8,
        separator: &[usize],
    ) -> Option<Self> {
        let n = upper.ncols();
        let (ptr, rows) = (upper.col_ptr(), upper.row_idx());
        let mut components: Vec<usize> = (0..n).filter(|&c| side[c / 3] == half).collect();
        let own = components.len();
        components.sort_unstable_by_key(|&c| rank[c]);
        components.extend(separator.iter().copied());
        let mut local = vec![usize::MAX; n];
        for (k, &c) in components.iter().enumerate() {
            local[c] = k;
        }
        let inside = |i: usize| side[i / 3] == half || side[i / 3] == SEPARATOR;
        // B_h's upper triangle in that order, each entry's place in A.
        let mut entries = Vec::new();
        let mut in_a = Vec::new();
        for j in 0..n {
            for (k, &i) in rows[ptr[j]..ptr[j + 1]].iter().enumerate() {
                if inside(i) && inside(j) {
                    entries.push((local[i].min(local[j]), local[i].max(local[j])));
                    in_a.push(place(ptr[j] + k));
                }
            }
        }
        let m = components.len();
        let (b, at) = pattern(m, entries.into_iter());
        let factor = FactorOrder::in_order(b.as_ref(), (0..m).collect(), true).ok()?;
        let from_a = at.iter().map(|&k| factor.place(k)).zip(in_a).collect();
        let symbolic = supernodal(&factor)?;
        let most_below = (0..symbolic.n_supernodes())
            .map(|s| {
                let (b, e) = (symbolic.supernode_begin()[s], symbolic.supernode_end()[s]);
                let pattern = symbolic.col_ptr_for_row_idx();
                e - b + pattern[s + 1] - pattern[s]
            })
            .max()
            .unwrap_or(0);
        let f = factor.symbolic();
        let stack = MemBuffer::new(StackReq::any_of(&[
            f.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            f.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
        ]));
        let s = separator.len();
        Some(Self {
            own,
            components,
            values: vec![0.0; factor.len()],
            factor_values: vec![0.0; f.len_val()],
            factor,
            from_a,
            stack,
            m: Mat::zeros(s, s),
            scaled: Mat::zeros(s, s),
            pivots: vec![0.0; own],
            gram: Mat::zeros(s, s),
            x: vec![0.0; m],
            below: vec![0.0; most_below],
        })
    }

    /// B_h's Cholesky (LDLᵀ where `ldlt`) from A's values `a`, and
    /// M_hM_hᵀ (M_hD_sM_hᵀ); the negative pivots of the own columns.
    fn factorise(&mut self, a: &[f64], ldlt: bool) -> Result<usize, NumericFailure> {
        for &(b, p) in &self.from_a {
            self.values[b] = a[p];
        }
        let factor = &self.factor;
        factor
            .factorise(&self.values, &mut self.factor_values, ldlt, &mut self.stack)
            .map_err(|failure| match failure {
                NumericFailure::ZeroPivot(p) => NumericFailure::ZeroPivot(self.components[p]),
                other => other,
            })?;
        let own = self.own;
        let symbolic = supernodal(factor).expect("checked when made");
        let llt = SupernodalLltRef::new(symbolic, &self.factor_values);
        // M_h's entries outside the factor's pattern stay zero from `new`:
        // every factorisation writes the same places.
        for s in 0..symbolic.n_supernodes() {
            let node = llt.supernode(s);
            let (begin, l) = (node.start(), node.val());
            let width = l.ncols();
            for j in 0..width.min(own.saturating_sub(begin)) {
                self.pivots[begin + j] = l[(j, j)];
            }
            if begin + width <= own {
                continue;
            }
            for j in own.saturating_sub(begin)..width {
                let c = begin + j - own;
                for i in j..width {
                    self.m[(begin + i - own, c)] = l[(i, j)];
                }
                for (p, &r) in node.pattern().iter().enumerate() {
                    self.m[(r - own, c)] = l[(width + p, j)];
                }
            }
        }
        let mut negative = 0;
        let lhs = if ldlt {
            negative = self.pivots.iter().filter(|&&d| d < 0.0).count();
            let s = self.m.ncols();
            for j in 0..s {
                let d = std::mem::replace(&mut self.m[(j, j)], 1.0);
                for i in j..s {
                    self.scaled[(i, j)] = self.m[(i, j)] * d;
                }
            }
            self.scaled.as_ref()
        } else {
            self.m.as_ref()
        };
        triangular::matmul(
            self.gram.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            lhs,
            BlockStructure::TriangularLower,
            self.m.transpose(),
            BlockStructure::TriangularUpper,
            1.0,
            Par::Seq,
        );
        Ok(negative)
    }

    /// The forward sweep over the half's own columns of `v` (A's order),
    /// with the separator's part of `v` where `with_separator` (one half
    /// takes it), else zero: leaves L_hh⁻¹·v_h in the own part of `x` and
    /// that part's update to the separator in the rest.
    fn forward(&mut self, v: &[f64], with_separator: bool, ldlt: bool) {
        for (x, &c) in self.x.iter_mut().zip(&self.components) {
            *x = v[c];
        }
        let own = self.own;
        if !with_separator {
            self.x[own..].fill(0.0);
        }
        let symbolic = supernodal(&self.factor).expect("checked when made");
        let llt = SupernodalLltRef::new(symbolic, &self.factor_values);
        for s in 0..symbolic.n_supernodes() {
            let node = llt.supernode(s);
            let (begin, l) = (node.start(), node.val());
            if begin >= own {
                break;
            }
            let (width, k) = (l.ncols(), l.ncols().min(own - begin));
            let (done, rest) = self.x.split_at_mut(begin + k);
            let mut top = MatMut::from_column_major_slice_mut(&mut done[begin..], k, 1);
            if ldlt {
                solve_unit_lower_triangular_in_place(
                    l.submatrix(0, 0, k, k),
                    top.rb_mut(),
                    Par::Seq,
                );
            } else {
                solve_lower_triangular_in_place(l.submatrix(0, 0, k, k), top.rb_mut(), Par::Seq);
            }
            let rows = l.nrows() - k;
            if rows == 0 {
                continue;
            }
            let below = &mut self.below[..rows];
            matmul(
                MatMut::from_column_major_slice_mut(below, rows, 1),
                Accum::Replace,
                l.submatrix(k, 0, rows, k),
                top.rb(),
                1.0,
                Par::Seq,
            );
            let off = begin + k;
            for (b, r) in below
                .iter()
                .zip((off..begin + width).chain(node.pattern().iter().copied()))
            {
                rest[r - off] -= b;
            }
        }
    }

    /// The backward sweep over the half's own columns (after LDLᵀ's
    /// division by the pivots where `ldlt`), the separator's answer `xs`
    /// given.
    fn backward(&mut self, xs: &[f64], ldlt: bool) {
        let own = self.own;
        self.x[own..].copy_from_slice(xs);
        if ldlt {
            for (x, d) in self.x.iter_mut().zip(&self.pivots) {
                *x /= d;
            }
        }
        let symbolic = supernodal(&self.factor).expect("checked when made");
        let llt = SupernodalLltRef::new(symbolic, &self.factor_values);
        for s in (0..symbolic.n_supernodes()).rev() {
            let node = llt.supernode(s);
            let (begin, l) = (node.start(), node.val());
            if begin >= own {
                continue;
            }
            let (width, k) = (l.ncols(), l.ncols().min(own - begin));
            let (done, rest) = self.x.split_at_mut(begin + k);
            let mut top = MatMut::from_column_major_slice_mut(&mut done[begin..], k, 1);
            let rows = l.nrows() - k;
            if rows > 0 {
                let off = begin + k;
                let below = &mut self.below[..rows];
                for (b, r) in below
                    .iter_mut()
                    .zip((off..begin + width).chain(node.pattern().iter().copied()))
                {
                    *b = rest[r - off];
                }
                matmul(
                    top.rb_mut(),
                    Accum::Add,
                    l.submatrix(k, 0, rows, k).transpose(),
                    MatRef::from_column_major_slice(below, rows, 1),
                    -1.0,
                    Par::Seq,
                );
            }
            let diagonal = l.submatrix(0, 0, k, k).transpose();
            if ldlt {
                solve_unit_upper_triangular_in_place(diagonal, top.rb_mut(), Par::Seq);
            } else {
                solve_upper_triangular_in_place(diagonal, top.rb_mut(), Par::Seq);
            }
        }
    }
}

/// The supernodal analysis of a factor (faer takes a simplicial one for
/// small or very sparse matrices: those are not split).
fn supernodal(factor: &FactorOrder) -> Option<&SymbolicSupernodalCholesky<usize>> {
    match factor.symbolic().raw() {
        SymbolicCholeskyRaw::Supernodal(s) => Some(s),
        SymbolicCholeskyRaw::Simplicial(_) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tangent::add_symmetric_product;
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

    /// A grid of `side` × `side` nodes, each coupled to its eight
    /// neighbours and to the nodes two away along the rows and columns (as
    /// yarn bending couples them): the upper pattern over 3 components a
    /// node, and values of a sum of positive semi-definite couplings plus
    /// `mass` on the diagonal.
    fn grid(side: usize, mass: f64) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
        let node = |x: usize, y: usize| y * side + x;
        let mut pairs = Vec::new();
        for y in 0..side {
            for x in 0..side {
                for (dx, dy) in [(1, 0), (0, 1), (1, 1), (2, 0), (0, 2)] {
                    if x + dx < side && y + dy < side {
                        pairs.push((node(x, y), node(x + dx, y + dy)));
                    }
                }
                if x >= 1 && y + 1 < side {
                    pairs.push((node(x, y), node(x - 1, y + 1)));
                }
            }
        }
        let g = [[2.0, 0.3, 0.1], [0.3, 1.5, 0.2], [0.1, 0.2, 1.0]];
        let mut entries = std::collections::BTreeMap::new();
        let mut add = |i: usize, j: usize, v: f64| {
            *entries.entry((i.min(j), i.max(j))).or_insert(0.0) += v;
        };
        for a in 0..side * side {
            for p in 0..3 {
                add(3 * a + p, 3 * a + p, mass);
            }
        }
        for (k, &(a, b)) in pairs.iter().enumerate() {
            let w = 1.0 + (k % 7) as f64;
            for (p, row) in g.iter().enumerate() {
                for (q, &gpq) in row.iter().enumerate() {
                    let v = w * gpq;
                    if p <= q {
                        add(3 * a + p, 3 * a + q, v);
                    }
                    if p <= q {
                        add(3 * b + p, 3 * b + q, v);
                    }
                    add(3 * a + p, 3 * b + q, -v);
                }
            }
        }
        let n = 3 * side * side;
        let (upper, place) = pattern(n, entries.keys().copied());
        let mut values = vec![0.0; place.len()];
        for (&k, v) in place.iter().zip(entries.values()) {
            values[k] = *v;
        }
        (upper, values)
    }

    /// The cut leaves no entry between the halves and a separator of about
    /// two grid lines (bending's reach), near the middle.
    #[test]
    fn the_cut_separates_the_halves() {
        let side = 30;
        let (upper, _) = grid(side, 1.0);
        let mark = cut(upper.as_ref()).expect("a grid is cut");
        let (ptr, rows) = (upper.col_ptr(), upper.row_idx());
        for j in 0..upper.ncols() {
            for &i in &rows[ptr[j]..ptr[j + 1]] {
                let (a, b) = (mark[i / 3], mark[j / 3]);
                assert!(a == b || a == SEPARATOR || b == SEPARATOR, "{i} – {j}");
            }
        }
        let count = |m: u8| mark.iter().filter(|&&x| x == m).count();
        let (first, second, separator) = (count(0), count(1), count(SEPARATOR));
        assert!(separator <= 3 * side, "{separator} separator nodes");
        assert!(
            first.abs_diff(second) <= 2 * side,
            "{first} against {second}"
        );
    }

    /// x = A⁻¹·b by the split factor (LDLᵀ where `ldlt`) and the relative
    /// residual of that answer, and the negative pivots counted.
    fn solve(
        split: &mut SplitCholesky,
        upper: &SymbolicSparseColMat<usize>,
        values: &[f64],
        ldlt: bool,
    ) -> (Vec<f64>, f64, usize) {
        let negative = split.factorise(values, ldlt).expect("factorised");
        let n = upper.ncols();
        let b: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let mut x = b.clone();
        split.solve_in_place(&mut x);
        let mut r = b.clone();
        add_symmetric_product(
            SparseColMatRef::new(upper.as_ref(), values),
            &x,
            &mut r,
            -1.0,
        );
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        (x, norm(&r) / norm(&b), negative)
    }

    /// The split Cholesky's solve is A's: the residual of the answer is at
    /// round-off, the same bits when repeated; an indefinite matrix is
    /// refused.
    #[test]
    fn the_split_cholesky_solves_the_matrix() {
        let (upper, values) = grid(30, 0.5);
        let n = upper.ncols();
        let mut split = new(&upper);
        assert!(split.separator_len() < n / 8);
        let (x, residual, negative) = solve(&mut split, &upper, &values, false);
        assert!(residual <= 1e-13, "{residual:e}");
        assert_eq!(negative, 0);
        assert_eq!(solve(&mut split, &upper, &values, false).0, x);
        let (_, indefinite) = grid(30, -0.37);
        assert_eq!(
            split.factorise(&indefinite, false),
            Err(NumericFailure::NotPositiveDefinite)
        );
    }

    /// The split LDLᵀ solves an indefinite matrix and counts its negative
    /// pivots as the whole matrix's LDLᵀ does (Sylvester's law of inertia:
    /// any order of elimination gives the same count).
    #[test]
    fn the_split_ldlt_solves_an_indefinite_matrix_and_counts_its_inertia() {
        use faer::Side;
        use faer::sparse::linalg::cholesky::{
            CholeskySymbolicParams, SymmetricOrdering, factorize_symbolic_cholesky,
        };
        let (upper, values) = grid(30, -0.37);
        let mut split = new(&upper);
        let (_, residual, negative) = solve(&mut split, &upper, &values, true);
        assert!(residual <= 1e-11, "{residual:e}");
        let whole = factorize_symbolic_cholesky(
            upper.as_ref(),
            Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .expect("analysed");
        let mut factor = vec![0.0; whole.len_val()];
        let mut stack = MemBuffer::new(
            whole.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
        );
        whole
            .factorize_numeric_ldlt(
                &mut factor,
                SparseColMatRef::new(upper.as_ref(), &values),
                Side::Upper,
                LdltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut stack),
                Default::default(),
            )
            .expect("no zero pivot");
        let expected = match whole.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => (0..s.n_supernodes())
                .map(|k| {
                    let node = SupernodalLltRef::new(s, &factor).supernode(k);
                    let l = node.val();
                    (0..l.ncols()).filter(|&j| l[(j, j)] < 0.0).count()
                })
                .sum::<usize>(),
            SymbolicCholeskyRaw::Simplicial(_) => unreachable!("a grid this size is supernodal"),
        };
        assert!(negative > 0);
        assert_eq!(negative, expected);
        // The positive definite matrix by LDLᵀ: no negative pivot, the
        // Cholesky's answer to round-off.
        let (_, positive) = grid(30, 0.5);
        let (x, residual, negative) = solve(&mut split, &upper, &positive, true);
        assert!(residual <= 1e-13, "{residual:e}");
        assert_eq!(negative, 0);
        let (y, _, _) = solve(&mut split, &upper, &positive, false);
        for (a, b) in x.iter().zip(&y) {
            assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{a} against {b}");
        }
    }

    fn new(upper: &SymbolicSparseColMat<usize>) -> SplitCholesky {
        let rank: Vec<usize> = (0..upper.ncols()).collect();
        SplitCholesky::new(upper.as_ref(), |k| k, &rank).expect("split")
    }

    /// The answer does not depend on the thread count.
    #[test]
    fn the_split_solve_is_the_same_on_one_thread() {
        let (upper, values) = grid(30, 0.5);
        let (_, indefinite) = grid(30, -0.37);
        let run = |threads: usize, values: &[f64], ldlt: bool| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| solve(&mut new(&upper), &upper, values, ldlt).0)
        };
        assert_eq!(run(1, &values, false), run(2, &values, false));
        assert_eq!(run(1, &indefinite, true), run(2, &indefinite, true));
    }
}
