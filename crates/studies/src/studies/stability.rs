//! Study 7 (`stability`): where the methods fail. Fixed-step Newmark over a (dt, k) grid
//! against the adaptive solver at the same k and a tight tolerance (the converged answer
//! of the same spring): spurious contact work (a linear spring returns all the energy it
//! stores, so any net contact work is integration error), restitution error and
//! story-shear error; adaptive cost against k, the paper impulse
//! variant's restitution violation against modes, chattering with and without the
//! persistent-contact phase.

use serde::Deserialize;
use solvers::Method;

use super::{
    default_pga, failures_note, is_restitution, logspace, record_label, require_count,
    require_list, require_pga, write_summary, Ctx, Study, MAX_GRID, MAX_MODES,
};
use crate::plot::{figure, Heat, Marker, Panel, PanelKind, Series};
use crate::sweep::{CaseSpec, Result, Results};
use crate::table::{e, f, Table};

pub struct Stability;

/// File stem of the second figure (adaptive cost, restitution violation).
const STABILITY_MODES: &str = "stability_cost_modes";

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
    /// Newmark time steps, s: at least one, each > 0 and at most the record's step (checked
    /// by the scene in every case).
    newmark_step: Vec<f64>,
    /// Gap-element stiffnesses of the Newmark grid, N/m: at least one, each > 0 (checked by
    /// the scene).
    newmark_stiffness: Vec<f64>,
    /// Stiffnesses of the adaptive cost sweep (log-spaced 1e7 … 1e13 N/m):
    /// 2 ..= [`MAX_GRID`] (1000).
    adaptive_stiffness_count: usize,
    /// The paper impulse variant's restitution violation is run with 1 … this many modes:
    /// 1 ..= [`MAX_MODES`] (1000).
    max_modes: usize,
    /// Coefficients of restitution of the chattering runs: at least one, each in [0, 1].
    chatter_restitution: Vec<f64>,
}

/// The definition's values the scene does not check in every case: bad input (exit 2)
/// before any case is built.
fn validate(ctx: &Ctx, d: &Def) -> Result<()> {
    require_pga(ctx, d.pga)?;
    super::require_gap(ctx, d.gap)?;
    for (key, v) in [
        ("newmark_step", &d.newmark_step),
        ("newmark_stiffness", &d.newmark_stiffness),
    ] {
        super::require_nonempty(ctx, key, v)?;
    }
    require_count(
        ctx,
        "adaptive_stiffness_count",
        d.adaptive_stiffness_count,
        2..=MAX_GRID,
        "stiffnesses",
    )?;
    require_count(ctx, "max_modes", d.max_modes, 1..=MAX_MODES, "mode")?;
    require_list(
        ctx,
        "chatter_restitution",
        &d.chatter_restitution,
        is_restitution,
        "a coefficient of restitution in [0, 1]",
    )
}

fn shrink(ctx: &Ctx, d: &mut Def) {
    if ctx.opts.quick {
        d.newmark_step.truncate(2);
        d.newmark_stiffness.truncate(2);
        d.adaptive_stiffness_count = 3;
        d.max_modes = 3;
        d.chatter_restitution.truncate(1);
    }
}

fn base(ctx: &Ctx, d: &Def, m: Method, cr: f64) -> CaseSpec {
    ctx.case(&d.scene, m, &d.record, d.pga)
        .with("contacts.0.gap", format!("{:?}", d.gap))
        .with("contacts.0.restitution", format!("{cr:?}"))
}

fn newmark(ctx: &Ctx, d: &Def, dt: f64, k: f64) -> CaseSpec {
    base(ctx, d, Method::Gap, 1.0)
        .with("gap_element.law", "linear")
        .with("gap_element.integrator", "newmark")
        .with("gap_element.stiffness", format!("{k:e}"))
        .with("gap_element.time_step", format!("{dt:e}"))
        .param("variant", "newmark")
}

fn adaptive(ctx: &Ctx, d: &Def, k: f64) -> CaseSpec {
    base(ctx, d, Method::Gap, 1.0)
        .with("gap_element.law", "linear")
        .with("gap_element.integrator", "adaptive")
        .with("gap_element.stiffness", format!("{k:e}"))
        .param("variant", "adaptive")
}

