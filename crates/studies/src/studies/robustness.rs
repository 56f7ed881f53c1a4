//! `robustness`: the solvers on every record the project holds (issue 9). Every `*.AT2` in
//! the definition's `record_dirs` × `gaps` × `restitution` × {momentum method, adaptive gap
//! element, Newmark, impulse method (default tolerance)}, on the paper scene. Not part of `--all` (a long sweep): `make
//! robustness`. Outputs `robustness.{md,csv}` (counts per method, c_r and gap) and
//! `failures.{md,csv}` (every failed run with its error).

use std::path::Path;

use serde::Deserialize;
use solvers::Method;

use super::{default_pga, write_summary, Ctx, Study};
use crate::sweep::{CaseSpec, Result, Results, StudyError};
use crate::table::{f, Table};

pub struct Robustness;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    /// Scene of the pair (relative to `studies/`); contact 0 joins the two buildings.
    scene: String,
    /// Analysis PGA, g: finite, > 0 (default 0.40).
    #[serde(default = "default_pga")]
    pga: f64,
    /// Folders whose every `*.AT2` is used (relative to `studies/`): at least one record in
    /// all.
    record_dirs: Vec<String>,
    /// Gaps of contact 0, m: at least one, each finite and >= 0.
    gaps: Vec<f64>,
    /// Coefficients of restitution: at least one, each in [0, 1].
    restitution: Vec<f64>,
    /// Kelvin–Voigt gap-element stiffness of both gap integrators, N/m: > 0 (checked by the
    /// scene in every case).
    gap_stiffness: f64,
    /// Newmark time step, s: > 0 and at most each record's step (checked by the scene).
    newmark_time_step: f64,
}

const METHODS: [&str; 4] = ["momentum", "gap adaptive", "gap newmark", "impulse"];

/// The records: those of `--records` if given, else every `*.AT2` in the folders, sorted by
/// file name within each folder. With `--quick`: the first three.
fn records(ctx: &Ctx, d: &Def) -> Result<Vec<String>> {
    let mut out = ctx.opts.records.clone();
    let dirs: &[String] = if out.is_empty() { &d.record_dirs } else { &[] };
    for dir in dirs {
        let full = ctx.studies_dir.join(dir);
        // A folder named by the definition that cannot be listed is bad input (exit 2).
        let rd = std::fs::read_dir(&full).map_err(|e| StudyError::Definition {
            file: ctx.def_file.clone(),
            message: format!(
                "`record_dirs`: {} cannot be listed ({e}); expected a folder of *.AT2 records, relative to the study's folder",
                full.display()
            ),
        })?;
        let mut names: Vec<String> = rd
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".AT2"))
            .collect();
        names.sort();
        out.extend(names.into_iter().map(|n| format!("{dir}/{n}")));
    }
    super::require(ctx, !out.is_empty(), || {
        format!(
            "`record_dirs` = {:?}: no *.AT2 record in them; expected at least one record",
            d.record_dirs
        )
    })?;
    if ctx.opts.quick {
        out.truncate(3);
    }
    Ok(out)
}

fn grid(ctx: &Ctx, d: &Def) -> (Vec<f64>, Vec<f64>) {
    if ctx.opts.quick {
        (vec![d.gaps[0]], vec![1.0, 0.3])
    } else {
        (d.gaps.clone(), d.restitution.clone())
    }
}

fn case(ctx: &Ctx, d: &Def, rec: &str, method: usize, gap: f64, cr: f64) -> CaseSpec {
    let m = match method {
        0 => Method::Momentum,
        3 => Method::Impulse,
        _ => Method::Gap,
    };
    let mut c = ctx
        .case(&d.scene, m, rec, d.pga)
        .with("contacts.0.gap", format!("{gap:?}"))
        .with("contacts.0.restitution", format!("{cr:?}"))
        .param("gap_m", gap)
        .param("restitution", cr)
        .param("variant", METHODS[method]);
    if method == 1 || method == 2 {
        c = c
            .with("gap_element.law", "kelvin-voigt")
            .with("gap_element.stiffness", format!("{:e}", d.gap_stiffness));
    }
    if method == 2 {
        c = c.with("gap_element.integrator", "newmark").with(
            "gap_element.time_step",
            format!("{:e}", d.newmark_time_step),
        );
    } else if method == 1 {
        c = c.with("gap_element.integrator", "adaptive");
    }
    c
}

