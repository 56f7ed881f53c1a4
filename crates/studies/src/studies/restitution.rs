//! Study 4 (`restitution`): amplification against the coefficient of restitution, both
//! methods (gap element: Kelvin–Voigt), with persistent-contact phases.

use serde::Deserialize;
use solvers::Method;

use super::{
    amp_contact, default_pga, default_records, failures_note, mean, write_summary, Ctx, Study,
};
use crate::plot::{figure, Marker, Panel, PanelKind, Series};
use crate::sweep::{CaseSpec, Result, Results};
use crate::table::{f, Table};

pub struct Restitution;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    scene: String,
    #[serde(default = "default_pga")]
    pga: f64,
    #[serde(default = "default_records")]
    records: Vec<String>,
    gap: f64,
    restitution: Vec<f64>,
    gap_stiffness: Vec<f64>,
}

fn crs(ctx: &Ctx, d: &Def) -> Vec<f64> {
    if ctx.opts.quick {
        vec![0.0, 0.5, 1.0]
    } else {
        d.restitution.clone()
    }
}

/// (label, case) for each method at `cr`.
fn methods(ctx: &Ctx, d: &Def, rec: &str, cr: f64) -> Vec<(String, CaseSpec)> {
    let base = |m| {
        ctx.case(&d.scene, m, rec, d.pga)
            .with("contacts.0.gap", format!("{:?}", d.gap))
            .with("contacts.0.restitution", format!("{cr:?}"))
            .param("restitution", cr)
    };
    let mut v = vec![(
        "momentum, all modes".to_string(),
        base(Method::Momentum)
            .with("momentum.impulse", "consistent")
            .param("variant", "momentum"),
    )];
    for &k in &d.gap_stiffness {
        v.push((
            format!("gap element KV k={k:.0e}"),
            base(Method::Gap)
                .with("gap_element.law", "kelvin-voigt")
                .with("gap_element.integrator", "adaptive")
                .with("gap_element.stiffness", format!("{k:e}"))
                .param("variant", format!("gap kelvin-voigt k={k:e}")),
        ));
    }
    v
}

