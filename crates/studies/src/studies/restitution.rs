//! Study 4 (`restitution`): amplification against the coefficient of restitution, both
//! methods (gap element: Kelvin–Voigt), with persistent-contact phases.
//!
//! Statistics over the records that pound (the momentum method records at least one impact
//! at that c_r): median and 16th/84th percentiles ([`super::stats`]), the count n in every
//! row.

use serde::Deserialize;
use solvers::Method;

use super::stats::{median_band, Spread};
use super::{
    amp_contact, default_pga, failures_note, record_classes, require_pga, study_records,
    write_summary, Ctx, Study,
};
use crate::plot::{figure, Panel, PanelKind, Series};
use crate::sweep::{CaseSpec, Result, Results};
use crate::table::{f, Table};

pub struct Restitution;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    /// Scene of the pair (relative to `studies/`); contact 0 joins the two buildings.
    scene: String,
    /// Analysis PGA, g: finite, > 0 (default 0.40).
    #[serde(default = "default_pga")]
    pga: f64,
    /// Record files (relative to `studies/`); default: the four Loma Prieta components
    /// when `record_dirs` is not given either. With `record_dirs`, at least one record in all.
    records: Option<Vec<String>>,
    /// Folders whose every `*.AT2` is added (sorted by file name); default none.
    #[serde(default)]
    record_dirs: Vec<String>,
    /// Record metadata (pulse classes), relative to `studies/`; without it
    /// `../data/ground-motions/records.csv` if that exists, else every record unclassified
    /// ([`super::record_classes`]).
    #[serde(default)]
    record_table: Option<String>,
    /// Gap of contact 0, m: finite, >= 0.
    gap: f64,
    /// Coefficients of restitution c_r of the sweep: at least one, each in [0, 1].
    restitution: Vec<f64>,
    /// Kelvin–Voigt gap-element stiffnesses, N/m: at least one, each > 0 (checked by the
    /// scene in every case).
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
    fn takes_record_table(&self) -> bool {
        true
    }

    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        super::require(
            ctx,
            !d.restitution.is_empty() && d.restitution.iter().all(|c| (0.0..=1.0).contains(c)),
            || {
                format!(
                    "`restitution` = {:?}: expected at least one c_r, each in [0, 1]",
                    d.restitution
                )
            },
        )?;
        require_pga(ctx, d.pga)?;
        super::require_gap(ctx, d.gap)?;
        super::require(ctx, !d.gap_stiffness.is_empty(), || {
            "`gap_stiffness` = []: expected at least one gap-element stiffness (N/m)".into()
        })?;
        let mut v = Vec::new();
        let recs = study_records(ctx, d.records.as_deref(), &d.record_dirs)?;
        record_classes(ctx, d.record_table.as_deref(), &recs)?;
        for rec in recs {
            for cr in crs(ctx, &d) {
                v.extend(methods(ctx, &d, &rec, cr).into_iter().map(|m| m.1));
            }
        }
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let d: Def = ctx.def()?;
        let recs = study_records(ctx, d.records.as_deref(), &d.record_dirs)?;
        let classes = record_classes(ctx, d.record_table.as_deref(), &recs)?;
        let cs = crs(ctx, &d);
        let labels: Vec<String> = methods(ctx, &d, &recs[0], 1.0)
            .into_iter()
            .map(|m| m.0)
            .collect();
        let mut t = Table::new(
            &format!(
                "Contact-story amplification against c_r (gap {} cm), {}: median and 16th–84th \
                percentiles over the n records that pound",
                d.gap * 100.0,
                crate::table::count(recs.len(), "record", "records")
            ),
            &[
                "c_r",
                "method",
                "n",
                "amp. b1 median",
                "amp. b1 p16",
                "amp. b1 p84",
                "amp. b2 median",
                "amp. b2 p16",
                "amp. b2 p84",
                "impacts median",
                "achieved c_r median",
                "persistent-contact phases median",
                "failed",
            ],
        );
        let panel = |title: &str, x: &str, y: &str| Panel {
            title: title.into(),
            x_label: x.into(),
            y_label: y.into(),
            legend_right: true,
            ..Default::default()
        };
        let xl = "coefficient of restitution c_r";
        let mut p1 = panel(
            "Contact-story amplification, building 1",
            xl,
            "amplification factor",
        );
        let mut p2 = panel(
            "Contact-story amplification, building 2",
            xl,
            "amplification factor",
        );
        let mut p3 = panel(
            "Achieved restitution (mean over impacts)",
            "target c_r",
            "achieved c_r",
        );
        p3.legend_right = false;
        let mut p4 = panel(
            "Persistent-contact phases (momentum)",
            xl,
            "phases per analysis",
        );
        // Records that pound at each c_r (momentum method).
        let pounding = |cr: f64| -> Vec<usize> {
            (0..recs.len())
                .filter(|&i| {
                    res.out(&methods(ctx, &d, &recs[i], cr).swap_remove(0).1)
                        .is_some_and(|o| o.impacts > 0)
                })
                .collect()
        };
        let amp = |cr: f64, mi: usize, b: usize, idx: &[usize]| {
            Spread::of(idx.iter().filter_map(|&i| {
                amp_contact(res, &methods(ctx, &d, &recs[i], cr).swap_remove(mi).1, b)
            }))
        };
        for (mi, lab) in labels.iter().enumerate() {
            let (mut a, mut b, mut e, mut pc) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for &cr in &cs {
                let idx = pounding(cr);
                let cases: Vec<CaseSpec> = recs
                    .iter()
                    .map(|r| methods(ctx, &d, r, cr).swap_remove(mi).1)
                    .collect();
                let sp = |fun: &dyn Fn(&CaseSpec) -> Option<f64>| {
                    Spread::of(idx.iter().filter_map(|&i| fun(&cases[i])))
                };
                let a1 = sp(&|c| amp_contact(res, c, 0));
                let a2 = sp(&|c| amp_contact(res, c, 1));
                let imp = sp(&|c| res.out(c).map(|o| o.impacts as f64));
                let er = sp(&|c| res.out(c).and_then(|o| o.restitution_mean));
                let per = sp(&|c| res.out(c).map(|o| o.persistent_contacts as f64));
                let failed = cases.iter().filter(|c| res.get(c).status != "ok").count();
                let mut row = vec![cr.to_string(), lab.clone(), a1.n.to_string()];
                row.extend(a1.cells(3));
                row.extend(a2.cells(3));
                row.extend([
                    f(imp.median, 1),
                    f(er.median, 3),
                    f(per.median, 1),
                    failed.to_string(),
                ]);
                t.push(row);
                a.push((cr, a1));
                b.push((cr, a2));
                e.push((cr, er));
                pc.push((cr, per));
            }
            p1.series.extend(median_band(lab, mi, &a));
            p2.series.extend(median_band(lab, mi, &b));
            p3.series.extend(median_band(lab, mi, &e));
            if mi == 0 {
                p4.series.extend(median_band(lab, mi, &pc));
            }
        }
        p3.series
            .push(Series::line("target", vec![(0.0, 0.0), (1.0, 1.0)], 7).width(1));
        figure(&ctx.dir, "restitution", (1200, 920), (2, 2), &[PanelKind::Xy(p1), PanelKind::Xy(p2), PanelKind::Xy(p3), PanelKind::Xy(p4)],
            "Against c_r, records that pound: solid = median, thin dashed = 16th and 84th percentiles; gap element with the Kelvin-Voigt law (force clamped at zero).")?;
        t.write(&ctx.dir, "restitution")?;
        let (lo, hi) = (cs[0], cs[cs.len() - 1]);
        let (ilo, ihi) = (pounding(lo), pounding(hi));
        let mut reading = vec![format!(
            "{} of {} records pound at c_r = {lo} and {} at c_r = {hi} (the statistics are over these). With the momentum method the contact-story amplification of building 1, median (16–84 %), is {} at c_r = {lo} and {} at c_r = {hi}; building 2: {} and {}.",
            ilo.len(),
            recs.len(),
            ihi.len(),
            amp(lo, 0, 0, &ilo).words(2),
            amp(hi, 0, 0, &ihi).words(2),
            amp(lo, 0, 1, &ilo).words(2),
            amp(hi, 0, 1, &ihi).words(2)
        )];
        for (mi, lab) in labels.iter().enumerate().skip(1) {
            reading.push(format!(
                "{lab}: {} at c_r = {lo}, {} at c_r = {hi} (building 1).",
                amp(lo, mi, 0, &ilo).words(2),
                amp(hi, mi, 0, &ihi).words(2)
            ));
        }
        let np = classes
            .iter()
            .filter(|c| **c == super::record_table::PulseClass::Pulse)
            .count();
        reading.push(format!(
            "Records: {} ({np} with a velocity pulse; classes in records.csv and restitution_all.csv).",
            recs.len()
        ));
        let mut long = Table::new(
            "Every record",
            &[
                "record",
                "pulse",
                "c_r",
                "method",
                "amp. contact story b1",
                "amp. contact story b2",
                "impacts",
                "achieved c_r (mean)",
                "status",
            ],
        );
        for (i, r) in recs.iter().enumerate() {
            for &cr in &cs {
                for (lab, c) in methods(ctx, &d, r, cr) {
                    let rr = res.get(&c);
                    let o = rr.ok();
                    long.push(vec![
                        super::record_name(r),
                        classes[i].label().into(),
                        cr.to_string(),
                        lab,
                        f(amp_contact(res, &c, 0), 3),
                        f(amp_contact(res, &c, 1), 3),
                        o.map_or("–".into(), |o| o.impacts.to_string()),
                        f(o.and_then(|o| o.restitution_mean), 4),
                        rr.error_kind
                            .clone()
                            .map_or(rr.status.clone(), |k| format!("failed: {k}")),
                    ]);
                }
            }
        }
        long.write(&ctx.dir, "restitution_all")?;
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