impl Study for Robustness {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        super::require_pga(ctx, d.pga)?;
        super::require(
            ctx,
            !d.gaps.is_empty() && d.gaps.iter().all(|&g| super::is_gap(g)),
            || {
                format!(
                    "`gaps` = {:?}: expected at least one gap, each finite and >= 0 (m)",
                    d.gaps
                )
            },
        )?;
        super::require(
            ctx,
            !d.restitution.is_empty() && d.restitution.iter().all(|c| (0.0..=1.0).contains(c)),
            || {
                format!(
                    "`restitution` = {:?}: expected at least one value in [0, 1]",
                    d.restitution
                )
            },
        )?;
        let (gaps, crs) = grid(ctx, &d);
        let mut v = Vec::new();
        for rec in records(ctx, &d)? {
            for m in 0..METHODS.len() {
                for &cr in &crs {
                    for &g in &gaps {
                        v.push(case(ctx, &d, &rec, m, g, cr));
                    }
                }
            }
        }
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let d: Def = ctx.def()?;
        let recs = records(ctx, &d)?;
        let (gaps, crs) = grid(ctx, &d);
        let mut t = Table::new(
            &format!(
                "Robustness over {} (paper scene, PGA {} g): counts per method, c_r and gap",
                crate::table::count(recs.len(), "record", "records"),
                d.pga
            ),
            &[
                "method",
                "c_r",
                "gap_m",
                "runs",
                "failed",
                "impacts",
                "impacts_nonpositive_approach",
                "restitution_outside_unit",
                "restitution_null",
                "persistent_phases",
                "max_rel_energy_error",
                "wall_total_s",
                "wall_max_s",
            ],
        );
        let mut fails = Table::new(
            "Failed runs",
            &["record", "method", "c_r", "gap_m", "error_kind", "error"],
        );
        let mut totals = [0usize; 5];
        let mut wall_all = 0.0;
        let mut max_err: f64 = 0.0;
        for (mi, mname) in METHODS.iter().enumerate() {
            for &cr in &crs {
                for &g in &gaps {
                    let cases: Vec<CaseSpec> =
                        recs.iter().map(|r| case(ctx, &d, r, mi, g, cr)).collect();
                    let (mut failed, mut imp, mut nonpos, mut outside, mut null, mut phases) =
                        (0usize, 0usize, 0usize, 0usize, 0usize, 0usize);
                    let (mut wall, mut wall_max, mut err): (f64, f64, f64) = (0.0, 0.0, 0.0);
                    for (c, rec) in cases.iter().zip(&recs) {
                        let r = res.get(c);
                        wall += r.wall_seconds;
                        wall_max = wall_max.max(r.wall_seconds);
                        match r.ok() {
                            Some(o) => {
                                imp += o.impacts;
                                nonpos += o.impacts_nonpositive_approach;
                                outside += o.restitution_outside_unit;
                                null += o.restitution_undefined;
                                phases += o.persistent_contacts;
                                let scale = o.energy_input.abs().max(f64::MIN_POSITIVE);
                                err = err.max(o.energy_balance_error.abs() / scale);
                            }
                            None => {
                                failed += 1;
                                fails.push(vec![
                                    file_name(rec),
                                    mname.to_string(),
                                    cr.to_string(),
                                    g.to_string(),
                                    r.error_kind.clone().unwrap_or_default(),
                                    r.error.clone().unwrap_or_default(),
                                ]);
                            }
                        }
                    }
                    totals[0] += cases.len();
                    totals[1] += failed;
                    totals[2] += nonpos;
                    totals[3] += outside;
                    totals[4] += null;
                    wall_all += wall;
                    max_err = max_err.max(err);
                    t.push(vec![
                        mname.to_string(),
                        cr.to_string(),
                        g.to_string(),
                        cases.len().to_string(),
                        failed.to_string(),
                        imp.to_string(),
                        nonpos.to_string(),
                        outside.to_string(),
                        null.to_string(),
                        phases.to_string(),
                        format!("{err:.1e}"),
                        f(Some(wall), 2),
                        f(Some(wall_max), 3),
                    ]);
                }
            }
        }
        t.write(&ctx.dir, "robustness")?;
        fails.write(&ctx.dir, "failures")?;
        let reading = vec![
            format!(
                "{} ({} × {} × {} of c_r × {}; every record scaled to {} g): {} failed, {} impacts \
                with a non-positive approach speed, {} achieved restitutions outside [0, 1]; {} \
                contact entries have a null restitution with its reason (touching or grazing \
                contacts, chattering captures, ground-driven gap-element episodes).",
                crate::table::count(totals[0], "run", "runs"),
                crate::table::count(recs.len(), "record", "records"),
                crate::table::count(gaps.len(), "gap", "gaps"),
                crate::table::count(crs.len(), "value", "values"),
                crate::table::count(METHODS.len(), "solver", "solvers"),
                d.pga, totals[1], totals[2], totals[3], totals[4]
            ),
            format!(
                "Largest energy-balance error relative to the input energy: {max_err:.1e}. Wall time of all runs: {wall_all:.1} s summed over cases (cases run in parallel; times vary by tens of per cent between runs on a shared machine)."
            ),
        ];
        let mut tables = vec![&t];
        if !fails.is_empty() {
            tables.push(&fails);
        }
        write_summary(ctx, "Robustness sweep", &reading, &tables, &[])
    }
}

fn file_name(rec: &str) -> String {
    Path::new(rec)
        .file_name()
        .map_or_else(|| rec.to_string(), |n| n.to_string_lossy().into_owned())
}
