//! Study 6 (`cost`): accuracy against CPU time, with the Pareto front.
//!
//! Reference: the momentum method with all modes, which is exact rigid impact with c_r = 1
//! (exact modal integration between events); the gap element (linear law) converges to it as
//! k → ∞, so its error includes the penalty error as well as the integration error.

use serde::Deserialize;
use solvers::Method;

use super::{default_pga, failures_note, record_label, shear_error, write_summary, Ctx, Study};
use crate::plot::{figure, Marker, Panel, PanelKind, Series, VLine};
use crate::sweep::{CaseSpec, Result, Results};
use crate::table::{e, Table};

pub struct Cost;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    scene: String,
    #[serde(default = "default_pga")]
    pga: f64,
    record: String,
    gap: f64,
    modes: Vec<usize>,
    adaptive_stiffness: Vec<f64>,
    adaptive_tolerance: Vec<f64>,
    newmark_step: Vec<f64>,
    newmark_stiffness: Vec<f64>,
    repeat: u32,
    /// Accuracy levels at which the speed ratio is reported.
    accuracy: Vec<f64>,
}

struct Point {
    family: usize,
    label: String,
    case: CaseSpec,
}

fn base(ctx: &Ctx, d: &Def, m: Method) -> CaseSpec {
    ctx.case(&d.scene, m, &d.record, d.pga)
        .with("contacts.0.gap", format!("{:?}", d.gap))
        .with("contacts.0.restitution", "1.0")
}

fn reference(ctx: &Ctx, d: &Def) -> CaseSpec {
    base(ctx, d, Method::Momentum)
        .with("momentum.impulse", "consistent")
        .param("variant", "reference: momentum, all modes")
}

fn points(ctx: &Ctx, d: &Def) -> Vec<Point> {
    let mut v = Vec::new();
    for &n in &d.modes {
        v.push(Point {
            family: 0,
            label: format!("momentum, {n} modes"),
            case: base(ctx, d, Method::Momentum)
                .with("momentum.impulse", "consistent")
                .with("momentum.modes", n)
                .repeat(d.repeat)
                .param("variant", format!("momentum, {n} modes")),
        });
    }
    for &k in &d.adaptive_stiffness {
        for &tol in &d.adaptive_tolerance {
            v.push(Point {
                family: 1,
                label: format!("gap adaptive k={k:.0e} tol={tol:.0e}"),
                case: base(ctx, d, Method::Gap)
                    .with("gap_element.law", "linear")
                    .with("gap_element.integrator", "adaptive")
                    .with("gap_element.stiffness", format!("{k:e}"))
                    .with("gap_element.tolerance", format!("{tol:e}"))
                    .repeat(d.repeat)
                    .param("variant", format!("gap adaptive k={k:e} tol={tol:e}")),
            });
        }
    }
    for &k in &d.newmark_stiffness {
        for &dt in &d.newmark_step {
            v.push(Point {
                family: 2,
                label: format!("gap Newmark k={k:.0e} dt={dt:.0e}"),
                case: base(ctx, d, Method::Gap)
                    .with("gap_element.law", "linear")
                    .with("gap_element.integrator", "newmark")
                    .with("gap_element.stiffness", format!("{k:e}"))
                    .with("gap_element.time_step", format!("{dt:e}"))
                    .repeat(d.repeat)
                    .param("variant", format!("gap newmark k={k:e} dt={dt:e}")),
            });
        }
    }
    v
}

