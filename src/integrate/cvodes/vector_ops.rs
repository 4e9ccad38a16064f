//! CVODES's serial vector kernels, compiled with footfall.
//!
//! Every step of CVODES with forward sensitivities is a series of vector operations on
//! the states and on each sensitivity column (linear sums, linear combinations over the
//! history array, weighted RMS norms): with 55 columns of 30 states, about a million
//! numbers per interval. Debian's `libsundials_nvecserial` (6.4.1) is compiled without
//! optimisation (each loop index is loaded from and stored to the stack), and those
//! kernels took 30 % of a diagnosis's time on a two-core machine (measured with `perf`).
//!
//! [`install`] puts these kernels into a serial vector's table of operations; CVODES
//! clones its work vectors and the sensitivity arrays from that vector, and the clones
//! copy the table. Each kernel computes what SUNDIALS's serial kernel computes, with the
//! same operations on each element in the same order (Rust never fuses a multiply and an
//! add, and each element's result depends on that element alone, so doing several
//! elements at a time changes no bit); the norms sum in SUNDIALS's order; SUNDIALS's
//! special cases of a linear sum are kept (see [`linear_sum`]). A unit test checks each
//! kernel against the library's, bit for bit.
#![allow(unsafe_code)]

use std::ffi::c_int;
use sundials_sys as sys;

/// Put this module's kernels into the table of operations of the serial vector `v`
/// (after `N_VEnableFusedOps_Serial`, whose fused and array operations they replace).
///
/// # Safety
/// `v` is a live serial vector (`N_VNew_Serial`) whose table of operations is its own.
pub(super) unsafe fn install(v: sys::N_Vector) {
    // SAFETY: `v` is live and owns its ops table (caller).
    let ops = unsafe { &mut *(*v).ops };
    ops.nvlinearsum = Some(linear_sum);
    ops.nvconst = Some(constant);
    ops.nvprod = Some(product);
    ops.nvdiv = Some(quotient);
    ops.nvscale = Some(scale);
    ops.nvabs = Some(absolute);
    ops.nvinv = Some(inverse);
    ops.nvaddconst = Some(add_constant);
    ops.nvmaxnorm = Some(max_norm);
    ops.nvwrmsnorm = Some(wrms_norm);
    ops.nvlinearcombination = Some(linear_combination);
    ops.nvscaleaddmulti = Some(scale_add_multi);
    ops.nvlinearsumvectorarray = Some(linear_sum_array);
    ops.nvscalevectorarray = Some(scale_array);
    ops.nvconstvectorarray = Some(constant_array);
    ops.nvwrmsnormvectorarray = Some(wrms_norm_array);
    ops.nvscaleaddmultivectorarray = Some(scale_add_multi_array);
    ops.nvlinearcombinationvectorarray = Some(linear_combination_array);
}

/// The data pointer and length of a serial vector.
///
/// # Safety
/// `v` is a live serial vector.
#[inline(always)]
unsafe fn parts(v: sys::N_Vector) -> (*mut f64, usize) {
    // SAFETY: a serial vector's content is `_N_VectorContent_Serial` (caller).
    unsafe {
        let c = &*(*v).content.cast::<sys::_N_VectorContent_Serial>();
        (c.data, usize::try_from(c.length).unwrap_or(0))
    }
}

/// The `n` numbers at `p` as a slice (none when `n` is 0, where `p` may be null).
///
/// # Safety
/// `p` points to `n` numbers that nothing else writes while the slice lives.
#[inline(always)]
unsafe fn numbers<'a>(p: *mut f64, n: usize) -> &'a [f64] {
    if n == 0 {
        &[]
    } else {
        // SAFETY: as documented (caller).
        unsafe { std::slice::from_raw_parts(p, n) }
    }
}

/// The `n` numbers at `p` as a mutable slice.
///
/// # Safety
/// `p` points to `n` numbers that nothing else reads or writes while the slice lives.
#[inline(always)]
unsafe fn numbers_mut<'a>(p: *mut f64, n: usize) -> &'a mut [f64] {
    if n == 0 {
        &mut []
    } else {
        // SAFETY: as documented (caller).
        unsafe { std::slice::from_raw_parts_mut(p, n) }
    }
}

