//! A dense LU linear solver for CVODES's Newton systems, in Rust.
//!
//! CVODES's staggered corrector solves the Newton system once per sensitivity column
//! and iteration: about 19,000 solves of a 30 × 30 system in one 40 ms interval of the
//! gait model with 55 columns. SUNDIALS's own dense solver (`SUNDlsMat_denseGETRS`)
//! spent a third of the interval's time there; this one factors with partial pivoting
//! into one contiguous column-major block and substitutes over contiguous columns.
#![allow(unsafe_code)]

use std::ffi::c_int;
use sundials_sys as sys;

/// Factors of the last setup.
struct Content {
    n: usize,
    /// L (unit lower, below the diagonal) and U, column-major.
    lu: Vec<f64>,
    /// Row exchanged with row k at step k.
    pivots: Vec<usize>,
    /// 0, or the 1-based column of a zero pivot found by the last setup.
    last_flag: i64,
}

/// A new solver for `n × n` dense matrices; null if SUNDIALS cannot allocate it.
///
/// # Safety
/// `ctx` is a live SUNDIALS context.
pub(super) unsafe fn new(n: usize, ctx: sys::SUNContext) -> sys::SUNLinearSolver {
    // SAFETY: `ctx` is live (caller); the returned solver has allocated, zeroed ops.
    let s = unsafe { sys::SUNLinSolNewEmpty(ctx) };
    if s.is_null() {
        return s;
    }
    let content = Box::new(Content {
        n,
        lu: vec![0.0; n * n],
        pivots: vec![0; n],
        last_flag: 0,
    });
    // SAFETY: `s` and its ops were just allocated by SUNDIALS and are ours to fill.
    unsafe {
        (*s).content = Box::into_raw(content).cast();
        let ops = &mut *(*s).ops;
        ops.gettype = Some(get_type);
        ops.setup = Some(setup);
        ops.solve = Some(solve);
        ops.lastflag = Some(last_flag);
        ops.free = Some(free);
    }
    s
}

/// # Safety
/// `s` was made by [`new`] and not freed.
unsafe fn content<'a>(s: sys::SUNLinearSolver) -> &'a mut Content {
    // SAFETY: `content` holds the boxed `Content` of `new` until `free`.
    unsafe { &mut *(*s).content.cast::<Content>() }
}

unsafe extern "C" fn get_type(_s: sys::SUNLinearSolver) -> sys::SUNLinearSolver_Type {
    sys::SUNLinearSolver_Type_SUNLINEARSOLVER_DIRECT
}

unsafe extern "C" fn last_flag(s: sys::SUNLinearSolver) -> sys::sunindextype {
    // SAFETY: CVODES passes the solver it was given.
    unsafe { content(s).last_flag as sys::sunindextype }
}

/// LU with partial pivoting of the dense matrix `a`; a zero pivot is a recoverable
/// failure (CVODES retries with a smaller step), as in SUNDIALS's dense solver.
unsafe extern "C" fn setup(s: sys::SUNLinearSolver, a: sys::SUNMatrix) -> c_int {
    // SAFETY: CVODES passes our solver and the n × n dense matrix it was built with,
    // stored column-major in one contiguous block.
    let (c, data) = unsafe {
        let c = content(s);
        let n = c.n;
        (
            c,
            std::slice::from_raw_parts(sys::SUNDenseMatrix_Data(a), n * n),
        )
    };
    c.lu.copy_from_slice(data);
    c.last_flag = factor(c.n, &mut c.lu, &mut c.pivots);
    if c.last_flag == 0 {
        0
    } else {
        sys::SUNLS_LUFACT_FAIL as c_int
    }
}

/// x = A⁻¹ b from the factors of the last setup.
unsafe extern "C" fn solve(
    s: sys::SUNLinearSolver,
    _a: sys::SUNMatrix,
    x: sys::N_Vector,
    b: sys::N_Vector,
    _tol: f64,
) -> c_int {
    // SAFETY: our solver; `x` and `b` are serial vectors of length n (possibly the
    // same vector), read before `x` is written.
    unsafe {
        let c = content(s);
        let n = c.n;
        let bp = sys::N_VGetArrayPointer(b);
        let xp = sys::N_VGetArrayPointer(x);
        if bp != xp {
            std::ptr::copy_nonoverlapping(bp, xp, n);
        }
        substitute(n, &c.lu, &c.pivots, std::slice::from_raw_parts_mut(xp, n));
    }
    0
}

