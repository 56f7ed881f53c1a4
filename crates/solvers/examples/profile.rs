//! Runs one solver on the paper scene `N` times (for profilers: perf, callgrind).
//! `cargo run --release -p solvers --example profile -- momentum 100 [--set k=v ...]`
fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let method = match a.first().map(String::as_str) {
        Some("gap") => solvers::Method::Gap,
        Some("impulse") => solvers::Method::Impulse,
        _ => solvers::Method::Momentum,
    };
    let n: usize = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(1);
    let o: Vec<&str> = a.iter().skip(2).map(String::as_str).collect();
    let s = structure::testing::paper_scene(&o);
    let t = std::time::Instant::now();
    let mut steps = 0;
    for _ in 0..n {
        steps += solvers::run(&s, method, None).unwrap().stats.steps;
    }
    eprintln!(
        "{:.3} ms per run ({steps} steps)",
        t.elapsed().as_secs_f64() * 1e3 / n as f64
    );
}
