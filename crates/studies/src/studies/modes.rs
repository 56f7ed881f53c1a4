//! Study 3 (`modes`): the momentum method's hidden parameter, the number of modes kept, for
//! both impulse variants: contact-story amplification, achieved restitution and r_N.
//!
//! Statistics over the records that pound in each case (at least one impact): median and
//! 16th/84th percentiles ([`super::stats`]), the count n in every row; the minimum achieved
//! restitution over every impact of every record besides.

use serde::Deserialize;
use solvers::Method;

use super::record_table::PulseClass;
use super::stats::{median_band, Spread};
use super::{
    amp_contact, default_pga, failures_note, is_restitution, record_classes, record_name,
    require_count, require_pga, study_records, write_summary, Ctx, Study, MAX_MODES,
};
use crate::plot::{figure, Marker, Panel, PanelKind, Series};
use crate::sweep::{CaseSpec, Result, Results};
use crate::table::{f, Table};

pub struct Modes;

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
    /// Coefficient of restitution of contact 0: in [0, 1].
    restitution: f64,
    /// Modes kept per building run 1 … this: 5 ..= [`MAX_MODES`] (1000; a count above a
    /// building's floors keeps all its modes).
    max_modes: usize,
    /// Impulse variants of the momentum method (`"consistent"`, `"paper"`): at least one,
    /// each once.
    variants: Vec<String>,
}

