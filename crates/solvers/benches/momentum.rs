//! `momentum/paper_scene`: two 15-storey sticks, all modes, 40 s Capitola record at 0.40 g,
//! 10 cm gap. The scene is loaded once outside the timed loop.

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

criterion_group!(benches, paper_scene);
criterion_main!(benches);
