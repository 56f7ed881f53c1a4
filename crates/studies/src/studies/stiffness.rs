//! Study 2 (`stiffness`): how the gap element's answer depends on its spring stiffness.
//!
//! Gap element (linear law for c_r = 1, Kelvin–Voigt for c_r < 1) at log-spaced k against
//! the momentum method with all modes (the rigid-impact limit of the same physics):
//! amplification at the impact story, peak contact-floor displacement, impacts; error against k with
//! a fitted log-log slope; CPU time against k.

use serde::Deserialize;
use solvers::Method;

use super::{
    amp_contact, default_pga, default_records, failures_note, fit_line, logspace, mean,
    record_label, shear_error, write_summary, Ctx, Study,
};
use crate::plot::{figure, Marker, Panel, PanelKind, Series};
use crate::sweep::{CaseSpec, Result, Results};
use crate::table::{e, f, Table};

pub struct Stiffness;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    scene: String,
    #[serde(default = "default_pga")]
    pga: f64,
    #[serde(default = "default_records")]
    records: Vec<String>,
    gap: f64,
    stiffness_min: f64,
    stiffness_max: f64,
    stiffness_count: usize,
    restitution: Vec<f64>,
    /// Smallest k used in the slope fit.
    fit_min_stiffness: f64,
    tolerance: f64,
}

struct Grid {
    records: Vec<String>,
    ks: Vec<f64>,
    crs: Vec<f64>,
}

fn grid(ctx: &Ctx, d: &Def) -> Grid {
    let (ks, crs) = if ctx.opts.quick {
        (
            logspace(d.stiffness_min, d.stiffness_max, 4),
            d.restitution.iter().take(1).copied().collect(),
        )
    } else {
        (
            logspace(d.stiffness_min, d.stiffness_max, d.stiffness_count),
            d.restitution.clone(),
        )
    };
    Grid {
        records: ctx.records(&d.records, true),
        ks,
        crs,
    }
}

fn momentum(ctx: &Ctx, d: &Def, rec: &str, cr: f64) -> CaseSpec {
    ctx.case(&d.scene, Method::Momentum, rec, d.pga)
        .with("contacts.0.gap", format!("{:?}", d.gap))
        .with("contacts.0.restitution", format!("{cr:?}"))
        .with("momentum.impulse", "consistent")
        .param("restitution", cr)
        .param("variant", "momentum, all modes")
}

fn gap_case(ctx: &Ctx, d: &Def, rec: &str, cr: f64, k: f64) -> CaseSpec {
    let law = if cr >= 1.0 { "linear" } else { "kelvin-voigt" };
    ctx.case(&d.scene, Method::Gap, rec, d.pga)
        .with("contacts.0.gap", format!("{:?}", d.gap))
        .with("contacts.0.restitution", format!("{cr:?}"))
        .with("gap_element.law", law)
        .with("gap_element.integrator", "adaptive")
        .with("gap_element.tolerance", format!("{:e}", d.tolerance))
        .with("gap_element.stiffness", format!("{k:e}"))
        .param("restitution", cr)
        .param("gap_stiffness_N_per_m", k)
        .param("variant", format!("gap element, {law}"))
}

