//! Study `modelform`: how much the paper pair's amplification owes to modelling choices the
//! paper does not state.
//!
//! One change at a time from the paper scene (the variants of `studies/modelform.toml`):
//! the stiffness profile of the sticks (two-frequency calibration, uniform, conventional
//! taper, the other reading of Table 1), the damping model (modal against Rayleigh
//! C = a M + b K, i.e. ζ_n = a/(2ω_n) + bω_n/2 through two anchor modes) and where the
//! buildings may touch (roof only against a contact at every facing floor). Each variant runs
//! on every record at every gap and coefficient of restitution with the momentum method
//! (all modes: the main answer) and the gap element at a stiff spring (a check); at c_r = 1
//! also the gap element at a typical stiffness and the momentum method with few modes.
//!
//! The amplification of story j is A_j = V_j,max (with contact) / V_j,max (same model and
//! method, no contact). The required separation s_req is the peak of u₁(t) − u₂(t) at the
//! floors of contact 0 without contact (momentum baseline); gap / s_req < 1 means the
//! buildings touch. The conclusions table evaluates, per variant and gap (c_r = 1):
//! (a) the top story of a building is amplified by more than the threshold (1.5);
//! (b) the amplification stays local: every story below mid-height (j ≤ n/2) of both
//!     buildings is within 1 ± band (10 %);
//! (c) the gap element at the typical stiffness (1e10 N/m) differs from the rigid answer
//!     (momentum, all modes) by more than the band (10 %) in top-story amplification;
//! (d) the top-story amplification grows from the few-mode (4) to the all-mode answer.

use serde::Deserialize;
use solvers::Method;
use structure::{Contact, Scene};

use super::stats::median;
use super::{
    amplification, default_pga, default_records, failures_note, is_gap, is_positive,
    is_restitution, record_label, require_count, require_list, require_pga, write_summary, Ctx,
    Study, MAX_MODES,
};
use crate::plot::{figure, Marker, Panel, PanelKind, Series, VLine};
use crate::sweep::{CaseSpec, Result, Results, StudyError};
use crate::table::{f, Table};

pub struct ModelForm;

/// Where the buildings may touch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
enum Contacts {
    /// The scene's contacts (the paper: roof to roof).
    #[default]
    Scene,
    /// One contact at every facing floor, roof first.
    EveryFloor,
}

/// A model variant (`[[variants]]`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Variant {
    /// Name in the tables.
    name: String,
    /// What the variant changes (the tables' description column).
    description: String,
    /// Scene overrides (`PATH=VALUE`); default none.
    #[serde(default)]
    set: Vec<String>,
    /// Where the buildings may touch: `"scene"` (default) or `"every-floor"`.
    #[serde(default)]
    contacts: Contacts,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    /// Scene of the pair (relative to `studies/`): two buildings.
    scene: String,
    /// Analysis PGA, g: finite, > 0 (default 0.40).
    #[serde(default = "default_pga")]
    pga: f64,
    /// Record files (relative to `studies/`): at least one (default: the four Loma Prieta
    /// components).
    #[serde(default = "default_records")]
    records: Vec<String>,
    /// Gaps of contact 0, m: at least one, each finite and >= 0.
    gaps: Vec<f64>,
    /// Coefficients of restitution: at least one, each in [0, 1], one of them 1.0.
    restitution: Vec<f64>,
    /// Gap-element stiffness beside every momentum run, N/m: > 0 (checked by the scene).
    check_stiffness: f64,
    /// Typical gap-element stiffness of conclusion (c), N/m: > 0 (checked by the scene).
    soft_stiffness: f64,
    /// Modes of the truncated momentum run, conclusion (d): 1 ..= [`super::MAX_MODES`] (1000).
    fewer_modes: usize,
    /// Local error tolerance of the adaptive gap element: in (0, 0.1) (checked by the scene).
    tolerance: f64,
    /// Conclusion (a): the top story is amplified by more than this: finite, > 0.
    amplification_threshold: f64,
    /// Conclusion (b): stories below mid-height within 1 ± this: finite, > 0.
    local_band: f64,
    /// Conclusion (c): relative difference of the soft answer from the rigid one: finite, > 0.
    gap_element_band: f64,
    /// The model variants: at least one.
    variants: Vec<Variant>,
}