/// The impulse variants (`momentum.impulse`) the study may compare.
const VARIANTS: [&str; 2] = ["consistent", "paper"];

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
    fn takes_record_table(&self) -> bool {
        true
    }

    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        require_pga(ctx, d.pga)?;
        super::require_gap(ctx, d.gap)?;
        super::require(ctx, is_restitution(d.restitution), || {
            format!(
                "`restitution` = {:?}: expected a coefficient of restitution in [0, 1]",
                d.restitution
            )
        })?;
        // (The study compares 1, 5, … modes.)
        require_count(ctx, "max_modes", d.max_modes, 5..=MAX_MODES, "modes")?;
        let known = d.variants.iter().all(|v| VARIANTS.contains(&v.as_str()));
        let once = d
            .variants
            .iter()
            .enumerate()
            .all(|(i, v)| !d.variants[..i].contains(v));
        super::require(ctx, !d.variants.is_empty() && known && once, || {
            format!(
                "`variants` = {:?}: expected at least one impulse variant, each once, of {VARIANTS:?}",
                d.variants
            )
        })?;
        let mut v = Vec::new();
        let recs = study_records(ctx, d.records.as_deref(), &d.record_dirs)?;
        record_classes(ctx, d.record_table.as_deref(), &recs)?;
        for rec in recs {
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
        let recs = study_records(ctx, d.records.as_deref(), &d.record_dirs)?;
        let classes = record_classes(ctx, d.record_table.as_deref(), &recs)?;
        let ns = modes(ctx, &d);
        let mut t = Table::new(
            &format!(
                "Momentum method against modes kept (gap {} cm, c_r = {}), {}: median and \
                16th–84th percentiles over the n records that pound; achieved c_r minimum over \
                every impact of every record",
                d.gap * 100.0,
                d.restitution,
                crate::table::count(recs.len(), "record", "records")
            ),
            &[
                "impulse",
                "modes",
                "r_N b1",
                "r_N b2",
                "n",
                "amp. b1 median",
                "amp. b1 p16",
                "amp. b1 p84",
                "amp. b2 median",
                "amp. b2 p16",
                "amp. b2 p84",
                "impacts median",
                "achieved c_r median",
                "achieved c_r min",
            ],
        );
        let mut by_class = Table::new(
            "Contact-story amplification of building 1 by pulse class (records that pound): median and 16th–84th percentiles",
            &["impulse", "modes", "records", "n", "amp. b1 median", "amp. b1 p16", "amp. b1 p84", "amp. b2 median"],
        );
        let mut long = Table::new(
            "Every record",
            &[
                "record",
                "pulse",
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
        let panel = |title: &str, y: &str| Panel {
            title: title.into(),
            x_label: "modes kept per building".into(),
            y_label: y.into(),
            legend_right: true,
            ..Default::default()
        };
        let mut amp_p = panel(
            "Contact-story amplification, building 1",
            "amplification factor",
        );
        let mut amp2_p = panel(
            "Contact-story amplification, building 2",
            "amplification factor",
        );
        let mut e_p = panel("Achieved restitution (per-record minimum)", "achieved c_r");
        let mut r_p = panel("Contact flexibility kept r_N", "r_N");
        r_p.legend_right = false;
        let mut reading = Vec::new();
        for (vi, var) in d.variants.iter().enumerate() {
            let (mut pa, mut pb, mut pe) = (Vec::new(), Vec::new(), Vec::new());
            let (mut r1, mut r2) = (Vec::new(), Vec::new());
            let mut emin_all: Option<(f64, usize)> = None;
            for &n in &ns {
                let cs: Vec<CaseSpec> = recs.iter().map(|r| case(ctx, &d, r, var, n)).collect();
                let pounds: Vec<usize> = (0..cs.len())
                    .filter(|&i| res.out(&cs[i]).is_some_and(|o| o.impacts > 0))
                    .collect();
                let sp = |idx: &[usize], fun: &dyn Fn(&CaseSpec) -> Option<f64>| {
                    Spread::of(idx.iter().filter_map(|&i| fun(&cs[i])))
                };
                let a1 = sp(&pounds, &|c| amp_contact(res, c, 0));
                let a2 = sp(&pounds, &|c| amp_contact(res, c, 1));
                let imp = sp(&pounds, &|c| res.out(c).map(|o| o.impacts as f64));
                let em = sp(&pounds, &|c| res.out(c).and_then(|o| o.restitution_mean));
                let emr = sp(&pounds, &|c| res.out(c).and_then(|o| o.restitution_min));
                let emin = cs
                    .iter()
                    .filter_map(|c| res.out(c).and_then(|o| o.restitution_min))
                    .fold(None, |a: Option<f64>, x| Some(a.map_or(x, |a| a.min(x))));
                if let Some(e) = emin {
                    if emin_all.is_none_or(|(m, _)| e < m) {
                        emin_all = Some((e, n));
                    }
                }
                let rn = cs.iter().find_map(|c| res.out(c).and_then(|o| o.r_n));
                let mut row = vec![
                    var.clone(),
                    n.to_string(),
                    f(rn.map(|r| r.0), 4),
                    f(rn.map(|r| r.1), 4),
                    a1.n.to_string(),
                ];
                row.extend(a1.cells(3));
                row.extend(a2.cells(3));
                row.extend([f(imp.median, 1), f(em.median, 4), f(emin, 4)]);
                t.push(row);
                for c in PulseClass::ALL {
                    let idx: Vec<usize> = pounds
                        .iter()
                        .copied()
                        .filter(|&i| classes[i] == c)
                        .collect();
                    if idx.is_empty() {
                        continue;
                    }
                    let b1 = sp(&idx, &|c| amp_contact(res, c, 0));
                    let b2 = sp(&idx, &|c| amp_contact(res, c, 1));
                    let mut row = vec![
                        var.clone(),
                        n.to_string(),
                        c.label().into(),
                        b1.n.to_string(),
                    ];
                    row.extend(b1.cells(3));
                    row.push(f(b2.median, 3));
                    by_class.push(row);
                }
                pa.push((n as f64, a1));
                pb.push((n as f64, a2));
                pe.push((n as f64, emr));
                if let Some(r) = rn {
                    r1.push((n as f64, r.0));
                    r2.push((n as f64, r.1));
                }
                for (i, c) in cs.iter().enumerate() {
                    let r = res.get(c);
                    let o = r.ok();
                    long.push(vec![
                        record_name(&recs[i]),
                        classes[i].label().into(),
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
            let name = format!("{var} impulse");
            amp_p.series.extend(median_band(&name, vi, &pa));
            amp2_p.series.extend(median_band(&name, vi, &pb));
            e_p.series.extend(median_band(&name, vi, &pe));
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
            let at_n = |v: &Vec<(f64, Spread)>, n: usize| {
                v.iter()
                    .find(|p| p.0 == n as f64)
                    .map_or(Spread::of([]), |p| p.1)
            };
            let (n0, n1) = (ns[0], ns[ns.len() - 1]);
            let restitution = match emin_all {
                Some((e, _)) if e >= d.restitution - 1e-9 => format!(
                    "the achieved restitution stays at the target {} for every mode count and record",
                    d.restitution
                ),
                Some((e, worst_n)) => format!(
                    "the achieved restitution falls to {} (worst impact of any record) with {} (target {})",
                    f(Some(e), 3),
                    crate::table::count(worst_n, "mode", "modes"),
                    d.restitution
                ),
                None => "no impact has a defined restitution".into(),
            };
            let (m0, m1) = (
                crate::table::count(n0, "mode", "modes"),
                crate::table::count(n1, "mode", "modes"),
            );
            reading.push(format!(
                "{var} impulse ({} of {} records pound with {m1}): the contact-story amplification of building 1, median (16–84 %), goes from {} with {m0} to {} with {m1}, of building 2 from {} to {}; with 10 modes {} and {}; {restitution}.",
                at_n(&pa, n1).n,
                recs.len(),
                at_n(&pa, n0).words(2),
                at_n(&pa, n1).words(2),
                at_n(&pb, n0).words(2),
                at_n(&pb, n1).words(2),
                at_n(&pa, 10).words(2),
                at_n(&pb, 10).words(2)
            ));
        }
        figure(
            &ctx.dir,
            "modes",
            (1200, 920),
            (2, 2),
            &[PanelKind::Xy(amp_p), PanelKind::Xy(amp2_p), PanelKind::Xy(e_p), PanelKind::Xy(r_p)],
            "Momentum method against modes kept, records that pound: solid = median, thin dashed = 16th and 84th percentiles.",
        )?;
        t.write(&ctx.dir, "modes")?;
        by_class.write(&ctx.dir, "modes_pulse")?;
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
