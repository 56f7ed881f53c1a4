//! Study `yielding`: where the linear modal (momentum) method stops being valid when the
//! buildings yield.
//!
//! The paper pair with contact at every facing floor (`floors = "aligned"`) on every record
//! of the set, scaled to each PGA level (0.1 … 1.2 g), with
//! - the momentum method with all modes: linear stories (it cannot yield: modal
//!   superposition needs constant K, the paper's eq. 5);
//! - each inelastic method of the definition (`inelastic`: the gap element, adaptive, and
//!   the impact law in physical coordinates, `impulse`, when it exists): bilinear stories
//!   with kinematic hardening (`story_law = "bilinear"`);
//!
//! each with pounding and without (the sweep's no-contact baseline, contact pushed 1 km
//! away).
//!
//! **Strength.** One strength per story, the same for every record and level: the yield
//! shear of story j of building b is the median over the records of the elastic no-contact
//! peak story shear at the reference PGA,
//!
//! ```text
//! F_y,bj = median_records V_bj,el(PGA_ref)     (momentum method, all modes, no contact)
//! ```
//!
//! computed when the cases are built (the momentum method is linear, so this is one short
//! run per record) and rounded to 6 significant digits. The elastic demand scales with the
//! PGA, so the median strength-reduction factor of every story is
//!
//! ```text
//! R = median V_el(PGA) / F_y = PGA / PGA_ref
//! ```
//!
//! (the "R" of seismic codes: elastic demand over strength). A given record has its own
//! R_rec = V_el,rec(PGA) / F_y, above or below R. Post-yield stiffness: `hardening_ratio`
//! × k₀ (0.02).
//!
//! **Responses** (per building b, from the case files): the contact-story shear
//! amplification A_b = V_b,top (with contact) / V_b,top (same method, no contact) at the
//! story below the floor of contact 0 (the roof); the peak story drift
//! d_b = max_j max_t |u_j − u_{j−1}| (m); the ductility demand μ_b = max_j d_bj / δ_y,bj with
//! the yield drift δ_y,bj = F_y,bj / k₀,bj (for the elastic method this is the elastic
//! prediction of the ductility demand, the equal-displacement estimate); the residual drift
//! max_j |u_j − u_{j−1}| at the end; the hysteretic energy of the energy audit (J).
//!
//! **Departure** of the elastic answer from an inelastic reference, per record and level:
//!
//! ```text
//! e_A = max_b |A_b,el / A_b,inel − 1|,   e_d = max_b |d_b,el / d_b,inel − 1|
//! ```
//!
//! (e_d with pounding and, separately, without). The domain of validity at a level is read
//! from the share of records with e > `band` (10 %): the figure marks the PGA where that
//! share first reaches one half (linear interpolation between levels).

use serde::Deserialize;
use solvers::Method;
use structure::Scene;

use super::stats::{median, median_band, Spread};
use super::{
    amp_contact, contact_floor, default_record_table, failures_note, record_classes, record_name,
    study_records, write_summary, Ctx, Study,
};
use crate::plot::{figure, Marker, Panel, PanelKind, Series, VLine};
use crate::sweep::{CaseOutputs, CaseSpec, Result, Results, StudyError};
use crate::table::{e, f, Table};

pub struct Yielding;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    /// Scene of the pair (relative to `studies/`); contact 0 joins the two buildings.
    scene: String,
    /// Record files (relative to `studies/`); default: the four Loma Prieta components
    /// when `record_dirs` is not given either.
    records: Option<Vec<String>>,
    /// Folders whose every `*.AT2` is added (sorted by file name).
    #[serde(default)]
    record_dirs: Vec<String>,
    /// Record metadata (pulse classes), relative to `studies/`.
    #[serde(default = "default_record_table")]
    record_table: String,
    /// PGA levels, g (increasing).
    pga: Vec<f64>,
    /// PGA levels with `--quick`, g (increasing).
    quick_pga: Vec<f64>,
    /// Reference PGA, g: the strength is the median elastic demand at this PGA, so
    /// R = PGA / reference_pga.
    reference_pga: f64,
    /// Post-yield stiffness over the elastic story stiffness (dimensionless).
    hardening_ratio: f64,
    /// Gap of every contact, m.
    gap: f64,
    /// Coefficient of restitution of every contact (the gap element uses the linear law at
    /// 1, the Kelvin–Voigt law below).
    restitution: f64,
    /// The inelastic methods compared with the elastic momentum method, the reference of
    /// the domain of validity first (`"gap"`, `"impulse"`).
    inelastic: Vec<Method>,
    /// Gap-element spring stiffness, N/m.
    gap_stiffness: f64,
    /// Local error tolerance of the adaptive integrators (gap element, impulse method).
    tolerance: f64,
    /// Departure threshold (relative), 0.10 = 10 %.
    band: f64,
}