impl Study for Stiffness {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        let g = grid(ctx, &d);
        let mut v = Vec::new();
        for rec in &g.records {
            for &cr in &g.crs {
                v.push(momentum(ctx, &d, rec, cr));
                for &k in &g.ks {
                    v.push(gap_case(ctx, &d, rec, cr, k));
                }
            }
        }
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let d: Def = ctx.def()?;
        let g = grid(ctx, &d);
        let top = super::contact_floor_displacement;
        let mut long = Table::new(
            "Gap element vs stiffness, every record (error = max relative story-shear difference from the momentum method with all modes)",
            &[
                "record", "c_r", "k (N/m)", "amp. contact story b1", "amp. contact story b2", "peak contact-floor disp. b1 (m)",
                "peak contact-floor disp. b2 (m)", "impacts", "first impact (s)", "achieved c_r (mean)", "error", "status",
            ],
        );
        let mut cpu = Table::new(
            "CPU time vs stiffness",
            &[
                "record",
                "c_r",
                "k (N/m)",
                "wall (s)",
                "steps",
                "rejected",
                "rhs evaluations",
            ],
        );
        let mut panels = Vec::new();
        let mut err_panel = Panel {
            title: "Error against the momentum method (all modes)".into(),
            x_label: "k (N/m)".into(),
            y_label: "max relative story-shear error".into(),
            log_x: true,
            log_y: true,
            legend_right: true,
            ..Default::default()
        };
        let mut imp_panel = Panel {
            title: "Impacts (contact episodes)".into(),
            x_label: "k (N/m)".into(),
            y_label: "number of impacts".into(),
            log_x: true,
            legend_right: false,
            no_legend: true,
            ..Default::default()
        };
        let mut cpu_panel = Panel {
            title: "CPU time of the gap element".into(),
            x_label: "k (N/m)".into(),
            y_label: "wall time (s)".into(),
            log_x: true,
            log_y: true,
            ..Default::default()
        };
        let mut summary = Table::new(
            "Mean over the records: contact-story amplification of building 1 and 2, impacts and error",
            &["c_r", "k (N/m)", "amp. b1", "amp. b2", "impacts", "error"],
        );
        let mut reading = Vec::new();
        let mut no_contact: Vec<String> = Vec::new();
        for (ci, &cr) in g.crs.iter().enumerate() {
            let mut amp_panel = Panel {
                title: format!("Top-story amplification, building 1, c_r = {cr}"),
                x_label: "k (N/m)".into(),
                y_label: "amplification factor".into(),
                log_x: true,
                legend_right: false,
                ..Default::default()
            };
            let mut fit_pts = Vec::new();
            for (ri, rec) in g.records.iter().enumerate() {
                let lab = record_label(rec);
                let m = momentum(ctx, &d, rec, cr);
                let mo = res.out(&m);
                let m_amp = amp_contact(res, &m, 0);
                let touches = mo.is_some_and(|o| o.impacts > 0);
                if !touches && !no_contact.contains(&lab) {
                    no_contact.push(lab.clone());
                }
                long.push(vec![
                    lab.clone(),
                    cr.to_string(),
                    "momentum".into(),
                    f(m_amp, 3),
                    f(amp_contact(res, &m, 1), 3),
                    f(mo.and_then(|o| top(o, 0)), 4),
                    f(mo.and_then(|o| top(o, 1)), 4),
                    mo.map_or("–".into(), |o| o.impacts.to_string()),
                    f(mo.and_then(|o| o.impact_times.first().copied()), 4),
                    f(mo.and_then(|o| o.restitution_mean), 4),
                    "0 (reference)".into(),
                    res.get(&m).status.clone(),
                ]);
                let mut amp_pts = Vec::new();
                let mut err_pts = Vec::new();
                let mut imp_pts = Vec::new();
                let mut cpu_pts = Vec::new();
                for &k in &g.ks {
                    let c = gap_case(ctx, &d, rec, cr, k);
                    let r = res.get(&c);
                    let o = r.ok();
                    let a = amp_contact(res, &c, 0);
                    let err = match (o, mo) {
                        (Some(o), Some(m)) => Some(shear_error(o, m)),
                        _ => None,
                    };
                    if let Some(a) = a {
                        amp_pts.push((k, a));
                    }
                    if let Some(e) = err {
                        if e > 0.0 {
                            err_pts.push((k, e));
                            if k >= d.fit_min_stiffness && touches {
                                fit_pts.push((k.log10(), e.log10()));
                            }
                        }
                    }
                    if let Some(o) = o {
                        imp_pts.push((k, o.impacts as f64));
                        cpu_pts.push((k, r.wall_seconds));
                    }
                    long.push(vec![
                        lab.clone(),
                        cr.to_string(),
                        format!("{k:.3e}"),
                        f(a, 3),
                        f(amp_contact(res, &c, 1), 3),
                        f(o.and_then(|o| top(o, 0)), 4),
                        f(o.and_then(|o| top(o, 1)), 4),
                        o.map_or("–".into(), |o| o.impacts.to_string()),
                        f(o.and_then(|o| o.impact_times.first().copied()), 4),
                        f(o.and_then(|o| o.restitution_mean), 4),
                        e(err, 3),
                        match &r.error_kind {
                            Some(k) => format!("failed: {k}"),
                            None => r.status.clone(),
                        },
                    ]);
                    cpu.push(vec![
                        lab.clone(),
                        cr.to_string(),
                        format!("{k:.3e}"),
                        format!("{:.4e}", r.wall_seconds),
                        o.map_or("–".into(), |o| o.steps.to_string()),
                        o.map_or("–".into(), |o| o.rejected_steps.to_string()),
                        o.map_or("–".into(), |o| o.rhs_evaluations.to_string()),
                    ]);
                }
                amp_panel.series.push(
                    Series::line(&format!("{lab}, gap element"), amp_pts, ri)
                        .marker(Marker::Circle),
                );
                if let Some(a) = m_amp {
                    amp_panel.series.push(
                        Series::line(
                            &format!("{lab}, momentum"),
                            vec![(g.ks[0], a), (*g.ks.last().unwrap_or(&g.ks[0]), a)],
                            ri,
                        )
                        .dashed()
                        .width(1),
                    );
                }
                let mk = if ci == 0 {
                    Marker::Circle
                } else {
                    Marker::Triangle
                };
                let s = Series::line(&format!("{lab}, c_r = {cr}"), err_pts, ri)
                    .marker(mk)
                    .width(1);
                err_panel.series.push(if ci == 0 { s } else { s.dashed() });
                imp_panel.series.push(
                    Series::line(&format!("{lab}, c_r = {cr}"), imp_pts, ri)
                        .marker(mk)
                        .width(1),
                );
                cpu_panel.series.push(
                    Series::line(&format!("{lab}, c_r = {cr}"), cpu_pts, ri)
                        .marker(mk)
                        .width(1),
                );
            }
            panels.push(PanelKind::Xy(amp_panel));
            // Mean rows.
            let mean_of =
                |fun: &dyn Fn(&str) -> Option<f64>| mean(g.records.iter().filter_map(|r| fun(r)));
            let mrow_err = Some(0.0);
            summary.push(vec![
                cr.to_string(),
                "momentum (rigid)".into(),
                f(
                    mean_of(&|r| amp_contact(res, &momentum(ctx, &d, r, cr), 0)),
                    3,
                ),
                f(
                    mean_of(&|r| amp_contact(res, &momentum(ctx, &d, r, cr), 1)),
                    3,
                ),
                f(
                    mean_of(&|r| res.out(&momentum(ctx, &d, r, cr)).map(|o| o.impacts as f64)),
                    1,
                ),
                f(mrow_err, 0),
            ]);
            let err_of = |r: &str, k: f64| match (
                res.out(&gap_case(ctx, &d, r, cr, k)),
                res.out(&momentum(ctx, &d, r, cr)),
            ) {
                (Some(o), Some(m)) => Some(shear_error(o, m)),
                _ => None,
            };
            for &k in &g.ks {
                summary.push(vec![
                    cr.to_string(),
                    format!("{k:.3e}"),
                    f(
                        mean_of(&|r| amp_contact(res, &gap_case(ctx, &d, r, cr, k), 0)),
                        3,
                    ),
                    f(
                        mean_of(&|r| amp_contact(res, &gap_case(ctx, &d, r, cr, k), 1)),
                        3,
                    ),
                    f(
                        mean_of(&|r| {
                            res.out(&gap_case(ctx, &d, r, cr, k))
                                .map(|o| o.impacts as f64)
                        }),
                        1,
                    ),
                    e(mean_of(&|r| err_of(r, k)), 2),
                ]);
            }
            let fit = fit_line(&fit_pts);
            if let Some((slope, icpt)) = fit {
                let xs = [
                    d.fit_min_stiffness,
                    *g.ks.last().unwrap_or(&d.stiffness_max),
                ];
                err_panel.series.push(
                    Series::line(
                        &format!("fit c_r = {cr}: slope {slope:.2}"),
                        xs.iter()
                            .map(|&k| (k, 10f64.powf(icpt + slope * k.log10())))
                            .collect(),
                        7 + ci,
                    )
                    .width(2),
                );
            }
            let (k0, k1) = (g.ks[0], *g.ks.last().unwrap_or(&g.ks[0]));
            let a0 = mean_of(&|r| amp_contact(res, &gap_case(ctx, &d, r, cr, k0), 0));
            let a1 = mean_of(&|r| amp_contact(res, &gap_case(ctx, &d, r, cr, k1), 0));
            let am = mean_of(&|r| amp_contact(res, &momentum(ctx, &d, r, cr), 0));
            let e1 = mean_of(&|r| err_of(r, k1));
            reading.push(format!(
                "For c_r = {cr} ({} law) the gap element's contact-story amplification of building 1 (mean over {} records) moves from {} at k = {k0:.0e} to {} at k = {k1:.0e} N/m, against {} for the momentum method; the story-shear error left at k = {k1:.0e} is {}{}.",
                if cr >= 1.0 { "linear" } else { "Kelvin–Voigt" },
                g.records.len(),
                f(a0, 2),
                f(a1, 2),
                f(am, 2),
                e(e1, 1),
                match fit {
                    Some((s, _)) => format!(
                        " and the error falls like k^{s:.2} for k >= {:.0e} N/m (fitted over the records with impacts){}",
                        d.fit_min_stiffness,
                        if cr >= 1.0 { "" } else { "; with the force clamped at zero the Kelvin–Voigt element does not reach the rigid answer, so the error levels off" }
                    ),
                    None => String::new(),
                }
            ));
        }
        if !no_contact.is_empty() {
            reading.push(format!(
                "Records whose buildings never touch at this gap ({}) are left out of the slope fits; their error is integration error only.",
                no_contact.join(", ")
            ));
        }
        panels.push(PanelKind::Xy(err_panel));
        panels.push(PanelKind::Xy(imp_panel));
        let rows = panels.len().div_ceil(2);
        figure(
            &ctx.dir,
            "stiffness",
            (1200, 460 * rows as u32),
            (rows, 2),
            &panels,
            "Gap element against spring stiffness k; dashed horizontal lines: momentum method (all modes), the rigid limit.",
        )?;
        figure(
            &ctx.dir,
            "stiffness_cpu",
            (700, 480),
            (1, 1),
            &[PanelKind::Xy(cpu_panel)],
            "Wall time of one gap-element analysis against k (machine-dependent).",
        )?;
        long.write(&ctx.dir, "stiffness_all")?;
        summary.write(&ctx.dir, "stiffness")?;
        cpu.write(&ctx.dir, "stiffness_cpu")?;
        if let Some(n) = failures_note(res) {
            reading.push(n);
        }
        write_summary(
            ctx,
            "Study 2: gap-element stiffness",
            &reading,
            &[&summary],
            &[(
                "stiffness",
                "Gap element against k, with the momentum method as the rigid limit",
            )],
        )
    }
}
