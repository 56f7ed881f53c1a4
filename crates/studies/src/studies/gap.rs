//! Study 5 (`gap`): amplification against gap size, with the exact no-contact gap and the
//! ABS, SRSS and DDC separation rules.

use serde::Deserialize;
use solvers::Method;

use super::{
    amp_contact, contact_floor_displacement, default_pga, default_records, failures_note,
    record_label, write_summary, Ctx, Study,
};
use crate::plot::{figure, Marker, Panel, PanelKind, Series, VLine};
use crate::sweep::{CaseSpec, Result, Results, StudyError};
use crate::table::{f, Table};

pub struct Gap;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    scene: String,
    #[serde(default = "default_pga")]
    pga: f64,
    #[serde(default = "default_records")]
    records: Vec<String>,
    gap_max: f64,
    gap_count: usize,
    gap_stiffness: f64,
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

/// CQC correlation coefficient of two modes with equal damping ζ and frequency ratio r.
pub fn cqc_rho(zeta: f64, r: f64) -> f64 {
    let z2 = zeta * zeta;
    8.0 * z2 * (1.0 + r) * r.powf(1.5) / ((1.0 - r * r).powi(2) + 4.0 * z2 * r * (1.0 + r).powi(2))
}

impl Study for Gap {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        let mut v = Vec::new();
        for rec in ctx.records(&d.records, true) {
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
        let recs = ctx.records(&d.records, true);
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
        let mut table = Table::new(
            "Top-story amplification against gap size (c_r = 1)",
            &[
                "record",
                "gap (cm)",
                "momentum b1",
                "momentum b2",
                "momentum impacts",
                "gap element b1",
                "gap element b2",
                "gap element impacts",
            ],
        );
        let mut sep = Table::new(
            &format!("Separation needed (cm): exact = peak of u1 − u2 without contact; Δ = peak contact-floor displacement without contact; DDC with ρ = {rho:.4} (CQC, ζ = {}, ω1/ω2 = {r:.4})", d.damping),
            &["record", "Δ1", "Δ2", "exact", "DDC", "SRSS", "ABS"],
        );
        let mut panels = Vec::new();
        let mut reading = Vec::new();
        let mut tests = Vec::new();
        for (ri, rec) in recs.iter().enumerate() {
            let lab = record_label(rec);
            let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 4];
            for &g in &gs {
                let (m, e) = (mom(ctx, &d, rec, g), gel(ctx, &d, rec, g));
                let vals = [
                    amp_contact(res, &m, 0),
                    amp_contact(res, &m, 1),
                    amp_contact(res, &e, 0),
                    amp_contact(res, &e, 1),
                ];
                for (k, v) in vals.iter().enumerate() {
                    if let Some(v) = v {
                        series[k].push((g * 100.0, *v));
                    }
                }
                table.push(vec![
                    lab.clone(),
                    f(Some(g * 100.0), 0),
                    f(vals[0], 3),
                    f(vals[1], 3),
                    res.out(&m).map_or("–".into(), |o| o.impacts.to_string()),
                    f(vals[2], 3),
                    f(vals[3], 3),
                    res.out(&e).map_or("–".into(), |o| o.impacts.to_string()),
                ]);
            }
            // Separation rules from the no-contact baseline of the momentum method.
            let base = res.out(&mom(ctx, &d, rec, gs[0]).baseline());
            let mut vlines = Vec::new();
            if let Some(b) = base {
                let d1 = contact_floor_displacement(b, 0).unwrap_or(f64::NAN);
                let d2 = contact_floor_displacement(b, 1).unwrap_or(f64::NAN);
                let exact = b.peak_closure.unwrap_or(f64::NAN);
                let abs = d1 + d2;
                let srss = (d1 * d1 + d2 * d2).sqrt();
                let ddc = (d1 * d1 + d2 * d2 - 2.0 * rho * d1 * d2).max(0.0).sqrt();
                sep.push(vec![
                    lab.clone(),
                    f(Some(d1 * 100.0), 2),
                    f(Some(d2 * 100.0), 2),
                    f(Some(exact * 100.0), 2),
                    f(Some(ddc * 100.0), 2),
                    f(Some(srss * 100.0), 2),
                    f(Some(abs * 100.0), 2),
                ]);
                for (i, (x, name)) in [(exact, "exact"), (ddc, "DDC"), (srss, "SRSS"), (abs, "ABS")]
                    .iter()
                    .enumerate()
                {
                    vlines.push(VLine {
                        x: x * 100.0,
                        label: format!("{name} {:.1} cm", x * 100.0),
                        color: 4 + i,
                    });
                }
                reading.push(format!(
                    "{lab}: contact is avoided beyond {:.1} cm (exact); the rules ask for DDC {:.1}, SRSS {:.1}, ABS {:.1} cm.",
                    exact * 100.0,
                    ddc * 100.0,
                    srss * 100.0,
                    abs * 100.0
                ));
            }
            let at = |g: f64, b| amp_contact(res, &mom(ctx, &d, rec, g), b);
            let has = |g: f64| gs.iter().any(|x| (x - g).abs() < 1e-9);
            if has(0.05) && has(0.10) {
                let (a5, a10) = (at(0.05, 1), at(0.10, 1));
                let (b5, b10) = (at(0.05, 0), at(0.10, 0));
                tests.push(format!(
                    "{lab}: 5 cm vs 10 cm contact-story amplification {} vs {} (building 1), {} vs {} (building 2)",
                    f(b5, 2), f(b10, 2), f(a5, 2), f(a10, 2)
                ));
            }
            let names = [
                "momentum b1",
                "momentum b2",
                "gap element b1",
                "gap element b2",
            ];
            let mk = [
                Marker::Circle,
                Marker::Triangle,
                Marker::Cross,
                Marker::Square,
            ];
            panels.push(PanelKind::Xy(Panel {
                title: format!("{lab}: contact-story amplification"),
                x_label: "gap (cm)".into(),
                y_label: "amplification factor".into(),
                series: series
                    .into_iter()
                    .enumerate()
                    .map(|(k, p)| {
                        Series::line(names[k], p, k)
                            .marker(mk[k])
                            .width(if k < 2 { 2 } else { 1 })
                    })
                    .collect(),
                vlines,
                legend_right: true,
                no_legend: ri > 0,
                ..Default::default()
            }));
        }
        let rows = panels.len().div_ceil(2);
        figure(
            &ctx.dir,
            "gap",
            (1200, 470 * rows as u32),
            (rows, 2.min(panels.len())),
            &panels,
            "Top-story amplification against the gap (c_r = 1); dashed: exact no-contact gap and the DDC, SRSS and ABS separation rules.",
        )?;
        table.write(&ctx.dir, "gap")?;
        sep.write(&ctx.dir, "separation")?;
        // Paper's statements.
        let mut worse5 = 0;
        let mut small_lower = 0;
        let mut n = 0;
        for rec in &recs {
            let at = |g: f64, b| amp_contact(res, &mom(ctx, &d, rec, g), b);
            if let (Some(a5), Some(a10)) = (at(0.05, 1), at(0.10, 1)) {
                n += 1;
                if a5 > a10 {
                    worse5 += 1;
                }
                let small = gs
                    .iter()
                    .filter(|g| **g > 0.0 && **g < 0.05)
                    .filter_map(|g| at(*g, 1))
                    .fold(f64::NAN, f64::min);
                if small < a5 {
                    small_lower += 1;
                }
            }
        }
        if n > 0 {
            reading.push(format!(
                "Paper's statements (momentum method, building 2, contact story): a 5 cm gap gives a larger amplification than 10 cm for {worse5} of {n} records; some gap below 5 cm gives a smaller amplification than 5 cm for {small_lower} of {n} records. {}.",
                tests.join("; ")
            ));
        }
        if let Some(nn) = failures_note(res) {
            reading.push(nn);
        }
        write_summary(
            ctx,
            "Study 5: gap size and separation rules",
            &reading,
            &[&sep],
            &[(
                "gap",
                "Top-story amplification against the gap, with the separation rules",
            )],
        )
    }
}
