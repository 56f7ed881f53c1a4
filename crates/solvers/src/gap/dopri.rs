//! Dormand–Prince 5(4) with FSAL, Hairer's PI step controller and 4th-order dense output.
//!
//! A focused implementation rather than a general ODE crate (diffsol): the contact
//! right-hand side is piecewise defined and switched only at located events, which needs a
//! trial/commit contact state that a rejected step never touches; every record point is a
//! breakpoint that no step may straddle; and the event search runs on the dense interpolant
//! of a handful of components (δ, δ̇ of each contact), with no allocation in the step loop.
//! Those three requirements are most of the code of an integrator; the tableau is 40 numbers.
//!
//! - Tableau, error estimate and continuous extension: Hairer, Nørsett & Wanner, *Solving
//!   ODEs I*, §II.5–6 (code `DOPRI5`): y(t₀+θh) = r₁ + θ(r₂ + (1−θ)(r₃ + θ(r₄ + (1−θ) r₅))).
//! - Error norm: err = √(mean_i (e_i / (atol_i + rtol·max(|y₀ᵢ|, |y₁ᵢ|)))²) over the first
//!   `n_err` components (the mechanical state); the trailing quadrature components (energy,
//!   impulse) ride along with the same stages but do not steer the step.
//! - Controller: Hairer's PI controller (β = 0.04, safety 0.9, factor within [0.2, 10]),
//!   no step growth right after a rejection.
//! - Starting step: `HINIT` of `dopri5.f` to the letter (Euclidean weighted norms, see
//!   [`Dopri5::initial_step`]); the step error norm above is the RMS norm, as in `dopri5.f`.
//! - Pinned: on the Arenstorf orbit at rtol = atol = 1e-7 the stepper reproduces
//!   `dopri5.f`'s step, rejection and evaluation counts exactly, with h₀ = 1e-4
//!   (238/217/21/1429) and with HINIT (240/216/22/1442, the published `dr_dop5` run)
//!   (`tests/dopri5_arenstorf.rs`).

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

const BETA: f64 = 0.04;
const SAFE: f64 = 0.9;
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 10.0;

/// The stepper's work arrays (allocated once).
#[derive(Debug, Clone)]
pub struct Dopri5 {
    pub dim: usize,
    n_err: usize,
    pub rtol: f64,
    atol: Vec<f64>,
    /// Stage derivatives k1 … k7; `k[0]` holds f(t, y) at the current point (FSAL).
    pub k: [Vec<f64>; 7],
    ytmp: Vec<f64>,
    /// Proposed solution at t + h after [`Dopri5::try_step`].
    pub y1: Vec<f64>,
    rcont: [Vec<f64>; 5],
    /// Start and length of the step the dense output describes.
    pub t0: f64,
    pub h: f64,
    facold: f64,
    /// The vector instructions of this machine ([`Dopri5::try_step`]).
    arch: pulp::Arch,
}

impl Dopri5 {
    /// `n_err` leading components enter the error norm with absolute tolerances `atol`.
    pub fn new(dim: usize, n_err: usize, rtol: f64, atol: Vec<f64>) -> Self {
        assert_eq!(atol.len(), n_err);
        let z = || vec![0.0; dim];
        Dopri5 {
            dim,
            n_err,
            rtol,
            atol,
            k: [z(), z(), z(), z(), z(), z(), z()],
            ytmp: z(),
            y1: z(),
            rcont: [z(), z(), z(), z(), z()],
            t0: 0.0,
            h: 0.0,
            facold: 1e-4,
            arch: pulp::Arch::new(),
        }
    }

    /// Weighted RMS norm of `v` with the scale of `y`.
    pub fn norm(&self, v: &[f64], y: &[f64]) -> f64 {
        let mut s = 0.0;
        for i in 0..self.n_err {
            let sc = self.atol[i] + self.rtol * y[i].abs();
            let r = v[i] / sc;
            s += r * r;
        }
        (s / self.n_err as f64).sqrt()
    }