/// The analyses of one (variant, record, gap, c_r).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Run {
    /// Momentum method, all modes.
    Rigid,
    /// Gap element at `check_stiffness`.
    Check,
    /// Gap element at `soft_stiffness` (c_r = 1 only).
    Soft,
    /// Momentum method with `fewer_modes` (c_r = 1 only).
    Fewer,
}

struct Grid {
    records: Vec<String>,
    crs: Vec<f64>,
}

fn grid(ctx: &Ctx, d: &Def) -> Grid {
    Grid {
        records: ctx.records(&d.records, true),
        crs: if ctx.opts.quick {
            d.restitution.iter().take(1).copied().collect()
        } else {
            d.restitution.clone()
        },
    }
}

/// The base scene (its building names and floor counts).
fn base_scene(ctx: &Ctx, d: &Def) -> Result<Scene> {
    CaseSpec::new(&d.scene, Method::Momentum)
        .load_scene(&ctx.studies_dir)
        .map_err(|message| StudyError::Definition {
            file: ctx.def_file.clone(),
            message,
        })
}

/// Contacts between buildings 1 and 2 at every facing floor (floors 1 … min(n₁, n₂)), the
/// highest first so that contact 0 is the roof pair the studies report.
fn every_floor(scene: &Scene, gap: f64, cr: f64) -> Vec<Contact> {
    let n = scene.buildings[0]
        .n_floors()
        .min(scene.buildings[1].n_floors());
    std::iter::once(n - 1)
        .chain(0..n - 1)
        .enumerate()
        .map(|(entry, dof)| Contact {
            left: 0,
            left_dof: dof,
            right: 1,
            right_dof: dof,
            gap,
            restitution: cr,
            wall: false,
            entry,
        })
        .collect()
}

/// `contacts=[…]`: contacts as a scene override (floors from 1, buildings by name).
fn contacts_override(scene: &Scene, contacts: &[Contact]) -> String {
    let items: Vec<String> = contacts
        .iter()
        .map(|c| {
            format!(
                "{{left = \"{}\", left_floor = {}, right = \"{}\", right_floor = {}, gap = {:?}, restitution = {:?}}}",
                scene.buildings[c.left].name,
                c.left_dof + 1,
                scene.buildings[c.right].name,
                c.right_dof + 1,
                c.gap,
                c.restitution
            )
        })
        .collect();
    format!("[{}]", items.join(", "))
}

/// The case of variant `v` on record `rec` at (gap (m), c_r, analysis).
fn case(
    ctx: &Ctx,
    d: &Def,
    scene: &Scene,
    v: &Variant,
    rec: &str,
    (gap, cr, run): (f64, f64, Run),
) -> CaseSpec {
    let method = match run {
        Run::Rigid | Run::Fewer => Method::Momentum,
        Run::Check | Run::Soft => Method::Gap,
    };
    let mut c = ctx.case(&d.scene, method, rec, d.pga);
    for s in &v.set {
        if let Some((path, value)) = s.split_once('=') {
            c = c.with(path.trim(), value.trim());
        }
    }
    c = match v.contacts {
        Contacts::Scene => c
            .with("contacts.0.gap", format!("{gap:?}"))
            .with("contacts.0.restitution", format!("{cr:?}")),
        Contacts::EveryFloor => c.with(
            "contacts",
            contacts_override(scene, &every_floor(scene, gap, cr)),
        ),
    };
    let law = if cr >= 1.0 { "linear" } else { "kelvin-voigt" };
    c = match run {
        Run::Rigid => c.with("momentum.impulse", "consistent"),
        Run::Fewer => c
            .with("momentum.impulse", "consistent")
            .with("momentum.modes", d.fewer_modes),
        Run::Check | Run::Soft => c
            .with("gap_element.law", law)
            .with("gap_element.integrator", "adaptive")
            .with("gap_element.tolerance", format!("{:e}", d.tolerance))
            .with(
                "gap_element.stiffness",
                format!(
                    "{:e}",
                    if run == Run::Check {
                        d.check_stiffness
                    } else {
                        d.soft_stiffness
                    }
                ),
            ),
    };
    let what = match run {
        Run::Rigid => "momentum, all modes".to_string(),
        Run::Fewer => format!("momentum, {} modes", d.fewer_modes),
        Run::Check => format!("gap element {law}, k = {:e} N/m", d.check_stiffness),
        Run::Soft => format!("gap element {law}, k = {:e} N/m", d.soft_stiffness),
    };
    c.param("model", v.name.as_str())
        .param("gap_m", gap)
        .param("restitution", cr)
        .param("variant", format!("{}: {what}", v.name))
}