/// `z[k] = f(x[k], y[k])` over the length of `z`. Any of the three may be the same
/// vector (SUNDIALS updates in place), so each case of sharing gets its own loop over
/// slices that do not overlap: loops over slices run several elements at a time, where
/// loops over raw pointers ran one at a time (with the test profile's checks of each
/// pointer's alignment).
///
/// # Safety
/// Live serial vectors of one length, each either the same vector as another or not
/// sharing its memory.
#[inline(always)]
unsafe fn zip_with(
    x: sys::N_Vector,
    y: sys::N_Vector,
    z: sys::N_Vector,
    f: impl Fn(f64, f64) -> f64,
) {
    // SAFETY: live vectors of one length (caller); the slices made in each branch do
    // not overlap.
    unsafe {
        let (zd, n) = parts(z);
        let (xd, _) = parts(x);
        let (yd, _) = parts(y);
        if zd == xd && zd == yd {
            for v in numbers_mut(zd, n) {
                *v = f(*v, *v);
            }
        } else if zd == xd {
            for (v, &b) in numbers_mut(zd, n).iter_mut().zip(numbers(yd, n)) {
                *v = f(*v, b);
            }
        } else if zd == yd {
            for (v, &a) in numbers_mut(zd, n).iter_mut().zip(numbers(xd, n)) {
                *v = f(a, *v);
            }
        } else {
            let (xs, ys) = (numbers(xd, n), numbers(yd, n));
            for ((v, &a), &b) in numbers_mut(zd, n).iter_mut().zip(xs).zip(ys) {
                *v = f(a, b);
            }
        }
    }
}

/// `z[k] = f(x[k])` over the length of `z`; `x` and `z` may be one vector.
///
/// # Safety
/// As [`zip_with`].
#[inline(always)]
unsafe fn map(x: sys::N_Vector, z: sys::N_Vector, f: impl Fn(f64) -> f64) {
    // SAFETY: as `zip_with`.
    unsafe {
        let (zd, n) = parts(z);
        let (xd, _) = parts(x);
        if zd == xd {
            for v in numbers_mut(zd, n) {
                *v = f(*v);
            }
        } else {
            for (v, &a) in numbers_mut(zd, n).iter_mut().zip(numbers(xd, n)) {
                *v = f(a);
            }
        }
    }
}

/// `z = a x + b y` as SUNDIALS's serial kernel computes it: its special cases for
/// coefficients of ±1 and for `a = ±b` differ from the general formula in a zero's sign
/// (`y - x` is +0 where `-(x - y)` is -0) or in rounding (`a (x + y)`), so they are
/// kept, in SUNDIALS's order. Its updates in place (`z` = `x` or `y`) compute the same
/// numbers as these cases.
unsafe extern "C" fn linear_sum(
    a: f64,
    x: sys::N_Vector,
    b: f64,
    y: sys::N_Vector,
    z: sys::N_Vector,
) {
    // SAFETY: CVODES passes live serial vectors of one length.
    unsafe {
        if a == 1.0 && b == 1.0 {
            zip_with(x, y, z, |x, y| x + y);
        } else if a == 1.0 && b == -1.0 {
            zip_with(x, y, z, |x, y| x - y);
        } else if a == -1.0 && b == 1.0 {
            zip_with(x, y, z, |x, y| y - x);
        } else if a == 1.0 {
            zip_with(x, y, z, |x, y| b * y + x);
        } else if b == 1.0 {
            zip_with(x, y, z, |x, y| a * x + y);
        } else if a == -1.0 {
            zip_with(x, y, z, |x, y| b * y - x);
        } else if b == -1.0 {
            zip_with(x, y, z, |x, y| a * x - y);
        } else if a == b {
            zip_with(x, y, z, |x, y| a * (x + y));
        } else if a == -b {
            zip_with(x, y, z, |x, y| a * (x - y));
        } else {
            zip_with(x, y, z, |x, y| a * x + b * y);
        }
    }
}

unsafe extern "C" fn constant(c: f64, z: sys::N_Vector) {
    // SAFETY: a live serial vector.
    unsafe {
        let (zd, n) = parts(z);
        numbers_mut(zd, n).fill(c);
    }
}

