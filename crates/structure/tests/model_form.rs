//! Model-form options: a tapered stick fitted to its first frequency (the uniform stick as
//! the ratio-1 case, checked against the closed form), Rayleigh damping as per-mode ratios
//! (checked against C = a M + b K), and the scene keys `top_stiffness_ratio` and
//! `rayleigh_modes`.

use std::f64::consts::PI;
use std::path::Path;

use structure::model::{calibrate_first_frequency, top_to_ground, Building, Damping, Rayleigh};
use structure::Scene;

const EPS: f64 = f64::EPSILON;

#[test]
fn uniform_stick_fitted_to_f1_matches_the_closed_form() {
    // Uniform stick, N floors: ω_n = 2 √(k/m) sin((2n − 1) π / (2 (2N + 1))).
    // Calibration by exact scaling of the eigenproblem: round-off, within 64·n·ε (measured
    // 3.7e-14).
    for &(n, m, f1) in &[(15usize, 2.0e6, 0.67), (15, 2.4e6, 0.81), (3, 1.0, 1.0)] {
        let tol = 64.0 * 15.0 * EPS;
        let c = calibrate_first_frequency("b", n, m, f1, 1.0, 0.05).unwrap();
        let f = c.building.modes().unwrap().frequencies_hz();
        assert!((f[0] - f1).abs() / f1 < tol, "f1 {} vs {f1}", f[0]);
        let s1 = (PI / (2.0 * (2 * n + 1) as f64)).sin();
        let k = m * (2.0 * PI * f1 / (2.0 * s1)).powi(2);
        for kj in &c.building.story_stiffness {
            assert!((kj - k).abs() / k < tol, "story stiffness {kj} vs {k}");
        }
        // The second mode of the uniform stick, from the closed form.
        let s2 = (3.0 * PI / (2.0 * (2 * n + 1) as f64)).sin();
        assert!((f[1] / f[0] - s2 / s1).abs() < tol * s2 / s1);
        assert_eq!(c.taper, 0.0);
    }
}

#[test]
fn tapered_stick_has_the_requested_ratio_and_f1() {
    for &r in &[0.45, 2.8, 8.7, 0.02] {
        let c = calibrate_first_frequency("b", 15, 2.0e6, 0.67, r, 0.05).unwrap();
        let k = &c.building.story_stiffness;
        assert!((top_to_ground(&c.building) - r).abs() <= 8.0 * EPS * r.max(1.0));
        assert!((c.top_to_ground_ratio() - r).abs() <= 8.0 * EPS * r.max(1.0));
        assert_eq!(k[0], c.k_base);
        // Linear: constant first differences.
        let d0 = k[1] - k[0];
        for w in k.windows(2) {
            assert!(((w[1] - w[0]) - d0).abs() <= 64.0 * EPS * k[0].max(k[14]));
        }
        let f = c.building.modes().unwrap().frequencies_hz();
        assert!(
            (f[0] - 0.67).abs() / 0.67 < 64.0 * 15.0 * EPS,
            "f1 {}",
            f[0]
        );
    }
    // A softer top lowers f2/f1 below the uniform stick's, a stiffer top raises it.
    let ratio = |r: f64| {
        let f = calibrate_first_frequency("b", 15, 1.0, 1.0, r, 0.05)
            .unwrap()
            .building
            .modes()
            .unwrap()
            .frequencies_hz();
        f[1] / f[0]
    };
    assert!(ratio(0.45) < ratio(1.0) && ratio(1.0) < ratio(2.8));
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(calibrate_first_frequency("b", 15, 1.0, 1.0, bad, 0.05).is_err());
    }
    assert!(calibrate_first_frequency("b", 15, 1.0, 0.0, 1.0, 0.05).is_err());
    assert!(calibrate_first_frequency("b", 1, 1.0, 1.0, 0.5, 0.05).is_err());
}

