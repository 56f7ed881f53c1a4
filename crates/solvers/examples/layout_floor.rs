//! The cost floor of a block layout for the momentum method (`benches/common/layout_floor.rs`,
//! issue 10) on the paper scene.
//!
//! - `cargo run --release -p solvers --example layout_floor -- N` runs the floor N times
//!   (for `valgrind --tool=callgrind`: the instructions of one run are those of 2 runs less
//!   those of 1);
//! - `… -- R compare` times, in R rounds, the floor, the momentum solver and the adaptive
//!   gap element at k = 1e12 N/m, tol 1e-4 (fastest of 5 batches each, alternated in one
//!   process) and prints the ratios (criterion's `cargo bench -p solvers --bench
//!   layout_floor` measures the same three).
//!
//! Its tests (run by `cargo test`) check that the floor does the solver's work: without
//! contact its sampled peaks are those of the momentum solver's history.

#[path = "../benches/common/layout_floor.rs"]
mod floor;

use solvers::momentum::Problem;

/// Fastest of `rounds` batches of `n` calls of `f`, ms per call.
fn fastest(rounds: usize, n: usize, mut f: impl FnMut()) -> f64 {
    (0..rounds)
        .map(|_| {
            let t = std::time::Instant::now();
            for _ in 0..n {
                f();
            }
            t.elapsed().as_secs_f64() * 1e3 / n as f64
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = a.first().and_then(|s| s.parse().ok()).unwrap_or(1);
    let scene = structure::testing::paper_scene(&[]);
    let p = Problem::new(&scene).expect("paper scene");
    let l = floor::layout(&p, &scene);
    if a.get(1).map(String::as_str) == Some("compare") {
        // The floor against the solvers of the `paper_scene` benchmark's first two cases, in
        // this process, alternated: fastest of 5 batches each, per round.
        let gap = structure::testing::paper_scene(&[
            "gap_element.law=linear",
            "gap_element.stiffness=1e12",
            "gap_element.tolerance=1e-4",
        ]);
        for round in 0..n {
            let fl = fastest(5, 50, || {
                std::hint::black_box(floor::run(std::hint::black_box(&p), &l));
            });
            let mo = fastest(5, 50, || {
                std::hint::black_box(
                    solvers::run(&scene, solvers::Method::Momentum, None).unwrap(),
                );
            });
            let ge = fastest(5, 10, || {
                std::hint::black_box(solvers::run(&gap, solvers::Method::Gap, None).unwrap());
            });
            println!(
                "round {round}: floor {fl:.3} ms, momentum {mo:.3} ms, gap element (k = 1e12, \
                 tol = 1e-4) {ge:.3} ms: gap/floor {:.1}x, gap/momentum {:.1}x",
                ge / fl,
                ge / mo
            );
        }
        return;
    }
    let t = std::time::Instant::now();
    let mut c = floor::Counts::default();
    for _ in 0..n {
        c = std::hint::black_box(floor::run(std::hint::black_box(&p), &l));
    }
    eprintln!(
        "{:.3} ms per run; {} steps, {} rate sign changes, {} steps near contact; \
         (checksums {:.6e} {:.6e})",
        t.elapsed().as_secs_f64() * 1e3 / n as f64,
        c.steps,
        c.turns,
        c.closed_form,
        c.disp_max.iter().chain(&c.shear_max).flatten().sum::<f64>(),
        c.work
    );
}

#[cfg(test)]
mod tests {
    use super::floor;
    use solvers::momentum::Problem;

    /// Without contact (a 10 m gap), the floor's peaks sampled at the base steps are the
    /// momentum solver's peaks of the same samples (its history, sampled at the same steps):
    /// the same propagators, Φ and story stiffnesses, so equal up to the round-off of the
    /// sums (another order of the same terms).
    #[test]
    fn floor_peaks_are_the_solvers_sampled_peaks_without_contact() {
        let scene = structure::testing::paper_scene(&["contacts.0.gap=10"]);
        let p = Problem::new(&scene).unwrap();
        let c = floor::run(&p, &floor::layout(&p, &scene));
        assert_eq!(c.steps, p.n_steps);
        assert_eq!(c.closed_form, 0, "no step comes near a 10 m gap");
        let mut h = solvers::History::default();
        let out = solvers::run(&scene, solvers::Method::Momentum, Some(&mut h)).unwrap();
        assert!(out.impacts.is_empty());
        let mut o = 0;
        for (b, (d, s)) in c.disp_max.iter().zip(&c.shear_max).enumerate() {
            let peaks = |rows: &[Vec<f64>]| -> Vec<f64> {
                (o..o + d.len())
                    .map(|i| rows.iter().map(|r| r[i].abs()).fold(0.0, f64::max))
                    .collect()
            };
            let (hd, hs) = (peaks(&h.displacement), peaks(&h.story_shear));
            o += d.len();
            for (x, y) in d.iter().zip(&hd).chain(s.iter().zip(&hs)) {
                assert!(
                    (x - y).abs() <= 1e-12 * y.abs(),
                    "building {b}: {x} against {y}"
                );
            }
            // And below the continuous peaks, by at most a few per cent.
            let r = &out.buildings[b];
            for (x, y) in d.iter().zip(&r.floor_displacement_max) {
                assert!(*x <= *y * (1.0 + 1e-12) && *x >= 0.9 * y, "{x} against {y}");
            }
        }
    }
}