unsafe extern "C" fn product(x: sys::N_Vector, y: sys::N_Vector, z: sys::N_Vector) {
    // SAFETY: live serial vectors of one length.
    unsafe { zip_with(x, y, z, |x, y| x * y) }
}

unsafe extern "C" fn quotient(x: sys::N_Vector, y: sys::N_Vector, z: sys::N_Vector) {
    // SAFETY: live serial vectors of one length.
    unsafe { zip_with(x, y, z, |x, y| x / y) }
}

unsafe extern "C" fn scale(c: f64, x: sys::N_Vector, z: sys::N_Vector) {
    // SAFETY: live serial vectors of one length.
    unsafe { map(x, z, |x| c * x) }
}

unsafe extern "C" fn absolute(x: sys::N_Vector, z: sys::N_Vector) {
    // SAFETY: live serial vectors of one length.
    unsafe { map(x, z, f64::abs) }
}

unsafe extern "C" fn inverse(x: sys::N_Vector, z: sys::N_Vector) {
    // SAFETY: live serial vectors of one length.
    unsafe { map(x, z, |x| 1.0 / x) }
}

unsafe extern "C" fn add_constant(x: sys::N_Vector, b: f64, z: sys::N_Vector) {
    // SAFETY: live serial vectors of one length.
    unsafe { map(x, z, |x| x + b) }
}

/// The largest `|x[k]|` (0 for an empty vector; NaNs are passed over, as SUNDIALS's `>`
/// does).
unsafe extern "C" fn max_norm(x: sys::N_Vector) -> f64 {
    // SAFETY: a live serial vector.
    let xs = unsafe {
        let (xd, n) = parts(x);
        numbers(xd, n)
    };
    let mut max = 0.0;
    for v in xs {
        if v.abs() > max {
            max = v.abs();
        }
    }
    max
}

/// `√(Σ (x[k] w[k])² / n)`, summed in order; 0 when the mean square is not positive.
unsafe extern "C" fn wrms_norm(x: sys::N_Vector, w: sys::N_Vector) -> f64 {
    // SAFETY: live serial vectors of one length.
    unsafe {
        let (xd, n) = parts(x);
        let (wd, _) = parts(w);
        let mut sum = 0.0;
        for (a, b) in numbers(xd, n).iter().zip(numbers(wd, n)) {
            let p = a * b;
            sum += p * p;
        }
        let mean = sum / n as f64;
        if mean <= 0.0 {
            0.0
        } else {
            mean.sqrt()
        }
    }
}

/// `z = Σ c[i] x(i)` over `terms` vectors, as SUNDIALS's linear combination: one term
/// is a scaling, two a linear sum, more `c[0] x(0)` then `+= c[i] x(i)` in order.
///
/// # Safety
/// `c` holds `terms` ≥ 1 numbers; `x(i)` and `z` are live serial vectors of one length.
#[inline(always)]
unsafe fn combine(
    terms: usize,
    c: *const f64,
    x: impl Fn(usize) -> sys::N_Vector,
    z: sys::N_Vector,
) {
    // SAFETY: as documented (caller).
    unsafe {
        match terms {
            1 => scale(*c, x(0), z),
            2 => linear_sum(*c, x(0), *c.add(1), x(1), z),
            _ => {
                let c0 = *c;
                map(x(0), z, |v| c0 * v);
                for i in 1..terms {
                    let ci = *c.add(i);
                    zip_with(x(i), z, z, |x, z| z + ci * x);
                }
            }
        }
    }
}

/// A count SUNDIALS passes as a C int (at least 1 for these operations).
fn count(n: c_int) -> usize {
    usize::try_from(n).unwrap_or(0)
}

unsafe extern "C" fn linear_combination(
    nvec: c_int,
    c: *mut f64,
    x: *mut sys::N_Vector,
    z: sys::N_Vector,
) -> c_int {
    let terms = count(nvec);
    if terms == 0 {
        return -1;
    }
    // SAFETY: CVODES passes `nvec` coefficients and vectors.
    unsafe { combine(terms, c, |i| *x.add(i), z) };
    0
}

