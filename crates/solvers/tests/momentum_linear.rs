//! No contact: linear in the PGA and equal to a fine-step RK4 of the full physical model.

use solvers::momentum::solve;
use solvers::History;
use structure::testing::paper_scene_path;
use structure::Scene;

fn scene(pga: f64, duration: f64) -> Scene {
    let ov = vec![
        format!("ground_motion.pga={pga}"),
        "contacts.0.gap=10.0".into(),
        format!("analysis.duration={duration}"),
    ];
    Scene::from_file_with_overrides(&paper_scene_path(), &ov).unwrap()
}

#[test]
fn response_is_linear_in_pga() {
    let (a, b) = (
        solve(&scene(0.1, 40.0), None).unwrap(),
        solve(&scene(0.2, 40.0), None).unwrap(),
    );
    assert!(a.impacts.is_empty() && b.impacts.is_empty());
    for (x, y) in a.buildings.iter().zip(&b.buildings) {
        for (p, q) in x.story_shear_max.iter().zip(&y.story_shear_max) {
            assert!((q / p - 2.0).abs() < 1e-12, "{q} / {p}");
        }
        for (p, q) in x
            .floor_displacement_max
            .iter()
            .zip(&y.floor_displacement_max)
        {
            assert!((q / p - 2.0).abs() < 1e-12);
        }
    }
    let e = &b.energy;
    assert!(e.balance_error.abs() < 1e-10 * e.input.abs());
}

/// Samples at the record points, and peaks |u_i| and |V_j| over every RK4 step.
struct Reference {
    samples: Vec<Vec<f64>>,
    disp_max: Vec<f64>,
    shear_max: Vec<f64>,
}

/// RK4 with h = dt/50 on M ü + C u̇ + K u = −M 1 a_g (a_g linear between samples).
fn rk4(b: &structure::Building, ag: &dyn Fn(f64) -> f64, dt: f64, nsteps: usize) -> Reference {
    let modes = b.modes().unwrap();
    let (m, k, c) = (
        b.mass_matrix(),
        b.stiffness_matrix(),
        b.damping_matrix(&modes),
    );
    let n = b.n_floors();
    let minv: Vec<f64> = (0..n).map(|i| 1.0 / m[(i, i)]).collect();
    let rhs = |t: f64, u: &[f64], v: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|i| {
                let f: f64 = (0..n).map(|j| k[(i, j)] * u[j] + c[(i, j)] * v[j]).sum();
                -ag(t) - f * minv[i]
            })
            .collect()
    };
    let h = dt / 50.0;
    let (mut u, mut v) = (vec![0.0; n], vec![0.0; n]);
    let mut out = vec![u.clone()];
    let (mut disp_max, mut shear_max) = (vec![0.0f64; n], vec![0.0f64; n]);
    let mut t = 0.0;
    for _ in 0..nsteps {
        for _ in 0..50 {
            let a1 = rhs(t, &u, &v);
            let (u2, v2): (Vec<f64>, Vec<f64>) = (0..n)
                .map(|i| (u[i] + 0.5 * h * v[i], v[i] + 0.5 * h * a1[i]))
                .unzip();
            let a2 = rhs(t + 0.5 * h, &u2, &v2);
            let (u3, v3): (Vec<f64>, Vec<f64>) = (0..n)
                .map(|i| (u[i] + 0.5 * h * v2[i], v[i] + 0.5 * h * a2[i]))
                .unzip();
            let a3 = rhs(t + 0.5 * h, &u3, &v3);
            let (u4, v4): (Vec<f64>, Vec<f64>) =
                (0..n).map(|i| (u[i] + h * v3[i], v[i] + h * a3[i])).unzip();
            let a4 = rhs(t + h, &u4, &v4);
            for i in 0..n {
                u[i] += h / 6.0 * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
                v[i] += h / 6.0 * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i]);
            }
            t += h;
            for i in 0..n {
                let below = if i > 0 { u[i - 1] } else { 0.0 };
                disp_max[i] = disp_max[i].max(u[i].abs());
                shear_max[i] = shear_max[i].max((b.story_stiffness[i] * (u[i] - below)).abs());
            }
        }
        out.push(u.clone());
    }
    Reference {
        samples: out,
        disp_max,
        shear_max,
    }
}

#[test]
fn equals_fine_step_rk4_of_the_full_model() {
    let s = scene(0.4, 8.0);
    let mut hist = History::default();
    let out = solve(&s, Some(&mut hist)).unwrap();
    let g = s.ground.as_ref().unwrap();
    let dt = g.dt;
    let nsteps = (8.0 / dt).round() as usize;
    let ag = |t: f64| g.accel_at(t);
    let nf0 = s.buildings[0].n_floors();
    for (b, bd) in s.buildings.iter().enumerate() {
        let reference = rk4(bd, &ag, dt, nsteps);
        let off = if b == 0 { 0 } else { nf0 };
        let scale = reference
            .samples
            .iter()
            .flatten()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let mut worst = 0.0f64;
        let mut compared = 0;
        for (row_t, row) in hist.time.iter().zip(&hist.displacement) {
            let k = (row_t / dt).round();
            if (row_t - k * dt).abs() > 1e-9 {
                continue;
            }
            compared += 1;
            let r = &reference.samples[k as usize];
            for i in 0..bd.n_floors() {
                worst = worst.max((row[off + i] - r[i]).abs());
            }
        }
        // Without contact the history has a row at every record point, 0 … 8 s.
        assert_eq!(compared, nsteps + 1, "building {b}: rows compared");
        // RK4 at h = dt/50 = 1e-4 s: its truncation error, of order (ωh)⁴, is below its
        // round-off, which grows with its N = 50 × 1600 = 80 000 steps: the difference is
        // 8.8e-12 and 2.4e-11 of the peak for the two buildings (0.5 and 1.35 N ε), and grows
        // to 4.1e-11 and 6.0e-11 when h is halved (measured). Asserted within 8 N ε (1.4e-10 of
        // the peak).
        let rk4_steps = (50 * nsteps) as f64;
        assert!(
            worst < 8.0 * rk4_steps * f64::EPSILON * scale,
            "building {b}: max diff {worst:e} vs peak {scale:e}"
        );
        // Continuous peaks against the peaks over every RK4 step (1e-4 s apart: their own
        // sampling error is below (ω h)²/8 ≈ 5e-6 for the highest modes that matter).
        let r = &out.buildings[b];
        for i in 0..bd.n_floors() {
            for (cont, refp) in [
                (r.floor_displacement_max[i], reference.disp_max[i]),
                (r.story_shear_max[i], reference.shear_max[i]),
            ] {
                let rel = (cont - refp) / cont;
                // Below: only RK4's own error (measured rel ≥ +1.4e-11); above: its sampling.
                assert!(
                    (-1e-9..1e-5).contains(&rel),
                    "building {b} floor/story {i}: continuous {cont:e}, RK4 {refp:e} ({rel:e})"
                );
            }
        }
    }
}
