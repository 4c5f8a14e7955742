//! A symmetric sparse matrix laid out in the order its Cholesky factor is
//! taken in, for the implicit driver's factorisations ([`crate::tangent`]'s
//! K̂ and [`crate::saddle`]'s A).
//!
//! faer's numeric factorisation of a matrix analysed with a fill-reducing
//! ordering first copies the matrix into that order, at every
//! factorisation (3.4 % of an implicit deep drawing's CPU, on the serial
//! path). Here the ordering (faer's AMD) is taken once, the matrix's
//! pattern is built in that order and analysed with no ordering of its
//! own, and the values are written to their places directly: the same
//! factor, the same bits, without the copy. The solves put the right-hand
//! side into that order and back.
//!
//! Not here: assembling the values or choosing between Cholesky and LDLᵀ.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// A pattern in its factor's order, with that order's symbolic
/// factorisation.
#[derive(Debug)]
pub(crate) struct FactorOrder {
    /// The component at each place of the factor's order.
    order: Vec<usize>,
    /// Where each entry of the upper-triangle pattern it was made from lies
    /// in `lower`'s values.
    to_factor: Vec<usize>,
    /// The lower triangle in the factor's order (faer's supernodal
    /// factorisation reads that one without a copy).
    lower: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    /// A right-hand side in the factor's order.
    ordered: Vec<f64>,
}

impl FactorOrder {
    /// faer's AMD ordering of the symmetric pattern `upper` (its upper
    /// triangle), and that pattern in the order, analysed.
    pub(crate) fn analyse(
        upper: SymbolicSparseColMatRef<'_, usize>,
    ) -> Result<Self, faer::sparse::FaerError> {
        Self::in_order(upper, amd(upper)?, false)
    }

