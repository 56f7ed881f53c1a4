//! The Dormand–Prince 5(4) stepper against Hairer's `dopri5.f` on the Arenstorf orbit
//! (Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.0 and the driver `dr_dop5.f`):
//! rtol = atol = 1e-7, initial step 1e-4, end point one period. The step counts
//! (238 steps, 217 accepted, 21 rejected, 1429 right-hand-side evaluations) and the final
//! state are those of `dopri5.f`, as pinned by russell_ode's `test_dopri5_arenstorf`.
//! Any change to the tableau, the error norm or the step controller changes these counts.

use solvers::gap::dopri::Dopri5;

const MU: f64 = 0.012277471;
const T_END: f64 = 17.065_216_560_157_962_558_891_720_624_9;
/// The initial state of `dr_dop5.f`, with the driver's digits (more than an f64 holds).
#[allow(clippy::excessive_precision)]
const Y0: [f64; 4] = [0.994, 0.0, 0.0, -2.001_585_106_379_082_522_405_378_622_24];

fn arenstorf(_t: f64, y: &[f64], f: &mut [f64]) {
    let mup = 1.0 - MU;
    let d1 = ((y[0] + MU).powi(2) + y[1].powi(2)).powf(1.5);
    let d2 = ((y[0] - mup).powi(2) + y[1].powi(2)).powf(1.5);
    f[0] = y[2];
    f[1] = y[3];
    f[2] = y[0] + 2.0 * y[3] - mup * (y[0] + MU) / d1 - MU * (y[0] - mup) / d2;
    f[3] = y[1] - 2.0 * y[2] - mup * y[1] / d1 - MU * y[1] / d2;
}

/// The driver loop of `dopri5.f` (end-point rule `x + 1.01 h > xend`, hmax = xend − x0).
struct Counts {
    steps: u64,
    accepted: u64,
    rejected: u64,
    /// Rejections after the first accepted step (what `dopri5.f` reports as `NREJCT`).
    rejected_after_first: u64,
    rhs: u64,
}

fn integrate(y: &mut [f64], h_init: Option<f64>, tol: f64) -> Counts {
    let mut d = Dopri5::new(4, 4, tol, vec![tol; 4]);
    let mut rhs = 0u64;
    let mut f = |t: f64, y: &[f64], o: &mut [f64]| {
        rhs += 1;
        arenstorf(t, y, o)
    };
    let mut t = 0.0;
    let hmax = T_END;
    f(t, y, &mut d.k[0]);
    let mut h = match h_init {
        Some(h) => h,
        None => d.initial_step(&mut f, t, y, hmax),
    };
    let (mut steps, mut accepted, mut rejected, mut after) = (0u64, 0u64, 0u64, 0u64);
    let mut reject = false;
    loop {
        let mut last = false;
        if t + 1.01 * h - T_END > 0.0 {
            h = T_END - t;
            last = true;
        }
        steps += 1;
        let err = d.try_step(&mut f, t, y, h);
        let (ok, hnew) = d.control(err, h, reject);
        if ok {
            accepted += 1;
            d.accept_full(y);
            t += h;
            if last {
                break;
            }
            reject = false;
            h = hnew.min(hmax);
        } else {
            rejected += 1;
            after += u64::from(accepted > 0);
            reject = true;
            h = hnew;
        }
        assert!(steps < 100_000, "no progress at t = {t}");
    }
    Counts {
        steps,
        accepted,
        rejected,
        rejected_after_first: after,
        rhs,
    }
}

#[test]
fn dopri5_arenstorf_matches_dopri5_f_step_counts() {
    let mut y = Y0;
    let c = integrate(&mut y, Some(1e-4), 1e-7);
    assert_eq!(
        (c.steps, c.accepted, c.rejected, c.rhs),
        (238, 217, 21, 1429)
    );
    let y_ref = [
        0.9940021704037415,
        9.040893396741956e-06,
        0.0014597586885445324,
        -2.0012455157289244,
    ];
    for (a, b) in y.iter().zip(y_ref) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
}

/// With the starting step of `initial_step` (HINIT): `dr_dop5.f`'s published run,
/// "tol=0.10D-06 fcn= 1442 step= 240 accpt= 216 rejct= 22" and
/// Y(XEND) = (0.9940021016, 0.8911185692e-5). `dopri5.f` counts NREJCT only after the
/// first accepted step; the two rejections before it are in `steps`.
#[test]
fn dopri5_arenstorf_with_hinit_matches_dr_dop5() {
    let mut y = Y0;
    let c = integrate(&mut y, None, 1e-7);
    assert_eq!(
        (
            c.rhs,
            c.steps,
            c.accepted,
            c.rejected_after_first,
            c.rejected
        ),
        (1442, 240, 216, 22, 24)
    );
    assert!((y[0] - 0.9940021016).abs() < 1e-9, "{}", y[0]);
    assert!((y[1] - 0.8911185692e-5).abs() < 1e-9, "{}", y[1]);
}
