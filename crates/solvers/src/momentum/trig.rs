//! The transcendental part of the closed form, e^p, sin q and cos q, four arguments at a
//! time: every arc of a segment is evaluated at the same instant s, so the segment end
//! state, the event location, the damping integral and the deferred peak refinement take
//! [e^{−ζ_n ω_n s}, sin ω_dn s, cos ω_dn s] for all modes n together
//! ([`exp_sin_cos_slices`]; [`exp_sin_cos_with`] inside the caller's dispatch,
//! [`exp_sin_cos1`] for one argument pair).
//!
//! The algorithms are fdlibm's (Sun Microsystems, 1993; the ones of musl and of the
//! `libm` crate), written branch-free over four lanes so that the compiler vectorises
//! them inside the caller's [`pulp`] dispatch:
//! - **exp** (`e_exp.c`): p = k ln 2 + r with |r| ≤ ½ ln 2 (ln 2 in two parts, so
//!   k ln2_hi is exact), R(r) = r − r²(P1 + r²(P2 + …)) a minimax fit of
//!   r(e^r + 1)/(e^r − 1), e^r = 1 − ((lo − r R/(2 − R)) − hi), then the exponent k is
//!   added to the bits. Error < 1 ulp.
//! - **sin, cos** (`e_rem_pio2.c`, `k_sin.c`, `k_cos.c`): q = k π/2 + (y₀ + y₁) by
//!   Cody–Waite reduction with π/2 in three 33-bit parts and a tail (exact products for
//!   |k| < 2²⁰, the remainder taken off in two-sum arithmetic), then the minimax polynomials on [−π/4, π/4] with the tail y₁, and the quadrant k mod 4
//!   picks ±sin or ±cos. Error < 1 ulp.
//!
//! Only IEEE additions, multiplications and divisions are used (no fused multiply-add),
//! so the results are the same bits on every machine and with every instruction set,
//! unlike a platform's libm. Why not a crate: the arguments live in `pulp` vectors inside
//! the caller's dispatch, and a single argument must get the bits of a vector lane (the
//! scalar paths, [`exp_sin_cos1`], run this kernel on `pulp::Scalar`); the vector libm
//! ports we know (sleef's) need nightly Rust or their own vector types. Arguments outside |p| ≤ 700 or |q| ≤ 10⁶ (and NaN) are
//! handed to the standard library lane by lane; the momentum method never produces them
//! for a physical scene (|p| = ζωs, |q| = ω_d s over one record step).

// fdlibm's constants as it publishes them (decimal strings that round to its doubles);
// `!(x <= max)` is the range test that NaN fails.
#![allow(clippy::excessive_precision, clippy::neg_cmp_op_on_partial_ord)]

/// 1.5 · 2⁵²: adding and subtracting it rounds |x| < 2⁵¹ to the nearest integer (ties to
/// even), and the sum's low mantissa bits hold that integer.
const ROUND: f64 = 6755399441055744.0;

const LN2_HI: f64 = 6.93147180369123816490e-01;
const LN2_LO: f64 = 1.90821492927058770002e-10;
const INV_LN2: f64 = std::f64::consts::LOG2_E; // fdlibm's invln2, the same double
const P1: f64 = 1.66666666666666019037e-01;
const P2: f64 = -2.77777777770155933842e-03;
const P3: f64 = 6.61375632143793436117e-05;
const P4: f64 = -1.65339022054652515390e-06;
const P5: f64 = 4.13813679705723846039e-08;

const INV_PIO2: f64 = std::f64::consts::FRAC_2_PI; // fdlibm's invpio2, the same double
const PIO2_1: f64 = 1.57079632673412561417e+00;
const PIO2_2: f64 = 6.07710050630396597660e-11;
const PIO2_3: f64 = 2.02226624871116645580e-21;
const PIO2_3T: f64 = 8.47842766036889956997e-32;

const S1: f64 = -1.66666666666666324348e-01;
const S2: f64 = 8.33333333332248946124e-03;
const S3: f64 = -1.98412698298579493134e-04;
const S4: f64 = 2.75573137070700676789e-06;
const S5: f64 = -2.50507602534068634195e-08;
const S6: f64 = 1.58969099521155010221e-10;
const C1: f64 = 4.16666666666666019037e-02;
const C2: f64 = -1.38888888888741095749e-03;
const C3: f64 = 2.48015872894767294178e-05;
const C4: f64 = -2.75573143513906633035e-07;
const C5: f64 = 2.08757232129817482790e-09;
const C6: f64 = -1.13596475577881948265e-11;

