//! Study 3 (`modes`): the momentum method's hidden parameter, the number of modes kept, for
//! both impulse variants: contact-story amplification, achieved restitution and r_N.

use serde::Deserialize;
use solvers::Method;

use super::{
    amp_contact, default_pga, default_records, failures_note, mean, record_label, write_summary,
    Ctx, Study,
};
use crate::plot::{figure, Marker, Panel, PanelKind, Series};
use crate::sweep::{CaseSpec, Result, Results};
use crate::table::{f, Table};

pub struct Modes;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    scene: String,
    #[serde(default = "default_pga")]
    pga: f64,
    #[serde(default = "default_records")]
    records: Vec<String>,
    gap: f64,
    restitution: f64,
    max_modes: usize,
    variants: Vec<String>,
}

fn case(ctx: &Ctx, d: &Def, rec: &str, variant: &str, n: usize) -> CaseSpec {
    ctx.case(&d.scene, Method::Momentum, rec, d.pga)
        .with("contacts.0.gap", format!("{:?}", d.gap))
        .with("contacts.0.restitution", format!("{:?}", d.restitution))
        .with("momentum.impulse", variant)
        .with("momentum.modes", n)
        .param("modes", n)
        .param("variant", variant)
}

fn modes(ctx: &Ctx, d: &Def) -> Vec<usize> {
    if ctx.opts.quick {
        vec![1, 5, d.max_modes]
    } else {
        (1..=d.max_modes).collect()
    }
}