/// The converged answer of the same spring: adaptive, tolerance 1e-10.
fn reference(ctx: &Ctx, d: &Def, k: f64) -> CaseSpec {
    adaptive(ctx, d, k)
        .with("gap_element.tolerance", "1e-10")
        .param("variant", "adaptive reference")
}

fn paper_modes(ctx: &Ctx, d: &Def, n: usize, variant: &str) -> CaseSpec {
    base(ctx, d, Method::Momentum, 1.0)
        .with("momentum.impulse", variant)
        .with("momentum.modes", n)
        .param("variant", variant)
}

fn chatter(ctx: &Ctx, d: &Def, cr: f64, persistent: bool) -> CaseSpec {
    let c = base(ctx, d, Method::Momentum, cr)
        .with("momentum.persistent_contact", persistent)
        .param("variant", format!("chatter persistent={persistent}"));
    // Without persistent contact, chattering at c_r < 1 has an accumulation point the
    // impact-by-impact method cannot pass: the failure is the finding.
    if persistent {
        c
    } else {
        c.expect_failure("Stalled")
    }
}

fn ks(d: &Def) -> Vec<f64> {
    logspace(1e7, 1e13, d.adaptive_stiffness_count)
}

impl Study for Stability {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let mut d: Def = ctx.def()?;
        validate(ctx, &d)?;
        shrink(ctx, &mut d);
        let mut v = Vec::new();
        for &k in &d.newmark_stiffness {
            v.push(reference(ctx, &d, k));
            for &dt in &d.newmark_step {
                v.push(newmark(ctx, &d, dt, k));
            }
        }
        for k in ks(&d) {
            v.push(adaptive(ctx, &d, k));
        }
        for n in 1..=d.max_modes {
            for var in ["paper", "consistent"] {
                v.push(paper_modes(ctx, &d, n, var));
            }
        }
        for &cr in &d.chatter_restitution {
            for p in [true, false] {
                v.push(chatter(ctx, &d, cr, p));
            }
        }
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let mut d: Def = ctx.def()?;
        shrink(ctx, &mut d);
        let mut reading = Vec::new();
        // (a) Newmark grid.
        let mut tn = Table::new(
            &format!(
                "Fixed-step Newmark, linear gap element, c_r = 1, {}, against the adaptive solver at the same k (tol 1e-10): spurious contact work |W_contact| / E_input (exact: 0), restitution error |mean c_r,achieved − reference|, max relative story-shear error; Newmark's own energy balance",
                record_label(&d.record)
            ),
            &[
                "k (N/m)",
                "dt (s)",
                "contact work error",
                "restitution error",
                "story-shear error",
                "balance error",
                "impacts",
                "reference impacts",
                "status",
            ],
        );
        // The grid in milliseconds: the ticks are the swept steps, with short labels.
        let mut heat_e = Heat {
            title: "Newmark: spurious contact work against the input energy".into(),
            x_label: "Newmark time step Δt (ms)".into(),
            y_label: "contact stiffness k (N/m)".into(),
            log_x: true,
            log_y: true,
            log_value: true,
            value_range: (1e-8, 1e-1),
            value_label: "|W_contact| / E_input".into(),
            ..Default::default()
        };
        let mut heat_r = Heat {
            title: "Newmark: restitution error against the same spring, converged".into(),
            x_label: "Newmark time step Δt (ms)".into(),
            y_label: "contact stiffness k (N/m)".into(),
            log_x: true,
            log_y: true,
            log_value: true,
            value_range: (1e-4, 1.0),
            value_label: "|mean c_r − reference|".into(),
            ..Default::default()
        };
        let mut worst_r: (f64, String) = (0.0, String::new());
        let mut worst_w: (f64, String) = (0.0, String::new());
        let mut worst_b: f64 = 0.0;
        for &k in &d.newmark_stiffness {
            let rf = res.out(&reference(ctx, &d, k));
            for &dt in &d.newmark_step {
                let c = newmark(ctx, &d, dt, k);
                let r = res.get(&c);
                let o = r.ok();
                let scale = |o: &crate::sweep::CaseOutputs| o.energy_input.abs().max(1e-300);
                let we = o.map(|o| o.energy_contact.abs() / scale(o));
                let be = o.map(|o| o.energy_balance_error.abs() / scale(o));
                let re = match (
                    o.and_then(|o| o.restitution_mean),
                    rf.and_then(|o| o.restitution_mean),
                ) {
                    (Some(a), Some(b)) => Some((a - b).abs()),
                    _ => None,
                };
                let se = match (o, rf) {
                    (Some(o), Some(rf)) => Some(max_rel(&o.story_shear_max, &rf.story_shear_max)),
                    _ => None,
                };
                let at = format!("k = {k:.0e} N/m, dt = {dt:.0e} s");
                if let Some(x) = re {
                    if x > worst_r.0 {
                        worst_r = (x, at.clone());
                    }
                }
                if let Some(x) = we {
                    if x > worst_w.0 {
                        worst_w = (x, at.clone());
                    }
                }
                worst_b = worst_b.max(be.unwrap_or(0.0));
                tn.push(vec![
                    format!("{k:.0e}"),
                    format!("{dt:.0e}"),
                    e(we, 2),
                    e(re, 2),
                    e(se, 2),
                    e(be, 2),
                    o.map_or("–".into(), |o| o.impacts.to_string()),
                    rf.map_or("–".into(), |o| o.impacts.to_string()),
                    r.error_kind
                        .clone()
                        .map_or(r.status.clone(), |x| format!("failed: {x}")),
                ]);
                heat_e.cells.push((dt * 1e3, k, we));
                // No impacts in either run: nothing to miss (0). Impacts in only one: the
                // restitution cannot be compared; the cell stays undefined (grey).
                let neither =
                    o.is_some_and(|o| o.impacts == 0) && rf.is_some_and(|r| r.impacts == 0);
                heat_r
                    .cells
                    .push((dt * 1e3, k, re.or(neither.then_some(0.0))));
            }
        }
        reading.push(format!(
            "Fixed-step Newmark keeps its own energy balance to {worst_b:.0e} of the input, so the balance cannot reveal its error; measured against the same spring integrated adaptively, its contact spring does net work up to {:.1e} of the input energy ({}) where the exact answer is zero, and its mean achieved restitution is off by up to {:.2} ({}); both fall only when a contact spans many steps (small dt, soft k).",
            worst_w.0, worst_w.1, worst_r.0, worst_r.1
        ));
        // (b) adaptive cost.
        let mut ta = Table::new(
            "Adaptive gap element: cost against k (linear law, tol 1e-8)",
            &["k (N/m)", "steps", "rejected", "rhs evaluations", "impacts"],
        );
        let mut pa = Vec::new();
        for k in ks(&d) {
            let c = adaptive(ctx, &d, k);
            let o = res.out(&c);
            ta.push(vec![
                format!("{k:.3e}"),
                o.map_or("–".into(), |o| o.steps.to_string()),
                o.map_or("–".into(), |o| o.rejected_steps.to_string()),
                o.map_or("–".into(), |o| o.rhs_evaluations.to_string()),
                o.map_or("–".into(), |o| o.impacts.to_string()),
            ]);
            if let Some(o) = o {
                pa.push((k, o.rhs_evaluations as f64));
            }
        }
        if let (Some(a), Some(b)) = (pa.first(), pa.last()) {
            reading.push(format!("The adaptive integrator needs {:.0} right-hand-side evaluations at k = {:.0e} and {:.0} at k = {:.0e} N/m (×{:.2}).", a.1, a.0, b.1, b.0, b.1 / a.1));
        }
        // (c) paper variant restitution violation.
        let mut tp = Table::new(
            "Momentum method, c_r = 1: achieved restitution (min over impacts) against modes kept",
            &[
                "modes",
                "paper impulse: min c_r",
                "paper: violation 1 − min",
                "consistent impulse: min c_r",
            ],
        );
        let (mut vp, mut vc) = (Vec::new(), Vec::new());
        for n in 1..=d.max_modes {
            let p = res
                .out(&paper_modes(ctx, &d, n, "paper"))
                .and_then(|o| o.restitution_min);
            let c = res
                .out(&paper_modes(ctx, &d, n, "consistent"))
                .and_then(|o| o.restitution_min);
            tp.push(vec![
                n.to_string(),
                f(p, 4),
                f(p.map(|x| 1.0 - x), 4),
                f(c, 4),
            ]);
            if let Some(p) = p {
                vp.push((n as f64, (1.0 - p).max(1e-16)));
            }
            if let Some(c) = c {
                vc.push((n as f64, (1.0 - c).abs().max(1e-16)));
            }
        }
        if let Some(p) = vp.first() {
            reading.push(format!("The paper's floor-mass impulse with {} violates the restitution law by up to {:.2} and with {} by {:.1e}.", crate::table::count(p.0, "mode", "modes"), p.1, crate::table::count(vp.last().map_or(0.0, |q| q.0), "mode", "modes"), vp.last().map_or(0.0, |q| q.1)));
        }
        // (d) chattering.
        let mut tc = Table::new(
            "Chattering: momentum method with and without the persistent-contact phase",
            &[
                "c_r",
                "persistent contact",
                "status",
                "impacts",
                "persistent phases",
                "reason",
            ],
        );
        for &cr in &d.chatter_restitution {
            for p in [true, false] {
                let r = res.get(&chatter(ctx, &d, cr, p));
                tc.push(vec![
                    cr.to_string(),
                    p.to_string(),
                    r.error_kind
                        .clone()
                        .map_or(r.status.clone(), |k| format!("failed: {k}")),
                    r.ok().map_or("–".into(), |o| o.impacts.to_string()),
                    r.ok()
                        .map_or("–".into(), |o| o.persistent_contacts.to_string()),
                    r.error.clone().unwrap_or_default(),
                ]);
            }
        }
        if let Some(cr) = d.chatter_restitution.first() {
            let on = res.get(&chatter(ctx, &d, *cr, true));
            let off = res.get(&chatter(ctx, &d, *cr, false));
            reading.push(format!(
                "At c_r = {cr} the run with the persistent-contact phase finishes ({}, {}); \
                without it the run ends as {}.",
                crate::table::count(on.ok().map_or(0, |o| o.impacts), "impact", "impacts"),
                crate::table::count(
                    on.ok().map_or(0, |o| o.persistent_contacts),
                    "phase",
                    "phases"
                ),
                off.error_kind.clone().unwrap_or_else(|| "ok".into())
            ));
        }
        let pa_panel = Panel {
            title: "Adaptive gap element: cost against k".into(),
            x_label: "contact stiffness k (N/m)".into(),
            y_label: "right-hand-side evaluations".into(),
            log_x: true,
            log_y: true,
            series: vec![Series::line("rhs evaluations", pa, 0).marker(Marker::Circle)],
            no_legend: true,
            ..Default::default()
        };
        let pv_panel = Panel {
            title: "Restitution violation against modes (c_r = 1)".into(),
            x_label: "modes kept".into(),
            y_label: "1 − min achieved c_r".into(),
            log_y: true,
            series: vec![
                Series::line("paper impulse", vp, 1).marker(Marker::Circle),
                Series::line("consistent impulse", vc, 0).marker(Marker::Triangle),
            ],
            legend_right: true,
            ..Default::default()
        };
        figure(
            &ctx.dir,
            "stability",
            (1200, 1500),
            (2, 1),
            &[PanelKind::Heat(heat_e), PanelKind::Heat(heat_r)],
            "Fixed-step Newmark (linear gap element, c_r = 1) against the adaptive solver at the same k (tolerance 1e-10), one cell per swept (Δt, k); grey crossed cells: failed run, or impacts in only one of the two runs.",
        )?;
        figure(
            &ctx.dir,
            STABILITY_MODES,
            (1200, 1300),
            (2, 1),
            &[PanelKind::Xy(pa_panel), PanelKind::Xy(pv_panel)],
            "Top: cost of the adaptive gap element against the spring stiffness. Bottom: the paper impulse's violation of the restitution law against modes kept (the consistent impulse keeps it to rounding).",
        )?;
        tn.write(&ctx.dir, "newmark_grid")?;
        ta.write(&ctx.dir, "adaptive_cost")?;
        tp.write(&ctx.dir, "paper_variant")?;
        tc.write(&ctx.dir, "chattering")?;
        if let Some(n) = failures_note(res) {
            reading.push(n);
        }
        write_summary(
            ctx,
            "Study 7: where methods fail",
            &reading,
            &[&tn, &tc],
            &[
                ("stability", "Newmark error maps over (Δt, k)"),
                (
                    STABILITY_MODES,
                    "Adaptive cost against k; the paper impulse's restitution violation against modes",
                ),
            ],
        )
    }
}

/// Largest relative difference of the peak story shears, over all stories of all buildings.
fn max_rel(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y))
        .map(|(x, y)| (x - y).abs() / y.abs().max(1e-300))
        .fold(0.0, f64::max)
}