/// The yield shear F_y (N) of every story, per building, story 1 first, and the elastic
/// story stiffness k₀ (N/m).
struct Strength {
    yield_shear: Vec<Vec<f64>>,
    stiffness: Vec<Vec<f64>>,
}

impl Strength {
    /// Yield drift F_y / k₀ of story j of building b, m.
    fn yield_drift(&self, b: usize, j: usize) -> f64 {
        self.yield_shear[b][j] / self.stiffness[b][j]
    }
}

fn levels(ctx: &Ctx, d: &Def) -> Vec<f64> {
    if ctx.opts.quick {
        d.quick_pga.clone()
    } else {
        d.pga.clone()
    }
}

fn method_label(m: Method) -> String {
    match m {
        Method::Momentum => "momentum, elastic".into(),
        Method::Gap => "gap element, inelastic".into(),
        #[allow(unreachable_patterns)]
        other => format!("{other}, inelastic"),
    }
}

/// The methods of the study: the elastic momentum method first.
fn methods(d: &Def) -> Vec<Method> {
    std::iter::once(Method::Momentum)
        .chain(d.inelastic.iter().copied())
        .collect()
}

/// 6 significant digits, so the overrides are short and stable.
fn round6(x: f64) -> f64 {
    format!("{x:.5e}").parse().unwrap_or(x)
}

fn validate(ctx: &Ctx, d: &Def) -> Result<()> {
    let bad = |message: String| {
        Err(StudyError::Definition {
            file: ctx.def_file.clone(),
            message,
        })
    };
    for (key, v) in [("pga", &d.pga), ("quick_pga", &d.quick_pga)] {
        if v.is_empty() {
            return bad(format!("`{key}` must list at least one level (g)"));
        }
        if !v.iter().all(|x| x.is_finite() && *x > 0.0) || v.windows(2).any(|w| w[1] <= w[0]) {
            return bad(format!(
                "`{key}` = {v:?}: expected finite levels > 0 g in increasing order"
            ));
        }
    }
    if !(d.reference_pga.is_finite() && d.reference_pga > 0.0) {
        return bad(format!(
            "`reference_pga` = {}: expected a PGA > 0 (g)",
            d.reference_pga
        ));
    }
    if !(d.band.is_finite() && d.band > 0.0) {
        return bad(format!("`band` = {}: expected a number > 0", d.band));
    }
    if d.inelastic.is_empty() || d.inelastic.contains(&Method::Momentum) {
        return bad(format!(
            "`inelastic` = {:?}: expected one or more methods that can yield (the momentum method is the elastic one, always run)",
            d.inelastic
        ));
    }
    Ok(())
}

/// The base scene of the study.
fn base_scene(ctx: &Ctx, d: &Def) -> Result<Scene> {
    CaseSpec::new(&d.scene, Method::Momentum)
        .load_scene(&ctx.studies_dir)
        .map_err(|message| StudyError::Definition {
            file: ctx.def_file.clone(),
            message,
        })
}

/// The strength of every story (see the module docs): the median over `recs` of the
/// momentum method's peak story shear without contact at the reference PGA.
fn strength(ctx: &Ctx, d: &Def, recs: &[String]) -> Result<Strength> {
    let scene = base_scene(ctx, d)?;
    let stiffness: Vec<Vec<f64>> = scene
        .buildings
        .iter()
        .map(|b| b.story_stiffness.clone())
        .collect();
    let mut shears: Vec<Vec<Vec<f64>>> = stiffness
        .iter()
        .map(|k| vec![Vec::new(); k.len()])
        .collect();
    for rec in recs {
        let spec = ctx.case(&d.scene, Method::Momentum, rec, d.reference_pga);
        let mut s =
            spec.load_scene(&ctx.studies_dir)
                .map_err(|message| StudyError::Definition {
                    file: ctx.def_file.clone(),
                    message: format!("record `{rec}`: {message}"),
                })?;
        for c in &mut s.contacts {
            c.gap = 1000.0;
        }
        let run = solvers::run(&s, Method::Momentum, None).map_err(|e| {
            StudyError::Other(format!(
                "study `yielding`: the elastic run that sets the strength failed on record `{rec}` at {} g: {e}",
                d.reference_pga
            ))
        })?;
        for (b, r) in run.buildings.iter().enumerate() {
            for (j, v) in r.story_shear_max.iter().enumerate() {
                shears[b][j].push(*v);
            }
        }
    }
    let yield_shear = shears
        .iter()
        .map(|bs| {
            bs.iter()
                .map(|v| median(v).map_or(f64::NAN, round6))
                .collect()
        })
        .collect();
    Ok(Strength {
        yield_shear,
        stiffness,
    })
}