fn runs(cr: f64) -> &'static [Run] {
    if cr >= 1.0 {
        &[Run::Rigid, Run::Check, Run::Soft, Run::Fewer]
    } else {
        &[Run::Rigid, Run::Check]
    }
}

fn validate(ctx: &Ctx, d: &Def, scene: &Scene) -> Result<()> {
    let bad = |message: String| {
        Err(StudyError::Definition {
            file: ctx.def_file.clone(),
            message,
        })
    };
    if d.variants.is_empty() || d.gaps.is_empty() || d.restitution.is_empty() {
        return bad("`variants`, `gaps` and `restitution` must not be empty".into());
    }
    // `--records` replace the definition's, so an empty `records` is refused only when used.
    super::require(ctx, !ctx.records(&d.records, true).is_empty(), || {
        "`records` = []: expected at least one record".into()
    })?;
    require_pga(ctx, d.pga)?;
    require_list(ctx, "gaps", &d.gaps, is_gap, "a finite gap >= 0 (m)")?;
    require_list(
        ctx,
        "restitution",
        &d.restitution,
        is_restitution,
        "a coefficient of restitution in [0, 1]",
    )?;
    if !d.restitution.contains(&1.0) {
        return bad("`restitution` must contain 1.0 (the conclusions use c_r = 1)".into());
    }
    require_count(ctx, "fewer_modes", d.fewer_modes, 1..=MAX_MODES, "mode")?;
    for (key, v) in [
        ("amplification_threshold", d.amplification_threshold),
        ("local_band", d.local_band),
        ("gap_element_band", d.gap_element_band),
    ] {
        super::require(ctx, is_positive(v), || {
            format!("`{key}` = {v:?}: expected a finite number > 0")
        })?;
    }
    for v in &d.variants {
        if let Some(s) = v.set.iter().find(|s| !s.contains('=')) {
            return bad(format!(
                "variant `{}`: override `{s}` is not PATH=VALUE",
                v.name
            ));
        }
    }
    if scene.buildings.len() != 2 {
        return bad(format!(
            "study `modelform` compares two buildings; `{}` has {}",
            d.scene,
            scene.buildings.len()
        ));
    }
    Ok(())
}

impl Study for ModelForm {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        let scene = base_scene(ctx, &d)?;
        validate(ctx, &d, &scene)?;
        let g = grid(ctx, &d);
        let mut out = Vec::new();
        for v in &d.variants {
            // A variant whose overrides the scene refuses is a bad definition, said before
            // anything runs.
            if let Some(rec) = g.records.first() {
                case(ctx, &d, &scene, v, rec, (d.gaps[0], g.crs[0], Run::Rigid))
                    .load_scene(&ctx.studies_dir)
                    .map_err(|message| StudyError::Definition {
                        file: ctx.def_file.clone(),
                        message: format!("variant `{}`: {message}", v.name),
                    })?;
            }
            for rec in &g.records {
                for &gap in &d.gaps {
                    for &cr in &g.crs {
                        for &run in runs(cr) {
                            out.push(case(ctx, &d, &scene, v, rec, (gap, cr, run)));
                        }
                    }
                }
            }
        }
        Ok(out)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let d: Def = ctx.def()?;
        let scene = base_scene(ctx, &d)?;
        let g = grid(ctx, &d);
        let head = g.records[0].as_str();
        let head_label = record_label(head);
        let n_rec = crate::table::count(g.records.len(), "record", "records");
        let c = |v: &Variant, rec: &str, gap: f64, cr: f64, run: Run| {
            case(ctx, &d, &scene, v, rec, (gap, cr, run))
        };
        let amps = |spec: &CaseSpec| amplification(res, spec);
        // Top-story and max-over-stories amplification of building b.
        let top = |spec: &CaseSpec, b: usize| {
            amps(spec).and_then(|a| a.get(b).and_then(|s| s.last().copied()))
        };
        let maxs = |spec: &CaseSpec, b: usize| {
            amps(spec).and_then(|a| {
                a.get(b)
                    .map(|s| s.iter().cloned().fold(f64::NEG_INFINITY, f64::max))
            })
        };
        // Required separation: the peak closure at contact 0 without contact.
        let s_req = |spec: &CaseSpec| res.out(&spec.baseline()).and_then(|o| o.peak_closure);