unsafe extern "C" fn free(s: sys::SUNLinearSolver) -> c_int {
    if s.is_null() {
        return 0;
    }
    // SAFETY: `content` is the box of `new` (or null after a previous free); the rest
    // is freed by SUNDIALS's own routine for a solver made by SUNLinSolNewEmpty.
    unsafe {
        let c = (*s).content.cast::<Content>();
        if !c.is_null() {
            drop(Box::from_raw(c));
            (*s).content = std::ptr::null_mut();
        }
        sys::SUNLinSolFreeEmpty(s);
    }
    0
}

/// In-place LU with partial pivoting of the column-major `n × n` matrix `a`
/// (`PA = LU`, L unit lower); 0, or the 1-based column of a zero pivot.
pub(super) fn factor(n: usize, a: &mut [f64], pivots: &mut [usize]) -> i64 {
    for k in 0..n {
        let col = &a[k * n..(k + 1) * n];
        let mut p = k;
        for i in k + 1..n {
            if col[i].abs() > col[p].abs() {
                p = i;
            }
        }
        pivots[k] = p;
        if a[k * n + p] == 0.0 {
            return k as i64 + 1;
        }
        if p != k {
            for j in 0..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        let inv = 1.0 / a[k * n + k];
        for v in &mut a[k * n + k + 1..(k + 1) * n] {
            *v *= inv;
        }
        let (left, right) = a.split_at_mut((k + 1) * n);
        let lk = &left[k * n + k + 1..(k + 1) * n];
        for j in 0..n - k - 1 {
            let colj = &mut right[j * n..(j + 1) * n];
            let akj = colj[k];
            if akj != 0.0 {
                for (v, l) in colj[k + 1..].iter_mut().zip(lk) {
                    *v -= l * akj;
                }
            }
        }
    }
    0
}

/// Solve `LU x = P b` in place (`x` holds b on entry).
pub(super) fn substitute(n: usize, lu: &[f64], pivots: &[usize], x: &mut [f64]) {
    for k in 0..n {
        x.swap(k, pivots[k]);
    }
    for k in 0..n {
        let xk = x[k];
        if xk != 0.0 {
            for (v, l) in x[k + 1..].iter_mut().zip(&lu[k * n + k + 1..(k + 1) * n]) {
                *v -= l * xk;
            }
        }
    }
    for k in (0..n).rev() {
        x[k] /= lu[k * n + k];
        let xk = x[k];
        for (v, u) in x[..k].iter_mut().zip(&lu[k * n..k * n + k]) {
            *v -= u * xk;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{factor, substitute};

    /// The LU solve against nalgebra's on matrices that need pivoting, and a singular
    /// matrix reported by the column of its zero pivot.
    #[test]
    fn dense_lu_solves_like_nalgebra_and_reports_a_zero_pivot() {
        let n = 30;
        let mut seed = 12345u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for trial in 0..5 {
            // small diagonal: every column needs a row exchange somewhere
            let a =
                nalgebra::DMatrix::from_fn(
                    n,
                    n,
                    |i, j| if i == j { 1e-3 * trial as f64 } else { rand() },
                );
            let b = nalgebra::DVector::from_fn(n, |_, _| rand());
            let mut lu: Vec<f64> = a.as_slice().to_vec();
            let mut piv = vec![0; n];
            assert_eq!(factor(n, &mut lu, &mut piv), 0);
            let mut x = b.as_slice().to_vec();
            substitute(n, &lu, &piv, &mut x);
            let want = a.clone().lu().solve(&b).unwrap();
            let err = (nalgebra::DVector::from_vec(x) - &want).amax() / want.amax();
            assert!(err < 1e-12, "trial {trial}: relative error {err}");
        }
        // column 3 a combination of columns 0 and 1: the third pivot is zero
        let mut a = nalgebra::DMatrix::<f64>::identity(4, 4);
        a[(0, 2)] = 1.0;
        a[(1, 2)] = 2.0;
        a[(2, 2)] = 0.0;
        let mut lu = a.as_slice().to_vec();
        assert_eq!(factor(4, &mut lu, &mut [0; 4]), 3);
    }
}