/// The case of `method` on record `rec` at `pga` (g), with pounding.
fn case(ctx: &Ctx, d: &Def, st: &Strength, rec: &str, pga: f64, m: Method) -> CaseSpec {
    let mut c = ctx
        .case(&d.scene, m, rec, pga)
        .with("contacts.0.gap", format!("{:?}", d.gap))
        .with("contacts.0.restitution", format!("{:?}", d.restitution))
        .param("strength_ratio", round6(pga / d.reference_pga))
        .param("variant", method_label(m));
    if m != Method::Momentum {
        for (b, fy) in st.yield_shear.iter().enumerate() {
            let list: Vec<String> = fy.iter().map(|x| format!("{x:e}")).collect();
            c = c
                .with(&format!("buildings.{b}.story_law"), "bilinear")
                .with(
                    &format!("buildings.{b}.yield_shear"),
                    format!("[{}]", list.join(", ")),
                )
                .with(
                    &format!("buildings.{b}.hardening_ratio"),
                    format!("{:?}", d.hardening_ratio),
                );
        }
    }
    match m {
        Method::Momentum => c.with("momentum.impulse", "consistent"),
        Method::Gap => c
            .with(
                "gap_element.law",
                if d.restitution >= 1.0 {
                    "linear"
                } else {
                    "kelvin-voigt"
                },
            )
            .with("gap_element.integrator", "adaptive")
            .with("gap_element.stiffness", format!("{:e}", d.gap_stiffness))
            .with("gap_element.tolerance", format!("{:e}", d.tolerance)),
        #[allow(unreachable_patterns)]
        _ => c,
    }
}

/// Peak drift of every story of building `b`, m: the solver's, or for linear stories
/// V_max / k₀ (exact: V = k₀ × drift).
fn drifts(o: &CaseOutputs, st: &Strength, b: usize) -> Option<Vec<f64>> {
    if let Some(v) = o.story_drift_max.get(b).filter(|v| !v.is_empty()) {
        return Some(v.clone());
    }
    let v = o.story_shear_max.get(b)?;
    Some(v.iter().zip(&st.stiffness[b]).map(|(v, k)| v / k).collect())
}

/// One (record, level, method) with and without pounding.
#[derive(Debug, Clone, Copy, Default)]
struct Resp {
    /// Contact-story shear amplification per building.
    amp: [Option<f64>; 2],
    /// Contact-story peak shear over its yield shear, with pounding.
    shear_ratio: [Option<f64>; 2],
    /// Peak drift (max over stories), m: with / without pounding.
    drift: [Option<f64>; 2],
    drift0: [Option<f64>; 2],
    /// Ductility demand (max over stories): with / without pounding.
    mu: [Option<f64>; 2],
    mu0: [Option<f64>; 2],
    /// Largest residual drift (m), with / without pounding (None: not reported).
    resid: [Option<f64>; 2],
    resid0: [Option<f64>; 2],
    /// Hysteretic energy (J), with / without pounding.
    hyst: Option<f64>,
    hyst0: Option<f64>,
    impacts: Option<usize>,
    /// Wall time with pounding (s), rhs evaluations + steps (deterministic cost).
    wall: Option<f64>,
    work: Option<f64>,
}

fn response(res: &Results, st: &Strength, c: &CaseSpec) -> Resp {
    let with = res.out(c);
    let without = res.out(&c.baseline());
    let mut r = Resp {
        hyst: with.and_then(|o| o.energy_hysteretic),
        hyst0: without.and_then(|o| o.energy_hysteretic),
        impacts: with.map(|o| o.impacts),
        wall: with.map(|_| res.get(c).wall_seconds),
        work: with.map(|o| (o.steps + o.rhs_evaluations) as f64),
        ..Default::default()
    };
    for b in 0..2 {
        r.amp[b] = amp_contact(res, c, b);
        let peak = |o: Option<&CaseOutputs>| -> (Option<f64>, Option<f64>) {
            let Some(o) = o else { return (None, None) };
            let Some(d) = drifts(o, st, b) else {
                return (None, None);
            };
            let dm = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let mu = d
                .iter()
                .enumerate()
                .map(|(j, x)| x / st.yield_drift(b, j))
                .fold(f64::NEG_INFINITY, f64::max);
            (Some(dm), Some(mu))
        };
        (r.drift[b], r.mu[b]) = peak(with);
        (r.drift0[b], r.mu0[b]) = peak(without);
        let resid = |o: Option<&CaseOutputs>| {
            o.and_then(|o| o.story_drift_residual.get(b))
                .filter(|v| !v.is_empty())
                .map(|v| v.iter().map(|x| x.abs()).fold(0.0, f64::max))
        };
        r.resid[b] = resid(with);
        r.resid0[b] = resid(without);
        r.shear_ratio[b] = with.and_then(|o| {
            let j = contact_floor(o, b)? - 1;
            Some(o.story_shear_max.get(b)?.get(j)? / st.yield_shear[b][j])
        });
    }
    r
}

