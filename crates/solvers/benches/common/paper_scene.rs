//! The cases of the `paper_scene` benchmark group, shared by the benchmark
//! (`benches/paper_scene.rs`) and the table of its runs (`examples/bench_table.rs`):
//! name (criterion's function id), method, and the overrides of the paper scene
//! ([`structure::testing::paper_scene`]).

/// One benchmark: its name, the method and the overrides of the paper scene.
pub type Case = (&'static str, solvers::Method, Vec<&'static str>);

/// The five solvers of the group, momentum first (the ratios are against it).
pub fn cases() -> Vec<Case> {
    vec![
        ("momentum", solvers::Method::Momentum, vec![]),
        (
            "gap/k=1e12/tol=1e-4",
            solvers::Method::Gap,
            vec![
                "gap_element.law=linear",
                "gap_element.stiffness=1e12",
                "gap_element.tolerance=1e-4",
            ],
        ),
        (
            "gap/k=1e10/tol=1e-4",
            solvers::Method::Gap,
            vec![
                "gap_element.law=kelvin-voigt",
                "gap_element.stiffness=1e10",
                "gap_element.tolerance=1e-4",
            ],
        ),
        (
            "newmark/k=1e10/dt=1e-3",
            solvers::Method::Gap,
            vec![
                "gap_element.law=kelvin-voigt",
                "gap_element.stiffness=1e10",
                "gap_element.integrator=newmark",
                "gap_element.time_step=1e-3",
            ],
        ),
        (
            "impulse/tol=1e-4",
            solvers::Method::Impulse,
            vec!["gap_element.tolerance=1e-4"],
        ),
    ]
}