        // --- Model table: the sticks each variant builds.
        let mut models = Table::new(
            "The sticks of each variant: stiffness top/ground story, first four frequencies, damping ratios of modes 1–4",
            &[
                "variant", "building", "k_top / k_ground", "f1 (Hz)", "f2 (Hz)", "f3 (Hz)", "f4 (Hz)",
                "ζ1", "ζ2", "ζ3", "ζ4", "description",
            ],
        );
        // Per variant and building: (k_top / k_ground, f2 / f1).
        let mut sticks: Vec<Vec<(f64, f64)>> = Vec::new();
        for v in &d.variants {
            let spec = c(v, head, d.gaps[0], 1.0, Run::Rigid);
            let mut mine = Vec::new();
            match spec.load_scene(&ctx.studies_dir) {
                Ok(s) => {
                    for b in s.buildings.iter().take(2) {
                        let m = b.modes().ok();
                        let fr = m.as_ref().map(|m| m.frequencies_hz()).unwrap_or_default();
                        mine.push((
                            structure::model::top_to_ground(b),
                            match fr.as_slice() {
                                [f1, f2, ..] => f2 / f1,
                                _ => f64::NAN,
                            },
                        ));
                        let z = m.as_ref().map(|m| m.zeta.clone()).unwrap_or_default();
                        let mut row = vec![
                            v.name.clone(),
                            b.name.clone(),
                            f(Some(structure::model::top_to_ground(b)), 3),
                        ];
                        row.extend((0..4).map(|i| f(fr.get(i).copied(), 3)));
                        row.extend((0..4).map(|i| f(z.get(i).copied(), 4)));
                        row.push(v.description.clone());
                        models.push(row);
                    }
                }
                Err(e) => models.push(vec![
                    v.name.clone(),
                    "–".into(),
                    format!("scene refused: {e}"),
                ]),
            }
            sticks.push(mine);
        }

        // --- Amplification table.
        let mut amp = Table::new(
            &format!(
                "Top-story and largest story amplification per variant (record {head_label}; medians over the records that pound in that case, n of {n_rec}, momentum method); s_req = peak u1 − u2 at the roof without contact"
            ),
            &[
                "variant", "gap (m)", "c_r", "s_req (m)", "gap / s_req",
                "top b1 momentum", "top b2 momentum", "top b1 gap el.", "top b2 gap el.",
                "max b1 momentum", "max b2 momentum", "max b1 gap el.", "max b2 gap el.",
                "n", "median top b1 momentum", "median top b2 momentum", "median top b1 gap el.", "median top b2 gap el.",
                "impacts momentum", "impacts gap el.",
            ],
        );
        let med = |vals: Vec<Option<f64>>| median(&vals.into_iter().flatten().collect::<Vec<_>>());
        // Records on which the momentum method (all modes) has at least one impact: the
        // statistics over records are taken over these only (a record that never pounds has
        // amplification 1 and would dilute them).
        let pounding_records = |v: &Variant, gap: f64, cr: f64| -> Vec<&String> {
            g.records
                .iter()
                .filter(|rec| {
                    res.out(&c(v, rec, gap, cr, Run::Rigid))
                        .is_some_and(|o| o.impacts > 0)
                })
                .collect()
        };
        for v in &d.variants {
            for &gap in &d.gaps {
                for &cr in &g.crs {
                    let r = c(v, head, gap, cr, Run::Rigid);
                    let k = c(v, head, gap, cr, Run::Check);
                    let sr = s_req(&r);
                    let pounding = pounding_records(v, gap, cr);
                    let over = |b: usize, run: Run| {
                        med(pounding
                            .iter()
                            .map(|rec| top(&c(v, rec, gap, cr, run), b))
                            .collect())
                    };
                    amp.push(vec![
                        v.name.clone(),
                        format!("{gap}"),
                        format!("{cr}"),
                        f(sr, 4),
                        f(sr.map(|s| gap / s), 3),
                        f(top(&r, 0), 2),
                        f(top(&r, 1), 2),
                        f(top(&k, 0), 2),
                        f(top(&k, 1), 2),
                        f(maxs(&r, 0), 2),
                        f(maxs(&r, 1), 2),
                        f(maxs(&k, 0), 2),
                        f(maxs(&k, 1), 2),
                        pounding.len().to_string(),
                        f(over(0, Run::Rigid), 2),
                        f(over(1, Run::Rigid), 2),
                        f(over(0, Run::Check), 2),
                        f(over(1, Run::Check), 2),
                        res.out(&r).map_or("–".into(), |o| o.impacts.to_string()),
                        res.out(&k).map_or("–".into(), |o| o.impacts.to_string()),
                    ]);
                }
            }
        }