#[test]
fn rayleigh_ratios_hit_the_anchors_and_equal_a_m_plus_b_k() {
    let c = calibrate_first_frequency("b", 15, 2.0e6, 0.67, 0.45, 0.05).unwrap();
    let mut b = c.building;
    let omega = b.modes().unwrap().omega;
    let r = b.set_rayleigh_damping(0.05, 0, 2).unwrap();
    let Damping::PerMode(z) = &b.damping else {
        panic!("per-mode ratios expected, got {:?}", b.damping)
    };
    assert_eq!(z.len(), 15);
    assert!((z[0] - 0.05).abs() <= 4.0 * EPS * 0.05);
    assert!((z[2] - 0.05).abs() <= 4.0 * EPS * 0.05);
    // Between the anchors below the target, outside above it.
    assert!(z[1] < 0.05 && z[3] > 0.05 && z[14] > z[3]);
    // Independent reference: the classical damping matrix from the per-mode ratios equals
    // a M + b K.
    let modes = b.modes().unwrap();
    let cm = b.damping_matrix(&modes);
    let reference = b.mass_matrix() * r.a + b.stiffness_matrix() * r.b;
    let scale = reference.norm();
    assert!(
        (&cm - &reference).norm() <= 1e-12 * scale,
        "C differs from aM + bK by {:e} of {scale:e}",
        (&cm - &reference).norm()
    );
    // The ratios follow a/(2ω) + bω/2 with the closed-form a, b.
    let (wi, wj) = (omega[0], omega[2]);
    let (a, bb) = (2.0 * 0.05 * wi * wj / (wi + wj), 2.0 * 0.05 / (wi + wj));
    for (w, zn) in omega.iter().zip(z) {
        let want = a / (2.0 * w) + bb * w / 2.0;
        assert!((zn - want).abs() <= 16.0 * EPS * want, "{zn} vs {want}");
    }
    assert!(Rayleigh::through(0.05, 1.0, 1.0).is_none());
    assert!(Rayleigh::through(0.05, 0.0, 1.0).is_none());
    let mut b2 = Building::uniform("u", 3, 1.0, 1.0, 0.05);
    assert!(b2.set_rayleigh_damping(0.05, 0, 0).is_err());
    assert!(b2.set_rayleigh_damping(0.05, 0, 3).is_err());
    // Ratios of 1 or more are refused (overdamped modes).
    let mut b3 = Building::uniform("u", 15, 1.0, 1.0, 0.05);
    assert!(b3.set_rayleigh_damping(0.9, 0, 1).is_err());
}

fn scene(body: &str) -> Result<Scene, String> {
    let text = format!("[[buildings]]\nname = \"a\"\nstories = 15\nmass = 2.0e6\n{body}\n[analysis]\nduration = 1.0\n");
    Scene::from_str_with_overrides(&text, "t.toml", Path::new("."), &[]).map_err(|e| e.to_string())
}

#[test]
fn scene_keys_build_the_same_models() {
    let s = scene("target_frequencies_hz = [0.67]\ntop_stiffness_ratio = 0.45\nrayleigh_modes = [1, 3]\ndamping_ratio = 0.05").unwrap();
    let b = &s.buildings[0];
    let mut direct = calibrate_first_frequency("a", 15, 2.0e6, 0.67, 0.45, 0.05)
        .unwrap()
        .building;
    direct.set_rayleigh_damping(0.05, 0, 2).unwrap();
    assert_eq!(b.story_stiffness, direct.story_stiffness);
    assert_eq!(b.damping, direct.damping);

    let err = |body: &str, want: &[&str]| {
        let e = scene(body).unwrap_err();
        for w in want {
            assert!(e.contains(w), "`{e}` lacks `{w}`");
        }
    };
    err(
        "target_frequencies_hz = [0.67, 2.23]\ntop_stiffness_ratio = 0.45",
        &["buildings[0].top_stiffness_ratio", "two target frequencies"],
    );
    err(
        "story_stiffness = 1e9\ntop_stiffness_ratio = 0.45",
        &["buildings[0].top_stiffness_ratio", "story_stiffness"],
    );
    err(
        "target_frequencies_hz = [0.67]\ntop_stiffness_ratio = -1.0",
        &["buildings[0].top_stiffness_ratio", "> 0"],
    );
    err(
        "target_frequencies_hz = [0.67]",
        &["buildings[0].target_frequencies_hz", "top_stiffness_ratio"],
    );
    err(
        "story_stiffness = 1e9\nrayleigh_modes = [1, 16]",
        &["buildings[0].rayleigh_modes", "1 ..= 15"],
    );
    err(
        "story_stiffness = 1e9\nrayleigh_modes = [2, 2]",
        &["buildings[0].rayleigh_modes"],
    );
    err(
        "story_stiffness = 1e9\nrayleigh_modes = [1, 2]\ndamping_ratio = [0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05]",
        &["buildings[0].rayleigh_modes", "not a list"],
    );
    err(
        "story_stiffness = 1e9\nrayleigh_modes = [1, 2]\ndamping_ratio = 0.5",
        &["buildings[0].rayleigh_modes", "damping_ratio"],
    );
}
