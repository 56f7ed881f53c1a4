//! The gap element converges to the momentum method's rigid impact as the contact spring
//! stiffens, at order ½ in k (the contact lasts π/ω_c ∝ k^(−½): the penalty solution is
//! first order in k^(−½) away from the rigid one when both use the same restitution).
//!
//! Scene: two springy single-storey oscillators, one elastic impact (c_r = 1, linear law).
//! Compared: the displacements of both masses at a fixed time after the impact.

use solvers::{gap, momentum, History};
use structure::scene::ContactLaw;
use structure::testing::two_oscillators;
use structure::Scene;

fn scene(k: f64) -> Scene {
    // ω₁ = 6.3, ω₂ = 10 rad/s; first impact at ≈ 0.040 s, one impact before t = 0.3 s.
    let mut s = two_oscillators(1.0e4, 4.0e5, 2.0e4, 2.0e6, 0.5, 0.02, 1.0, 0.3);
    s.gap_element.law = ContactLaw::Linear;
    s.gap_element.stiffness = k;
    s.gap_element.tolerance = 1e-11;
    s
}

fn final_row(h: &History) -> (f64, Vec<f64>) {
    (
        *h.time.last().unwrap(),
        h.displacement.last().unwrap().clone(),
    )
}

#[test]
fn gap_element_converges_to_the_momentum_answer_with_order_one_half_in_k() {
    let mut hm = History::default();
    let mref = momentum::solve(&scene(1e9), Some(&mut hm)).expect("momentum");
    assert_eq!(mref.impacts.len(), 1, "{:#?}", mref.impacts);
    let (tm, um) = final_row(&hm);
    assert!((tm - 0.3).abs() < 1e-12, "momentum history ends at {tm}");

    let ks = [1e8, 1e9, 1e10, 1e11, 1e12];
    let mut errs = Vec::new();
    for &k in &ks {
        let mut hg = History::default();
        let out = gap::solve(&scene(k), Some(&mut hg)).expect("gap");
        assert_eq!(out.impacts.len(), 1, "k={k}: {:#?}", out.impacts);
        let (tg, ug) = final_row(&hg);
        assert!((tg - 0.3).abs() < 1e-12);
        let e = ug
            .iter()
            .zip(&um)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let imp = &out.impacts[0];
        eprintln!(
            "k={k:.0e}: |u_gap − u_mom|(0.3 s) = {e:.3e} m, contact {:.3e} s, rebound ratio {:.6} (momentum {:.6})",
            imp.duration.unwrap(),
            imp.achieved_restitution,
            mref.impacts[0].achieved_restitution
        );
        errs.push(e);
    }
    let lx: Vec<f64> = ks.iter().map(|k| k.ln()).collect();
    let ly: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let slope = lx
        .iter()
        .zip(&ly)
        .map(|(a, b)| (a - mx) * (b - my))
        .sum::<f64>()
        / lx.iter().map(|a| (a - mx).powi(2)).sum::<f64>();
    eprintln!("fitted log-log slope of the error against k: {slope:.3}");
    // Order ½ in k within ±0.06 (the band wall.rs uses for the same physics, [−0.55, −0.45],
    // widened by 0.01 each side for the two-body scene): measured −0.490, 0.05 and 0.07 from
    // the edges; refuses k^-1/3 and k^-2/3.
    assert!(
        (-0.56..=-0.44).contains(&slope),
        "order in k: {slope} (errors {errs:?})"
    );
    for w in errs.windows(2) {
        assert!(w[1] < w[0], "{errs:?}");
    }
}