        // --- Conclusions (c_r = 1).
        // Each conclusion on one record: (holds, text).
        let concl = |v: &Variant, rec: &str, gap: f64| -> [(Option<bool>, String); 4] {
            let r = c(v, rec, gap, 1.0, Run::Rigid);
            let (t1, t2) = (top(&r, 0), top(&r, 1));
            let th = d.amplification_threshold;
            let yn = |x: Option<bool>| match x {
                Some(true) => "yes",
                Some(false) => "no",
                None => "–",
            };
            let a = match (t1, t2) {
                (Some(x), Some(y)) => Some(x > th && y > th),
                _ => None,
            };
            let a_txt = format!(
                "{} / {} ({} / {})",
                yn(t1.map(|x| x > th)),
                yn(t2.map(|x| x > th)),
                f(t1, 2),
                f(t2, 2)
            );
            // (b): stories j <= n/2 of both buildings.
            let low_dev = amps(&r).map(|a| {
                a.iter()
                    .flat_map(|s| s.iter().take(s.len() / 2))
                    .map(|x| (x - 1.0).abs())
                    .fold(0.0, f64::max)
            });
            let b = low_dev.map(|x| x <= d.local_band);
            let b_txt = format!("{} (max |A−1| = {})", yn(b), f(low_dev, 3));
            let s = c(v, rec, gap, 1.0, Run::Soft);
            let rel = |b: usize| match (top(&s, b), top(&r, b)) {
                (Some(x), Some(y)) => Some((x - y).abs() / y),
                _ => None,
            };
            let cdev = match (rel(0), rel(1)) {
                (Some(x), Some(y)) => Some(x.max(y)),
                _ => None,
            };
            let cc = cdev.map(|x| x > d.gap_element_band);
            let c_txt = format!(
                "{} ({} / {} vs {} / {})",
                yn(cc),
                f(top(&s, 0), 2),
                f(top(&s, 1), 2),
                f(t1, 2),
                f(t2, 2)
            );
            let fw = c(v, rec, gap, 1.0, Run::Fewer);
            let (f1, f2) = (top(&fw, 0), top(&fw, 1));
            let dd = match (f1, f2, t1, t2) {
                (Some(a1), Some(a2), Some(b1), Some(b2)) => Some(b1 > a1 && b2 > a2),
                _ => None,
            };
            let grows = |a: Option<f64>, b: Option<f64>| match (a, b) {
                (Some(a), Some(b)) => Some(b > a),
                _ => None,
            };
            let d_txt = format!(
                "{} / {} ({} → {} / {} → {})",
                yn(grows(f1, t1)),
                yn(grows(f2, t2)),
                f(f1, 2),
                f(t1, 2),
                f(f2, 2),
                f(t2, 2)
            );
            [(a, a_txt), (b, b_txt), (cc, c_txt), (dd, d_txt)]
        };
        let mut survive = Table::new(
            &format!(
                "Which conclusions survive (c_r = 1, record {head_label}; verdicts and values building 1 / building 2; last column: of the records that pound (momentum method), on how many each holds for both buildings)"
            ),
            &[
                "variant",
                "gap (m)",
                &format!("(a) top story amplified > {}", d.amplification_threshold),
                &format!("(b) local: stories ≤ n/2 within 1 ± {}", d.local_band),
                &format!(
                    "(c) gap element at k = {:.0e} N/m differs from rigid by > {:.0} % (max over b1, b2)",
                    d.soft_stiffness,
                    100.0 * d.gap_element_band
                ),
                &format!("(d) top amplification grows {} → all modes", d.fewer_modes),
                "records where (a) (b) (c) (d) hold",
            ],
        );
        let mut reading = Vec::new();
        for v in &d.variants {
            for &gap in &d.gaps {
                let h = concl(v, head, gap);
                let pounding = pounding_records(v, gap, 1.0);
                let counts: Vec<String> = (0..4)
                    .map(|i| {
                        let n = pounding
                            .iter()
                            .filter(|rec| concl(v, rec, gap)[i].0 == Some(true))
                            .count();
                        format!("{n}/{}", pounding.len())
                    })
                    .collect();
                let mut row = vec![v.name.clone(), format!("{gap}")];
                row.extend(h.iter().map(|(_, t)| t.clone()));
                row.push(counts.join(" "));
                survive.push(row);
            }
        }