    /// Hairer's starting step, exactly as `HINIT` in `dopri5.f`: with the weights
    /// sᵢ = atolᵢ + rtol·|yᵢ| and *Euclidean* (not RMS) weighted norms over the first
    /// `n_err` components,
    ///
    /// ```text
    /// d₀ = ‖y‖,  d₁ = ‖f(t, y)‖,  h₀ = 0.01·d₀/d₁   (1e-6 if d₀² or d₁² ≤ 1e-10)
    /// d₂ = ‖f(t + h₀, y + h₀ f) − f(t, y)‖ / h₀
    /// h₁ = (0.01 / max(d₁, d₂))^(1/5)               (max(1e-6, 1e-3 h₀) if that max ≤ 1e-15)
    /// h  = min(100 h₀, h₁, hmax)
    /// ```
    ///
    /// `k[0]` must hold f(t, y). Uses `ytmp`/`k[1]`; costs one evaluation of f.
    pub fn initial_step<F: FnMut(f64, &[f64], &mut [f64])>(
        &mut self,
        f: &mut F,
        t: f64,
        y: &[f64],
        hmax: f64,
    ) -> f64 {
        let (mut dnf, mut dny) = (0.0, 0.0);
        for i in 0..self.n_err {
            let sk = self.atol[i] + self.rtol * y[i].abs();
            dnf += (self.k[0][i] / sk).powi(2);
            dny += (y[i] / sk).powi(2);
        }
        let mut h0 = if dnf <= 1e-10 || dny <= 1e-10 {
            1e-6
        } else {
            (dny / dnf).sqrt() * 0.01
        };
        h0 = h0.min(hmax);
        for i in 0..self.dim {
            self.ytmp[i] = y[i] + h0 * self.k[0][i];
        }
        let (ytmp, rest) = (&self.ytmp, &mut self.k);
        let (k0, k1) = rest.split_at_mut(1);
        f(t + h0, ytmp, &mut k1[0]);
        let mut der2 = 0.0;
        for i in 0..self.n_err {
            let sk = self.atol[i] + self.rtol * y[i].abs();
            der2 += ((k1[0][i] - k0[0][i]) / sk).powi(2);
        }
        let der2 = der2.sqrt() / h0;
        let der12 = der2.abs().max(dnf.sqrt());
        let h1 = if der12 <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            (0.01 / der12).powf(0.2)
        };
        (100.0 * h0).min(h1).min(hmax)
    }

    /// One trial step of length `h` from (t, y) with `k[0]` = f(t, y). Fills `y1` and
    /// `k[6]` = f(t + h, y1) and returns the error norm (NaN if anything is not finite).
    ///
    /// The stage combinations run with the widest vector instructions the machine has
    /// (AVX2 where available, [`pulp::Arch`]), as do the calls of `f` when the compiler
    /// inlines them: the same operations in the same order (no fused multiply-add), so the
    /// results are bit-identical on every machine.
    pub fn try_step<F: FnMut(f64, &[f64], &mut [f64])>(
        &mut self,
        f: &mut F,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> f64 {
        struct Op<'s, 'f, 'y, F> {
            dp: &'s mut Dopri5,
            f: &'f mut F,
            t: f64,
            y: &'y [f64],
            h: f64,
        }
        impl<F: FnMut(f64, &[f64], &mut [f64])> pulp::WithSimd for Op<'_, '_, '_, F> {
            type Output = f64;
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _: S) -> f64 {
                self.dp.try_step_body(self.f, self.t, self.y, self.h)
            }
        }
        let arch = self.arch;
        arch.dispatch(Op {
            dp: self,
            f,
            t,
            y,
            h,
        })
    }

    #[inline(always)]
    fn try_step_body<F: FnMut(f64, &[f64], &mut [f64])>(
        &mut self,
        f: &mut F,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> f64 {
        let n = self.dim;
        let [k1, k2, k3, k4, k5, k6, k7] = &mut self.k;
        let (k1, k2, k3, k4, k5, k6, k7) = (
            &mut k1[..n],
            &mut k2[..n],
            &mut k3[..n],
            &mut k4[..n],
            &mut k5[..n],
            &mut k6[..n],
            &mut k7[..n],
        );
        let yt = &mut self.ytmp[..n];
        let y = &y[..n];
        // Every component a stage reads is re-sliced to length n above, so the loops below
        // carry no bounds checks and vectorise.
        for i in 0..n {
            yt[i] = y[i] + h * A21 * k1[i];
        }
        f(t + C2 * h, yt, k2);
        for i in 0..n {
            yt[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i]);
        }
        f(t + C3 * h, yt, k3);
        for i in 0..n {
            yt[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
        }
        f(t + C4 * h, yt, k4);
        for i in 0..n {
            yt[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
        }
        f(t + C5 * h, yt, k5);
        for i in 0..n {
            yt[i] =
                y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
        }
        f(t + h, yt, k6);
        let y1 = &mut self.y1[..n];
        for i in 0..n {
            y1[i] =
                y[i] + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] + A76 * k6[i]);
        }
        f(t + h, y1, k7);
        // The weighted errors r_i² in a vector loop (into `ytmp`, free by now), then their
        // sum in index order: the same sum as one scalar loop.
        let ne = self.n_err;
        let atol = &self.atol[..ne];
        let rtol = self.rtol;
        let rr = &mut yt[..ne];
        for i in 0..ne {
            let e =
                h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
            let sc = atol[i] + rtol * y[i].abs().max(y1[i].abs());
            let r = e / sc;
            rr[i] = r * r;
        }
        let mut s = 0.0;
        for &r2 in rr.iter() {
            s += r2;
        }
        let err = (s / ne as f64).sqrt();
        let mut finite = true;
        for x in y1.iter() {
            finite &= x.is_finite();
        }
        if !err.is_finite() || !finite {
            return f64::NAN;
        }
        err
    }

    /// Builds the dense output of the step just tried (from `y` to `y1`, length `h`).
    pub fn prepare_dense(&mut self, t: f64, y: &[f64], h: f64) {
        struct Op<'s, 'y> {
            dp: &'s mut Dopri5,
            y: &'y [f64],
            h: f64,
        }
        impl pulp::WithSimd for Op<'_, '_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _: S) {
                self.dp.prepare_dense_body(self.y, self.h)
            }
        }
        let arch = self.arch;
        arch.dispatch(Op { dp: self, y, h });
        self.t0 = t;
        self.h = h;
    }

    #[inline(always)]
    fn prepare_dense_body(&mut self, y: &[f64], h: f64) {
        let n = self.dim;
        let [k1, _k2, k3, k4, k5, k6, k7] = &self.k;
        let (k1, k3, k4, k5, k6, k7) = (&k1[..n], &k3[..n], &k4[..n], &k5[..n], &k6[..n], &k7[..n]);
        let [r1, r2, r3, r4, r5] = &mut self.rcont;
        let (r1, r2, r3, r4, r5) = (
            &mut r1[..n],
            &mut r2[..n],
            &mut r3[..n],
            &mut r4[..n],
            &mut r5[..n],
        );
        let (y, y1) = (&y[..n], &self.y1[..n]);
        for i in 0..n {
            let ydiff = y1[i] - y[i];
            let bspl = h * k1[i] - ydiff;
            r1[i] = y[i];
            r2[i] = ydiff;
            r3[i] = bspl;
            r4[i] = ydiff - h * k7[i] - bspl;
            r5[i] =
                h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
        }
    }

    /// Dense output of component `i` at θ ∈ [0, 1] of the last prepared step.
    #[inline]
    pub fn dense(&self, i: usize, theta: f64) -> f64 {
        let t1 = 1.0 - theta;
        let r = &self.rcont;
        r[0][i] + theta * (r[1][i] + t1 * (r[2][i] + theta * (r[3][i] + t1 * r[4][i])))
    }

    /// The dense-output coefficients (r₁ … r₅) of component `i`, for [`dense_at`].
    #[inline]
    pub fn coefficients(&self, i: usize) -> [f64; 5] {
        std::array::from_fn(|k| self.rcont[k][i])
    }

    /// The coefficient r₅ of component `i`: the dense output is the cubic Hermite
    /// interpolant of the step's end values and slopes plus r₅ θ²(1−θ)².
    #[inline]
    pub fn quartic(&self, i: usize) -> f64 {
        self.rcont[4][i]
    }

    /// Time derivative of the dense output of component `i` at θ.
    #[inline]
    pub fn dense_rate(&self, i: usize, theta: f64) -> f64 {
        let r = &self.rcont;
        let d = r[1][i]
            + (1.0 - 2.0 * theta) * r[2][i]
            + theta * (2.0 - 3.0 * theta) * r[3][i]
            + 2.0 * theta * (1.0 - theta) * (1.0 - 2.0 * theta) * r[4][i];
        d / self.h
    }

    /// The whole state at θ into `out`.
    pub fn dense_all(&self, theta: f64, out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.dense(i, theta);
        }
    }

    /// Step-size factor for an error `err` of a step; returns (accepted, new h).
    pub fn control(&mut self, err: f64, h: f64, rejected_before: bool) -> (bool, f64) {
        let expo1 = 0.2 - BETA * 0.75;
        if err.is_nan() {
            return (false, 0.1 * h);
        }
        let fac11 = err.max(1e-300).powf(expo1);
        if err <= 1.0 {
            let mut fac = fac11 / self.facold.powf(BETA);
            fac = (fac / SAFE).clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
            let mut hnew = h / fac;
            if rejected_before {
                hnew = hnew.min(h);
            }
            self.facold = err.max(1e-4);
            (true, hnew)
        } else {
            (false, h / (fac11 / SAFE).min(1.0 / FAC_MIN))
        }
    }

    /// Commits the tried step: y ← y1, k\[0\] ← k\[6\] (FSAL).
    pub fn accept_full(&mut self, y: &mut [f64]) {
        y.copy_from_slice(&self.y1);
        let [k1, .., k7] = &mut self.k;
        k1.copy_from_slice(k7);
    }

    /// [`Dopri5::accept_full`] by swapping the buffers instead of copying them: afterwards
    /// `y1` and `k[6]` hold stale values (the next [`Dopri5::try_step`] overwrites both).
    pub fn accept_swap(&mut self, y: &mut Vec<f64>) {
        assert_eq!(y.len(), self.dim);
        std::mem::swap(y, &mut self.y1);
        self.k.swap(0, 6);
    }
}

