//! The bilinear story law (kinematic hardening) against closed forms and invariants: the
//! monotonic envelope, elastic unloading over a 2F_y range, the area of the stabilised loop,
//! the energy balance ∫F du = spring + hardening + hysteretic energy, and trial / revert
//! leaving the committed state untouched.

use structure::model::{Bilinear, BilinearParams};

const P: BilinearParams = BilinearParams {
    stiffness: 4.0e9,
    yield_shear: 8.0e6,
    hardening_ratio: 0.02,
};

fn drive(s: &mut Bilinear, path: &[f64]) -> Vec<f64> {
    path.iter()
        .map(|&u| {
            let t = s.trial(u);
            s.commit();
            t.force
        })
        .collect()
}

#[test]
fn monotonic_loading_follows_the_bilinear_envelope() {
    let uy = P.yield_drift();
    let mut s = Bilinear::new(P);
    for i in 1..=400 {
        let u = 5.0 * uy * i as f64 / 400.0;
        let t = s.trial(u);
        s.commit();
        let expect = if u <= uy {
            P.stiffness * u
        } else {
            P.yield_shear + P.hardening_ratio * P.stiffness * (u - uy)
        };
        assert!(
            (t.force - expect).abs() <= 1e-12 * P.yield_shear * 5.0,
            "u = {u}: {} vs {expect}",
            t.force
        );
        let k = if u <= uy {
            P.stiffness
        } else {
            P.hardening_ratio * P.stiffness
        };
        // Exact arithmetic on the law's own constants: round-off (64 ε).
        assert!(
            (t.tangent - k).abs() <= 64.0 * f64::EPSILON * P.stiffness,
            "tangent at u = {u}"
        );
    }
    // One large step gives the same answer as many small ones (monotonic path).
    let mut big = Bilinear::new(P);
    let t = big.trial(5.0 * uy);
    assert!((t.force - s.evaluate(5.0 * uy).force).abs() <= 64.0 * f64::EPSILON * P.yield_shear);
}

#[test]
fn unloading_is_elastic_over_twice_the_yield_shear_then_yields_in_reverse() {
    let uy = P.yield_drift();
    let mut s = Bilinear::new(P);
    let f_max = drive(&mut s, &[3.0 * uy])[0];
    let (lo, hi) = s.elastic_range();
    assert!(
        (hi - 3.0 * uy).abs() <= 1e-12 * uy,
        "loaded point is the upper limit"
    );
    assert!(
        (hi - lo - 2.0 * uy).abs() <= 1e-12 * uy,
        "elastic range 2 F_y / k0"
    );
    // Unload elastically to the lower limit: force drops by exactly 2 F_y.
    let t = s.trial(lo);
    assert!(!t.yielded);
    assert!((f_max - t.force - 2.0 * P.yield_shear).abs() <= 64.0 * f64::EPSILON * P.yield_shear);
    // Beyond it the spring yields in reverse with the hardening tangent.
    let t = s.trial(lo - uy);
    assert!(t.yielded);
    assert!(
        (t.tangent - P.hardening_ratio * P.stiffness).abs() <= 64.0 * f64::EPSILON * P.stiffness
    );
}

#[test]
fn trial_and_revert_leave_the_committed_state_alone() {
    let uy = P.yield_drift();
    let mut s = Bilinear::new(P);
    drive(&mut s, &[2.0 * uy]);
    let before = s.clone();
    let _ = s.trial(10.0 * uy); // a rejected adaptive step
    s.revert();
    s.commit(); // nothing to commit after a revert
    assert_eq!(s.state(), before.state());
    assert_eq!(s.plastic_work(), before.plastic_work());
    // The next trial answers from the committed state, as if the rejected one never was.
    assert_eq!(s.trial(2.5 * uy), before.evaluate(2.5 * uy));
}

