//! The transcendental part of the closed form, e^p, sin q and cos q, four arguments at a
//! time: every arc of a segment is evaluated at the same instant s, so the segment end
//! state, the event location, the damping integral and the deferred peak refinement take
//! [e^{−ζ_n ω_n s}, sin ω_dn s, cos ω_dn s] for all modes n together ([`exp_sin_cos`]).
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
//! unlike a platform's libm. Arguments outside |p| ≤ 700 or |q| ≤ 10⁶ (and NaN) are
//! handed to the standard library lane by lane; the momentum method never produces them
//! for a physical scene (|p| = ζωs, |q| = ω_d s over one record step).

/// 1.5 · 2⁵²: adding and subtracting it rounds |x| < 2⁵¹ to the nearest integer (ties to
/// even), and the sum's low mantissa bits hold that integer.
const ROUND: f64 = 6755399441055744.0;

const LN2_HI: f64 = 6.93147180369123816490e-01;
const LN2_LO: f64 = 1.90821492927058770002e-10;
const INV_LN2: f64 = 1.44269504088896338700e+00;
const P1: f64 = 1.66666666666666019037e-01;
const P2: f64 = -2.77777777770155933842e-03;
const P3: f64 = 6.61375632143793436117e-05;
const P4: f64 = -1.65339022054652515390e-06;
const P5: f64 = 4.13813679705723846039e-08;

const INV_PIO2: f64 = 6.36619772367581382433e-01;
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
const EXP_MAX: f64 = 700.0;
/// Largest |q| of the vector reduction (k < 2²⁰: the products k · PIO2_i are exact).
const TRIG_MAX: f64 = 1.0e6;

/// (e^p, sin q, cos q), lane by lane (see module docs).
#[inline(always)]
pub fn exp_sin_cos(p: [f64; 4], q: [f64; 4]) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let e = exp4(p);
    let (s, c) = sin_cos4(q);
    let mut out = (e, s, c);
    let odd = |i: usize| !(p[i].abs() <= EXP_MAX) || !(q[i].abs() <= TRIG_MAX);
    if (0..4).any(odd) {
        for i in 0..4 {
            if !(p[i].abs() <= EXP_MAX) {
                out.0[i] = p[i].exp();
            }
            if !(q[i].abs() <= TRIG_MAX) {
                (out.1[i], out.2[i]) = q[i].sin_cos();
            }
        }
    }
    out
}

/// (e^p, sin q, cos q) of one argument pair: lane 0 of [`exp_sin_cos`] (the same bits).
#[inline]
pub fn exp_sin_cos1(p: f64, q: f64) -> [f64; 3] {
    let (e, s, c) = exp_sin_cos([p; 4], [q; 4]);
    [e[0], s[0], c[0]]
}

/// e^p for |p| ≤ 700 (fdlibm's e_exp.c without its special cases).
#[inline(always)]
fn exp4(x: [f64; 4]) -> [f64; 4] {
    let x = x.map(|v| v.clamp(-EXP_MAX, EXP_MAX));
    let sum: [f64; 4] = std::array::from_fn(|i| x[i] * INV_LN2 + ROUND);
    let k: [f64; 4] = sum.map(|s| s - ROUND);
    let hi: [f64; 4] = std::array::from_fn(|i| x[i] - k[i] * LN2_HI);
    let lo: [f64; 4] = k.map(|k| k * LN2_LO);
    let r: [f64; 4] = std::array::from_fn(|i| hi[i] - lo[i]);
    std::array::from_fn(|i| {
        let (r, hi, lo) = (r[i], hi[i], lo[i]);
        let t = r * r;
        let c = r - t * (P1 + t * (P2 + t * (P3 + t * (P4 + t * P5))));
        let y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
        // 2^k from the integer in the low bits of `sum` (two's complement offset).
        let ki = (sum[i].to_bits() as i64).wrapping_sub(ROUND.to_bits() as i64);
        let scale = f64::from_bits(((ki + 1023) as u64) << 52);
        y * scale
    })
}

/// (sin q, cos q) for |q| ≤ 10⁶ (fdlibm's medium-size reduction, always to the third part).
#[inline(always)]
fn sin_cos4(x: [f64; 4]) -> ([f64; 4], [f64; 4]) {
    let x = x.map(|v| v.clamp(-TRIG_MAX, TRIG_MAX));
    let sum: [f64; 4] = std::array::from_fn(|i| x[i] * INV_PIO2 + ROUND);
    let f: [f64; 4] = sum.map(|s| s - ROUND);
    let mut s = [0.0; 4];
    let mut c = [0.0; 4];
    for i in 0..4 {
        let fl = f[i];
        // x − k·pio2_1 is exact (k < 2²⁰, and x is near k·pio2_1); the rest of k π/2,
        // k·pio2_2 (exact) + k·(pio2_3 + pio2_3t), is taken off in two-sum arithmetic.
        let t = x[i] - fl * PIO2_1;
        let wh = fl * PIO2_2;
        let wl = fl * PIO2_3 + fl * PIO2_3T;
        let r = t - wh;
        let bb = r - t;
        let err = (t - (r - bb)) + (-wh - bb);
        let tail = err - wl;
        let y0 = r + tail;
        let y1 = (r - y0) + tail;
        // Kernels on [−π/4, π/4] with the tail y1.
        let z = y0 * y0;
        let v = z * y0;
        let rs = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
        let ks = y0 - ((z * (0.5 * y1 - v * rs) - y1) - v * S1);
        let zz = z * z;
        let rc = z * (C1 + z * (C2 + z * C3)) + zz * zz * (C4 + z * (C5 + z * C6));
        let hz = 0.5 * z;
        let w1 = 1.0 - hz;
        let kc = w1 + (((1.0 - w1) - hz) + (z * rc - y0 * y1));
        let n = sum[i].to_bits() & 3;
        let (sn, cs) = if n & 1 == 0 { (ks, kc) } else { (kc, ks) };
        // Quadrant n: (sin, cos) = (ks, kc), (kc, −ks), (−ks, −kc), (−kc, ks).
        let neg_s = (n >> 1) << 63;
        let neg_c = (((n + 1) >> 1) & 1) << 63;
        s[i] = f64::from_bits(sn.to_bits() ^ neg_s);
        if x[i] == 0.0 {
            s[i] = x[i]; // sin(±0) = ±0
        }
        c[i] = f64::from_bits(cs.to_bits() ^ neg_c);
    }
    (s, c)
}

#[cfg(test)]
mod tests {
    use super::*;

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
