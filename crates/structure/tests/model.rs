//! Model tests: closed-form frequencies, orthonormality, participation, calibration.

use proptest::prelude::*;
use structure::model::{calibrate_two_frequencies, Building};

const EPS: f64 = f64::EPSILON;

/// ω_n = 2√(k/m)·sin((2n−1)π/(2(2N+1))) for a uniform shear building of N floors.
#[test]
fn uniform_shear_building_frequencies_match_closed_form() {
    for &n in &[1usize, 2, 5, 15, 40] {
        let (m, k) = (2.0e6, 3.0e9);
        let modes = Building::uniform("u", n, m, k, 0.05).modes().unwrap();
        for i in 0..n {
            let exact = 2.0
                * (k / m).sqrt()
                * (((2 * (i + 1) - 1) as f64) * std::f64::consts::PI / (2.0 * (2 * n + 1) as f64))
                    .sin();
            let rel = (modes.omega[i] - exact).abs() / exact;
            assert!(
                rel < 200.0 * EPS * n as f64,
                "n={n} mode {i}: {} vs {exact} (rel {rel:e})",
                modes.omega[i]
            );
        }
    }
}

fn stick(masses: Vec<f64>, ks: Vec<f64>) -> Building {
    Building::new("r", masses, ks, 0.05)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// ‖Kφ − ω²Mφ‖ and ‖ΦᵀMΦ − I‖ at round-off for random sticks; Σφ_n[c]² = 1/m_c;
    /// effective masses sum to the total mass; modes sorted ascending.
    #[test]
    fn random_sticks_have_orthonormal_modes(
        spec in prop::collection::vec((1.0e5f64..5.0e6, 1.0e8f64..1.0e10), 1..25)
    ) {
        let (masses, ks): (Vec<f64>, Vec<f64>) = spec.into_iter().unzip();
        let n = masses.len();
        let b = stick(masses.clone(), ks);
        let modes = b.modes().unwrap();
        let (m, k) = (b.mass_matrix(), b.stiffness_matrix());
        let phi = &modes.phi;
        let kscale = k.norm();
        let tol = 1e3 * EPS * n as f64;
        for i in 0..n {
            let p = phi.column(i);
            let r = &k * p - modes.omega[i].powi(2) * (&m * p);
            prop_assert!(r.norm() <= tol * kscale * p.norm(), "residual {} mode {i}", r.norm());
            if i > 0 { prop_assert!(modes.omega[i] >= modes.omega[i - 1]); }
        }
        let ortho = phi.transpose() * &m * phi - nalgebra::DMatrix::<f64>::identity(n, n);
        prop_assert!(ortho.amax() <= tol, "PhiT M Phi - I = {}", ortho.amax());
        for c in 0..n {
            let w = modes.delassus(c);
            prop_assert!((w * masses[c] - 1.0).abs() <= tol, "sum phi^2 m_c = {}", w * masses[c]);
            let r = modes.contact_flexibility(c);
            prop_assert!((r[n - 1] - 1.0).abs() <= tol);
        }
        let eff: f64 = modes.effective_mass_ratios().iter().sum();
        prop_assert!((eff - 1.0).abs() <= tol, "effective mass ratios sum to {eff}");
        // Classical damping: Φᵀ C Φ = diag(2ζω).
        let c = b.damping_matrix(&modes);
        let cd = phi.transpose() * c * phi;
        for i in 0..n {
            for j in 0..n {
                let want = if i == j { 2.0 * 0.05 * modes.omega[i] } else { 0.0 };
                prop_assert!((cd[(i, j)] - want).abs() <= tol * modes.omega[n - 1]);
            }
        }
    }
}

#[test]
fn mode_signs_are_deterministic_top_floor_positive() {
    let modes = Building::uniform("u", 6, 1e6, 1e9, 0.05).modes().unwrap();
    for i in 0..6 {
        assert!(modes.phi[(5, i)] > 0.0);
    }
}

