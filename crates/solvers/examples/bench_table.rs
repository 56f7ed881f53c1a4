//! The speed table of the README from several runs of the `paper_scene` benchmark group:
//! `cargo run --release -p solvers --example bench_table -- RUN_DIR...` (what
//! `make bench-table` runs), where each `RUN_DIR` is a copy of criterion's
//! `target/criterion/paper_scene` taken after one run of
//! `cargo bench -p solvers --bench paper_scene`.
//!
//! Prints Markdown: per benchmark its fastest and slowest criterion median over the runs, its
//! ratio to the momentum method fastest against fastest with the range of the ratios within
//! runs, its deterministic work (from one run of each case here) and the time per unit of
//! work; then the project's three speed targets (issue 10) with how many runs meet each; then
//! every run's medians. Times are never compared across runs except as "fastest of N".
//! Exit 2 with a message naming the file if a run lacks a benchmark or its files do not parse.

use structure::testing::paper_scene as paper;

#[path = "../benches/common/paper_scene.rs"]
mod cases;

/// Criterion's median (ns) of benchmark `name` in one run directory.
fn median_ns(run: &std::path::Path, name: &str) -> Result<f64, String> {
    // Criterion's directory name of a function id: '/' becomes '_'.
    let dir = run.join(name.replace('/', "_")).join("new");
    let read = |file: &str| -> Result<serde_json::Value, String> {
        let path = dir.join(file);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            format!(
                "{}: {e} (is {} a run of paper_scene?)",
                path.display(),
                run.display()
            )
        })?;
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
    };
    let id = read("benchmark.json")?;
    if id["group_id"].as_str() != Some("paper_scene") || id["function_id"].as_str() != Some(name) {
        return Err(format!(
            "{}: holds benchmark {}/{}, expected paper_scene/{name}",
            dir.join("benchmark.json").display(),
            id["group_id"],
            id["function_id"]
        ));
    }
    read("estimates.json")?["median"]["point_estimate"]
        .as_f64()
        .filter(|t| t.is_finite() && *t > 0.0)
        .ok_or_else(|| {
            format!(
                "{}: expected median.point_estimate, a time > 0 (ns)",
                dir.join("estimates.json").display()
            )
        })
}

/// The work of one run of a case (deterministic) and its unit, for the table (`newmark`: the
/// gap element with the Newmark integrator, counted in Newton iterations).
fn work(
    out: &solvers::RunOutput,
    method: solvers::Method,
    newmark: bool,
) -> (String, f64, &'static str) {
    let st = &out.stats;
    let group = |n: u64| {
        let s = n.to_string();
        let mut g = String::new();
        for (i, c) in s.chars().enumerate() {
            if i > 0 && (s.len() - i).is_multiple_of(3) {
                g.push(' ');
            }
            g.push(c);
        }
        g
    };
    match method {
        solvers::Method::Momentum => {
            let modes: usize = out.r_n.first().map_or(0, |r| r.modes_left + r.modes_right);
            let ms = modes as u64 * st.steps;
            (
                format!("{} mode-steps, {} impacts", group(ms), out.impacts.len()),
                ms as f64,
                "mode-step",
            )
        }
        _ if newmark => (
            format!(
                "{} steps, {} Newton iterations",
                group(st.steps),
                group(st.newton_iterations)
            ),
            st.newton_iterations as f64,
            "Newton iteration",
        ),
        solvers::Method::Gap => (
            format!("{} right-hand sides", group(st.rhs_evaluations)),
            st.rhs_evaluations as f64,
            "right-hand side",
        ),
        solvers::Method::Impulse => (
            format!(
                "{} right-hand sides, {} impacts",
                group(st.rhs_evaluations),
                out.impacts.len()
            ),
            st.rhs_evaluations as f64,
            "right-hand side",
        ),
    }
}

/// `x` > 0 to three significant digits (rounded first, so 9.996 gives 10.0), without an
/// exponent: 2.53, 10.6, 199, 1590.
fn sig3(x: f64) -> String {
    let digits = |y: f64| y.abs().log10().floor() as i32;
    let scale = 10f64.powi(2 - digits(x));
    let y = (x * scale).round() / scale;
    let decimals = (2 - digits(y)).max(0) as usize;
    format!("{y:.decimals$}")
}

/// A time in ns as ms, three significant digits.
fn ms(ns: f64) -> String {
    format!("{} ms", sig3(ns * 1e-6))
}

/// A time per unit of work, three significant digits: ns, or µs from 1 000 ns (after
/// rounding).
fn per_unit(ns: f64) -> String {
    if ns >= 999.5 {
        format!("{} µs", sig3(ns * 1e-3))
    } else {
        format!("{} ns", sig3(ns))
    }
}