    /// The symmetric pattern `upper` (its upper triangle) in `order` (the
    /// component at each place), analysed; `supernodal` forces faer's
    /// supernodal layout (it takes a simplicial one for small or very
    /// sparse factors).
    pub(crate) fn in_order(
        upper: SymbolicSparseColMatRef<'_, usize>,
        order: Vec<usize>,
        supernodal: bool,
    ) -> Result<Self, faer::sparse::FaerError> {
        let n = upper.ncols();
        let params = || CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: if supernodal {
                SupernodalThreshold::FORCE_SUPERNODAL
            } else {
                SupernodalThreshold::AUTO
            },
            ..Default::default()
        };
        let mut place = vec![0; n];
        for (new, &old) in order.iter().enumerate() {
            place[old] = new;
        }
        // Entry (i, j) of the upper triangle is the entry at the places of
        // i and j: the lower triangle for the numeric factorisation, the
        // upper one for the analysis (which, without an ordering of its
        // own, reads the matrix as given).
        let (ptr, rows) = (upper.col_ptr(), upper.row_idx());
        let entries: Vec<(usize, usize)> = (0..n)
            .flat_map(|j| rows[ptr[j]..ptr[j + 1]].iter().map(move |&i| (i, j)))
            .map(|(i, j)| {
                let (a, b) = (place[i], place[j]);
                (a.max(b), a.min(b))
            })
            .collect();
        let (lower, to_factor) = pattern(n, entries.iter().copied());
        let (ordered_upper, _) = pattern(n, entries.iter().map(|&(r, c)| (c, r)));
        let symbolic = factorize_symbolic_cholesky(
            ordered_upper.as_ref(),
            Side::Upper,
            SymmetricOrdering::Identity,
            params(),
        )?;
        Ok(Self {
            order,
            to_factor,
            lower,
            symbolic,
            ordered: vec![0.0; n],
        })
    }

    /// The symbolic factorisation every numeric one reuses.
    pub(crate) fn symbolic(&self) -> &SymbolicCholesky<usize> {
        &self.symbolic
    }

    /// The number of values.
    pub(crate) fn len(&self) -> usize {
        self.to_factor.len()
    }

    /// Where entry `k` of the upper-triangle pattern lies in the values.
    pub(crate) fn place(&self, k: usize) -> usize {
        self.to_factor[k]
    }

    /// Each component's place in the factor's order.
    pub(crate) fn ranks(&self) -> Vec<usize> {
        let mut rank = vec![0; self.order.len()];
        for (p, &c) in self.order.iter().enumerate() {
            rank[c] = p;
        }
        rank
    }

    /// The component at place `p` of the factor's order (a pivot's).
    pub(crate) fn component(&self, p: usize) -> usize {
        self.order[p]
    }

    /// Writes the `upper`-triangle values to their places in `values`.
    pub(crate) fn scatter(&self, upper: &[f64], values: &mut [f64]) {
        for (&k, &v) in self.to_factor.iter().zip(upper) {
            values[k] = v;
        }
    }

    /// The matrix of `values` (its lower triangle, in the factor's order),
    /// as faer factorises it (`Side::Lower`).
    pub(crate) fn matrix<'a>(&'a self, values: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
        SparseColMatRef::new(self.lower.as_ref(), values)
    }

    /// faer's numeric Cholesky (LDLᵀ without pivoting where `ldlt`) of
    /// `values` (in this order) into `factor`.
    pub(crate) fn factorise(
        &self,
        values: &[f64],
        factor: &mut [f64],
        ldlt: bool,
        stack: &mut MemBuffer,
    ) -> Result<(), NumericFailure> {
        let (symbolic, matrix) = (&self.symbolic, self.matrix(values));
        let stack = MemStack::new(stack);
        if ldlt {
            symbolic
                .factorize_numeric_ldlt(
                    factor,
                    matrix,
                    Side::Lower,
                    LdltRegularization::default(),
                    Par::Seq,
                    stack,
                    Default::default(),
                )
                .map(|_| ())
                .map_err(|LdltError::ZeroPivot { index }| NumericFailure::ZeroPivot(index))
        } else {
            symbolic
                .factorize_numeric_llt(
                    factor,
                    matrix,
                    Side::Lower,
                    LltRegularization::default(),
                    Par::Seq,
                    stack,
                    Default::default(),
                )
                .map(|_| ())
                .map_err(|_| NumericFailure::NotPositiveDefinite)
        }
    }

    /// v ← A⁻¹·v with the `factor` [`Self::factorise`] left (LDLᵀ's where
    /// `ldlt`), in place: v put into the factor's order and back.
    pub(crate) fn solve(
        &mut self,
        v: &mut [f64],
        factor: &[f64],
        ldlt: bool,
        stack: &mut MemBuffer,
    ) {
        for (o, &k) in self.ordered.iter_mut().zip(&self.order) {
            *o = v[k];
        }
        let n = self.ordered.len();
        let rhs = MatMut::from_column_major_slice_mut(&mut self.ordered, n, 1);
        let stack = MemStack::new(stack);
        if ldlt {
            LdltRef::new(&self.symbolic, factor).solve_in_place_with_conj(
                Conj::No,
                rhs,
                Par::Seq,
                stack,
            );
        } else {
            LltRef::new(&self.symbolic, factor).solve_in_place_with_conj(
                Conj::No,
                rhs,
                Par::Seq,
                stack,
            );
        }
        for (&o, &k) in self.ordered.iter().zip(&self.order) {
            v[k] = o;
        }
    }
}

/// Why a numeric factorisation failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NumericFailure {
    /// Cholesky met a pivot that is not positive.
    NotPositiveDefinite,
    /// LDLᵀ met a zero pivot at this place of the factor's order.
    ZeroPivot(usize),
}

/// faer's AMD ordering of the symmetric pattern `upper` (its upper
/// triangle): the component at each place.
fn amd(upper: SymbolicSparseColMatRef<'_, usize>) -> Result<Vec<usize>, faer::sparse::FaerError> {
    let n = upper.ncols();
    let amd = factorize_symbolic_cholesky(
        upper,
        Side::Upper,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )?;
    Ok(amd
        .perm()
        .map_or_else(|| (0..n).collect(), |p| p.arrays().0.to_vec()))
}