impl Study for Restitution {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        let mut v = Vec::new();
        for rec in ctx.records(&d.records, true) {
            for cr in crs(ctx, &d) {
                v.extend(methods(ctx, &d, &rec, cr).into_iter().map(|m| m.1));
            }
        }
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let d: Def = ctx.def()?;
        let recs = ctx.records(&d.records, true);
        let cs = crs(ctx, &d);
        let labels: Vec<String> = methods(ctx, &d, &recs[0], 1.0)
            .into_iter()
            .map(|m| m.0)
            .collect();
        let mut t = Table::new(
            &format!(
                "Top-story amplification against c_r (gap {} cm), means over {} records",
                d.gap * 100.0,
                recs.len()
            ),
            &[
                "c_r",
                "method",
                "amp. contact story b1",
                "amp. contact story b2",
                "impacts",
                "achieved c_r (mean)",
                "persistent-contact phases",
                "failed",
            ],
        );
        let mut p1 = Panel {
            title: "Top-story amplification, building 1".into(),
            x_label: "coefficient of restitution c_r".into(),
            y_label: "amplification factor".into(),
            legend_right: false,
            ..Default::default()
        };
        let mut p2 = Panel {
            title: "Top-story amplification, building 2".into(),
            x_label: "coefficient of restitution c_r".into(),
            y_label: "amplification factor".into(),
            no_legend: true,
            ..Default::default()
        };
        let mut p3 = Panel {
            title: "Achieved restitution (mean over impacts)".into(),
            x_label: "target c_r".into(),
            y_label: "achieved c_r".into(),
            legend_right: false,
            ..Default::default()
        };
        let mut p4 = Panel {
            title: "Persistent-contact phases (momentum)".into(),
            x_label: "coefficient of restitution c_r".into(),
            y_label: "phases per analysis".into(),
            no_legend: true,
            ..Default::default()
        };
        let mk = [
            Marker::Circle,
            Marker::Triangle,
            Marker::Square,
            Marker::Cross,
        ];
        for (mi, lab) in labels.iter().enumerate() {
            let (mut a, mut b, mut e, mut pc) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for &cr in &cs {
                let cases: Vec<CaseSpec> = recs
                    .iter()
                    .map(|r| methods(ctx, &d, r, cr).swap_remove(mi).1)
                    .collect();
                let a1 = mean(cases.iter().filter_map(|c| amp_contact(res, c, 0)));
                let a2 = mean(cases.iter().filter_map(|c| amp_contact(res, c, 1)));
                let imp = mean(
                    cases
                        .iter()
                        .filter_map(|c| res.out(c).map(|o| o.impacts as f64)),
                );
                let er = mean(
                    cases
                        .iter()
                        .filter_map(|c| res.out(c).and_then(|o| o.restitution_mean)),
                );
                let per = mean(
                    cases
                        .iter()
                        .filter_map(|c| res.out(c).map(|o| o.persistent_contacts as f64)),
                );
                let failed = cases.iter().filter(|c| res.get(c).status != "ok").count();
                t.push(vec![
                    cr.to_string(),
                    lab.clone(),
                    f(a1, 3),
                    f(a2, 3),
                    f(imp, 1),
                    f(er, 3),
                    f(per, 1),
                    failed.to_string(),
                ]);
                if let Some(x) = a1 {
                    a.push((cr, x));
                }
                if let Some(x) = a2 {
                    b.push((cr, x));
                }
                if let Some(x) = er {
                    e.push((cr, x));
                }
                if let Some(x) = per {
                    pc.push((cr, x));
                }
            }
            p1.series.push(Series::line(lab, a, mi).marker(mk[mi % 4]));
            p2.series.push(Series::line(lab, b, mi).marker(mk[mi % 4]));
            p3.series.push(Series::line(lab, e, mi).marker(mk[mi % 4]));
            if mi == 0 {
                p4.series.push(Series::line(lab, pc, mi).marker(mk[0]));
            }
        }
        p3.series.push(
            Series::line("target", vec![(0.0, 0.0), (1.0, 1.0)], 7)
                .dashed()
                .width(1),
        );
        figure(&ctx.dir, "restitution", (1200, 920), (2, 2), &[PanelKind::Xy(p1), PanelKind::Xy(p2), PanelKind::Xy(p3), PanelKind::Xy(p4)],
            "Amplification against the coefficient of restitution; gap element with the Kelvin-Voigt law (force clamped at zero).")?;
        t.write(&ctx.dir, "restitution")?;
        let pick =
            |cr: f64, mi: usize, b: usize| {
                mean(recs.iter().filter_map(|r| {
                    amp_contact(res, &methods(ctx, &d, r, cr).swap_remove(mi).1, b)
                }))
            };
        let (lo, hi) = (cs[0], cs[cs.len() - 1]);
        let mut reading = vec![format!(
            "With the momentum method the contact-story amplification of building 1 (mean over records) is {} at c_r = {lo} and {} at c_r = {hi}; building 2: {} and {}.",
            f(pick(lo, 0, 0), 2), f(pick(hi, 0, 0), 2), f(pick(lo, 0, 1), 2), f(pick(hi, 0, 1), 2)
        )];
        for (mi, lab) in labels.iter().enumerate().skip(1) {
            reading.push(format!(
                "{lab}: {} at c_r = {lo}, {} at c_r = {hi} (building 1).",
                f(pick(lo, mi, 0), 2),
                f(pick(hi, mi, 0), 2)
            ));
        }
        if let Some(n) = failures_note(res) {
            reading.push(n);
        }
        write_summary(
            ctx,
            "Study 4: coefficient of restitution",
            &reading,
            &[&t],
            &[(
                "restitution",
                "Amplification, achieved restitution and persistent contact against c_r",
            )],
        )
    }
}