/// Largest |p| of the vector exp (k stays a normal exponent).
pub const EXP_MAX: f64 = 700.0;
/// Largest |q| of the vector reduction (k < 2²⁰: the products k · PIO2_i are exact).
pub const TRIG_MAX: f64 = 1.0e6;

/// e^p, sin q, cos q of every element of `p`, `q` into `e`, `s`, `c` (all of one length),
/// in the widest instruction set ([`pulp::Arch`]).
pub fn exp_sin_cos_slices(p: &[f64], q: &[f64], e: &mut [f64], s: &mut [f64], c: &mut [f64]) {
    struct Op<'x> {
        p: &'x [f64],
        q: &'x [f64],
        e: &'x mut [f64],
        s: &'x mut [f64],
        c: &'x mut [f64],
    }
    impl pulp::WithSimd for Op<'_> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: pulp::Simd>(self, simd: S) {
            exp_sin_cos_with(simd, self.p, self.q, self.e, self.s, self.c)
        }
    }
    pulp::Arch::new().dispatch(Op { p, q, e, s, c })
}

/// [`exp_sin_cos_slices`] in the caller's instruction set `simd`: whole vectors, then the
/// remainder lane by lane (the same arithmetic: the same bits), then the standard library
/// for arguments out of the vector range.
#[inline(always)]
pub fn exp_sin_cos_with<S: pulp::Simd>(
    simd: S,
    p: &[f64],
    q: &[f64],
    e: &mut [f64],
    s: &mut [f64],
    c: &mut [f64],
) {
    let n = p.len();
    let (q, e, s, c) = (&q[..n], &mut e[..n], &mut s[..n], &mut c[..n]);
    let (pv, pt) = S::as_simd_f64s(p);
    let (qv, _) = S::as_simd_f64s(q);
    let (ev, _) = S::as_mut_simd_f64s(e);
    let (sv, _) = S::as_mut_simd_f64s(s);
    let (cv, _) = S::as_mut_simd_f64s(c);
    let nv = pv
        .len()
        .min(qv.len())
        .min(ev.len())
        .min(sv.len())
        .min(cv.len());
    for i in 0..nv {
        (ev[i], sv[i], cv[i]) = kernel(simd, pv[i], qv[i]);
    }
    for i in n - pt.len()..n {
        let one = pulp::Scalar::new();
        (e[i], s[i], c[i]) = kernel(one, p[i], q[i]);
    }
    for i in 0..n {
        if !(p[i].abs() <= EXP_MAX) {
            e[i] = p[i].exp();
        }
        if !(q[i].abs() <= TRIG_MAX) {
            (s[i], c[i]) = q[i].sin_cos();
        }
    }
}

/// (e^p, sin q, cos q) of one argument pair (the same bits as the vector lanes).
#[inline]
pub fn exp_sin_cos1(p: f64, q: f64) -> [f64; 3] {
    let (mut e, mut s, mut c) = kernel(pulp::Scalar::new(), p, q);
    if !(p.abs() <= EXP_MAX) {
        e = p.exp();
    }
    if !(q.abs() <= TRIG_MAX) {
        (s, c) = q.sin_cos();
    }
    [e, s, c]
}