/// [`Dopri5::dense`] from a component's coefficients ([`Dopri5::coefficients`]): the same
/// arithmetic, so the same value.
#[inline(always)]
pub fn dense_at(r: &[f64; 5], theta: f64) -> f64 {
    let t1 = 1.0 - theta;
    r[0] + theta * (r[1] + t1 * (r[2] + theta * (r[3] + t1 * r[4])))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harmonic_oscillator_and_dense_output() {
        // y'' = −y: y = (cos t, −sin t).
        let mut d = Dopri5::new(2, 2, 1e-10, vec![1e-13, 1e-13]);
        let mut f = |_t: f64, y: &[f64], o: &mut [f64]| {
            o[0] = y[1];
            o[1] = -y[0];
        };
        let mut y = vec![1.0, 0.0];
        let mut t = 0.0;
        f(t, &y.clone(), &mut d.k[0]);
        let mut h = d.initial_step(&mut f, t, &y.clone(), 1.0);
        let mut rej = false;
        let mut max_dense_err: f64 = 0.0;
        while t < 10.0 {
            h = h.min(10.0 - t);
            let err = d.try_step(&mut f, t, &y, h);
            let (ok, hn) = d.control(err, h, rej);
            if ok {
                d.prepare_dense(t, &y, h);
                for j in 1..4 {
                    let th = j as f64 / 4.0;
                    let tt = t + th * h;
                    max_dense_err = max_dense_err.max((d.dense(0, th) - tt.cos()).abs());
                    max_dense_err = max_dense_err.max((d.dense_rate(0, th) + tt.sin()).abs());
                }
                d.accept_full(&mut y);
                t += h;
            }
            rej = !ok;
            h = hn;
        }
        assert!((y[0] - 10f64.cos()).abs() < 1e-8, "{}", y[0] - 10f64.cos());
        assert!(max_dense_err < 1e-7, "{max_dense_err}");
    }
}