#[test]
fn story_shears_and_energies() {
    let b = stick(vec![1.0, 2.0, 3.0], vec![10.0, 20.0, 30.0]);
    let u = [0.1, 0.3, 0.2];
    let v = b.story_shears(&u);
    for (got, want) in v
        .iter()
        .zip([10.0 * 0.1, 20.0 * (0.3 - 0.1), 30.0 * (0.2 - 0.3)])
    {
        assert!(
            (got - want).abs() <= 4.0 * EPS * want.abs(),
            "{got} vs {want}"
        );
    }
    let k = b.stiffness_matrix();
    let uv = nalgebra::DVector::from_column_slice(&u);
    let e = 0.5 * uv.dot(&(&k * &uv));
    assert!((b.strain_energy(&u) - e).abs() < 1e-15);
}

#[test]
fn calibration_hits_both_targets() {
    for &(m, f1, f2) in &[
        (2.0e6, 0.67, 2.23),
        (2.4e6, 0.81, 3.06),
        (1.0e6, 1.0, 2.9),
        (1.0e6, 1.0, 3.0),
    ] {
        let c = calibrate_two_frequencies("b", 15, m, f1, f2, 0.05).unwrap();
        let f = c.building.modes().unwrap().frequencies_hz();
        // The root search stops at 1e-14: 1e-12 relative (measured ≤ 6e-14).
        assert!((f[0] - f1).abs() / f1 < 1e-12, "f1 {} vs {f1}", f[0]);
        assert!((f[1] - f2).abs() / f2 < 1e-12, "f2 {} vs {f2}", f[1]);
        assert!(c.building.story_stiffness.iter().all(|k| *k > 0.0));
    }
}

/// Calibrations are remembered per process by (floors, mass, f₁, f₂): a second call, under
/// another name and damping ratio, gives the same stiffnesses bit for bit, and inputs that
/// differ in any one of the four keys get their own calibration, each on its targets.
#[test]
fn remembered_calibrations_are_keyed_by_every_input() {
    let a = calibrate_two_frequencies("a", 12, 1.3e6, 0.7, 2.4, 0.05).unwrap();
    let again = calibrate_two_frequencies("other", 12, 1.3e6, 0.7, 2.4, 0.02).unwrap();
    assert_eq!(a.building.story_stiffness, again.building.story_stiffness);
    assert_eq!(again.building.name, "other");
    assert_eq!(
        again.building.damping,
        structure::model::Damping::Uniform(0.02)
    );
    // A bad damping ratio is refused as a fresh calibration refuses it, remembered targets
    // or not.
    let remembered = calibrate_two_frequencies("c", 12, 1.3e6, 0.7, 2.4, 1.5).unwrap_err();
    let fresh = calibrate_two_frequencies("c", 12, 1.35e6, 0.7, 2.4, 1.5).unwrap_err();
    assert_eq!(remembered.to_string(), fresh.to_string());
    for (n, m, f1, f2) in [
        (13, 1.3e6, 0.7, 2.4),
        (12, 1.4e6, 0.7, 2.4),
        (12, 1.3e6, 0.75, 2.4),
        (12, 1.3e6, 0.7, 2.5),
    ] {
        let c = calibrate_two_frequencies("b", n, m, f1, f2, 0.05).unwrap();
        assert_ne!(c.building.story_stiffness, a.building.story_stiffness);
        let f = c.building.modes().unwrap().frequencies_hz();
        assert!((f[0] - f1).abs() / f1 < 1e-12 && (f[1] - f2).abs() / f2 < 1e-12);
    }
}

#[test]
fn calibration_rejects_unreachable_targets() {
    assert!(calibrate_two_frequencies("b", 15, 1e6, 1.0, 1.2, 0.05).is_err());
    assert!(calibrate_two_frequencies("b", 15, 1e6, 2.0, 1.0, 0.05).is_err());
    assert!(calibrate_two_frequencies("b", 1, 1e6, 1.0, 3.0, 0.05).is_err());
}

#[test]
fn invalid_buildings_name_the_field() {
    let e = stick(vec![1.0, -2.0], vec![1.0, 1.0])
        .validate()
        .unwrap_err()
        .to_string();
    assert!(e.contains("masses[1]"), "{e}");
    let e = stick(vec![1.0, 2.0], vec![1.0])
        .validate()
        .unwrap_err()
        .to_string();
    assert!(e.contains("story_stiffness"), "{e}");
}