/// max_b |x_b / y_b − 1| over the buildings where both are known.
fn departure(x: [Option<f64>; 2], y: [Option<f64>; 2]) -> Option<f64> {
    let v: Vec<f64> = x
        .iter()
        .zip(&y)
        .filter_map(|(a, b)| Some((a.as_ref()? / b.as_ref()? - 1.0).abs()))
        .collect();
    (v.len() == 2).then(|| v.iter().copied().fold(0.0, f64::max))
}

/// The departures of the elastic answer from one inelastic reference.
#[derive(Debug, Clone, Copy)]
enum Quantity {
    Amplification,
    Drift,
    DriftNoContact,
}

impl Quantity {
    const ALL: [Quantity; 3] = [
        Quantity::Amplification,
        Quantity::Drift,
        Quantity::DriftNoContact,
    ];
    fn label(self) -> &'static str {
        match self {
            Quantity::Amplification => "top-story shear amplification",
            Quantity::Drift => "peak drift with pounding",
            Quantity::DriftNoContact => "peak drift without pounding",
        }
    }
    fn short(self) -> &'static str {
        match self {
            Quantity::Amplification => "amplification",
            Quantity::Drift => "drift",
            Quantity::DriftNoContact => "drift, no contact",
        }
    }
    fn of(self, el: &Resp, inel: &Resp) -> Option<f64> {
        match self {
            Quantity::Amplification => departure(el.amp, inel.amp),
            Quantity::Drift => departure(el.drift, inel.drift),
            Quantity::DriftNoContact => departure(el.drift0, inel.drift0),
        }
    }
}

/// Share of the values above `band`, and the count.
fn share_above(v: &[f64], band: f64) -> (Option<f64>, usize) {
    let n = v.len();
    (
        (n > 0).then(|| v.iter().filter(|x| **x > band).count() as f64 / n as f64),
        n,
    )
}

/// The first PGA at which `share` reaches `level` (linear interpolation between levels).
fn crossing(pts: &[(f64, f64)], level: f64) -> Option<f64> {
    if let Some(&(x, y)) = pts.first() {
        if y >= level {
            return Some(x);
        }
    }
    pts.windows(2).find_map(|w| {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        (y0 < level && y1 >= level).then(|| x0 + (level - y0) / (y1 - y0) * (x1 - x0))
    })
}

