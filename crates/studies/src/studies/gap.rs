//! Study 5 (`gap`): amplification against gap size, with the exact no-contact gap and the
//! ABS, SRSS and DDC separation rules.
//!
//! Per record, from the no-contact baseline: Δ_b = peak displacement of building b at the
//! contact floor, the exact separation = peak of u1(t) − u2(t), and the rules
//! ABS = Δ1 + Δ2, SRSS = √(Δ1² + Δ2²), DDC = √(Δ1² + Δ2² − 2ρΔ1Δ2) with the CQC
//! correlation ρ of the two fundamental modes ([`cqc_rho`]). The gap grid should reach past
//! the largest exact separation (the reading says whether it does).
//!
//! Statistics over the records that pound at each gap (the method records at least one
//! impact): median and 16th/84th percentiles ([`super::stats`]), the count n in every row,
//! and the same split by pulse class (records.csv).

use serde::Deserialize;
use solvers::Method;

use super::record_table::PulseClass;
use super::stats::{median_band, Spread};
use super::{
    amp_contact, contact_floor_displacement, default_pga, failures_note, record_classes,
    record_name, require_count, require_pga, study_records, write_summary, Ctx, Study, MAX_GRID,
};
use crate::plot::{figure, Marker, Panel, PanelKind, Series};
use crate::sweep::{CaseSpec, Result, Results, StudyError};
use crate::table::{f, Table};

pub struct Gap;

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
    /// Largest gap of the grid, m: finite, > 0 (the grid runs from 0 to it).
    gap_max: f64,
    /// Gaps in the grid (evenly spaced, 0 … `gap_max`): 2 ..= [`MAX_GRID`] (1000).
    gap_count: usize,
    /// Linear gap-element stiffness, N/m: > 0 (checked by the scene in every case).
    gap_stiffness: f64,
    /// Damping ratio of the CQC correlation of the DDC rule: 0 <= ζ < 1.
    damping: f64,
}

fn gaps(ctx: &Ctx, d: &Def) -> Vec<f64> {
    let n = if ctx.opts.quick { 6 } else { d.gap_count };
    (0..n)
        .map(|i| {
            let g = d.gap_max * i as f64 / (n - 1).max(1) as f64;
            (g * 1e6).round() / 1e6
        })
        .collect()
}

/// The gap grid in words, cm: every gap when there are few, else the first ones and the last.
fn grid_words(gs: &[f64]) -> String {
    let cm: Vec<String> = gs
        .iter()
        .map(|g| crate::table::trimmed(g * 100.0, 2))
        .collect();
    if cm.len() <= 6 {
        format!("{} cm", cm.join(", "))
    } else {
        format!("{}, {}, {} … {} cm", cm[0], cm[1], cm[2], cm[cm.len() - 1])
    }
}

fn mom(ctx: &Ctx, d: &Def, rec: &str, gap: f64) -> CaseSpec {
    ctx.case(&d.scene, Method::Momentum, rec, d.pga)
        .with("contacts.0.gap", format!("{gap:?}"))
        .with("contacts.0.restitution", "1.0")
        .with("momentum.impulse", "consistent")
        .param("gap_m", gap)
        .param("variant", "momentum, all modes")
}

fn gel(ctx: &Ctx, d: &Def, rec: &str, gap: f64) -> CaseSpec {
    ctx.case(&d.scene, Method::Gap, rec, d.pga)
        .with("contacts.0.gap", format!("{gap:?}"))
        .with("contacts.0.restitution", "1.0")
        .with("gap_element.law", "linear")
        .with("gap_element.integrator", "adaptive")
        .with("gap_element.stiffness", format!("{:e}", d.gap_stiffness))
        .param("gap_m", gap)
        .param("variant", format!("gap element k = {:e}", d.gap_stiffness))
}

/// CQC correlation coefficient of two modes with equal damping ζ and frequency ratio r
/// (1 at r = 1 for any ζ, the limit of the formula, which reads 0/0 there when ζ = 0).
pub fn cqc_rho(zeta: f64, r: f64) -> f64 {
    if r == 1.0 {
        return 1.0;
    }
    let z2 = zeta * zeta;
    8.0 * z2 * (1.0 + r) * r.powf(1.5) / ((1.0 - r * r).powi(2) + 4.0 * z2 * r * (1.0 + r).powi(2))
}