/// `Z[i] = a[i] x + Y[i]` (every special case of SUNDIALS's is this in floating point).
unsafe extern "C" fn scale_add_multi(
    nvec: c_int,
    a: *mut f64,
    x: sys::N_Vector,
    y: *mut sys::N_Vector,
    z: *mut sys::N_Vector,
) -> c_int {
    // SAFETY: CVODES passes `nvec` coefficients and vectors in each array.
    unsafe {
        for i in 0..count(nvec) {
            let ai = *a.add(i);
            zip_with(x, *y.add(i), *z.add(i), |x, y| ai * x + y);
        }
    }
    0
}

unsafe extern "C" fn linear_sum_array(
    nvec: c_int,
    a: f64,
    x: *mut sys::N_Vector,
    b: f64,
    y: *mut sys::N_Vector,
    z: *mut sys::N_Vector,
) -> c_int {
    // SAFETY: CVODES passes `nvec` vectors in each array.
    unsafe {
        for i in 0..count(nvec) {
            linear_sum(a, *x.add(i), b, *y.add(i), *z.add(i));
        }
    }
    0
}

unsafe extern "C" fn scale_array(
    nvec: c_int,
    c: *mut f64,
    x: *mut sys::N_Vector,
    z: *mut sys::N_Vector,
) -> c_int {
    // SAFETY: CVODES passes `nvec` coefficients and vectors in each array.
    unsafe {
        for i in 0..count(nvec) {
            scale(*c.add(i), *x.add(i), *z.add(i));
        }
    }
    0
}

unsafe extern "C" fn constant_array(nvec: c_int, c: f64, z: *mut sys::N_Vector) -> c_int {
    // SAFETY: CVODES passes `nvec` vectors.
    unsafe {
        for i in 0..count(nvec) {
            constant(c, *z.add(i));
        }
    }
    0
}

unsafe extern "C" fn wrms_norm_array(
    nvec: c_int,
    x: *mut sys::N_Vector,
    w: *mut sys::N_Vector,
    norms: *mut f64,
) -> c_int {
    // SAFETY: CVODES passes `nvec` vectors in each array and room for `nvec` norms.
    unsafe {
        for i in 0..count(nvec) {
            *norms.add(i) = wrms_norm(*x.add(i), *w.add(i));
        }
    }
    0
}

/// `Z[j][i] = a[j] X[i] + Y[j][i]` for `nsum` arrays `Y[j]`, `Z[j]` of `nvec` vectors.
unsafe extern "C" fn scale_add_multi_array(
    nvec: c_int,
    nsum: c_int,
    a: *mut f64,
    x: *mut sys::N_Vector,
    y: *mut *mut sys::N_Vector,
    z: *mut *mut sys::N_Vector,
) -> c_int {
    // SAFETY: CVODES passes `nsum` coefficients and arrays, each of `nvec` vectors.
    unsafe {
        for i in 0..count(nvec) {
            let xi = *x.add(i);
            for j in 0..count(nsum) {
                let aj = *a.add(j);
                zip_with(xi, *(*y.add(j)).add(i), *(*z.add(j)).add(i), |x, y| {
                    aj * x + y
                });
            }
        }
    }
    0
}

/// `Z[j] = Σ c[i] X[i][j]` over `nsum` arrays of `nvec` vectors, each `j` as
/// [`linear_combination`].
unsafe extern "C" fn linear_combination_array(
    nvec: c_int,
    nsum: c_int,
    c: *mut f64,
    x: *mut *mut sys::N_Vector,
    z: *mut sys::N_Vector,
) -> c_int {
    let terms = count(nsum);
    if terms == 0 {
        return -1;
    }
    // SAFETY: CVODES passes `nsum` coefficients and arrays, each of `nvec` vectors.
    unsafe {
        for j in 0..count(nvec) {
            combine(terms, c, |i| *(*x.add(i)).add(j), *z.add(j));
        }
    }
    0
}

#[cfg(test)]
mod tests {
    //! Each kernel against SUNDIALS's own serial kernel on the same vectors, bit for
    //! bit, including the special coefficients and updates in place.
    use super::install;
    use sundials_sys as sys;

    /// A context and vectors with SUNDIALS's kernels (`plain`) and with ours (`ours`).
    struct Vectors {
        ctx: sys::SUNContext,
        plain: Vec<sys::N_Vector>,
        ours: Vec<sys::N_Vector>,
    }

    const N: usize = 37;
    const COUNT: usize = 12;