impl Study for Yielding {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        validate(ctx, &d)?;
        let recs = study_records(ctx, d.records.as_deref(), &d.record_dirs)?;
        record_classes(ctx, &d.record_table, &recs)?;
        let st = strength(ctx, &d, &recs)?;
        let mut v = Vec::new();
        for rec in &recs {
            for &pga in &levels(ctx, &d) {
                for m in methods(&d) {
                    v.push(case(ctx, &d, &st, rec, pga, m));
                }
            }
        }
        Ok(v)
    }

    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()> {
        let d: Def = ctx.def()?;
        let recs = study_records(ctx, d.records.as_deref(), &d.record_dirs)?;
        let st = strength(ctx, &d, &recs)?;
        let scene = base_scene(ctx, &d)?;
        let names: Vec<String> = scene.buildings.iter().map(|b| b.name.clone()).collect();
        let lv = levels(ctx, &d);
        let ms = methods(&d);
        let reference = d.inelastic[0];
        let r_of = |pga: f64| pga / d.reference_pga;
        // resp[m][l][i]
        let resp: Vec<Vec<Vec<Resp>>> = ms
            .iter()
            .map(|&m| {
                lv.iter()
                    .map(|&pga| {
                        recs.iter()
                            .map(|rec| response(res, &st, &case(ctx, &d, &st, rec, pga, m)))
                            .collect()
                    })
                    .collect()
            })
            .collect();
        let failed = |m: Method, pga: f64| {
            recs.iter()
                .filter(|rec| {
                    let c = case(ctx, &d, &st, rec, pga, m);
                    res.get(&c).status != "ok" || res.get(&c.baseline()).status != "ok"
                })
                .count()
        };

        // --- Strength table.
        let mut strength_t = Table::new(
            &format!(
                "Strength of every story: F_y = median over the {} record(s) of the elastic no-contact peak story shear at {} g (momentum method, all modes); yield drift F_y / k0; hardening ratio {}",
                recs.len(),
                d.reference_pga,
                d.hardening_ratio
            ),
            &["building", "story", "k0 (N/m)", "F_y (N)", "yield drift (m)"],
        );
        for (b, name) in names.iter().enumerate() {
            for j in 0..st.yield_shear[b].len() {
                strength_t.push(vec![
                    name.clone(),
                    (j + 1).to_string(),
                    e(Some(st.stiffness[b][j]), 4),
                    e(Some(st.yield_shear[b][j]), 5),
                    e(Some(st.yield_drift(b, j)), 4),
                ]);
            }
        }

        // --- Response table: median and 16–84 % per level, method, pounding.
        let mut resp_t = Table::new(
            &format!(
                "Responses over the records: median, 16th and 84th percentiles (n = records with both runs finished); R = PGA / {} g; amplification = contact-story (roof) peak shear with / without pounding; drift and ductility demand = largest over the stories (elastic method: the elastic prediction, peak drift / yield drift)",
                d.reference_pga
            ),
            &[
                "PGA (g)", "R", "method", "pounding", "n",
                "amp. b1 median", "amp. b1 p16", "amp. b1 p84",
                "amp. b2 median", "amp. b2 p16", "amp. b2 p84",
                "drift b1 median (m)", "drift b1 p16 (m)", "drift b1 p84 (m)",
                "drift b2 median (m)", "drift b2 p16 (m)", "drift b2 p84 (m)",
                "ductility b1 median", "ductility b1 p16", "ductility b1 p84",
                "ductility b2 median", "ductility b2 p16", "ductility b2 p84",
                "residual drift b1 median (m)", "residual drift b2 median (m)",
                "hysteretic energy median (J)", "records yielding", "failed",
            ],
        );
        for (li, &pga) in lv.iter().enumerate() {
            for (mi, &m) in ms.iter().enumerate() {
                for pounding in [true, false] {
                    let rs = &resp[mi][li];
                    let sp = |g: &dyn Fn(&Resp) -> Option<f64>| Spread::of(rs.iter().filter_map(g));
                    let amp = |b: usize| {
                        if pounding {
                            sp(&|r: &Resp| r.amp[b])
                        } else {
                            Spread::of([])
                        }
                    };
                    let pick = |a: [Option<f64>; 2], a0: [Option<f64>; 2], b: usize| {
                        if pounding {
                            a[b]
                        } else {
                            a0[b]
                        }
                    };
                    let dr = |b| sp(&|r: &Resp| pick(r.drift, r.drift0, b));
                    let mu = |b| sp(&|r: &Resp| pick(r.mu, r.mu0, b));
                    let rd = |b| sp(&|r: &Resp| pick(r.resid, r.resid0, b));
                    let hy = sp(&|r: &Resp| if pounding { r.hyst } else { r.hyst0 });
                    let n = rs
                        .iter()
                        .filter(|r| pick(r.drift, r.drift0, 0).is_some())
                        .count();
                    let yielding = rs
                        .iter()
                        .filter(|r| (0..2).any(|b| pick(r.mu, r.mu0, b).is_some_and(|x| x > 1.0)))
                        .count();
                    let mut row = vec![
                        pga.to_string(),
                        f(Some(r_of(pga)), 2),
                        method_label(m),
                        if pounding { "yes" } else { "no" }.into(),
                        n.to_string(),
                    ];
                    row.extend(amp(0).cells(3));
                    row.extend(amp(1).cells(3));
                    row.extend(dr(0).cells(4));
                    row.extend(dr(1).cells(4));
                    row.extend(mu(0).cells(2));
                    row.extend(mu(1).cells(2));
                    row.push(f(rd(0).median, 4));
                    row.push(f(rd(1).median, 4));
                    row.push(e(hy.median, 3));
                    // For the elastic method: records whose elastic demand exceeds the
                    // strength somewhere (where it would yield).
                    row.push(format!("{yielding}/{n}"));
                    row.push(failed(m, pga).to_string());
                    resp_t.push(row);
                }
            }
        }

        // --- Validity: departure of the elastic answer from each inelastic reference.
        let mut val_t = Table::new(
            &format!(
                "Departure of the elastic momentum method from the inelastic answer per level: e = max over the two buildings of |elastic / inelastic − 1|; share of the n records with e > {:.0} %, and the median (16–84 %) of e",
                100.0 * d.band
            ),
            &[
                "PGA (g)", "R", "inelastic reference", "quantity", "n",
                "share e > band", "e median", "e p16", "e p84",
            ],
        );
        // (reference index, quantity) -> [(pga, share)], [(pga, spread)]
        let mut shares: Vec<(usize, Quantity, Vec<(f64, f64)>, Vec<(f64, Spread)>)> = Vec::new();
        for (ri, _) in d.inelastic.iter().enumerate() {
            let mi = ri + 1;
            for q in Quantity::ALL {
                let (mut sh, mut sp) = (Vec::new(), Vec::new());
                for (li, &pga) in lv.iter().enumerate() {
                    let v: Vec<f64> = (0..recs.len())
                        .filter_map(|i| q.of(&resp[0][li][i], &resp[mi][li][i]))
                        .collect();
                    let (s, n) = share_above(&v, d.band);
                    let spread = Spread::of(v.iter().copied());
                    let mut row = vec![
                        pga.to_string(),
                        f(Some(r_of(pga)), 2),
                        method_label(ms[mi]),
                        q.label().into(),
                        n.to_string(),
                        f(s, 3),
                    ];
                    row.extend(spread.cells_e(2));
                    val_t.push(row);
                    if let Some(s) = s {
                        sh.push((pga, s));
                    }
                    sp.push((pga, spread));
                }
                shares.push((ri, q, sh, sp));
            }
        }

        // --- Cost: deterministic work and wall time per run (with pounding).
        let mut cpu_t = Table::new(
            "Cost per analysis with pounding: median over every record and level of the wall time (one run per case on a shared machine, cases side by side: indicative) and of the work (steps + right-hand-side evaluations, deterministic)",
            &[
                "method", "runs", "wall median (s)", "wall p16 (s)", "wall p84 (s)",
                "wall median / momentum", "steps + rhs evaluations median",
            ],
        );
        let walls: Vec<Spread> = (0..ms.len())
            .map(|mi| Spread::of(resp[mi].iter().flatten().filter_map(|r| r.wall)))
            .collect();
        let works: Vec<Spread> = (0..ms.len())
            .map(|mi| Spread::of(resp[mi].iter().flatten().filter_map(|r| r.work)))
            .collect();
        for (mi, &m) in ms.iter().enumerate() {
            let mut row = vec![method_label(m), walls[mi].n.to_string()];
            row.extend(walls[mi].cells_e(3));
            row.push(f(
                walls[mi].median.zip(walls[0].median).map(|(a, b)| a / b),
                2,
            ));
            row.push(f(works[mi].median, 0));
            cpu_t.push(row);
        }

        // --- Every case: one row per record, level, method, pounding.
        let mut all = Table::new(
            "Every record, level, method, with and without pounding",
            &[
                "record",
                "pga_g",
                "strength_ratio",
                "method",
                "pounding",
                "impacts",
                "amplification_b1",
                "amplification_b2",
                "top_shear_over_yield_b1",
                "top_shear_over_yield_b2",
                "drift_max_b1_m",
                "drift_max_b2_m",
                "ductility_b1",
                "ductility_b2",
                "residual_drift_max_b1_m",
                "residual_drift_max_b2_m",
                "hysteretic_energy_J",
                "status",
            ],
        );
        for (i, rec) in recs.iter().enumerate() {
            for (li, &pga) in lv.iter().enumerate() {
                for (mi, &m) in ms.iter().enumerate() {
                    let r = &resp[mi][li][i];
                    let c = case(ctx, &d, &st, rec, pga, m);
                    for pounding in [true, false] {
                        let rr = if pounding {
                            res.get(&c)
                        } else {
                            res.get(&c.baseline())
                        };
                        let p = |a: [Option<f64>; 2], a0: [Option<f64>; 2], b: usize| {
                            if pounding {
                                a[b]
                            } else {
                                a0[b]
                            }
                        };
                        let ex = |v: Option<f64>| v.map(|x| format!("{x:e}")).unwrap_or_default();
                        all.push(vec![
                            record_name(rec),
                            pga.to_string(),
                            format!("{}", round6(r_of(pga))),
                            m.to_string(),
                            pounding.to_string(),
                            if pounding {
                                r.impacts.map(|x| x.to_string()).unwrap_or_default()
                            } else {
                                "0".into()
                            },
                            if pounding {
                                ex(r.amp[0])
                            } else {
                                String::new()
                            },
                            if pounding {
                                ex(r.amp[1])
                            } else {
                                String::new()
                            },
                            if pounding {
                                ex(r.shear_ratio[0])
                            } else {
                                String::new()
                            },
                            if pounding {
                                ex(r.shear_ratio[1])
                            } else {
                                String::new()
                            },
                            ex(p(r.drift, r.drift0, 0)),
                            ex(p(r.drift, r.drift0, 1)),
                            ex(p(r.mu, r.mu0, 0)),
                            ex(p(r.mu, r.mu0, 1)),
                            ex(p(r.resid, r.resid0, 0)),
                            ex(p(r.resid, r.resid0, 1)),
                            ex(if pounding { r.hyst } else { r.hyst0 }),
                            rr.error_kind
                                .clone()
                                .map_or(rr.status.clone(), |k| format!("failed: {k}")),
                        ]);
                    }
                }
            }
        }

        // --- Figure: the domain of validity.
        let x_label = "PGA (g)".to_string();
        let x_range = Some((0.0, lv[lv.len() - 1] * 1.04));
        let mut p1 = Panel {
            title: format!("Records departing by > {:.0} %", 100.0 * d.band),
            x_label: x_label.clone(),
            y_label: "share of records".into(),
            y_range: Some((-0.02, 1.3)),
            x_range,
            legend_right: false,
            ..Default::default()
        };
        let mut p2 = Panel {
            title: "Departure, median and 16–84 %".into(),
            x_label,
            y_label: "relative departure".into(),
            log_y: true,
            x_range,
            no_legend: true,
            ..Default::default()
        };
        let markers = [
            Marker::Circle,
            Marker::Triangle,
            Marker::Square,
            Marker::Cross,
        ];
        let mut crossings: Vec<(usize, Quantity, Option<f64>)> = Vec::new();
        for (ri, q, sh, sp) in &shares {
            let color = match q {
                Quantity::Amplification => 0,
                Quantity::Drift => 1,
                Quantity::DriftNoContact => 2,
            };
            let name = format!("{} vs {}", q.short(), d.inelastic[*ri]);
            let mut s1 = Series::line(&name, sh.clone(), color).marker(markers[ri % 4]);
            if *ri > 0 {
                s1 = s1.dashed();
            }
            p1.series.push(s1);
            let x = crossing(sh, 0.5);
            crossings.push((*ri, *q, x));
            if *ri == 0 {
                if let Some(x) = x {
                    p1.vlines.push(VLine {
                        x,
                        label: format!("{}: half at {x:.2} g", q.short()),
                        color,
                    });
                }
                // The median with its band, floored at 1e-7 for the log axis.
                let floored: Vec<(f64, Spread)> = sp
                    .iter()
                    .map(|(x, s)| {
                        let fl = |v: Option<f64>| v.map(|y| y.max(1e-7));
                        (
                            *x,
                            Spread {
                                n: s.n,
                                median: fl(s.median),
                                p16: fl(s.p16),
                                p84: fl(s.p84),
                            },
                        )
                    })
                    .collect();
                p2.series.extend(median_band(
                    &format!("{} vs {}", q.short(), d.inelastic[*ri]),
                    color,
                    &floored,
                ));
            }
        }
        let (x0, x1) = (0.0, lv[lv.len() - 1] * 1.04);
        p1.series
            .push(Series::line("half the records", vec![(x0, 0.5), (x1, 0.5)], 7).width(1));
        p2.series.push(
            Series::line(
                &format!("{:.0} %", 100.0 * d.band),
                vec![(x0, d.band), (x1, d.band)],
                7,
            )
            .width(1),
        );
        figure(
            &ctx.dir,
            "yielding_validity",
            (1200, 520),
            (1, 2),
            &[PanelKind::Xy(p1), PanelKind::Xy(p2)],
            &format!(
                "Domain of validity of the elastic momentum method on {} record(s) of the paper pair (contact at every floor, gap {} cm, c_r = {}; R = PGA / {} g): left, the share of records where its answer departs by more than {:.0} % from the inelastic one (solid: {}{}); right, the departure max over the two buildings of |elastic / inelastic − 1| against {}: median (solid) and 16th–84th percentiles (thin dashed), floored at 1e-7; same colours as on the left.",
                recs.len(),
                d.gap * 100.0,
                d.restitution,
                d.reference_pga,
                100.0 * d.band,
                d.inelastic[0],
                if d.inelastic.len() > 1 {
                    format!(", dashed: {}", d.inelastic[1..].iter().map(|m| m.to_string()).collect::<Vec<_>>().join(", "))
                } else {
                    String::new()
                },
                d.inelastic[0]
            ),
        )?;

        // --- Readings.
        let mut reading = Vec::new();
        let li_lo = 0;
        let li_hi = lv.len() - 1;
        let (pga_lo, pga_hi) = (lv[li_lo], lv[li_hi]);
        let classes = record_classes(ctx, &d.record_table, &recs)?;
        let np = classes
            .iter()
            .filter(|c| **c == super::record_table::PulseClass::Pulse)
            .count();
        reading.push(format!(
            "{} record(s) ({np} with a velocity pulse), {} levels from {pga_lo} to {pga_hi} g; strength per story = median elastic no-contact demand at {} g, so R = PGA / {} g runs from {:.2} to {:.2} (table `yielding_strength`). Elastic: the momentum method with all modes; inelastic: {} with bilinear stories (hardening ratio {}).",
            recs.len(),
            lv.len(),
            d.reference_pga,
            d.reference_pga,
            r_of(pga_lo),
            r_of(pga_hi),
            d.inelastic
                .iter()
                .map(|m| method_label(*m))
                .collect::<Vec<_>>()
                .join(" and "),
            d.hardening_ratio
        ));
        let sp_at = |mi: usize, li: usize, g: &dyn Fn(&Resp) -> Option<f64>| {
            Spread::of(resp[mi][li].iter().filter_map(g))
        };
        for (mi, &m) in ms.iter().enumerate() {
            reading.push(format!(
                "{}: top-story amplification of {} / {}, median (16–84 %), {} / {} at {pga_lo} g and {} / {} at {pga_hi} g; ductility demand with pounding {} / {} at {pga_hi} g (without: {} / {}).",
                method_label(m),
                names[0],
                names[1],
                sp_at(mi, li_lo, &|r| r.amp[0]).words(2),
                sp_at(mi, li_lo, &|r| r.amp[1]).words(2),
                sp_at(mi, li_hi, &|r| r.amp[0]).words(2),
                sp_at(mi, li_hi, &|r| r.amp[1]).words(2),
                sp_at(mi, li_hi, &|r| r.mu[0]).words(1),
                sp_at(mi, li_hi, &|r| r.mu[1]).words(1),
                sp_at(mi, li_hi, &|r| r.mu0[0]).words(1),
                sp_at(mi, li_hi, &|r| r.mu0[1]).words(1),
            ));
        }
        let mut dom = Vec::new();
        for (ri, q, x) in &crossings {
            let (_, _, sh, _) = shares
                .iter()
                .find(|(r, qq, _, _)| r == ri && qq.short() == q.short())
                .expect("a share series for every crossing");
            let first = sh.iter().find(|(_, s)| *s > 0.0).map(|(x, _)| *x);
            dom.push(format!(
                "{} against {}: the first level where any record departs is {}, half the records depart from {}",
                q.label(),
                d.inelastic[*ri],
                first.map_or(format!("beyond {pga_hi} g"), |x| format!("{x} g (R = {:.2})", r_of(x))),
                x.map_or(format!("no level up to {pga_hi} g"), |x| format!(
                    "{x:.2} g (R = {:.2})",
                    r_of(x)
                ))
            ));
        }
        reading.push(format!(
            "Domain of validity (table `yielding_validity`, figure): {}.",
            dom.join("; ")
        ));
        let w = &works;
        reading.push(format!(
            "Cost (table `yielding_cpu`): the work per analysis with pounding, median steps + right-hand-side evaluations, is {} (wall times, machine-dependent, in `yielding_cpu.md`).",
            ms.iter()
                .enumerate()
                .map(|(mi, m)| format!("{} {}", method_label(*m), f(w[mi].median, 0)))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        let _ = reference;
        if let Some(n) = failures_note(res) {
            reading.push(n);
        }

        strength_t.write(&ctx.dir, "yielding_strength")?;
        resp_t.write(&ctx.dir, "yielding")?;
        val_t.write(&ctx.dir, "yielding_validity")?;
        cpu_t.write(&ctx.dir, "yielding_cpu")?;
        all.write(&ctx.dir, "yielding_all")?;
        write_summary(
            ctx,
            "Yielding buildings: the domain of validity of the linear modal method",
            &reading,
            &[&val_t, &resp_t, &strength_t],
            &[(
                "yielding_validity",
                "Where the elastic momentum method departs by more than the band from the inelastic answer",
            )],
        )
    }
}
