//! Study 6 (`cost`): accuracy against cost, with the Pareto front.
//!
//! Reference: the momentum method with all modes, the continuous rigid-impact answer with
//! c_r = 1 (exact modal integration between events, peaks located between samples: the same
//! record on a 16× finer grid moves its peaks by ≤ 3e-13, `tests/momentum_peaks.rs`). The
//! linear gap element converges to it as k → ∞, so its error e_total = |V(k, tol) − V_rigid|
//! (max over stories of the relative peak story-shear difference) is split into
//! - the spring-model error e_k = |V(k, tol_ref) − V_rigid|, with the gap element integrated
//!   at the reference tolerance `reference_tolerance` (the answer the penalty model gives when
//!   integrated exactly), and
//! - the integration error e_int = |V(k, tol) − V(k, tol_ref)| (tolerance or Newmark step).
//!
//! Times are not deterministic: each timed case runs `repeat` times and the fastest, median
//! and slowest are reported; the deterministic work counts (steps, right-hand-side
//! evaluations, Newton iterations, mode-steps) stand beside them.

use serde::Deserialize;
use solvers::Method;

use super::stats::percentile;
use super::{
    default_pga, failures_note, is_positive, record_label, require_count, require_list,
    require_mode_counts, require_pga, shear_error, write_summary, Ctx, Study, MAX_REPEAT,
};
use crate::plot::{figure, Marker, Panel, PanelKind, Series, VLine};
use crate::sweep::{CaseOutputs, CaseResult, CaseSpec, Result, Results};
use crate::table::{e, Table};

pub struct Cost;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    /// Scene of the pair (relative to `studies/`); contact 0 joins the two buildings.
    scene: String,
    /// Analysis PGA, g: finite, > 0 (default 0.40).
    #[serde(default = "default_pga")]
    pga: f64,
    /// The record (relative to `studies/`).
    record: String,
    /// Gap of contact 0, m: finite, >= 0.
    gap: f64,
    /// Modes kept per building by the truncated momentum runs: at least one, each in
    /// 1 ..= [`super::MAX_MODES`] (1000).
    modes: Vec<usize>,
    /// Gap-element stiffness of the adaptive runs, N/m: at least one, each > 0 (checked by
    /// the scene in every case).
    adaptive_stiffness: Vec<f64>,
    /// Local error tolerances of the adaptive runs: at least one, each in (0, 0.1) (checked
    /// by the scene).
    adaptive_tolerance: Vec<f64>,
    /// Newmark time steps, s: at least one, each > 0 and at most the record's step (checked
    /// by the scene).
    newmark_step: Vec<f64>,
    /// Gap-element stiffness of the Newmark runs, N/m: at least one, each > 0 (checked by
    /// the scene).
    newmark_stiffness: Vec<f64>,
    /// Tolerance of the converged gap-element answer at each k (default 1e-12; in (0, 0.1),
    /// checked by the scene).
    #[serde(default = "default_reference_tolerance")]
    reference_tolerance: f64,
    /// Runs of each timed case (fastest, median and slowest reported): 1 ..= [`MAX_REPEAT`]
    /// (1000).
    repeat: u32,
    /// Accuracy levels (relative story-shear errors, 0.05 = 5 %) at which the speed ratio is
    /// reported: at least one, each finite and > 0.
    accuracy: Vec<f64>,
}

/// The definition's values the scene does not check in every case: bad input (exit 2)
/// before any case is built.
fn validate(ctx: &Ctx, d: &Def) -> Result<()> {
    require_pga(ctx, d.pga)?;
    super::require_gap(ctx, d.gap)?;
    require_mode_counts(ctx, "modes", &d.modes, false)?;
    for (key, v) in [
        ("adaptive_stiffness", &d.adaptive_stiffness),
        ("adaptive_tolerance", &d.adaptive_tolerance),
        ("newmark_step", &d.newmark_step),
        ("newmark_stiffness", &d.newmark_stiffness),
    ] {
        super::require_nonempty(ctx, key, v)?;
    }
    require_count(ctx, "repeat", d.repeat, 1..=MAX_REPEAT, "run")?;
    require_list(
        ctx,
        "accuracy",
        &d.accuracy,
        is_positive,
        "a finite relative error > 0 (0.05 = 5 %)",
    )
}

fn default_reference_tolerance() -> f64 {
    1e-12
}