    impl Vectors {
        fn new() -> Self {
            let mut ctx = std::ptr::null_mut();
            // SAFETY: creating a context and serial vectors, checked for null.
            unsafe {
                assert_eq!(sys::SUNContext_Create(std::ptr::null_mut(), &mut ctx), 0);
                let template = sys::N_VNew_Serial(N as i64, ctx);
                assert_eq!(sys::N_VEnableFusedOps_Serial(template, 1), 0);
                let mine = sys::N_VNew_Serial(N as i64, ctx);
                assert_eq!(sys::N_VEnableFusedOps_Serial(mine, 1), 0);
                install(mine);
                let mut seed = 99u64;
                let mut next = || {
                    seed = seed
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 3.0
                };
                let mut plain = Vec::new();
                let mut ours = Vec::new();
                for v in 0..COUNT {
                    let p = sys::N_VClone(template);
                    let o = sys::N_VClone(mine);
                    for k in 0..N {
                        // some exact zeros and negative numbers among them
                        let value = if (k + v) % 7 == 0 { 0.0 } else { next() };
                        *sys::N_VGetArrayPointer(p).add(k) = value;
                        *sys::N_VGetArrayPointer(o).add(k) = value;
                    }
                    plain.push(p);
                    ours.push(o);
                }
                sys::N_VDestroy(template);
                sys::N_VDestroy(mine);
                Vectors { ctx, plain, ours }
            }
        }

        /// Both sets' vector `i`, bit for bit equal.
        fn assert_same(&self, what: &str) {
            for i in 0..COUNT {
                for k in 0..N {
                    // SAFETY: live vectors of length N.
                    let (p, o) = unsafe {
                        (
                            *sys::N_VGetArrayPointer(self.plain[i]).add(k),
                            *sys::N_VGetArrayPointer(self.ours[i]).add(k),
                        )
                    };
                    assert_eq!(
                        p.to_bits(),
                        o.to_bits(),
                        "{what}: vector {i}[{k}]: {p} against {o}"
                    );
                }
            }
        }
    }

    impl Drop for Vectors {
        fn drop(&mut self) {
            // SAFETY: the vectors and context made in `new`.
            unsafe {
                for v in self.plain.iter().chain(&self.ours) {
                    sys::N_VDestroy(*v);
                }
                sys::SUNContext_Free(&mut self.ctx);
            }
        }
    }

    /// Apply `op` to both sets (it dispatches through the first vector's table, so it
    /// runs SUNDIALS's kernels on `plain` and ours on `ours`) and compare.
    fn check(v: &Vectors, what: &str, op: impl Fn(&[sys::N_Vector])) {
        op(&v.plain);
        op(&v.ours);
        v.assert_same(what);
    }

    /// The kernels' checks in one sequence on one set of vectors: each step starts from
    /// the vectors the steps before it left.
    #[test]
    fn the_kernels_compute_sundials_serial_results_bit_for_bit() {
        let v = Vectors::new();
        check_elementwise(&v);
        check_norms(&v);
        // fused and array operations, with 1, 2 and more terms, out of place and in place
        for terms in 1..=4usize {
            for c in [
                [1.0, 0.5, -0.25, 2.0],
                [0.3, 0.3, 1.5, -1.0],
                [-2.0, 2.0, 1.0, 0.1],
            ] {
                check_fused(&v, terms, c);
                check_vector_arrays(&v, terms, c);
            }
        }
        check_linear_sum_arrays(&v);
        check_array_norms(&v);
    }