impl Study for Cost {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let mut d: Def = ctx.def()?;
        shrink(ctx, &mut d);
        let mut v = vec![reference(ctx, &d)];
        v.extend(points(ctx, &d).into_iter().map(|p| p.case));
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let mut d: Def = ctx.def()?;
        shrink(ctx, &mut d);
        let refo = res.out(&reference(ctx, &d));
        let mut det = Table::new(
            &format!(
                "Accuracy of each setting ({}, gap {} cm, c_r = 1): max relative story-shear error against the momentum method with all modes (exact rigid impact)",
                record_label(&d.record),
                d.gap * 100.0
            ),
            &["setting", "error", "impacts", "steps", "rhs evaluations", "status"],
        );
        let mut cpu = Table::new(
            "Accuracy against CPU time (fastest of the repeats; machine-dependent)",
            &["setting", "error", "wall (s)", "on Pareto front"],
        );
        let pts = points(ctx, &d);
        // (family, label, wall time (s), error, integration steps incl. rejected)
        let mut data: Vec<(usize, String, f64, f64, f64)> = Vec::new();
        for p in &pts {
            let r = res.get(&p.case);
            let err = match (r.ok(), refo) {
                (Some(o), Some(m)) => Some(shear_error(o, m)),
                _ => None,
            };
            det.push(vec![
                p.label.clone(),
                e(err, 3),
                r.ok().map_or("–".into(), |o| o.impacts.to_string()),
                r.ok().map_or("–".into(), |o| o.steps.to_string()),
                r.ok().map_or("–".into(), |o| o.rhs_evaluations.to_string()),
                r.error_kind
                    .clone()
                    .map_or(r.status.clone(), |k| format!("failed: {k}")),
            ]);
            if let (Some(err), Some(o)) = (err, r.ok()) {
                data.push((
                    p.family,
                    p.label.clone(),
                    r.wall_seconds,
                    err,
                    (o.steps + o.rejected_steps) as f64,
                ));
            }
        }
        // Pareto front: sorted by time, keep points better than every faster one.
        let mut order: Vec<usize> = (0..data.len()).collect();
        order.sort_by(|a, b| data[*a].2.total_cmp(&data[*b].2));
        let mut front = Vec::new();
        let mut best = f64::INFINITY;
        for i in order {
            if data[i].3 < best {
                best = data[i].3;
                front.push(i);
            }
        }
        for (i, (_, l, t, er, _)) in data.iter().enumerate() {
            cpu.push(vec![
                l.clone(),
                format!("{er:.3e}"),
                format!("{t:.4e}"),
                if front.contains(&i) {
                    "yes".into()
                } else {
                    "".into()
                },
            ]);
        }
        let fam = [
            "momentum (modes)",
            "gap element, adaptive",
            "gap element, Newmark",
        ];
        let mk = [Marker::Circle, Marker::Triangle, Marker::Square];
        // A setting that reproduces the reference exactly (the momentum method with all
        // modes) has error 0, which a log axis cannot show: it is drawn as a vertical line at
        // its cost instead of at an invented error.
        let exact: Vec<&(usize, String, f64, f64, f64)> =
            data.iter().filter(|p| p.3 == 0.0).collect();
        let panel = |x: fn(&(usize, String, f64, f64, f64)) -> f64,
                     title: &str,
                     x_label: &str,
                     front: &[usize]| {
            let mut series: Vec<Series> = (0..3)
                .map(|k| {
                    Series::points(
                        fam[k],
                        data.iter()
                            .filter(|p| p.0 == k && p.3 > 0.0)
                            .map(|p| (x(p), p.3))
                            .collect(),
                        k,
                        mk[k],
                    )
                })
                .collect();
            let line: Vec<(f64, f64)> = front
                .iter()
                .filter(|&&i| data[i].3 > 0.0)
                .map(|&i| (x(&data[i]), data[i].3))
                .collect();
            if line.len() >= 2 {
                series.push(Series::line("Pareto front (wall time)", line, 7).width(1));
            }
            Panel {
                title: title.into(),
                x_label: x_label.into(),
                y_label: "story-shear error (max, relative)".into(),
                log_x: true,
                log_y: true,
                series,
                vlines: exact
                    .iter()
                    .map(|p| VLine {
                        x: x(p),
                        label: format!("{} (error 0: the reference)", p.1),
                        color: 0,
                    })
                    .collect(),
                ..Default::default()
            }
        };
        figure(
            &ctx.dir,
            "cost_pareto_cpu",
            (1200, 1400),
            (2, 1),
            &[
                PanelKind::Xy(panel(
                    |p| p.2,
                    "Error against wall time",
                    "wall time per analysis (s)",
                    &front,
                )),
                PanelKind::Xy(panel(
                    |p| p.4,
                    "Error against integration steps",
                    "time steps incl. rejected (count)",
                    &[],
                )),
            ],
            "Error against the momentum method with all modes (exact rigid impact). Top: fastest wall time of the repeats (machine-dependent). Bottom: deterministic work, the integration steps taken (an adaptive step costs 6 right-hand-side evaluations, a Newmark step a linear solve, a momentum step a modal update).",
        )?;
        det.write(&ctx.dir, "cost")?;
        cpu.write(&ctx.dir, "cost_cpu")?;
        let mut reading = Vec::new();
        let mom_all = data
            .iter()
            .filter(|p| p.0 == 0)
            .min_by(|a, b| a.3.total_cmp(&b.3));
        if let Some(m) = mom_all {
            reading.push(format!(
                "The momentum method with {} takes {:.2e} s per analysis with error {:.1e}.",
                m.1.trim_start_matches("momentum, "),
                m.2,
                m.3
            ));
            for &acc in &d.accuracy {
                let fastest_gap = data
                    .iter()
                    .filter(|p| p.0 > 0 && p.3 <= acc)
                    .min_by(|a, b| a.2.total_cmp(&b.2));
                reading.push(match fastest_gap {
                    Some(g) => format!(
                        "The fastest gap-element setting within {:.0} % ({}) takes {:.2e} s: {:.1}× the momentum method's time.",
                        acc * 100.0,
                        g.1,
                        g.2,
                        g.2 / m.2
                    ),
                    None => format!("No gap-element setting reaches {:.0} % accuracy.", acc * 100.0),
                });
            }
        }
        if let Some(n) = failures_note(res) {
            reading.push(n);
        }
        write_summary(
            ctx,
            "Study 6: accuracy against cost",
            &reading,
            &[&det, &cpu],
            &[(
                "cost_pareto_cpu",
                "Accuracy against wall time (with the Pareto front) and against integration steps",
            )],
        )
    }
}

fn shrink(ctx: &Ctx, d: &mut Def) {
    if ctx.opts.quick {
        d.modes.truncate(1);
        d.adaptive_stiffness.truncate(1);
        d.adaptive_tolerance.truncate(1);
        d.newmark_stiffness.truncate(1);
        d.newmark_step.truncate(1);
        d.repeat = 1;
    }
}