#[derive(Clone, Copy, PartialEq)]
enum Family {
    Momentum,
    Adaptive,
    Newmark,
}

struct Point {
    family: Family,
    label: String,
    /// Gap-element stiffness, N/m (gap element only).
    k: Option<f64>,
    /// Tolerance (adaptive) or time step (Newmark, s).
    setting: Option<f64>,
    /// Modes kept per building (momentum only).
    modes: Option<usize>,
    case: CaseSpec,
}

fn base(ctx: &Ctx, d: &Def, m: Method) -> CaseSpec {
    ctx.case(&d.scene, m, &d.record, d.pga)
        .with("contacts.0.gap", format!("{:?}", d.gap))
        .with("contacts.0.restitution", "1.0")
}

fn adaptive(ctx: &Ctx, d: &Def, k: f64, tol: f64) -> CaseSpec {
    base(ctx, d, Method::Gap)
        .with("gap_element.law", "linear")
        .with("gap_element.integrator", "adaptive")
        .with("gap_element.stiffness", format!("{k:e}"))
        .with("gap_element.tolerance", format!("{tol:e}"))
}

/// The rigid-impact reference, timed like every other point.
fn reference(ctx: &Ctx, d: &Def) -> CaseSpec {
    base(ctx, d, Method::Momentum)
        .with("momentum.impulse", "consistent")
        .repeat(d.repeat)
        .param("variant", "reference: momentum, all modes")
}

/// Every stiffness used by either gap integrator, in order of appearance.
fn stiffnesses(d: &Def) -> Vec<f64> {
    let mut ks: Vec<f64> = Vec::new();
    for &k in d.adaptive_stiffness.iter().chain(&d.newmark_stiffness) {
        if !ks.contains(&k) {
            ks.push(k);
        }
    }
    ks
}

/// The converged gap-element answer at stiffness k (not timed).
fn spring_reference(ctx: &Ctx, d: &Def, k: f64) -> CaseSpec {
    adaptive(ctx, d, k, d.reference_tolerance).param(
        "variant",
        format!(
            "converged gap element k={k:e} tol={:e}",
            d.reference_tolerance
        ),
    )
}