        // --- Reading: the headline numbers, computed.
        let gap0 = d.gaps[0];
        let calib = &d.variants[0];
        let t = |v: &Variant, b: usize| top(&c(v, head, gap0, 1.0, Run::Rigid), b);
        let tm = |v: &Variant, b: usize| {
            med(pounding_records(v, gap0, 1.0)
                .iter()
                .map(|rec| top(&c(v, rec, gap0, 1.0, Run::Rigid), b))
                .collect())
        };
        let mut parts = Vec::new();
        for v in &d.variants {
            parts.push(format!(
                "{} {} / {} (median {} / {}, n = {})",
                v.name,
                f(t(v, 0), 2),
                f(t(v, 1), 2),
                f(tm(v, 0), 2),
                f(tm(v, 1), 2),
                pounding_records(v, gap0, 1.0).len()
            ));
        }
        reading.push(format!(
            "Top-story amplification of buildings 1 / 2 with the momentum method (all modes), record {head_label} (median over the records that pound, n of {n_rec}), gap {gap0} m, c_r = 1: {}.",
            parts.join("; ")
        ));
        if let (Some(a), Some(b)) = (t(calib, 0), t(calib, 1)) {
            let rel: Vec<String> = d
                .variants
                .iter()
                .skip(1)
                .map(|v| {
                    format!(
                        "{} {:+.0} % / {:+.0} %",
                        v.name,
                        t(v, 0).map_or(f64::NAN, |x| 100.0 * (x / a - 1.0)),
                        t(v, 1).map_or(f64::NAN, |x| 100.0 * (x / b - 1.0))
                    )
                })
                .collect();
            reading.push(format!(
                "Relative to the `{}` variant: {}.",
                calib.name,
                rel.join("; ")
            ));
        }
        // The variant that moves the headline most (mean of |relative change| over the two
        // buildings).
        if let (Some(a), Some(b)) = (t(calib, 0), t(calib, 1)) {
            let change = |v: &Variant| match (t(v, 0), t(v, 1)) {
                (Some(x), Some(y)) => Some(0.5 * ((x / a - 1.0).abs() + (y / b - 1.0).abs())),
                _ => None,
            };
            let mut ranked: Vec<(&Variant, f64)> = d
                .variants
                .iter()
                .skip(1)
                .filter_map(|v| change(v).map(|x| (v, x)))
                .collect();
            ranked.sort_by(|p, q| q.1.total_cmp(&p.1));
            if !ranked.is_empty() {
                reading.push(format!(
                    "Ranked by the mean |relative change| of the two top-story amplifications: {}.",
                    ranked
                        .iter()
                        .map(|(v, x)| format!("{} {:.0} %", v.name, 100.0 * x))
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
        }
        // Why the calibrated sticks look as they do, from the models themselves.
        if let (Some(cal), Some(n)) = (
            sticks.first(),
            scene.buildings.first().map(|b| b.n_floors()),
        ) {
            let x = std::f64::consts::PI / (2.0 * (2 * n + 1) as f64);
            let uniform_ratio = (3.0 * x).sin() / x.sin();
            let desc: Vec<String> = cal
                .iter()
                .zip(&scene.buildings)
                .map(|((k, r), b)| {
                    format!("{} k_top / k_ground = {k:.2} (f2 / f1 = {r:.2})", b.name)
                })
                .collect();
            let stiffer = cal.iter().filter(|(k, _)| *k > 1.0).count();
            reading.push(format!(
                "The `{}` sticks: {}; a uniform {n}-floor stick has f2 / f1 = {uniform_ratio:.3}, so a target ratio above it needs stories that stiffen toward the roof ({stiffer} of {} buildings here).",
                calib.name,
                desc.join(", "),
                cal.len()
            ));
        }
        reading.push(format!(
            "The gap element at k = {:.0e} N/m is the check on every momentum run (columns `gap el.`); s_req is the separation needed to avoid contact, so gap / s_req < 1 means the buildings touch.",
            d.check_stiffness
        ));
        if let Some(n) = failures_note(res) {
            reading.push(n);
        }

        // --- Figure: amplification profiles over height (headline record, c_r = 1).
        let mut panels = Vec::new();
        for &gap in &d.gaps {
            for b in 0..2 {
                let mut p = Panel {
                    title: format!(
                        "{}, gap {} cm, {head_label}",
                        scene.buildings[b].name,
                        gap * 100.0
                    ),
                    x_label: "amplification factor V_max / V_max without contact".into(),
                    y_label: "story".into(),
                    legend_right: true,
                    vlines: vec![VLine {
                        x: 1.0,
                        label: "no amplification".into(),
                        color: 7,
                    }],
                    ..Default::default()
                };
                // Room on the right for the legend (the profiles peak at the top story).
                let hi = d
                    .variants
                    .iter()
                    .filter_map(|v| maxs(&c(v, head, gap, 1.0, Run::Rigid), b))
                    .fold(1.0, f64::max);
                let lo = d
                    .variants
                    .iter()
                    .filter_map(|v| amps(&c(v, head, gap, 1.0, Run::Rigid)))
                    .flat_map(|a| a[b].clone())
                    .fold(1.0, f64::min);
                p.x_range = Some((lo - 0.05 * (hi - lo), hi + 0.45 * (hi - lo)));
                for (i, v) in d.variants.iter().enumerate() {
                    if let Some(a) = amps(&c(v, head, gap, 1.0, Run::Rigid)) {
                        let pts = a[b]
                            .iter()
                            .enumerate()
                            .map(|(j, x)| (*x, (j + 1) as f64))
                            .collect();
                        p.series.push(
                            Series::line(&v.name, pts, i)
                                .marker(Marker::Circle)
                                .width(2),
                        );
                    }
                }
                panels.push(PanelKind::Xy(p));
            }
        }
        figure(
            &ctx.dir,
            "modelform_profiles",
            (1200, 920),
            (2, 2),
            &panels,
            "Amplification of every story, momentum method with all modes, c_r = 1, per model variant.",
        )?;
        // Second figure: top-story amplification against gap / s_req, every record.
        let mut scatter = Vec::new();
        for b in 0..2 {
            let mut p = Panel {
                title: format!("Top story, {}, every record", scene.buildings[b].name),
                x_label: "gap / required separation".into(),
                y_label: "top-story amplification".into(),
                legend_right: true,
                ..Default::default()
            };
            for (i, v) in d.variants.iter().enumerate() {
                let pts: Vec<(f64, f64)> = g
                    .records
                    .iter()
                    .flat_map(|rec| d.gaps.iter().map(move |&gap| (rec, gap)))
                    .filter_map(|(rec, gap)| {
                        let r = c(v, rec, gap, 1.0, Run::Rigid);
                        Some((gap / s_req(&r)?, top(&r, b)?))
                    })
                    .collect();
                p.series
                    .push(Series::points(&v.name, pts, i, Marker::Circle));
            }
            scatter.push(PanelKind::Xy(p));
        }
        figure(
            &ctx.dir,
            "modelform_gap_ratio",
            (1200, 480),
            (1, 2),
            &scatter,
            "Top-story amplification against the gap over the separation needed to avoid contact (momentum method, all modes, c_r = 1).",
        )?;

        models.write(&ctx.dir, "modelform_models")?;
        amp.write(&ctx.dir, "modelform")?;
        survive.write(&ctx.dir, "modelform_conclusions")?;
        write_summary(
            ctx,
            "Model form: stiffness profile, damping model, contact floors",
            &reading,
            &[&survive, &amp, &models],
            &[
                (
                    "modelform_profiles",
                    "Amplification profiles over height per model variant",
                ),
                (
                    "modelform_gap_ratio",
                    "Top-story amplification against gap / required separation",
                ),
            ],
        )
    }
}