impl Study for Gap {
    fn takes_record_table(&self) -> bool {
        true
    }

    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        require_pga(ctx, d.pga)?;
        require_count(ctx, "gap_count", d.gap_count, 2..=MAX_GRID, "gaps")?;
        super::require(ctx, d.gap_max.is_finite() && d.gap_max > 0.0, || {
            format!("`gap_max` = {:?}: expected a gap > 0 (m)", d.gap_max)
        })?;
        super::require(ctx, (0.0..1.0).contains(&d.damping), || {
            format!(
                "`damping` = {:?}: expected a damping ratio 0 <= ζ < 1 (the CQC correlation of the DDC rule)",
                d.damping
            )
        })?;
        let mut v = Vec::new();
        let recs = study_records(ctx, d.records.as_deref(), &d.record_dirs)?;
        record_classes(ctx, d.record_table.as_deref(), &recs)?;
        for rec in recs {
            for g in gaps(ctx, &d) {
                v.push(mom(ctx, &d, &rec, g));
                v.push(gel(ctx, &d, &rec, g));
            }
        }
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let d: Def = ctx.def()?;
        let gs = gaps(ctx, &d);
        let recs = study_records(ctx, d.records.as_deref(), &d.record_dirs)?;
        let classes = record_classes(ctx, d.record_table.as_deref(), &recs)?;
        let scene = CaseSpec::new(&d.scene, Method::Momentum)
            .load_scene(&ctx.studies_dir)
            .map_err(StudyError::Other)?;
        let w: Vec<f64> = scene
            .buildings
            .iter()
            .map(|b| b.modes().map(|m| m.omega[0]).unwrap_or(f64::NAN))
            .collect();
        let r = w[0].min(w[1]) / w[0].max(w[1]);
        let rho = cqc_rho(d.damping, r);
        let kname = format!("gap element (k = {:.0e} N/m)", d.gap_stiffness);
        let mut table = Table::new(
            &format!(
                "Contact-story amplification against gap size (c_r = 1), every record; {kname}"
            ),
            &[
                "record",
                "pulse",
                "gap (cm)",
                "momentum b1",
                "momentum b2",
                "momentum impacts",
                "gap element b1",
                "gap element b2",
                "gap element impacts",
            ],
        );
        let mut summary = Table::new(
            &format!(
                "Contact-story amplification against gap size (c_r = 1), {}: median and \
            16th–84th percentiles over the n records that pound with each method; {kname}",
                crate::table::count(recs.len(), "record", "records")
            ),
            &[
                "gap (cm)",
                "momentum n",
                "momentum b1 median",
                "momentum b1 p16",
                "momentum b1 p84",
                "momentum b2 median",
                "momentum b2 p16",
                "momentum b2 p84",
                "gap element n",
                "gap element b1 median",
                "gap element b1 p16",
                "gap element b1 p84",
                "gap element b2 median",
                "gap element b2 p16",
                "gap element b2 p84",
            ],
        );
        let mut pulse = Table::new(
            "Momentum method by pulse class: records that pound (n of N) and their contact-story amplification, median and 16th–84th percentiles",
            &[
                "gap (cm)", "records", "N", "n", "b1 median", "b1 p16", "b1 p84", "b2 median", "b2 p16", "b2 p84",
            ],
        );
        let mut sep = Table::new(
            &format!("Separation needed (cm): exact = peak of u1 − u2 without contact; Δ = peak contact-floor displacement without contact; DDC with ρ = {rho:.4} (CQC, ζ = {}, ω1/ω2 = {r:.4})", d.damping),
            &["record", "pulse", "Δ1", "Δ2", "exact", "DDC", "SRSS", "ABS"],
        );
        let mut sep_sum = Table::new(
            "Separations over the records (cm; ratios to the exact separation): median and 16th–84th percentiles",
            &["records", "n", "quantity", "median", "p16", "p84"],
        );
        // Separations per record: (exact, ddc, srss, abs).
        let mut seps: Vec<Option<[f64; 4]>> = Vec::new();
        for (ri, rec) in recs.iter().enumerate() {
            let lab = record_name(rec);
            for &g in &gs {
                let (m, e) = (mom(ctx, &d, rec, g), gel(ctx, &d, rec, g));
                table.push(vec![
                    lab.clone(),
                    classes[ri].label().into(),
                    f(Some(g * 100.0), 1),
                    f(amp_contact(res, &m, 0), 3),
                    f(amp_contact(res, &m, 1), 3),
                    res.out(&m).map_or("–".into(), |o| o.impacts.to_string()),
                    f(amp_contact(res, &e, 0), 3),
                    f(amp_contact(res, &e, 1), 3),
                    res.out(&e).map_or("–".into(), |o| o.impacts.to_string()),
                ]);
            }
            let base = res.out(&mom(ctx, &d, rec, gs[0]).baseline());
            seps.push(base.map(|b| {
                let d1 = contact_floor_displacement(b, 0).unwrap_or(f64::NAN);
                let d2 = contact_floor_displacement(b, 1).unwrap_or(f64::NAN);
                let exact = b.peak_closure.unwrap_or(f64::NAN);
                let abs = d1 + d2;
                let srss = (d1 * d1 + d2 * d2).sqrt();
                let ddc = (d1 * d1 + d2 * d2 - 2.0 * rho * d1 * d2).max(0.0).sqrt();
                sep.push(vec![
                    lab.clone(),
                    classes[ri].label().into(),
                    f(Some(d1 * 100.0), 2),
                    f(Some(d2 * 100.0), 2),
                    f(Some(exact * 100.0), 2),
                    f(Some(ddc * 100.0), 2),
                    f(Some(srss * 100.0), 2),
                    f(Some(abs * 100.0), 2),
                ]);
                [exact, ddc, srss, abs]
            }));
        }
        let pounds = |c: &CaseSpec| res.out(c).is_some_and(|o| o.impacts > 0);
        let all: Vec<usize> = (0..recs.len()).collect();
        let mut groups: Vec<(&str, Vec<usize>)> = vec![("all", all.clone())];
        for c in PulseClass::ALL {
            let idx: Vec<usize> = all.iter().copied().filter(|&i| classes[i] == c).collect();
            if !idx.is_empty() {
                groups.push((c.label(), idx));
            }
        }
        for (gname, idx) in &groups {
            let s: Vec<[f64; 4]> = idx.iter().filter_map(|&i| seps[i]).collect();
            let names = ["exact", "DDC", "SRSS", "ABS"];
            for (q, name) in names.iter().enumerate() {
                let sp = Spread::of(s.iter().map(|v| v[q] * 100.0));
                let mut row = vec![gname.to_string(), sp.n.to_string(), format!("{name} (cm)")];
                row.extend(sp.cells(1));
                sep_sum.push(row);
            }
            for (q, name) in names.iter().enumerate().skip(1) {
                let sp = Spread::of(s.iter().map(|v| v[q] / v[0]));
                let mut row = vec![
                    gname.to_string(),
                    sp.n.to_string(),
                    format!("{name} / exact"),
                ];
                row.extend(sp.cells(2));
                sep_sum.push(row);
            }
        }
        // Aggregates against the gap.
        let amp_sp = |case: &dyn Fn(&str, f64) -> CaseSpec, g: f64, b: usize, idx: &[usize]| {
            Spread::of(idx.iter().filter_map(|&i| {
                let c = case(&recs[i], g);
                if pounds(&c) {
                    amp_contact(res, &c, b)
                } else {
                    None
                }
            }))
        };
        let momc = |rec: &str, g: f64| mom(ctx, &d, rec, g);
        let gelc = |rec: &str, g: f64| gel(ctx, &d, rec, g);
        let mut curves: Vec<Vec<(f64, Spread)>> = vec![Vec::new(); 4];
        type Curve = Vec<(f64, Spread)>;
        let mut class_curves: Vec<(PulseClass, [Curve; 2])> = Vec::new();
        for c in [PulseClass::Pulse, PulseClass::NoPulse] {
            class_curves.push((c, [Vec::new(), Vec::new()]));
        }
        let mut count_curves: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        for (gname, _) in &groups {
            count_curves.push((format!("pounding, {gname} records"), Vec::new()));
        }
        let rule_names = ["DDC", "SRSS", "ABS"];
        let mut rule_counts: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 3];
        for &g in &gs {
            let x = g * 100.0;
            let m1 = amp_sp(&momc, g, 0, &all);
            let m2 = amp_sp(&momc, g, 1, &all);
            let e1 = amp_sp(&gelc, g, 0, &all);
            let e2 = amp_sp(&gelc, g, 1, &all);
            let mut row = vec![f(Some(x), 1), m1.n.to_string()];
            row.extend(m1.cells(3));
            row.extend(m2.cells(3));
            row.push(e1.n.to_string());
            row.extend(e1.cells(3));
            row.extend(e2.cells(3));
            summary.push(row);
            for (k, s) in [m1, m2, e1, e2].into_iter().enumerate() {
                curves[k].push((x, s));
            }
            for (gi, (gname, idx)) in groups.iter().enumerate() {
                let n = idx.iter().filter(|&&i| pounds(&momc(&recs[i], g))).count();
                count_curves[gi].1.push((x, n as f64));
                if *gname == "all" {
                    continue;
                }
                let b1 = amp_sp(&momc, g, 0, idx);
                let b2 = amp_sp(&momc, g, 1, idx);
                let mut row = vec![
                    f(Some(x), 1),
                    gname.to_string(),
                    idx.len().to_string(),
                    b1.n.to_string(),
                ];
                row.extend(b1.cells(3));
                row.extend(b2.cells(3));
                pulse.push(row);
                for (c, cc) in class_curves.iter_mut() {
                    if c.label() == *gname {
                        cc[0].push((x, b1));
                        cc[1].push((x, b2));
                    }
                }
            }
            for (q, rc) in rule_counts.iter_mut().enumerate() {
                let n = seps.iter().flatten().filter(|s| s[q + 1] > g).count();
                rc.push((x, n as f64));
            }
        }
        // Figure.
        let exacts: Vec<f64> = seps.iter().flatten().map(|s| s[0]).collect();
        let exact_sp = Spread::of(exacts.iter().map(|v| v * 100.0));
        let exact_max = exacts.iter().copied().fold(f64::NAN, f64::max);
        let vline = |series: &[Series]| -> Option<Series> {
            let m = exact_sp.median?;
            let ys: Vec<f64> = series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1))
                .collect();
            let lo = ys.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo <= hi).then(|| {
                Series::line(
                    &format!("median exact separation {m:.1} cm"),
                    vec![(m, lo), (m, hi)],
                    7,
                )
                .width(1)
            })
        };
        let amp_panel = |title: String, series: Vec<Series>| {
            let mut series = series;
            if let Some(v) = vline(&series) {
                series.push(v);
            }
            Panel {
                title,
                x_label: "gap (cm)".into(),
                y_label: "amplification factor".into(),
                series,
                legend_right: true,
                ..Default::default()
            }
        };
        // Medians over fewer than MIN_N records are not drawn (the tables keep them).
        const MIN_N: usize = 5;
        let enough = |v: &[(f64, Spread)]| -> Vec<(f64, Spread)> {
            v.iter().filter(|p| p.1.n >= MIN_N).copied().collect()
        };
        let mut panels = Vec::new();
        for b in 0..2 {
            let mut s = median_band("momentum (all modes)", 0, &enough(&curves[b]));
            s.extend(median_band(&kname, 1, &enough(&curves[2 + b])));
            panels.push(amp_panel(
                format!("Building {}: contact-story amplification", b + 1),
                s,
            ));
        }
        for b in 0..2 {
            let mut s = Vec::new();
            for (c, cc) in &class_curves {
                let col = if *c == PulseClass::Pulse { 3 } else { 2 };
                s.extend(median_band(
                    &format!("momentum, {}", c.label()),
                    col,
                    &enough(&cc[b]),
                ));
            }
            panels.push(amp_panel(
                format!("Building {}: pulse vs no pulse (momentum)", b + 1),
                s,
            ));
        }
        let mut cnt = Panel {
            title: "Records that pound vs records the rules flag".into(),
            x_label: "gap (cm)".into(),
            y_label: "number of records".into(),
            legend_right: true,
            ..Default::default()
        };
        for (gi, (name, pts)) in count_curves.into_iter().enumerate() {
            let col = match gi {
                0 => 0,
                _ => match groups[gi].0 {
                    "pulse" => 3,
                    "no pulse" => 2,
                    _ => 8,
                },
            };
            cnt.series.push(Series::line(&name, pts, col));
        }
        for (q, pts) in rule_counts.into_iter().enumerate() {
            cnt.series.push(
                Series::line(&format!("{} separation > gap", rule_names[q]), pts, 4 + q).width(1),
            );
        }
        let mut sc = Panel {
            title: "Separation rules against the exact separation".into(),
            x_label: "exact no-contact separation (cm)".into(),
            y_label: "rule separation (cm)".into(),
            legend_right: false,
            ..Default::default()
        };
        let mk = [Marker::Circle, Marker::Triangle, Marker::Cross];
        for q in 0..3 {
            sc.series.push(Series::points(
                rule_names[q],
                seps.iter()
                    .flatten()
                    .map(|s| (s[0] * 100.0, s[q + 1] * 100.0))
                    .collect(),
                4 + q,
                mk[q],
            ));
        }
        if exact_max.is_finite() {
            let hi = exact_max * 100.0;
            sc.series
                .push(Series::line("rule = exact", vec![(0.0, 0.0), (hi, hi)], 7).width(1));
        }
        panels.push(cnt);
        panels.push(sc);
        let rows = panels.len().div_ceil(2);
        figure(
            &ctx.dir,
            "gap",
            (1200, 470 * rows as u32),
            (rows, 2),
            &panels.into_iter().map(PanelKind::Xy).collect::<Vec<_>>(),
            &format!("Contact-story amplification against the gap, c_r = 1, {kname}; records that pound: solid = median, thin dashed = 16th and 84th percentiles (drawn where at least {MIN_N} records pound)."),
        )?;
        table.write(&ctx.dir, "gap")?;
        summary.write(&ctx.dir, "gap_summary")?;
        pulse.write(&ctx.dir, "gap_pulse")?;
        sep.write(&ctx.dir, "separation")?;
        sep_sum.write(&ctx.dir, "separation_summary")?;
        // Readings.
        let mut reading = Vec::new();
        let gmax = gs.last().copied().unwrap_or(0.0);
        reading.push(format!(
            "{} ({}), gaps 0 to {:.1} cm. The exact no-contact separation (peak of u1 − u2) has \
            median {} cm and reaches {:.1} cm; {}",
            crate::table::count(recs.len(), "record", "records"),
            groups
                .iter()
                .skip(1)
                .map(|(g, i)| format!("{} {g}", i.len()))
                .collect::<Vec<_>>()
                .join(", "),
            gmax * 100.0,
            exact_sp.words(1),
            exact_max * 100.0,
            if exact_max <= gmax {
                "the gap grid extends past it for every record, so every curve ends with no contact.".to_string()
            } else {
                format!(
                    "{} at the largest gap of the grid.",
                    crate::table::count(
                        exacts.iter().filter(|&&x| x > gmax).count(),
                        "record still pounds",
                        "records still pound"
                    )
                )
            }
        ));
        let ratio = |q: usize| Spread::of(seps.iter().flatten().map(|s| s[q] / s[0]));
        reading.push(format!(
            "The rules ask for DDC {}, SRSS {}, ABS {} times the exact separation (median, 16–84 %).",
            ratio(1).words(2),
            ratio(2).words(2),
            ratio(3).words(2)
        ));
        let at = |g: f64| gs.iter().position(|x| (x - g).abs() < 1e-9);
        for g in [0.05, 0.10] {
            if let Some(gi) = at(g) {
                let p = &class_curves[0].1;
                let np = &class_curves[1].1;
                reading.push(format!(
                    "At {:.0} cm, {} of {} records pound (momentum); contact-story amplification, median (16–84 %): building 1 {}, building 2 {}; the gap element gives {} and {}. Pulse records (n = {}): building 1 {}, building 2 {}; no-pulse records (n = {}): {}, {}.",
                    g * 100.0,
                    curves[0][gi].1.n,
                    recs.len(),
                    curves[0][gi].1.words(2),
                    curves[1][gi].1.words(2),
                    curves[2][gi].1.words(2),
                    curves[3][gi].1.words(2),
                    p[0].get(gi).map_or(0, |s| s.1.n),
                    p[0].get(gi).map_or("–".into(), |s| s.1.words(2)),
                    p[1].get(gi).map_or("–".into(), |s| s.1.words(2)),
                    np[0].get(gi).map_or(0, |s| s.1.n),
                    np[0].get(gi).map_or("–".into(), |s| s.1.words(2)),
                    np[1].get(gi).map_or("–".into(), |s| s.1.words(2)),
                ));
            }
        }
        // Paper's statements, over the records that pound at both 5 and 10 cm.
        let (mut worse5, mut small_lower, mut n) = (0, 0, 0);
        for rec in &recs {
            let c = |g: f64| mom(ctx, &d, rec, g);
            if !(pounds(&c(0.05)) && pounds(&c(0.10))) {
                continue;
            }
            let a = |g: f64| amp_contact(res, &c(g), 1);
            if let (Some(a5), Some(a10)) = (a(0.05), a(0.10)) {
                n += 1;
                if a5 > a10 {
                    worse5 += 1;
                }
                let small = gs
                    .iter()
                    .filter(|g| **g > 0.0 && **g < 0.05)
                    .filter_map(|g| a(*g))
                    .fold(f64::NAN, f64::min);
                if small < a5 {
                    small_lower += 1;
                }
            }
        }
        if n > 0 {
            // The grid's gaps strictly between 0 and 5 cm (the comparison above).
            let between: Vec<String> = gs
                .iter()
                .filter(|g| **g > 0.0 && **g < 0.05)
                .map(|g| crate::table::trimmed(g * 100.0, 2))
                .collect();
            let smaller = match between.len() {
                0 => "no gap of the grid lies strictly between 0 and 5 cm".to_string(),
                1 => format!(
                    "the {} cm gap (the grid's only one strictly between 0 and 5 cm) gives a smaller amplification than 5 cm for {small_lower} of {n}",
                    between[0]
                ),
                _ => format!(
                    "one of the grid's gaps strictly between 0 and 5 cm ({} cm) gives a smaller amplification than 5 cm for {small_lower} of {n}",
                    between.join(", ")
                ),
            };
            reading.push(format!(
                "Paper's statements (momentum method, building 2, contact story, the {n} records that pound at both 5 and 10 cm): a 5 cm gap gives a larger amplification than 10 cm for {worse5} of {n}; {smaller}."
            ));
        }
        // The paper attributes the larger effect of a 5 cm gap to higher impact velocities:
        // per record, the 5 cm / 10 cm ratios of the amplification and of the approach speeds.
        let mut claims = Table::new(
            "5 cm against 10 cm gap, per record that pounds at both (momentum method, all modes, c_r = 1, building 2 contact story): ratios 5 cm / 10 cm, median (16th–84th percentile), and how many records have a ratio above 1",
            &["quantity", "n", "median", "p16", "p84", "records with ratio > 1"],
        );
        let mut ratios: [Vec<f64>; 3] = [vec![], vec![], vec![]];
        for rec in &recs {
            let c = |g: f64| mom(ctx, &d, rec, g);
            let (Some(o5), Some(o10)) = (res.out(&c(0.05)), res.out(&c(0.10))) else {
                continue;
            };
            if o5.impacts == 0 || o10.impacts == 0 {
                continue;
            }
            let a = |g: f64| amp_contact(res, &c(g), 1);
            if let (Some(a5), Some(a10)) = (a(0.05), a(0.10)) {
                ratios[0].push(a5 / a10);
            }
            if let (Some(v5), Some(v10)) = (o5.approach_speed_median, o10.approach_speed_median) {
                ratios[1].push(v5 / v10);
            }
            if let (Some(v5), Some(v10)) = (o5.approach_speed_max, o10.approach_speed_max) {
                ratios[2].push(v5 / v10);
            }
        }
        for (name, r) in [
            "amplification, building 2 contact story",
            "median approach speed of the impacts",
            "largest approach speed of the impacts",
        ]
        .iter()
        .zip(&ratios)
        {
            let s = Spread::of(r.iter().copied());
            let [m, lo, hi] = s.cells(3);
            claims.push(vec![
                name.to_string(),
                r.len().to_string(),
                m,
                lo,
                hi,
                r.iter().filter(|x| **x > 1.0).count().to_string(),
            ]);
        }
        // Without a 5 cm or a 10 cm gap in the grid there is nothing to compare: one line
        // saying so instead of a table of n = 0 (the CSV keeps its header, without rows).
        let missing: Vec<&str> = [(0.05, "5 cm"), (0.10, "10 cm")]
            .into_iter()
            .filter(|(g, _)| at(*g).is_none())
            .map(|(_, name)| name)
            .collect();
        let not_computed = (!missing.is_empty()).then(|| {
            format!(
                "not computed: the gap grid ({}) has no {} value{}",
                grid_words(&gs),
                missing.join(" and "),
                if missing.len() > 1 { "s" } else { "" }
            )
        });
        if let Some(why) = &not_computed {
            // The rows pushed above are all n = 0: the CSV keeps the header alone.
            claims.rows.clear();
            crate::io::write_atomic(&ctx.dir.join("gap_5_vs_10.csv"), &claims.csv()?)?;
            crate::io::write_atomic(
                &ctx.dir.join("gap_5_vs_10.md"),
                format!("5 cm against 10 cm gap: {why}.\n").as_bytes(),
            )?;
            reading.push(format!("5 cm against 10 cm (`gap_5_vs_10.md`): {why}."));
        } else {
            claims.write(&ctx.dir, "gap_5_vs_10")?;
        }
        if !ratios[0].is_empty() {
            reading.push(format!(
                "5 cm against 10 cm (`gap_5_vs_10.md`, {} records that pound at both): the amplification ratio is {} (the paper: 1.42 for building 2's top story) and above 1 for {} records; the median approach speed ratio is {} (above 1 for {}), the largest approach speed ratio {} (above 1 for {}).",
                ratios[0].len(),
                Spread::of(ratios[0].iter().copied()).words(2),
                ratios[0].iter().filter(|x| **x > 1.0).count(),
                Spread::of(ratios[1].iter().copied()).words(2),
                ratios[1].iter().filter(|x| **x > 1.0).count(),
                Spread::of(ratios[2].iter().copied()).words(2),
                ratios[2].iter().filter(|x| **x > 1.0).count(),
            ));
        }
        if let Some(nn) = failures_note(res) {
            reading.push(nn);
        }
        write_summary(
            ctx,
            "Study 5: gap size and separation rules",
            &reading,
            &if not_computed.is_some() {
                vec![&sep_sum, &summary]
            } else {
                vec![&sep_sum, &summary, &claims]
            },
            &[(
                "gap",
                "Contact-story amplification against the gap, pulse vs no pulse, and the separation rules",
            )],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::cqc_rho;
    use std::f64::consts::{FRAC_PI_2, PI};

    /// Compensated (Neumaier) summation: the sum of n terms to about 2ε of Σ|terms|, whatever
    /// n.
    #[derive(Default)]
    struct Sum(f64, f64);

    impl Sum {
        fn add(&mut self, x: f64) {
            let t = self.0 + x;
            self.1 += if self.0.abs() >= x.abs() {
                (self.0 - t) + x
            } else {
                (x - t) + self.0
            };
            self.0 = t;
        }
        fn value(&self) -> f64 {
            self.0 + self.1
        }
    }

    /// The correlation of the stationary displacement responses of two oscillators (ω₁ = r,
    /// ω₂ = 1, damping ζ) to white noise, ρ = ∫ Re[H₁ H₂*] dω / √(∫|H₁|² dω ∫|H₂|² dω) over
    /// the real line, H_i(ω) = 1/(ω_i² − ω² + 2iζω_iω), by the trapezoidal rule with `n` nodes
    /// in θ = atan ω. The integrands times dω/dθ = sec²θ are smooth and π-periodic in θ
    /// (they vanish as cos²θ at ±π/2), so the rule converges geometrically, as e^(−2nd) for
    /// poles a distance d (about ζω_i/(1 + ω_i²)) off the real θ axis: at n = 2¹³ below
    /// e^(−130) for ζ ≥ 0.02, r ≥ 0.3, so what is left is round-off.
    fn white_noise_rho(zeta: f64, r: f64, n: usize) -> f64 {
        let (mut s12, mut s11, mut s22) = (Sum::default(), Sum::default(), Sum::default());
        // Node 0 (θ = −π/2, ω = −∞) contributes nothing.
        for k in 1..n {
            let theta = -FRAC_PI_2 + PI * k as f64 / n as f64;
            let w = theta.tan();
            let jac = 1.0 / (theta.cos() * theta.cos());
            // D_i = ω_i² − ω² + 2iζω_iω = a_i + i b_i, H_i = 1/D_i, so
            // Re[H₁ H₂*] = Re[D₁* D₂] / (|D₁|² |D₂|²) = (a₁a₂ + b₁b₂) / (|D₁|² |D₂|²).
            let d = |wi: f64| (wi * wi - w * w, 2.0 * zeta * wi * w);
            let ((a1, b1), (a2, b2)) = (d(r), d(1.0));
            let (m1, m2) = (a1 * a1 + b1 * b1, a2 * a2 + b2 * b2);
            s12.add(jac * (a1 * a2 + b1 * b2) / (m1 * m2));
            s11.add(jac / m1);
            s22.add(jac / m2);
        }
        s12.value() / (s11.value() * s22.value()).sqrt()
    }

    /// ρ = 1 for equal frequencies (also undamped, where the formula reads 0/0), symmetric in
    /// r ↔ 1/r, 0 for distinct undamped modes, and Der Kiureghian's closed form
    /// 8ζ²(1+r)r^1.5 / ((1−r²)² + 4ζ²r(1+r)²) against its definition, the correlation of two
    /// oscillators' responses to white noise, integrated numerically.
    #[test]
    fn cqc_correlation() {
        assert_eq!(cqc_rho(0.0, 1.0), 1.0);
        assert_eq!(cqc_rho(0.05, 1.0), 1.0);
        assert!((cqc_rho(0.05, 0.8) - cqc_rho(0.05, 1.25)).abs() < 1e-12);
        assert_eq!(cqc_rho(0.0, 0.8), 0.0);
        for (zeta, r) in [
            (0.05, 0.8),
            (0.05, 1.25),
            (0.02, 0.5),
            (0.05, 0.95),
            (0.05, 1.0),
            (0.2, 0.3),
            (0.5, 0.7),
        ] {
            // Round-off only (the rule's own error is below e^(−130), above): each term
            // carries a few ε of its size, the compensated sums 2ε of Σ|terms|, and
            // Σ|Re H₁H₂*| ≤ √(Σ|H₁|² Σ|H₂|²), so ρ is within a few ε absolute; the closed form
            // adds a few ε. Asserted 16 ε, for the rule's convergence (2¹³ against 2¹⁴ nodes)
            // and the closed form (measured at most 0.5 ε for both).
            let tol = 16.0 * f64::EPSILON;
            let (half, full) = (
                white_noise_rho(zeta, r, 1 << 13),
                white_noise_rho(zeta, r, 1 << 14),
            );
            assert!(
                (half - full).abs() <= tol,
                "ζ {zeta} r {r}: quadrature {half} with 2^13 nodes, {full} with 2^14"
            );
            let rho = cqc_rho(zeta, r);
            assert!(
                (full - rho).abs() <= tol,
                "ζ {zeta} r {r}: closed form {rho} vs white-noise correlation {full} ({:.2} ε)",
                (full - rho).abs() / f64::EPSILON
            );
        }
    }
}