    /// Linear sums, scaling, constants and the element-wise operations.
    fn check_elementwise(v: &Vectors) {
        let coefficients = [1.0, -1.0, 0.0, 0.7, -0.7, 2.5, 1.0 / 3.0];
        // SAFETY (all closures): the live vectors of `v`.
        for &a in &coefficients {
            for &b in &coefficients {
                check(v, &format!("linear sum {a} {b}"), |x| unsafe {
                    sys::N_VLinearSum(a, x[0], b, x[1], x[2])
                });
                check(
                    v,
                    &format!("linear sum in place of y {a} {b}"),
                    |x| unsafe { sys::N_VLinearSum(a, x[3], b, x[4], x[4]) },
                );
                check(
                    v,
                    &format!("linear sum in place of x {a} {b}"),
                    |x| unsafe { sys::N_VLinearSum(a, x[5], b, x[6], x[5]) },
                );
            }
            check(v, &format!("scale {a}"), |x| unsafe {
                sys::N_VScale(a, x[1], x[7])
            });
            check(v, &format!("scale in place {a}"), |x| unsafe {
                sys::N_VScale(a, x[7], x[7])
            });
            check(v, &format!("add constant {a}"), |x| unsafe {
                sys::N_VAddConst(x[2], a, x[8])
            });
        }
        check(v, "product", |x| unsafe { sys::N_VProd(x[0], x[1], x[9]) });
        check(v, "quotient", |x| unsafe { sys::N_VDiv(x[9], x[2], x[10]) });
        check(v, "absolute", |x| unsafe { sys::N_VAbs(x[10], x[11]) });
        check(v, "inverse", |x| unsafe { sys::N_VInv(x[11], x[11]) });
        check(v, "constant", |x| unsafe { sys::N_VConst(0.25, x[11]) });
    }

    /// The norms: equal numbers.
    fn check_norms(v: &Vectors) {
        for (i, j) in [(0, 1), (2, 3), (4, 4), (9, 10)] {
            // SAFETY: live vectors.
            unsafe {
                assert_eq!(
                    sys::N_VWrmsNorm(v.plain[i], v.plain[j]).to_bits(),
                    sys::N_VWrmsNorm(v.ours[i], v.ours[j]).to_bits()
                );
                assert_eq!(
                    sys::N_VMaxNorm(v.plain[i]).to_bits(),
                    sys::N_VMaxNorm(v.ours[i]).to_bits()
                );
            }
        }
    }

    /// The fused operations with `terms` terms and coefficients `c`, out of place and in
    /// place.
    fn check_fused(v: &Vectors, terms: usize, c: [f64; 4]) {
        // SAFETY (all closures): the live vectors of `v`, arrays of the stated lengths.
        check(
            v,
            &format!("linear combination {terms} {c:?}"),
            |x| unsafe {
                let mut xs = x[..terms].to_vec();
                let mut c = c;
                sys::N_VLinearCombination(terms as i32, c.as_mut_ptr(), xs.as_mut_ptr(), x[11]);
            },
        );
        check(
            v,
            &format!("linear combination in place {terms} {c:?}"),
            |x| unsafe {
                let mut xs = x[4..4 + terms].to_vec();
                let mut c = c;
                sys::N_VLinearCombination(terms as i32, c.as_mut_ptr(), xs.as_mut_ptr(), x[4]);
            },
        );
        check(v, &format!("scale add multi {terms} {c:?}"), |x| unsafe {
            let mut ys = x[1..1 + terms].to_vec();
            let mut zs = x[6..6 + terms].to_vec();
            let mut c = c;
            sys::N_VScaleAddMulti(
                terms as i32,
                c.as_mut_ptr(),
                x[0],
                ys.as_mut_ptr(),
                zs.as_mut_ptr(),
            );
        });
        check(
            v,
            &format!("scale add multi in place {terms} {c:?}"),
            |x| unsafe {
                let mut ys = x[6..6 + terms].to_vec();
                let mut c = c;
                let p = ys.as_mut_ptr();
                sys::N_VScaleAddMulti(terms as i32, c.as_mut_ptr(), x[0], p, p);
            },
        );
        check(v, &format!("scale array {terms} {c:?}"), |x| unsafe {
            let mut xs = x[..terms].to_vec();
            let mut zs = x[7..7 + terms].to_vec();
            let mut c = c;
            sys::N_VScaleVectorArray(
                terms as i32,
                c.as_mut_ptr(),
                xs.as_mut_ptr(),
                zs.as_mut_ptr(),
            );
        });
    }