fn points(ctx: &Ctx, d: &Def) -> Vec<Point> {
    let mut v = Vec::new();
    for &n in &d.modes {
        v.push(Point {
            family: Family::Momentum,
            label: format!("momentum, {n} modes"),
            k: None,
            setting: None,
            modes: Some(n),
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
                family: Family::Adaptive,
                label: format!("gap adaptive k={k:.0e} tol={tol:.0e}"),
                k: Some(k),
                setting: Some(tol),
                modes: None,
                case: adaptive(ctx, d, k, tol)
                    .repeat(d.repeat)
                    .param("variant", format!("gap adaptive k={k:e} tol={tol:e}")),
            });
        }
    }
    for &k in &d.newmark_stiffness {
        for &dt in &d.newmark_step {
            v.push(Point {
                family: Family::Newmark,
                label: format!("gap Newmark k={k:.0e} dt={dt:.0e}"),
                k: Some(k),
                setting: Some(dt),
                modes: None,
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

/// Fastest, median and slowest of a case's repeats, s.
fn spread(r: &CaseResult) -> (f64, f64, f64) {
    let w: &[f64] = if r.wall_seconds_all.is_empty() {
        std::slice::from_ref(&r.wall_seconds)
    } else {
        &r.wall_seconds_all
    };
    let q = |p: f64| percentile(w, p).unwrap_or(r.wall_seconds);
    (q(0.0), q(0.5), q(1.0))
}

/// The range (least, greatest) of a setting's wall time over the reference's, round by round
/// (repeat i of each ran in round i of the timed cases, [`crate::sweep::run_interleaved`]);
/// None without two or more repeats of each, the same number.
fn round_ratios(r: &CaseResult, reference: &CaseResult) -> Option<(f64, f64)> {
    let (a, b) = (&r.wall_seconds_all, &reference.wall_seconds_all);
    (a.len() >= 2 && a.len() == b.len()).then(|| {
        a.iter()
            .zip(b)
            .map(|(x, y)| x / y)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| {
                (lo.min(q), hi.max(q))
            })
    })
}

/// One measured point of the figure and the CPU table.
struct Measured {
    family: Family,
    label: String,
    error: f64,
    wall: (f64, f64, f64),
    /// Its time over the reference's, least and greatest over the rounds ([`round_ratios`]).
    rounds: Option<(f64, f64)>,
}

impl Study for Cost {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let mut d: Def = ctx.def()?;
        validate(ctx, &d)?;
        shrink(ctx, &mut d);
        let mut v = vec![reference(ctx, &d)];
        v.extend(
            stiffnesses(&d)
                .into_iter()
                .map(|k| spring_reference(ctx, &d, k)),
        );
        v.extend(points(ctx, &d).into_iter().map(|p| p.case));
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let mut d: Def = ctx.def()?;
        shrink(ctx, &mut d);
        let ref_case = reference(ctx, &d);
        let refo = res.out(&ref_case);
        let ref_wall = spread(res.get(&ref_case));
        let converged = |k: f64| res.out(&spring_reference(ctx, &d, k));
        let mut det = Table::new(
            &format!(
                "Accuracy of each setting ({}, gap {} cm, c_r = 1): max relative story-shear error against rigid impact (momentum method, all modes), split for the gap element into the spring-model error (the same k integrated at tol {:.0e}) and the integration error (against that converged answer)",
                record_label(&d.record),
                d.gap * 100.0,
                d.reference_tolerance
            ),
            &[
                "setting",
                "error vs rigid",
                "spring error",
                "integration error",
                "impacts",
                "steps",
                "rhs evaluations",
                "Newton iterations",
                "mode-steps",
                "status",
            ],
        );
        let mut cpu = Table::new(
            &format!(
                "Accuracy against wall time: fastest, median and slowest of {} (machine-dependent; \
                each timed case runs alone, after the untimed ones, so the spread is the machine's \
                own noise; the timed cases run in rounds, every setting once per round, so a slow \
                spell of the machine falls on one repeat of many settings, not on every repeat of one)",
                crate::table::count(d.repeat, "run", "runs")
            ),
            &[
                "setting",
                "error vs rigid",
                "fastest (s)",
                "median (s)",
                "slowest (s)",
                "on Pareto front",
            ],
        );
        let pts = points(ctx, &d);
        let mut data: Vec<Measured> = Vec::new();
        if let Some(m) = refo {
            det.push(vec![
                "momentum, all modes (reference)".into(),
                "0 (reference)".into(),
                "–".into(),
                "–".into(),
                m.impacts.to_string(),
                m.steps.to_string(),
                "–".into(),
                "–".into(),
                (m.steps * total_modes(m, None)).to_string(),
                "ok".into(),
            ]);
        }
        for p in &pts {
            let r = res.get(&p.case);
            let o = r.ok();
            let err = match (o, refo) {
                (Some(o), Some(m)) => Some(shear_error(o, m)),
                _ => None,
            };
            let conv = p.k.and_then(converged);
            let spring = match (conv, refo) {
                (Some(c), Some(m)) => Some(shear_error(c, m)),
                _ => None,
            };
            let integ = match (o, conv) {
                (Some(o), Some(c)) => Some(shear_error(o, c)),
                _ => None,
            };
            let mode_steps = match (p.family, o) {
                (Family::Momentum, Some(o)) => (o.steps * total_modes(o, p.modes)).to_string(),
                _ => "–".into(),
            };
            let count = |v: Option<u64>| v.map_or("–".into(), |x| x.to_string());
            det.push(vec![
                p.label.clone(),
                e(err, 3),
                e(spring, 3),
                e(integ, 3),
                o.map_or("–".into(), |o| o.impacts.to_string()),
                count(o.map(|o| o.steps)),
                if p.family == Family::Adaptive {
                    count(o.map(|o| o.rhs_evaluations))
                } else {
                    "–".into()
                },
                if p.family == Family::Newmark {
                    count(o.map(|o| o.newton_iterations))
                } else {
                    "–".into()
                },
                mode_steps,
                r.error_kind
                    .clone()
                    .map_or(r.status.clone(), |k| format!("failed: {k}")),
            ]);
            if let Some(err) = err {
                data.push(Measured {
                    family: p.family,
                    label: p.label.clone(),
                    error: err,
                    wall: spread(r),
                    rounds: round_ratios(r, res.get(&ref_case)),
                });
            }
        }
        // Pareto front over the fastest times: keep points more accurate than every faster
        // one. The reference (error 0, exact) is not a point of it: it is the vertical line.
        let mut order: Vec<usize> = (0..data.len()).collect();
        order.sort_by(|a, b| data[*a].wall.0.total_cmp(&data[*b].wall.0));
        let mut front = Vec::new();
        let mut best = f64::INFINITY;
        for i in order {
            if data[i].error < best {
                best = data[i].error;
                front.push(i);
            }
        }
        if refo.is_some() {
            cpu.push(vec![
                "momentum, all modes (reference)".into(),
                "0 (reference)".into(),
                format!("{:.4e}", ref_wall.0),
                format!("{:.4e}", ref_wall.1),
                format!("{:.4e}", ref_wall.2),
                "".into(),
            ]);
        }
        for (i, m) in data.iter().enumerate() {
            cpu.push(vec![
                m.label.clone(),
                format!("{:.3e}", m.error),
                format!("{:.4e}", m.wall.0),
                format!("{:.4e}", m.wall.1),
                format!("{:.4e}", m.wall.2),
                if front.contains(&i) {
                    "yes".into()
                } else {
                    "".into()
                },
            ]);
        }

        // Figure: (a) error against the fastest time, the slowest-to-fastest range as a bar,
        // the reference's time as a vertical line; (b) the gap element's error split into
        // spring and integration error against k.
        let fam = [
            (
                Family::Momentum,
                "momentum, truncated modes",
                Marker::Circle,
            ),
            (Family::Adaptive, "gap element, adaptive", Marker::Triangle),
            (Family::Newmark, "gap element, Newmark", Marker::Square),
        ];
        let mut series: Vec<Series> = fam
            .iter()
            .enumerate()
            .map(|(c, (f, name, mk))| {
                Series::points(
                    name,
                    data.iter()
                        .filter(|p| p.family == *f)
                        .map(|p| (p.wall.0, p.error))
                        .collect(),
                    c,
                    *mk,
                )
            })
            .collect();
        for p in &data {
            if p.error > 0.0 && p.wall.2 > p.wall.0 {
                let c = fam.iter().position(|f| f.0 == p.family).unwrap_or(0);
                series.push(
                    Series::line("", vec![(p.wall.0, p.error), (p.wall.2, p.error)], c).width(1),
                );
            }
        }
        series.push(
            Series::line(
                "Pareto front (fastest times)",
                front
                    .iter()
                    .map(|&i| (data[i].wall.0, data[i].error))
                    .collect(),
                7,
            )
            .width(1),
        );
        let mut vlines = Vec::new();
        if refo.is_some() {
            vlines.push(VLine {
                x: ref_wall.0,
                label: "momentum, all modes (reference, exact)".into(),
                color: 3,
            });
        }
        let mut split: Vec<Series> = Vec::new();
        let ks: Vec<f64> = d.adaptive_stiffness.clone();
        split.push(
            Series::line(
                &format!("spring error (tol {:.0e})", d.reference_tolerance),
                ks.iter()
                    .filter_map(|&k| {
                        let c = converged(k)?;
                        let m = refo?;
                        Some((k, shear_error(c, m)))
                    })
                    .collect(),
                0,
            )
            .marker(Marker::Circle),
        );
        let tol_marks = [Marker::Triangle, Marker::Square, Marker::Cross];
        for (i, &tol) in d.adaptive_tolerance.iter().enumerate() {
            split.push(Series::points(
                &format!("integration error, tol {tol:.0e}"),
                pts.iter()
                    .filter(|p| p.family == Family::Adaptive && p.setting == Some(tol))
                    .filter_map(|p| {
                        let o = res.out(&p.case)?;
                        let c = converged(p.k?)?;
                        let v = shear_error(o, c);
                        (v > 0.0).then_some((p.k?, v))
                    })
                    .collect(),
                i + 1,
                tol_marks[i % tol_marks.len()],
            ));
        }
        figure(
            &ctx.dir,
            "cost_pareto_cpu",
            (900, 1000),
            (2, 1),
            &[
                PanelKind::Xy(Panel {
                    title: "(a) Accuracy against wall time".into(),
                    x_label: "wall time per analysis, fastest of the repeats (s)".into(),
                    y_label: "max relative story-shear error vs rigid impact".into(),
                    log_x: true,
                    log_y: true,
                    series,
                    vlines,
                    legend_right: true,
                    ..Default::default()
                }),
                PanelKind::Xy(Panel {
                    title: "(b) Gap element: spring-model and integration error".into(),
                    x_label: "gap-element stiffness k (N/m)".into(),
                    y_label: "max relative story-shear error".into(),
                    log_x: true,
                    log_y: true,
                    series: split,
                    legend_right: true,
                    ..Default::default()
                }),
            ],
            &format!(
                "(a) Vertical line: the reference (rigid impact, momentum method, all modes) at \
                its fastest time. Bars: fastest to slowest of {}. (b) Spring error: k integrated \
                at tol {:.0e}, against rigid impact; integration error: against that.",
                crate::table::count(d.repeat, "run", "runs"),
                d.reference_tolerance
            ),
        )?;
        det.write(&ctx.dir, "cost")?;
        cpu.write(&ctx.dir, "cost_cpu")?;

        let mut reading = Vec::new();
        if refo.is_some() {
            reading.push(format!(
                "The momentum method with all modes (the reference) takes {:.2e} s per analysis (fastest of {}; median {:.2e}, slowest {:.2e}).",
                ref_wall.0, d.repeat, ref_wall.1, ref_wall.2
            ));
            for &acc in &d.accuracy {
                let mut within: Vec<&Measured> = data
                    .iter()
                    .filter(|p| p.family != Family::Momentum && p.error <= acc)
                    .collect();
                within.sort_by(|a, b| a.wall.0.total_cmp(&b.wall.0));
                reading.push(match within.first() {
                    Some(g) => {
                        let near: Vec<String> = within
                            .iter()
                            .skip(1)
                            .take(2)
                            .map(|q| format!("{} {:.1}×", q.label, q.wall.0 / ref_wall.0))
                            .collect();
                        format!(
                            "Within {:.0} % of rigid impact the fastest gap-element setting is {} at {:.2e} s: **{:.1}×** the momentum method's fastest time (median against median {:.1}×; slowest-to-fastest range over the repeats {:.1}–{:.1}×{}){}.",
                            acc * 100.0,
                            g.label,
                            g.wall.0,
                            g.wall.0 / ref_wall.0,
                            g.wall.1 / ref_wall.1,
                            g.wall.0 / ref_wall.2,
                            g.wall.2 / ref_wall.0,
                            g.rounds.map_or(String::new(), |(lo, hi)| format!(
                                "; round by round, each repeat against the reference's of the same round, {lo:.1}–{hi:.1}×"
                            )),
                            if near.is_empty() {
                                String::new()
                            } else {
                                format!("; the next fastest: {}", near.join(", "))
                            }
                        )
                    }
                    None => format!(
                        "No gap-element setting reaches {:.0} % of rigid impact.",
                        acc * 100.0
                    ),
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
                "Accuracy against wall time, and the gap element's error split into spring and integration error",
            )],
        )
    }
}

/// Total modes kept over the buildings of a momentum run with `modes` per building (None:
/// all; a shear stick has one mode per floor), for the mode-step count.
fn total_modes(o: &CaseOutputs, modes: Option<usize>) -> u64 {
    o.story_shear_max
        .iter()
        .map(|s| modes.map_or(s.len(), |m| m.min(s.len())) as u64)
        .sum()
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

#[cfg(test)]
mod tests {
    use super::*;

    fn timed(walls: &[f64]) -> CaseResult {
        CaseResult {
            spec: CaseSpec::new("paper/scene.toml", solvers::Method::Momentum),
            status: "ok".into(),
            error_kind: None,
            error: None,
            outputs: None,
            wall_seconds: walls.iter().copied().fold(f64::INFINITY, f64::min),
            wall_seconds_all: walls.to_vec(),
        }
    }

    #[test]
    fn round_ratios_pair_the_repeats_of_a_round() {
        // Round 2 was slow for both: its ratio is 4 like round 1's; round 3 only for the
        // reference. Fastest against fastest would say 4, slowest-to-fastest 2–8.
        let reference = timed(&[1.0, 2.0, 2.0]);
        let gap = timed(&[4.0, 8.0, 4.0]);
        assert_eq!(round_ratios(&gap, &reference), Some((2.0, 4.0)));
        // One repeat, or unequal counts: no rounds to pair.
        assert_eq!(round_ratios(&timed(&[4.0]), &timed(&[1.0])), None);
        assert_eq!(round_ratios(&timed(&[4.0, 5.0]), &reference), None);
    }
}
