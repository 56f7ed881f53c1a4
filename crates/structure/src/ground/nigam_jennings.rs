//! Exact one-step propagator for a damped oscillator under piecewise-linear load
//! (Nigam & Jennings 1969).
//!
//! For  x'' + 2ζω x' + ω² x = f(τ),  f(τ) = f₀ + (f₁ − f₀) τ/h  on 0 ≤ τ ≤ h, 0 ≤ ζ < 1:
//!
//! ```text
//! [x₁, v₁]ᵀ = A [x₀, v₀]ᵀ + B [f₀, f₁]ᵀ
//! ```
//!
//! With the particular solution x_p = α/ω² − 2ζβ/ω³ + βτ/ω² (α = f₀, β = (f₁−f₀)/h) and the
//! homogeneous part propagated by ω_d = ω√(1−ζ²), e = exp(−ζωh):
//! `x_h(h) = e[(cos ω_d h + ζω/ω_d sin ω_d h) x_h0 + sin(ω_d h)/ω_d v_h0]`,
//! `v_h(h) = e[−ω²/ω_d sin(ω_d h) x_h0 + (cos ω_d h − ζω/ω_d sin ω_d h) v_h0]`.
//! For ωh < 0.5 the closed form loses digits to cancellation, so A and B come instead from the
//! Taylor series of the exact solution (derivatives by the recursion
//! x⁽ᵏ⁺²⁾ = f⁽ᵏ⁾ − 2ζω x⁽ᵏ⁺¹⁾ − ω² x⁽ᵏ⁾), summed to 30 terms: exact to round-off there.

/// The propagator of one step of length `h`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Propagator {
    /// Maps the initial state [x₀, v₀].
    pub a: [[f64; 2]; 2],
    /// Maps the load at both ends [f₀, f₁].
    pub b: [[f64; 2]; 2],
}

/// The exact step response for (x₀, v₀) and the load f₀ → f₁, given e^{−ζωh} and
/// (sin ω_d h, cos ω_d h) (computed once for the four columns of the propagator).
#[allow(clippy::too_many_arguments)]
#[inline]
fn closed_form_with(
    omega: f64,
    zeta: f64,
    h: f64,
    (e, (s, c)): (f64, (f64, f64)),
    x0: f64,
    v0: f64,
    f0: f64,
    f1: f64,
) -> (f64, f64) {
    let alpha = f0;
    let beta = (f1 - f0) / h;
    let w2 = omega * omega;
    let bb = beta / w2;
    let aa = alpha / w2 - 2.0 * zeta * beta / (w2 * omega);
    let wd = omega * (1.0 - zeta * zeta).sqrt();
    let xh0 = x0 - aa;
    let vh0 = v0 - bb;
    let xh = e * ((c + zeta * omega / wd * s) * xh0 + s / wd * vh0);
    let vh = e * (-w2 / wd * s * xh0 + (c - zeta * omega / wd * s) * vh0);
    (xh + aa + bb * h, vh + bb)
}

const TERMS: usize = 30;

/// The Taylor series of the step (ωh < 0.5) for four initial states and loads at once,
/// lane by lane (each lane the same arithmetic as one scalar series: the same bits).
/// Scaled derivatives D_k = x^(k) h^k / k!: D_{k+2} = (g_k h² − 2ζωh (k+1) D_{k+1} − ω²h² D_k)
/// / ((k+1)(k+2)), with g_k h^k / k! = f0 (k = 0), f' h (k = 1), 0 otherwise; then
/// x = Σ_k D_k and v = Σ_k x^(k+1) h^k / k! = (1/h) Σ_k (k+1) D_{k+1}, summed from the
/// highest term.
fn taylor4(omega: f64, zeta: f64, h: f64, z: [[f64; 4]; 4]) -> [(f64, f64); 4] {
    let [x0, v0, f0, f1] = z;
    let fdot_h: [f64; 4] = std::array::from_fn(|i| f1[i] - f0[i]);
    let (wh, two_zwh) = (omega * h, 2.0 * zeta * omega * h);
    let wh2 = wh * wh;
    let mut d = [[0.0f64; 4]; TERMS + 2];
    d[0] = x0;
    d[1] = v0.map(|v| v * h);
    for k in 0..TERMS {
        let g: [f64; 4] = match k {
            0 => f0.map(|f| f * h * h),
            1 => fdot_h.map(|f| f * h * h),
            _ => [0.0; 4],
        };
        let kf = k as f64;
        let den = (kf + 1.0) * (kf + 2.0);
        d[k + 2] = std::array::from_fn(|i| {
            (g[i] - two_zwh * (kf + 1.0) * d[k + 1][i] - wh2 * d[k][i]) / den
        });
    }
    // (`Iterator::sum` of f64 folds from −0.0.)
    let mut x = [-0.0f64; 4];
    for dk in d.iter().rev() {
        x = std::array::from_fn(|i| x[i] + dk[i]);
    }
    let mut v = [-0.0f64; 4];
    for k in (1..TERMS + 2).rev() {
        v = std::array::from_fn(|i| v[i] + k as f64 * d[k][i]);
    }
    std::array::from_fn(|i| (x[i], v[i] / h))
}

impl Propagator {
    /// Propagator for x'' + 2ζωx' + ω²x = f over a step `h` (ω > 0, 0 ≤ ζ < 1, h ≥ 0).
    pub fn new(omega: f64, zeta: f64, h: f64) -> Self {
        if h == 0.0 {
            return Propagator {
                a: [[1.0, 0.0], [0.0, 1.0]],
                b: [[0.0, 0.0], [0.0, 0.0]],
            };
        }
        // The responses to the four unit columns (x₀, v₀, f₀, f₁) = e_i.
        let [c0, c1, c2, c3] = if omega * h < 0.5 {
            let unit = |i: usize| std::array::from_fn(|k| if k == i { 1.0 } else { 0.0 });
            taylor4(omega, zeta, h, [unit(0), unit(1), unit(2), unit(3)])
        } else {
            let e = (-zeta * omega * h).exp();
            let wd = omega * (1.0 - zeta * zeta).sqrt();
            let t = (e, (wd * h).sin_cos());
            let eval = |x0, v0, f0, f1| closed_form_with(omega, zeta, h, t, x0, v0, f0, f1);
            [
                eval(1.0, 0.0, 0.0, 0.0),
                eval(0.0, 1.0, 0.0, 0.0),
                eval(0.0, 0.0, 1.0, 0.0),
                eval(0.0, 0.0, 0.0, 1.0),
            ]
        };
        Propagator {
            a: [[c0.0, c1.0], [c0.1, c1.1]],
            b: [[c2.0, c3.0], [c2.1, c3.1]],
        }
    }

    /// Advances (x₀, v₀) over the step with load f₀ at the start and f₁ at the end.
    #[inline]
    pub fn step(&self, x0: f64, v0: f64, f0: f64, f1: f64) -> (f64, f64) {
        (
            self.a[0][0] * x0 + self.a[0][1] * v0 + self.b[0][0] * f0 + self.b[0][1] * f1,
            self.a[1][0] * x0 + self.a[1][1] * v0 + self.b[1][0] * f0 + self.b[1][1] * f1,
        )
    }
}

/// Acceleration x'' = f − 2ζωx' − ω²x.
#[inline]
pub fn acceleration(omega: f64, zeta: f64, x: f64, v: f64, f: f64) -> f64 {
    f - 2.0 * zeta * omega * v - omega * omega * x
}