    /// The vector-array operations with `terms` arrays of two vectors each and
    /// coefficients `c`: X[i] = (x[i], x[i+1]), Z = (x[10], x[11]).
    fn check_vector_arrays(v: &Vectors, terms: usize, c: [f64; 4]) {
        let nvec = 2usize;
        // SAFETY (all closures): the live vectors of `v`, arrays of the stated lengths.
        check(
            v,
            &format!("linear combination array {terms} {c:?}"),
            |x| unsafe {
                let mut arrays: Vec<Vec<sys::N_Vector>> =
                    (0..terms).map(|i| vec![x[2 * i], x[2 * i + 1]]).collect();
                let mut ptrs: Vec<*mut sys::N_Vector> =
                    arrays.iter_mut().map(|a| a.as_mut_ptr()).collect();
                let mut zs = vec![x[10], x[11]];
                let mut c = c;
                sys::N_VLinearCombinationVectorArray(
                    nvec as i32,
                    terms as i32,
                    c.as_mut_ptr(),
                    ptrs.as_mut_ptr(),
                    zs.as_mut_ptr(),
                );
            },
        );
        check(
            v,
            &format!("scale add multi array {terms} {c:?}"),
            |x| unsafe {
                let mut xs = vec![x[0], x[1]];
                let mut ys: Vec<Vec<sys::N_Vector>> =
                    (0..terms).map(|j| vec![x[2 + j], x[6 + j]]).collect();
                let mut zs: Vec<Vec<sys::N_Vector>> =
                    (0..terms).map(|j| vec![x[2 + j], x[6 + j]]).collect();
                let mut yp: Vec<*mut sys::N_Vector> =
                    ys.iter_mut().map(|a| a.as_mut_ptr()).collect();
                let mut zp: Vec<*mut sys::N_Vector> =
                    zs.iter_mut().map(|a| a.as_mut_ptr()).collect();
                let mut c = c;
                sys::N_VScaleAddMultiVectorArray(
                    nvec as i32,
                    terms as i32,
                    c.as_mut_ptr(),
                    xs.as_mut_ptr(),
                    yp.as_mut_ptr(),
                    zp.as_mut_ptr(),
                );
            },
        );
    }

    /// Linear sums of arrays, out of place and in place, and a constant array.
    fn check_linear_sum_arrays(v: &Vectors) {
        // SAFETY (all closures): the live vectors of `v`, arrays of the stated lengths.
        for (a, b) in [
            (1.0, 1.0),
            (1.0, -1.0),
            (-1.0, 1.0),
            (0.5, 0.5),
            (0.5, -0.5),
            (0.25, 3.0),
        ] {
            check(v, &format!("linear sum array {a} {b}"), |x| unsafe {
                let mut xs = vec![x[0], x[1], x[2]];
                let mut ys = vec![x[3], x[4], x[5]];
                let mut zs = vec![x[6], x[7], x[8]];
                sys::N_VLinearSumVectorArray(
                    3,
                    a,
                    xs.as_mut_ptr(),
                    b,
                    ys.as_mut_ptr(),
                    zs.as_mut_ptr(),
                );
            });
            check(
                v,
                &format!("linear sum array in place {a} {b}"),
                |x| unsafe {
                    let mut xs = vec![x[0], x[1], x[2]];
                    let mut ys = vec![x[3], x[4], x[5]];
                    let p = ys.as_mut_ptr();
                    sys::N_VLinearSumVectorArray(3, a, xs.as_mut_ptr(), b, p, p);
                },
            );
        }
        check(v, "constant array", |x| unsafe {
            let mut zs = vec![x[9], x[10]];
            sys::N_VConstVectorArray(2, -3.5, zs.as_mut_ptr());
        });
    }

    /// Norms of arrays: equal numbers.
    fn check_array_norms(v: &Vectors) {
        // SAFETY: live vectors.
        unsafe {
            let mut norms_plain = [0.0; 3];
            let mut norms_ours = [0.0; 3];
            let mut xp = vec![v.plain[0], v.plain[1], v.plain[2]];
            let mut wp = vec![v.plain[3], v.plain[4], v.plain[5]];
            let mut xo = vec![v.ours[0], v.ours[1], v.ours[2]];
            let mut wo = vec![v.ours[3], v.ours[4], v.ours[5]];
            sys::N_VWrmsNormVectorArray(
                3,
                xp.as_mut_ptr(),
                wp.as_mut_ptr(),
                norms_plain.as_mut_ptr(),
            );
            sys::N_VWrmsNormVectorArray(
                3,
                xo.as_mut_ptr(),
                wo.as_mut_ptr(),
                norms_ours.as_mut_ptr(),
            );
            for (p, o) in norms_plain.iter().zip(&norms_ours) {
                assert_eq!(p.to_bits(), o.to_bits());
            }
        }
    }
}
