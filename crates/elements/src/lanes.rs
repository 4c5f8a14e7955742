//! Four `f64` lanes for the element kernels that run a block of elements
//! at a time ([`crate::quad_lanes`], [`crate::truss_lanes`]).
//!
//! What it is for: writing a kernel once, lane-wise, so that each lane
//! does exactly the scalar path's operations in the scalar path's order
//! (results equal bit for bit). What it is not: a SIMD library. The lanes
//! are a plain `[f64; 4]` with element-wise operators that the compiler
//! turns into vector instructions; a kernel is compiled twice, for the
//! target's baseline (two SSE2 operations per lane operation on x86-64)
//! and with AVX2 (one), and picked at run time. Neither build contracts a
//! multiply and an add into an FMA, so both give the same bits. Everything
//! here is `#[inline(always)]` and written lane by lane rather than with
//! `array::map` or iterator folds: those are generic helpers compiled
//! without the kernel's target features, which LLVM then does not inline
//! into it (a call per lane).

use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub};

/// Elements per block.
pub(crate) const LANES: usize = 4;

/// Four f64 lanes.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
#[allow(non_camel_case_types)]
pub(crate) struct f64x4(pub(crate) [f64; 4]);

macro_rules! lane_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for f64x4 {
            type Output = f64x4;
            #[inline(always)]
            fn $method(self, rhs: f64x4) -> f64x4 {
                f64x4([
                    self.0[0] $op rhs.0[0],
                    self.0[1] $op rhs.0[1],
                    self.0[2] $op rhs.0[2],
                    self.0[3] $op rhs.0[3],
                ])
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl AddAssign for f64x4 {
    #[inline(always)]
    fn add_assign(&mut self, rhs: f64x4) {
        *self = *self + rhs;
    }
}

impl f64x4 {
    #[inline(always)]
    pub(crate) fn new(v: [f64; 4]) -> Self {
        Self(v)
    }

    #[inline(always)]
    pub(crate) fn splat(v: f64) -> Self {
        Self([v; 4])
    }

    #[inline(always)]
    pub(crate) fn sqrt(self) -> Self {
        let v = self.0;
        Self([v[0].sqrt(), v[1].sqrt(), v[2].sqrt(), v[3].sqrt()])
    }

    /// Lane by lane, |v|.
    #[inline(always)]
    pub(crate) fn abs(self) -> Self {
        let v = self.0;
        Self([v[0].abs(), v[1].abs(), v[2].abs(), v[3].abs()])
    }

    /// Lane by lane, `f64::max` (a NaN lane takes the other's value).
    #[inline(always)]
    pub(crate) fn max(self, rhs: f64x4) -> Self {
        let (v, w) = (self.0, rhs.0);
        Self([
            v[0].max(w[0]),
            v[1].max(w[1]),
            v[2].max(w[2]),
            v[3].max(w[3]),
        ])
    }

    /// Whether every lane is finite.
    #[inline(always)]
    pub(crate) fn all_finite(self) -> bool {
        let v = self.0;
        v[0].is_finite() & v[1].is_finite() & v[2].is_finite() & v[3].is_finite()
    }

    /// Whether every lane is above `rhs`'s (false for a NaN).
    #[inline(always)]
    pub(crate) fn all_gt(self, rhs: f64x4) -> bool {
        let (v, w) = (self.0, rhs.0);
        (v[0] > w[0]) & (v[1] > w[1]) & (v[2] > w[2]) & (v[3] > w[3])
    }
}

impl Neg for f64x4 {
    type Output = f64x4;
    #[inline(always)]
    fn neg(self) -> f64x4 {
        let v = self.0;
        f64x4([-v[0], -v[1], -v[2], -v[3]])
    }
}

impl f64x4 {
    /// Lane k of `a` where `mask[k]`, else of `b`.
    #[inline(always)]
    pub(crate) fn select(mask: [bool; 4], a: f64x4, b: f64x4) -> f64x4 {
        let (a, b) = (a.0, b.0);
        f64x4([
            if mask[0] { a[0] } else { b[0] },
            if mask[1] { a[1] } else { b[1] },
            if mask[2] { a[2] } else { b[2] },
            if mask[3] { a[3] } else { b[3] },
        ])
    }

    /// Lane by lane, whether it is at most `rhs`'s.
    #[inline(always)]
    pub(crate) fn le(self, rhs: f64x4) -> [bool; 4] {
        let (v, w) = (self.0, rhs.0);
        [v[0] <= w[0], v[1] <= w[1], v[2] <= w[2], v[3] <= w[3]]
    }

    /// Lane by lane, whether it is below `rhs`'s.
    #[inline(always)]
    pub(crate) fn lt(self, rhs: f64x4) -> [bool; 4] {
        let (v, w) = (self.0, rhs.0);
        [v[0] < w[0], v[1] < w[1], v[2] < w[2], v[3] < w[3]]
    }
}