/// Symmetric cycles between ±u_a, each in `n` increments per quarter.
fn cycles(b: f64, ua_over_uy: f64, n_cycles: usize, n: usize) -> (Bilinear, f64, Vec<f64>) {
    let p = BilinearParams {
        hardening_ratio: b,
        ..P
    };
    let ua = ua_over_uy * p.yield_drift();
    let mut s = Bilinear::new(p);
    let mut path = Vec::new();
    for i in 1..=n {
        path.push(ua * i as f64 / n as f64);
    }
    for _ in 0..n_cycles {
        for i in 1..=2 * n {
            path.push(ua - 2.0 * ua * i as f64 / (2 * n) as f64);
        }
        for i in 1..=2 * n {
            path.push(-ua + 2.0 * ua * i as f64 / (2 * n) as f64);
        }
    }
    // Work of the story force by the trapezoidal rule (exact on each linear piece except
    // where a kink falls inside an increment).
    let mut work = 0.0;
    let (mut u0, mut f0) = (0.0, 0.0);
    let mut energies = Vec::new();
    for &u in &path {
        let t = s.trial(u);
        s.commit();
        work += 0.5 * (f0 + t.force) * (u - u0);
        (u0, f0) = (u, t.force);
        energies.push(s.hysteretic_energy());
    }
    (s, work, energies)
}

#[test]
fn energy_balance_closes_over_cycles() {
    for b in [0.0, 0.02, 0.1] {
        let (s, work, _) = cycles(b, 4.0, 3, 20_000);
        let st = s.state();
        let spring =
            0.5 * s.params.stiffness * (4.0 * s.params.yield_drift() - st.plastic_drift).powi(2);
        let stored = spring + s.hardening_energy();
        // The trapezoidal work is exact on a piecewise-linear law whose kinks are path
        // points: round-off over the path's points (passes at 1e-12).
        let rel = (work - stored - s.hysteretic_energy()).abs() / work;
        assert!(rel < 1e-11, "b = {b}: balance error {rel:e}");
    }
}

#[test]
fn loop_area_matches_the_closed_form() {
    // A stabilised symmetric cycle of amplitude u_a dissipates 4 F_y (1 − b)(u_a − u_y)
    // (the parallelogram between the plastic branches, 2 F_y (1 − b) apart vertically,
    // spanning 2 (u_a − u_y) of drift); for b = 0 the elastic–perfectly plastic 4 F_y (u_a − u_y).
    for b in [0.0, 0.02, 0.1] {
        let n = 20_000;
        let (s, _, e) = cycles(b, 4.0, 2, n);
        let per_cycle = e[e.len() - 1] - e[e.len() - 1 - 4 * n];
        let p = s.params;
        let expect = 4.0 * p.yield_shear * (1.0 - b) * (4.0 * p.yield_drift() - p.yield_drift());
        // Only round-off remains (every kink is a path point): the cycle's energy is the
        // difference of two running sums 4n increments apart, each increment adding at
        // most about one rounding (ε relative to the cycle's energy), so the bound is
        // 4n ε = 1.8e-11 for n = 20 000. Measured 2.1e-12 (b = 0), 7.4e-15 (0.02) and
        // 7.6e-14 (0.1): 8× below at the worst.
        let bound = (4 * n) as f64 * f64::EPSILON;
        assert!(
            ((per_cycle - expect) / expect).abs() < bound,
            "b = {b}: {per_cycle} vs {expect}"
        );
    }
}

#[test]
fn parameters_are_checked() {
    assert!(P.check().is_ok());
    for bad in [
        BilinearParams {
            stiffness: 0.0,
            ..P
        },
        BilinearParams {
            yield_shear: -1.0,
            ..P
        },
        BilinearParams {
            hardening_ratio: 1.0,
            ..P
        },
        BilinearParams {
            hardening_ratio: f64::NAN,
            ..P
        },
    ] {
        assert!(bad.check().is_err(), "{bad:?}");
    }
}