/// (e^p, sin q, cos q) lane by lane, for |p| ≤ 700 and |q| ≤ 10⁶ (other lanes hold
/// garbage, replaced by the callers): fdlibm's e_exp.c without its special cases, and its
/// medium-size reduction (always to the third part of π/2) with k_sin.c and k_cos.c.
#[inline(always)]
pub fn kernel<S: pulp::Simd>(simd: S, p: S::f64s, q: S::f64s) -> (S::f64s, S::f64s, S::f64s) {
    let k = |x: f64| simd.splat_f64s(x);
    let add = |a, b| simd.add_f64s(a, b);
    let sub = |a, b| simd.sub_f64s(a, b);
    let mul = |a, b| simd.mul_f64s(a, b);
    let bits = |a| simd.transmute_u64s_f64s(a);
    let round = k(ROUND);

    // e^p = 2^j e^r, p = j ln 2 + r.
    let sum = add(mul(p, k(INV_LN2)), round);
    let j = sub(sum, round);
    let hi = sub(p, mul(j, k(LN2_HI)));
    let lo = mul(j, k(LN2_LO));
    let r = sub(hi, lo);
    let t = mul(r, r);
    let poly = add(k(P4), mul(t, k(P5)));
    let poly = add(k(P3), mul(t, poly));
    let poly = add(k(P2), mul(t, poly));
    let poly = add(k(P1), mul(t, poly));
    let cr = sub(r, mul(t, poly));
    let ratio = simd.div_f64s(mul(r, cr), sub(k(2.0), cr));
    let y = sub(k(1.0), sub(sub(lo, ratio), hi));
    // 2^j from the integer in the low bits of `sum`: (j + 1023) · 2⁵² as bits.
    let ji = simd.sub_u64s(bits(sum), simd.splat_u64s(ROUND.to_bits()));
    let biased = simd.add_u64s(ji, simd.splat_u64s(1023));
    let scale = simd.transmute_f64s_u64s(simd.mul_u64s(biased, simd.splat_u64s(1 << 52)));
    let e = mul(y, scale);

    // sin, cos: q = n π/2 + (y0 + y1).
    let sum = add(mul(q, k(INV_PIO2)), round);
    let f = sub(sum, round);
    // q − n·pio2_1 is exact (n < 2²⁰, q near n·pio2_1); the rest of n π/2, n·pio2_2 (exact)
    // + n·(pio2_3 + pio2_3t), is taken off in two-sum arithmetic.
    let t = sub(q, mul(f, k(PIO2_1)));
    let wh = mul(f, k(PIO2_2));
    let wl = add(mul(f, k(PIO2_3)), mul(f, k(PIO2_3T)));
    let r = sub(t, wh);
    let bb = sub(r, t);
    let err = add(sub(t, sub(r, bb)), sub(simd.neg_f64s(wh), bb));
    let tail = sub(err, wl);
    let y0 = add(r, tail);
    let y1 = add(sub(r, y0), tail);
    // The kernels on [−π/4, π/4] with the tail y1.
    let z = mul(y0, y0);
    let v = mul(z, y0);
    let rs = add(k(S5), mul(z, k(S6)));
    let rs = add(k(S4), mul(z, rs));
    let rs = add(k(S3), mul(z, rs));
    let rs = add(k(S2), mul(z, rs));
    let ks = sub(
        y0,
        sub(
            sub(mul(z, sub(mul(k(0.5), y1), mul(v, rs))), y1),
            mul(v, k(S1)),
        ),
    );
    let zz = mul(z, z);
    let c_lo = add(k(C1), mul(z, add(k(C2), mul(z, k(C3)))));
    let c_hi = add(k(C4), mul(z, add(k(C5), mul(z, k(C6)))));
    let rc = add(mul(z, c_lo), mul(mul(zz, zz), c_hi));
    let hz = mul(k(0.5), z);
    let w1 = sub(k(1.0), hz);
    let kc = add(
        w1,
        add(sub(sub(k(1.0), w1), hz), sub(mul(z, rc), mul(y0, y1))),
    );
    // Quadrant n: (sin, cos) = (ks, kc), (kc, −ks), (−ks, −kc), (−kc, ks).
    let n = bits(sum);
    let is = |m: S::u64s, v: u64| {
        simd.equal_u64s(simd.and_u64s(m, simd.splat_u64s(v)), simd.splat_u64s(v))
    };
    let swap = is(n, 1);
    let sn = simd.select_f64s(swap, kc, ks);
    let cs = simd.select_f64s(swap, ks, kc);
    let sn = simd.select_f64s(is(n, 2), simd.neg_f64s(sn), sn);
    let n1 = simd.add_u64s(n, simd.splat_u64s(1));
    let cs = simd.select_f64s(is(n1, 2), simd.neg_f64s(cs), cs);
    // sin(±0) = ±0.
    let sn = simd.select_f64s(simd.equal_f64s(q, k(0.0)), q, sn);
    (e, sn, cs)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The slices entry point on four arguments.
    fn exp_sin_cos(p: [f64; 4], q: [f64; 4]) -> ([f64; 4], [f64; 4], [f64; 4]) {
        let (mut e, mut s, mut c) = ([0.0; 4], [0.0; 4], [0.0; 4]);
        exp_sin_cos_slices(&p, &q, &mut e, &mut s, &mut c);
        (e, s, c)
    }

    /// Distance in units in the last place (of the reference).
    fn ulps(a: f64, b: f64) -> f64 {
        if a == b {
            return 0.0;
        }
        let ulp = f64::from_bits(b.abs().to_bits() + 1) - b.abs();
        ((a - b) / ulp).abs()
    }

    /// A deterministic stream in [lo, hi).
    fn stream(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
        let mut z: u64 = 0x9E37_79B9_7F4A_7C15;
        (0..n).map(move |_| {
            z ^= z << 13;
            z ^= z >> 7;
            z ^= z << 17;
            lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
        })
    }

    #[test]
    fn within_one_ulp_of_the_standard_library() {
        // The standard library (glibc: correctly rounded in practice) is the reference;
        // fdlibm's bound is < 1 ulp, so the two differ by at most 1 ulp.
        let mut worst = [0.0f64; 3];
        let ranges = [
            (-1e-9, 1e-9),
            (-0.5, 0.5),
            (-3.0, 3.0),
            (-60.0, 60.0),
            (-700.0, 700.0),
        ];
        for (lo, hi) in ranges {
            let xs: Vec<f64> = stream(lo, hi, 40_000).collect();
            for c in xs.chunks_exact(4) {
                let a: [f64; 4] = c.try_into().unwrap();
                let (e, s, co) = exp_sin_cos(a, a);
                for i in 0..4 {
                    worst[0] = worst[0].max(ulps(e[i], a[i].exp()));
                    worst[1] = worst[1].max(ulps(s[i], a[i].sin()));
                    worst[2] = worst[2].max(ulps(co[i], a[i].cos()));
                }
            }
        }
        assert!(worst.iter().all(|&w| w <= 1.0), "worst ulps {worst:?}");
    }

    #[test]
    fn near_multiples_of_half_pi_keep_their_relative_accuracy() {
        // Where the reduction cancels most digits (q near k π/2) the sine or cosine is
        // small; the three-part π/2 keeps it to 1 ulp.
        for k in 1..2000 {
            let q = k as f64 * std::f64::consts::FRAC_PI_2;
            for x in [
                q,
                f64::from_bits(q.to_bits() + 1),
                f64::from_bits(q.to_bits() - 1),
            ] {
                let [_, s, c] = exp_sin_cos1(0.0, x);
                assert!(ulps(s, x.sin()) <= 1.0, "sin {x}: {s} vs {}", x.sin());
                assert!(ulps(c, x.cos()) <= 1.0, "cos {x}: {c} vs {}", x.cos());
            }
        }
    }

    #[test]
    fn exact_values_and_edges() {
        assert_eq!(exp_sin_cos1(0.0, 0.0), [1.0, 0.0, 1.0]);
        let [e, s, c] = exp_sin_cos1(-0.0, -0.0);
        assert_eq!((e, c), (1.0, 1.0));
        assert!(s == 0.0 && s.is_sign_negative());
        // Past the vector range: the standard library's values, lane by lane.
        let (e, s, c) = exp_sin_cos([-800.0, 800.0, f64::NAN, 1.0], [2e6, -1e7, f64::NAN, 1.0]);
        assert_eq!(e[0], 0.0);
        assert_eq!(e[1], f64::INFINITY);
        assert!(e[2].is_nan() && s[2].is_nan() && c[2].is_nan());
        assert_eq!((s[0], c[0]), 2e6f64.sin_cos());
        assert_eq!((s[1], c[1]), (-1e7f64).sin_cos());
        assert!(ulps(e[3], 1f64.exp()) <= 1.0);
    }

    #[test]
    fn lanes_are_independent() {
        // A lane's value depends on its own argument only (the scalar form is lane 0).
        let p = [-0.3, -12.0, 0.0, -1e-5];
        let q = [0.7, 40.0, 1e-300, 3.0];
        let (e, s, c) = exp_sin_cos(p, q);
        for i in 0..4 {
            assert_eq!([e[i], s[i], c[i]], exp_sin_cos1(p[i], q[i]));
        }
    }
}