impl Study for Modes {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        let mut v = Vec::new();
        for rec in ctx.records(&d.records, true) {
            for var in &d.variants {
                for n in modes(ctx, &d) {
                    v.push(case(ctx, &d, &rec, var, n));
                }
            }
        }
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let d: Def = ctx.def()?;
        let recs = ctx.records(&d.records, true);
        let ns = modes(ctx, &d);
        let mut t = Table::new(
            &format!("Momentum method against modes kept (gap {} cm, c_r = {}); means over {} records, achieved c_r minimum over all", d.gap * 100.0, d.restitution, recs.len()),
            &["impulse", "modes", "r_N b1", "r_N b2", "amp. contact story b1", "amp. contact story b2", "impacts", "achieved c_r mean", "achieved c_r min"],
        );
        let mut long = Table::new(
            "Every record",
            &[
                "record",
                "impulse",
                "modes",
                "amp. contact story b1",
                "amp. contact story b2",
                "impacts",
                "achieved c_r mean",
                "achieved c_r min",
                "status",
            ],
        );
        let mut amp_p = Panel {
            title: "Top-story amplification, building 1".into(),
            x_label: "modes kept per building".into(),
            y_label: "amplification factor".into(),
            legend_right: true,
            ..Default::default()
        };
        let mut amp2_p = Panel {
            title: "Top-story amplification, building 2".into(),
            x_label: "modes kept per building".into(),
            y_label: "amplification factor".into(),
            no_legend: true,
            ..Default::default()
        };
        let mut e_p = Panel {
            title: "Achieved restitution (min over impacts)".into(),
            x_label: "modes kept per building".into(),
            y_label: "achieved c_r".into(),
            legend_right: true,
            ..Default::default()
        };
        let mut r_p = Panel {
            title: "Contact flexibility kept r_N".into(),
            x_label: "modes kept per building".into(),
            y_label: "r_N".into(),
            legend_right: false,
            ..Default::default()
        };
        let mut reading = Vec::new();
        for (vi, var) in d.variants.iter().enumerate() {
            let mut pa = Vec::new();
            let mut pb = Vec::new();
            let mut pe = Vec::new();
            let (mut r1, mut r2) = (Vec::new(), Vec::new());
            for &n in &ns {
                let cs: Vec<CaseSpec> = recs.iter().map(|r| case(ctx, &d, r, var, n)).collect();
                let a1 = mean(cs.iter().filter_map(|c| amp_contact(res, c, 0)));
                let a2 = mean(cs.iter().filter_map(|c| amp_contact(res, c, 1)));
                let imp = mean(
                    cs.iter()
                        .filter_map(|c| res.out(c).map(|o| o.impacts as f64)),
                );
                let em = mean(
                    cs.iter()
                        .filter_map(|c| res.out(c).and_then(|o| o.restitution_mean)),
                );
                let emin = cs
                    .iter()
                    .filter_map(|c| res.out(c).and_then(|o| o.restitution_min))
                    .fold(None, |a: Option<f64>, x| Some(a.map_or(x, |a| a.min(x))));
                let rn = cs.iter().find_map(|c| res.out(c).and_then(|o| o.r_n));
                t.push(vec![
                    var.clone(),
                    n.to_string(),
                    f(rn.map(|r| r.0), 4),
                    f(rn.map(|r| r.1), 4),
                    f(a1, 3),
                    f(a2, 3),
                    f(imp, 1),
                    f(em, 4),
                    f(emin, 4),
                ]);
                if let Some(a) = a1 {
                    pa.push((n as f64, a));
                }
                if let Some(a) = a2 {
                    pb.push((n as f64, a));
                }
                if let Some(e) = emin {
                    pe.push((n as f64, e));
                }
                if let Some(r) = rn {
                    r1.push((n as f64, r.0));
                    r2.push((n as f64, r.1));
                }
                for c in &cs {
                    let r = res.get(c);
                    let o = r.ok();
                    long.push(vec![
                        c.params
                            .get("record")
                            .and_then(|v| v.as_str())
                            .unwrap_or("")
                            .to_string(),
                        var.clone(),
                        n.to_string(),
                        f(amp_contact(res, c, 0), 3),
                        f(amp_contact(res, c, 1), 3),
                        o.map_or("–".into(), |o| o.impacts.to_string()),
                        f(o.and_then(|o| o.restitution_mean), 4),
                        f(o.and_then(|o| o.restitution_min), 4),
                        r.error_kind
                            .clone()
                            .map_or(r.status.clone(), |k| format!("failed: {k}")),
                    ]);
                }
            }
            let mk = if vi == 0 {
                Marker::Circle
            } else {
                Marker::Triangle
            };
            amp_p
                .series
                .push(Series::line(&format!("{var} impulse"), pa.clone(), vi).marker(mk));
            amp2_p
                .series
                .push(Series::line(&format!("{var} impulse"), pb.clone(), vi).marker(mk));
            e_p.series
                .push(Series::line(&format!("{var} impulse"), pe.clone(), vi).marker(mk));
            if vi == 0 {
                r_p.series
                    .push(Series::line("building 1 (roof)", r1.clone(), 2).marker(Marker::Circle));
                r_p.series.push(
                    Series::line("building 2 (roof)", r2.clone(), 3).marker(Marker::Triangle),
                );
                let at = |v: &Vec<(f64, f64)>, n: f64| v.iter().find(|p| p.0 == n).map(|p| p.1);
                reading.push(format!(
                    "With 5 modes the roofs keep r_N = {} and {} of their contact flexibility, with 10 modes {} and {}.",
                    f(at(&r1, 5.0), 2), f(at(&r2, 5.0), 2), f(at(&r1, 10.0), 2), f(at(&r2, 10.0), 2)
                ));
            }
            let at_n =
                |v: &Vec<(f64, f64)>, n: usize| v.iter().find(|p| p.0 == n as f64).map(|p| p.1);
            let (n0, n1) = (ns[0], ns[ns.len() - 1]);
            let emin_all = pe.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            let restitution = if emin_all >= d.restitution - 1e-9 {
                format!(
                    "the achieved restitution stays at the target {} for every mode count",
                    d.restitution
                )
            } else {
                let worst_n = pe
                    .iter()
                    .find(|p| p.1 == emin_all)
                    .map_or(0, |p| p.0 as usize);
                format!(
                    "the achieved restitution falls to {} with {worst_n} mode(s) (target {})",
                    f(Some(emin_all), 3),
                    d.restitution
                )
            };
            reading.push(format!(
                "{var} impulse: the contact-story amplification (mean over records) of building 1 goes from {} with {n0} mode(s) to {} with {n1}, of building 2 from {} to {}; with 10 modes {} and {}; {restitution}.",
                f(at_n(&pa, n0), 2), f(at_n(&pa, n1), 2), f(at_n(&pb, n0), 2), f(at_n(&pb, n1), 2),
                f(at_n(&pa, 10), 2), f(at_n(&pb, 10), 2)
            ));
        }
        let _ = record_label;
        figure(
            &ctx.dir,
            "modes",
            (1200, 920),
            (2, 2),
            &[PanelKind::Xy(amp_p), PanelKind::Xy(amp2_p), PanelKind::Xy(e_p), PanelKind::Xy(r_p)],
            "Momentum method against modes kept: consistent impulse (exact restitution, contact too heavy) vs the paper's floor-mass impulse (restitution violated).",
        )?;
        t.write(&ctx.dir, "modes")?;
        long.write(&ctx.dir, "modes_all")?;
        if let Some(n) = failures_note(res) {
            reading.push(n);
        }
        write_summary(
            ctx,
            "Study 3: modes kept by the momentum method",
            &reading,
            &[&t],
            &[(
                "modes",
                "Amplification, achieved restitution and r_N against modes kept",
            )],
        )
    }
}
