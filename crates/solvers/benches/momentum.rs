//! `momentum/paper_scene`: two 15-storey sticks, all modes, 40 s Capitola record at 0.40 g,
//! 10 cm gap. `held/paper_scene`: the same at c_r = 0.65 and a 1 cm gap, where chattering
//! ends in 27 persistent-contact phases, the momentum method (held segments) beside the
//! impulse method (exact instantaneous holding forces, tolerance 1e-8). Scenes are loaded
//! once outside the timed loop.

use criterion::{criterion_group, criterion_main, Criterion};
use structure::testing::paper_scene_path;
use structure::Scene;

fn paper_scene(c: &mut Criterion) {
    let scene = Scene::from_file(&paper_scene_path()).expect("paper scene");
    let out = solvers::momentum::solve(&scene, None).expect("run");
    let modes: usize = out.r_n.first().map_or(0, |r| r.modes_left + r.modes_right);
    let record_steps = scene.ground.as_ref().map_or(0, |g| g.npts() - 1);
    eprintln!(
        "paper scene: {} impacts, {} segments, {modes} modes x {record_steps} record steps = {} mode-steps",
        out.impacts.len(),
        out.stats.steps,
        modes * record_steps
    );
    c.bench_function("momentum/paper_scene", |b| {
        b.iter(|| solvers::momentum::solve(std::hint::black_box(&scene), None).unwrap())
    });
}

fn held_phases(c: &mut Criterion) {
    let scene =
        structure::testing::paper_scene(&["contacts.0.restitution=0.65", "contacts.0.gap=0.01"]);
    let (out, d) = solvers::momentum::solve_with_diagnostics(&scene, None).expect("run");
    eprintln!(
        "held paper scene: {} impacts, {} held phases, {} segments, {} held segments, {} \
         shortened",
        out.impacts.len(),
        out.persistent_contacts.len(),
        out.stats.steps,
        d.held_segments,
        d.held_subdivisions
    );
    let mut g = c.benchmark_group("held/paper_scene");
    g.sample_size(20);
    g.bench_function("momentum", |b| {
        b.iter(|| solvers::momentum::solve(std::hint::black_box(&scene), None).unwrap())
    });
    g.bench_function("impulse", |b| {
        b.iter(|| solvers::impulse::solve(std::hint::black_box(&scene), None).unwrap())
    });
    g.finish();
}

criterion_group!(benches, paper_scene, held_phases);
criterion_main!(benches);