/// The ratio of the times `slow` to `fast` (one of each per run): fastest against fastest,
/// the least and largest ratio within a run, and how many runs reach `goal`.
#[derive(Debug, PartialEq)]
struct Ratio {
    fastest: f64,
    lo: f64,
    hi: f64,
    met: usize,
}

fn ratio(slow: &[f64], fast: &[f64], goal: f64) -> Ratio {
    let min = |t: &[f64]| t.iter().copied().fold(f64::INFINITY, f64::min);
    let within: Vec<f64> = slow.iter().zip(fast).map(|(s, f)| s / f).collect();
    Ratio {
        fastest: min(slow) / min(fast),
        lo: min(&within),
        hi: within.iter().copied().fold(0.0, f64::max),
        met: within.iter().filter(|&&x| x >= goal).count(),
    }
}

fn main() {
    if let Err(e) = run() {
        eprintln!("bench_table: {e}");
        std::process::exit(2);
    }
}

fn run() -> Result<(), String> {
    let table = table()?;
    // Written whole, once every run has been read: no partial table. A reader that stops
    // early (`| head`) is not an error.
    use std::io::Write;
    match std::io::stdout().lock().write_all(table.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(format!("stdout: {e}")),
        _ => Ok(()),
    }
}

/// The table (Markdown) of the runs named on the command line.
fn table() -> Result<String, String> {
    let mut out = String::new();
    // One line of the table.
    macro_rules! say {
        ($($t:tt)*) => {{
            out.push_str(&format!($($t)*));
            out.push('\n');
        }};
    }
    let runs: Vec<std::path::PathBuf> = std::env::args().skip(1).map(Into::into).collect();
    if runs.is_empty() {
        return Err(
            "expected one or more run directories (copies of target/criterion/paper_scene)".into(),
        );
    }
    let cases = cases::cases();
    // t[c][r]: the median of case c in run r, ns.
    let mut t = Vec::new();
    for (name, ..) in &cases {
        t.push(
            runs.iter()
                .map(|r| median_ns(r, name))
                .collect::<Result<Vec<f64>, String>>()?,
        );
    }
    let n = runs.len();
    let fastest = |c: usize| t[c].iter().copied().fold(f64::INFINITY, f64::min);
    let slowest = |c: usize| t[c].iter().copied().fold(0.0, f64::max);
    let runs_word = if n == 1 { "run" } else { "runs" };
    say!(
        "The `paper_scene` group in {n} {runs_word} of `cargo bench -p solvers --bench paper_scene`: the \
         time is the fastest of the {n} criterion medians (slowest in brackets), the ratio is \
         fastest against fastest with its range within runs (each ratio within one run).\n"
    );
    say!("| benchmark | time, fastest (slowest) of {n} | × momentum (range within runs) | work per run | per unit of work |");
    say!("|---|---|---|---|---|");
    for (c, (name, method, set)) in cases.iter().enumerate() {
        let scene = paper(set);
        let out = solvers::run(&scene, *method, None)
            .map_err(|e| format!("{name}: the run for its work counts failed: {e}"))?;
        let newmark = scene.gap_element.integrator == structure::scene::Integrator::Newmark;
        let (w, units, unit) = work(&out, *method, newmark);
        let x = if c == 0 {
            "1".to_string()
        } else {
            let r = ratio(&t[c], &t[0], f64::INFINITY);
            format!("{:.1}× ({:.1}–{:.1}×)", r.fastest, r.lo, r.hi)
        };
        say!(
            "| `paper_scene/{name}` | {} ({}) | {x} | {w} | {} per {unit} |",
            ms(fastest(c)),
            ms(slowest(c)),
            per_unit(fastest(c) / units)
        );
    }
    let idx = |name: &str| {
        cases
            .iter()
            .position(|c| c.0 == name)
            .expect("a case of the group")
    };
    let (mom, g12, g10, nm) = (
        idx("momentum"),
        idx("gap/k=1e12/tol=1e-4"),
        idx("gap/k=1e10/tol=1e-4"),
        idx("newmark/k=1e10/dt=1e-3"),
    );
    say!("\n| target (issue 10) | fastest against fastest | range within runs | runs meeting it |");
    say!("|---|---|---|---|");
    for (label, slow, fast, goal) in [
        (
            "momentum ≥ 10× the adaptive gap element at k = 1e12 N/m",
            g12,
            mom,
            10.0,
        ),
        ("momentum ≥ 25× Newmark at Δt = 1 ms", nm, mom, 25.0),
        (
            "adaptive gap element (k = 1e10 N/m) ≥ 5× Newmark",
            nm,
            g10,
            5.0,
        ),
    ] {
        let r = ratio(&t[slow], &t[fast], goal);
        say!(
            "| {label} | {:.1}× | {:.1}–{:.1}× | {} of {n} |",
            r.fastest,
            r.lo,
            r.hi,
            r.met
        );
    }
    say!(
        "\nMedians of each run, ms ({}):\n",
        cases.iter().map(|c| c.0).collect::<Vec<_>>().join(", ")
    );
    for r in 0..n {
        let row: Vec<String> = t.iter().map(|tc| format!("{:.3}", tc[r] * 1e-6)).collect();
        say!("- run {}: {}", r + 1, row.join(", "));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run directory as criterion writes it, with the given medians (ns) per benchmark.
    fn fake_run(dir: &std::path::Path, medians: &[(&str, f64)]) {
        for (name, t) in medians {
            let d = dir.join(name.replace('/', "_")).join("new");
            std::fs::create_dir_all(&d).unwrap();
            let id = serde_json::json!({"group_id": "paper_scene", "function_id": name});
            std::fs::write(d.join("benchmark.json"), id.to_string()).unwrap();
            let est = serde_json::json!({"median": {"point_estimate": t}});
            std::fs::write(d.join("estimates.json"), est.to_string()).unwrap();
        }
    }

    #[test]
    fn reads_criterion_medians_and_names_what_is_wrong() {
        let root = std::env::temp_dir().join(format!("pound-bench-table-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let run = root.join("1");
        fake_run(
            &run,
            &[("momentum", 2.5e6), ("gap/k=1e12/tol=1e-4", 1.06e7)],
        );
        assert_eq!(median_ns(&run, "momentum"), Ok(2.5e6));
        assert_eq!(median_ns(&run, "gap/k=1e12/tol=1e-4"), Ok(1.06e7));
        // A missing benchmark names the file it looked for.
        let e = median_ns(&run, "impulse/tol=1e-4").unwrap_err();
        assert!(
            e.contains("impulse_tol=1e-4") && e.contains("benchmark.json"),
            "{e}"
        );
        // Another benchmark's files under this name.
        let d = run.join("other").join("new");
        std::fs::create_dir_all(&d).unwrap();
        std::fs::copy(
            run.join("momentum/new/benchmark.json"),
            d.join("benchmark.json"),
        )
        .unwrap();
        let e = median_ns(&run, "other").unwrap_err();
        assert!(
            e.contains("holds benchmark \"paper_scene\"/\"momentum\", expected paper_scene/other"),
            "{e}"
        );
        // A median that is not a positive time.
        fake_run(&run, &[("momentum", -1.0)]);
        let e = median_ns(&run, "momentum").unwrap_err();
        assert!(
            e.contains("estimates.json") && e.contains("median.point_estimate"),
            "{e}"
        );
        std::fs::write(run.join("momentum/new/estimates.json"), "{").unwrap();
        assert!(median_ns(&run, "momentum")
            .unwrap_err()
            .contains("estimates.json"));
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn formats_three_significant_digits() {
        assert_eq!(ms(2.534e6), "2.53 ms");
        assert_eq!(ms(1.0612e7), "10.6 ms");
        assert_eq!(per_unit(10.49), "10.5 ns");
        assert_eq!(per_unit(198.6), "199 ns");
        assert_eq!(per_unit(1591.0), "1.59 µs");
        assert_eq!(per_unit(9.87), "9.87 ns");
        assert_eq!(ms(1.234e8), "123 ms");
        assert_eq!(ms(9.996e6), "10.0 ms");
        assert_eq!(per_unit(999.7), "1.00 µs");
        assert_eq!(per_unit(9.996), "10.0 ns");
    }

    /// Ratios: fastest against fastest (not the best within-run ratio), the within-run
    /// range, and the runs that reach the goal (exactly at it counts).
    #[test]
    fn ratios_are_fastest_against_fastest_with_the_within_run_range() {
        // Run 2 is slow for both; run 3 fast for the fast case only.
        let slow = [60.0, 70.0, 62.0];
        let fast = [2.5, 2.8, 2.4];
        let r = ratio(&slow, &fast, 25.0);
        assert_eq!(r.fastest, 60.0 / 2.4);
        assert_eq!((r.lo, r.hi), (24.0, 62.0 / 2.4));
        assert_eq!(r.met, 2); // 24.0 (no), 25.0 (yes, exactly), 25.83 (yes)
        let one = ratio(&[10.0], &[4.0], 10.0);
        assert_eq!(
            one,
            Ratio {
                fastest: 2.5,
                lo: 2.5,
                hi: 2.5,
                met: 0
            }
        );
    }
}
