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

fn closed_form(omega: f64, zeta: f64, h: f64, x0: f64, v0: f64, f0: f64, f1: f64) -> (f64, f64) {
    let alpha = f0;
    let beta = (f1 - f0) / h;
    let w2 = omega * omega;
    let bb = beta / w2;
    let aa = alpha / w2 - 2.0 * zeta * beta / (w2 * omega);
    let wd = omega * (1.0 - zeta * zeta).sqrt();
    let e = (-zeta * omega * h).exp();
    let (s, c) = (wd * h).sin_cos();
    let xh0 = x0 - aa;
    let vh0 = v0 - bb;
    let xh = e * ((c + zeta * omega / wd * s) * xh0 + s / wd * vh0);
    let vh = e * (-w2 / wd * s * xh0 + (c - zeta * omega / wd * s) * vh0);
    (xh + aa + bb * h, vh + bb)
}

fn taylor(omega: f64, zeta: f64, h: f64, x0: f64, v0: f64, f0: f64, f1: f64) -> (f64, f64) {
    const TERMS: usize = 30;
    let fdot_h = f1 - f0; // f' · h
                          // Scaled derivatives D_k = x^(k) h^k / k!: D_{k+2} = (g_k h² − 2ζωh (k+1) D_{k+1} − ω²h² D_k) / ((k+1)(k+2)),
                          // with g_k h^k / k! = f0 (k = 0), fdot_h (k = 1), 0 otherwise.
    let (wh, two_zwh) = (omega * h, 2.0 * zeta * omega * h);
    let wh2 = wh * wh;
    let mut d = [0.0f64; TERMS + 2];
    d[0] = x0;
    d[1] = v0 * h;
    for k in 0..TERMS {
        let g = match k {
            0 => f0 * h * h,
            1 => fdot_h * h * h,
            _ => 0.0,
        };
        let kf = k as f64;
        d[k + 2] = (g - two_zwh * (kf + 1.0) * d[k + 1] - wh2 * d[k]) / ((kf + 1.0) * (kf + 2.0));
    }
    let x: f64 = d.iter().rev().sum();
    // v = Σ_k x^(k+1) h^k / k! = (1/h) Σ_k (k+1) D_{k+1}
    let v: f64 = (1..TERMS + 2).rev().map(|k| k as f64 * d[k]).sum::<f64>() / h;
    (x, v)
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
        let eval = |x0, v0, f0, f1| {
            if omega * h < 0.5 {
                taylor(omega, zeta, h, x0, v0, f0, f1)
            } else {
                closed_form(omega, zeta, h, x0, v0, f0, f1)
            }
        };
        let c0 = eval(1.0, 0.0, 0.0, 0.0);
        let c1 = eval(0.0, 1.0, 0.0, 0.0);
        let c2 = eval(0.0, 0.0, 1.0, 0.0);
        let c3 = eval(0.0, 0.0, 0.0, 1.0);
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