/// The n × n pattern of the (row, column) `entries` (each once), its row
/// indices sorted, and each entry's place in it.
pub(crate) fn pattern(
    n: usize,
    entries: impl Iterator<Item = (usize, usize)> + Clone,
) -> (SymbolicSparseColMat<usize>, Vec<usize>) {
    let mut col_ptr = vec![0; n + 1];
    for (_, c) in entries.clone() {
        col_ptr[c + 1] += 1;
    }
    for c in 0..n {
        col_ptr[c + 1] += col_ptr[c];
    }
    let mut fill = col_ptr.clone();
    let mut row_idx = vec![0; col_ptr[n]];
    let mut place = Vec::with_capacity(col_ptr[n]);
    for (r, c) in entries.clone() {
        row_idx[fill[c]] = r;
        place.push(fill[c]);
        fill[c] += 1;
    }
    // Sorted within each column, the entries' places following.
    let mut at = vec![0; col_ptr[n]];
    for c in 0..n {
        let range = col_ptr[c]..col_ptr[c + 1];
        let mut column: Vec<(usize, usize)> = range.clone().map(|k| (row_idx[k], k)).collect();
        column.sort_unstable();
        for (k, (r, old)) in range.zip(column) {
            row_idx[k] = r;
            at[old] = k;
        }
    }
    let place = place.into_iter().map(|k| at[k]).collect();
    (
        SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
        place,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Entries in any order: columns counted, rows sorted within each,
    /// and each entry told where it went.
    #[test]
    fn a_pattern_sorts_its_rows_and_places_each_entry() {
        let entries = [(2, 0), (0, 0), (2, 2), (1, 1), (0, 2)];
        let (m, place) = pattern(3, entries.iter().copied());
        assert_eq!(m.col_ptr(), &[0, 2, 3, 5]);
        assert_eq!(m.row_idx(), &[0, 2, 1, 0, 2]);
        for (&(r, c), &k) in entries.iter().zip(&place) {
            assert_eq!(m.row_idx()[k], r);
            assert!(m.col_ptr()[c] <= k && k < m.col_ptr()[c + 1]);
        }
    }

    /// A matrix in the factor's order, solved through it, gives the
    /// solution of the matrix as it was (checked by its product).
    #[test]
    fn a_solve_in_the_factor_order_solves_the_matrix() {
        // A 6 × 6 band matrix (a chain with next-but-one couplings),
        // upper triangle by columns.
        let n: usize = 6;
        let mut col_ptr = vec![0];
        let (mut rows, mut values) = (Vec::new(), Vec::new());
        for j in 0..n {
            for i in j.saturating_sub(2)..=j {
                rows.push(i);
                values.push(if i == j {
                    4.0 + j as f64
                } else {
                    -1.0 / (1 + j - i) as f64
                });
            }
            col_ptr.push(rows.len());
        }
        let upper = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
        let mut f = FactorOrder::analyse(upper.as_ref()).expect("analysed");
        let mut ordered = vec![0.0; f.len()];
        f.scatter(&values, &mut ordered);
        let mut factor = vec![0.0; f.symbolic().len_val()];
        let mut stack = MemBuffer::new(
            f.symbolic()
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
                .or(f.symbolic().solve_in_place_scratch::<f64>(1, Par::Seq)),
        );
        f.factorise(&ordered, &mut factor, false, &mut stack)
            .expect("positive definite");
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut x = b.clone();
        f.solve(&mut x, &factor, false, &mut stack);
        let mut product = vec![0.0; n];
        let m = SparseColMatRef::new(upper.as_ref(), &values);
        for j in 0..n {
            for (k, &i) in m.row_idx()[m.col_ptr()[j]..m.col_ptr()[j + 1]]
                .iter()
                .enumerate()
            {
                let v = m.val()[m.col_ptr()[j] + k];
                product[i] += v * x[j];
                if i != j {
                    product[j] += v * x[i];
                }
            }
        }
        for (p, b) in product.iter().zip(&b) {
            assert!((p - b).abs() <= 1e-13 * b, "{p} against {b}");
        }
    }
}
