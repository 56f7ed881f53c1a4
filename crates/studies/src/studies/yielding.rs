//! Study `yielding`: where the linear modal (momentum) method stops being valid when the
//! buildings yield.
//!
//! The paper pair with contact at every facing floor (`floors = "aligned"`) on every record
//! of the set, scaled to each PGA level (0.05 … 1.2 g), with
//! - the momentum method with all modes: linear stories (it cannot yield: modal
//!   superposition needs constant K, the paper's eq. 5);
//! - each inelastic method of the definition (`inelastic`: the impulse method, i.e. the
//!   paper's impact law in physical coordinates, and the gap element, adaptive): bilinear
//!   stories with kinematic hardening (`story_law = "bilinear"`);
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
//! share first reaches one half (linear interpolation between levels). The self-check table
//! bins the same departures by the elastic run's own demand over strength,
//! μ_el = max over every story of both buildings (with and without pounding) of the elastic
//! peak drift over the yield drift: below 1 nothing can yield, so the inelastic methods must
//! give the elastic answer to their integration (and, for the gap element, contact-spring)
//! error.
//!
//! Statistics over records: median and 16th/84th percentiles ([`super::stats`]) with the
//! count n. Wall times (`yielding_cpu.*` and the cost paragraph of `summary.md`) are
//! machine-dependent; everything else is deterministic.

use serde::Deserialize;
use solvers::Method;
use structure::Scene;

use super::stats::{median, median_band, Spread};
use super::{
    amp_contact, contact_floor, failures_note, record_classes, record_name, study_records,
    write_summary, Ctx, Study,
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
    /// when `record_dirs` is not given either. With `record_dirs`, at least one record in all.
    records: Option<Vec<String>>,
    /// Folders whose every `*.AT2` is added (sorted by file name).
    #[serde(default)]
    record_dirs: Vec<String>,
    /// Record metadata (pulse classes), relative to `studies/`; without it
    /// `../data/ground-motions/records.csv` if that exists, else every record unclassified
    /// ([`super::record_classes`]).
    #[serde(default)]
    record_table: Option<String>,
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
        Method::Impulse => "impulse, inelastic".into(),
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
    if !(d.hardening_ratio.is_finite() && (0.0..1.0).contains(&d.hardening_ratio)) {
        return bad(format!(
            "`hardening_ratio` = {}: expected a number in [0, 1)",
            d.hardening_ratio
        ));
    }
    if !(d.gap.is_finite() && d.gap >= 0.0) {
        return bad(format!("`gap` = {} m: expected a length >= 0", d.gap));
    }
    if !(d.restitution.is_finite() && (0.0..=1.0).contains(&d.restitution)) {
        return bad(format!(
            "`restitution` = {}: expected a number in [0, 1]",
            d.restitution
        ));
    }
    for (key, v) in [
        ("gap_stiffness", d.gap_stiffness),
        ("tolerance", d.tolerance),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return bad(format!("`{key}` = {v}: expected a number > 0"));
        }
    }
    let mut seen = Vec::new();
    if let Some(m) = d.inelastic.iter().find(|m| {
        let dup = seen.contains(*m);
        seen.push(**m);
        dup
    }) {
        return bad(format!("`inelastic` lists `{m}` twice"));
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
                "study `{}`: the elastic run that sets the strength failed on record `{rec}` at {} g: {e}",
                ctx.name,
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
        // The impulse method reads the adaptive stepper's tolerance from
        // `gap_element.tolerance`.
        Method::Impulse => c.with("gap_element.tolerance", format!("{:e}", d.tolerance)),
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
    /// Peak closure u_left − u_right at the roof contact without contact, m (the
    /// separation the pair needs).
    closure0: Option<f64>,
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
        closure0: without.and_then(|o| o.peak_closure),
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

impl Resp {
    /// The largest ductility demand over the stories of both buildings, with and without
    /// pounding (for the elastic method: its demand over the strength).
    fn mu_max(&self) -> Option<f64> {
        let v: Vec<f64> = self.mu.iter().chain(&self.mu0).flatten().copied().collect();
        (v.len() == 4).then(|| v.iter().copied().fold(f64::NEG_INFINITY, f64::max))
    }
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
    fn takes_record_table(&self) -> bool {
        true
    }

    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
        let d: Def = ctx.def()?;
        validate(ctx, &d)?;
        let recs = study_records(ctx, d.records.as_deref(), &d.record_dirs)?;
        record_classes(ctx, d.record_table.as_deref(), &recs)?;
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
                "Strength of every story: F_y = median over the {} of the elastic no-contact peak story shear at {} g (momentum method, all modes); yield drift F_y / k0; hardening ratio {}",
                crate::table::count(recs.len(), "record", "records"),
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
        type Shares = (usize, Quantity, Vec<(f64, f64)>, Vec<(f64, Spread)>);
        let mut shares: Vec<Shares> = Vec::new();
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

        // --- Pounding: how often and how hard, and what it does to the ductility demand.
        let mut pound_t = Table::new(
            "Pounding per level and method: records with at least one impact, impacts (median), the peak roof closure without contact (the separation the pair would need; median, 16–84 %) and the ratio of the ductility demand with pounding to that without, per record (median, 16–84 %)",
            &[
                "PGA (g)", "R", "method", "n", "records pounding", "impacts median",
                "closure without contact median (m)", "closure p16 (m)", "closure p84 (m)",
                "ductility ratio b1 median", "ductility ratio b1 p16", "ductility ratio b1 p84",
                "ductility ratio b2 median", "ductility ratio b2 p16", "ductility ratio b2 p84",
            ],
        );
        let ratio = |r: &Resp, b: usize| Some(r.mu[b]? / r.mu0[b]?);
        for (li, &pga) in lv.iter().enumerate() {
            for (mi, &m) in ms.iter().enumerate() {
                let rs = &resp[mi][li];
                let sp = |g: &dyn Fn(&Resp) -> Option<f64>| Spread::of(rs.iter().filter_map(g));
                let n = rs.iter().filter(|r| r.impacts.is_some()).count();
                let pounding = rs
                    .iter()
                    .filter(|r| r.impacts.is_some_and(|i| i > 0))
                    .count();
                let mut row = vec![
                    pga.to_string(),
                    f(Some(r_of(pga)), 2),
                    method_label(m),
                    n.to_string(),
                    pounding.to_string(),
                    f(sp(&|r: &Resp| r.impacts.map(|i| i as f64)).median, 1),
                ];
                row.extend(sp(&|r: &Resp| r.closure0).cells(4));
                row.extend(sp(&|r: &Resp| ratio(r, 0)).cells(3));
                row.extend(sp(&|r: &Resp| ratio(r, 1)).cells(3));
                pound_t.push(row);
            }
        }

        // --- Self-check: the departure against the elastic run's own demand over strength.
        let bins: [(f64, f64); 6] = [
            (0.0, 1.0),
            (1.0, 1.5),
            (1.5, 2.0),
            (2.0, 4.0),
            (4.0, 8.0),
            (8.0, f64::INFINITY),
        ];
        let mut self_t = Table::new(
            &format!(
                "Departure against the elastic run's own demand: μ_el = largest elastic story drift over yield drift over every story of both buildings, with and without pounding (μ_el < 1: the elastic run never reaches the strength); per bin, the (record, level) pairs and the share of them with e > {:.0} %, and the largest e",
                100.0 * d.band
            ),
            &[
                "μ_el from", "μ_el below", "inelastic reference", "n",
                "share amplification e > band", "share drift e > band",
                "largest e amplification", "largest e drift",
            ],
        );
        // Per reference: (n, max e_A, max e_d) of the pairs with μ_el < 1, and the share
        // departing among those with μ_el >= 1.
        let mut self_summary: Vec<(usize, f64, f64, usize, usize, usize)> = Vec::new();
        for (ri, &rm) in d.inelastic.iter().enumerate() {
            let mi = ri + 1;
            let pairs: Vec<(f64, Option<f64>, Option<f64>)> = (0..lv.len())
                .flat_map(|li| (0..recs.len()).map(move |i| (li, i)))
                .filter_map(|(li, i)| {
                    let (el, inel) = (&resp[0][li][i], &resp[mi][li][i]);
                    Some((
                        el.mu_max()?,
                        Quantity::Amplification.of(el, inel),
                        Quantity::Drift.of(el, inel),
                    ))
                })
                .collect();
            for (lo_b, hi_b) in bins {
                let inbin: Vec<_> = pairs.iter().filter(|p| p.0 >= lo_b && p.0 < hi_b).collect();
                let ea: Vec<f64> = inbin.iter().filter_map(|p| p.1).collect();
                let ed: Vec<f64> = inbin.iter().filter_map(|p| p.2).collect();
                let mx = |v: &[f64]| v.iter().copied().reduce(f64::max);
                self_t.push(vec![
                    lo_b.to_string(),
                    if hi_b.is_finite() {
                        hi_b.to_string()
                    } else {
                        "∞".into()
                    },
                    method_label(rm),
                    inbin.len().to_string(),
                    f(share_above(&ea, d.band).0, 3),
                    f(share_above(&ed, d.band).0, 3),
                    e(mx(&ea), 2),
                    e(mx(&ed), 2),
                ]);
            }
            let el: Vec<_> = pairs.iter().filter(|p| p.0 < 1.0).collect();
            let yl: Vec<_> = pairs.iter().filter(|p| p.0 >= 1.0).collect();
            let depart = |p: &&&(f64, Option<f64>, Option<f64>)| {
                p.1.is_some_and(|x| x > d.band) || p.2.is_some_and(|x| x > d.band)
            };
            // Of the pairs below the strength, those where the elastic run pounds.
            let el_pound = (0..lv.len())
                .flat_map(|li| (0..recs.len()).map(move |i| (li, i)))
                .filter(|&(li, i)| {
                    let r = &resp[0][li][i];
                    r.mu_max().is_some_and(|m| m < 1.0) && r.impacts.is_some_and(|n| n > 0)
                })
                .count();
            self_summary.push((
                el.len(),
                el.iter().filter_map(|p| p.1).fold(0.0, f64::max),
                el.iter().filter_map(|p| p.2).fold(0.0, f64::max),
                yl.len(),
                yl.iter().filter(depart).count(),
                el_pound,
            ));
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
        let x1 = lv[lv.len() - 1] * 1.04;
        let mut p1 = Panel {
            title: format!(
                "Share of the {} where the elastic answer departs by more than {:.0} %",
                crate::table::count(recs.len(), "record", "records"),
                100.0 * d.band
            ),
            x_label: format!("PGA (g); R = PGA / {} g", d.reference_pga),
            y_label: "share of records".into(),
            y_range: Some((-0.02, 1.02)),
            x_range: Some((0.0, x1)),
            legend_right: true,
            ..Default::default()
        };
        let mut p2 = Panel {
            title: format!(
                "Departure from the {} answer: median and 16–84 % over the records",
                d.inelastic[0]
            ),
            x_label: format!("PGA (g); R = PGA / {} g", d.reference_pga),
            y_label: "departure e (%)".into(),
            x_range: Some((0.0, x1)),
            no_legend: true,
            ..Default::default()
        };
        let markers = [
            Marker::Circle,
            Marker::Triangle,
            Marker::Square,
            Marker::Cross,
        ];
        let color = |q: Quantity| match q {
            Quantity::Amplification => 0,
            Quantity::Drift => 1,
            Quantity::DriftNoContact => 2,
        };
        let mut crossings: Vec<(usize, Quantity, Option<f64>, Option<f64>)> = Vec::new();
        for (ri, q, sh, sp) in &shares {
            let name = format!("{} vs {}", q.short(), d.inelastic[*ri]);
            let mut s1 = Series::line(&name, sh.clone(), color(*q)).marker(markers[ri % 4]);
            if *ri > 0 {
                s1 = s1.dashed();
            }
            p1.series.push(s1);
            let first = sh.iter().find(|(_, s)| *s > 0.0).map(|(x, _)| *x);
            let x = crossing(sh, 0.5);
            crossings.push((*ri, *q, first, x));
            if *ri == 0 {
                if let (Some(x), Quantity::Amplification | Quantity::Drift) = (x, q) {
                    p1.vlines.push(VLine {
                        x,
                        label: format!("half at {} g", crate::table::trimmed(x, 3)),
                        color: color(*q),
                    });
                }
                let pct: Vec<(f64, Spread)> = sp
                    .iter()
                    .map(|(x, s)| {
                        let pc = |v: Option<f64>| v.map(|y| 100.0 * y);
                        (
                            *x,
                            Spread {
                                n: s.n,
                                median: pc(s.median),
                                p16: pc(s.p16),
                                p84: pc(s.p84),
                            },
                        )
                    })
                    .collect();
                p2.series.extend(median_band(&name, color(*q), &pct));
            }
        }
        p1.series
            .push(Series::line("half the records", vec![(0.0, 0.5), (x1, 0.5)], 7).width(1));
        p2.series.push(
            Series::line(
                &format!("{:.0} %", 100.0 * d.band),
                vec![(0.0, 100.0 * d.band), (x1, 100.0 * d.band)],
                7,
            )
            .width(1),
        );
        figure(
            &ctx.dir,
            "yielding_validity",
            (1200, 700),
            (2, 1),
            &[PanelKind::Xy(p1), PanelKind::Xy(p2)],
            &format!(
                "Domain of validity of the elastic momentum method (all modes) on {} of the paper pair, contact at every floor, gap {} cm, c_r = {}; strength per story = median elastic demand at {} g. e = max over the two buildings of |elastic / inelastic − 1| per record: top-story shear amplification (blue), peak story drift with pounding (orange), without (green). Top: share of records with e > {:.0} % against {}{}; vertical lines where half the records depart. Bottom: median (solid) and 16th–84th percentiles (thin dashed) of e; grey: {:.0} %.",
                crate::table::count(recs.len(), "record", "records"),
                d.gap * 100.0,
                d.restitution,
                d.reference_pga,
                100.0 * d.band,
                d.inelastic[0],
                if d.inelastic.len() > 1 {
                    format!(
                        " (solid), {} (dashed)",
                        d.inelastic[1..]
                            .iter()
                            .map(|m| m.to_string())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                } else {
                    String::new()
                },
                100.0 * d.band,
            ),
        )?;

        // --- Readings (numbers from the tables, rows named by level and method).
        let mut reading = Vec::new();
        let (li_lo, li_hi) = (0, lv.len() - 1);
        let (pga_lo, pga_hi) = (lv[li_lo], lv[li_hi]);
        let classes = record_classes(ctx, d.record_table.as_deref(), &recs)?;
        let np = classes
            .iter()
            .filter(|c| **c == super::record_table::PulseClass::Pulse)
            .count();
        let mname = |mi: usize| method_label(ms[mi]);
        reading.push(format!(
            "**Set-up.** {} ({np} with a velocity pulse) at {} from {pga_lo} to {pga_hi} g. Strength: the yield shear of every story is the median over the records of its elastic no-contact peak shear at {} g (table `yielding_strength`), the same for every record and level, so the median elastic demand over strength is R = PGA / {} g, from {:.2} to {:.2}; a given record's own ratio scatters about it. Elastic: the momentum method with all modes (linear stories; it cannot yield). Inelastic: {} with bilinear stories (post-yield stiffness {} × k0, kinematic hardening).",
            crate::table::count(recs.len(), "record", "records"),
            crate::table::count(lv.len(), "PGA level", "PGA levels"),
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
        let pounding_n = |mi: usize, li: usize| {
            resp[mi][li]
                .iter()
                .filter(|r| r.impacts.is_some_and(|i| i > 0))
                .count()
        };
        // The response at the top level, elastic against the reference.
        let mut parts = Vec::new();
        for mi in 0..ms.len() {
            parts.push(format!(
                "{}: {} / {} records pound, top-story amplification of {} / {} {} / {}, peak roof closure without contact {} m",
                mname(mi),
                pounding_n(mi, li_hi),
                recs.len(),
                names[0],
                names[1],
                sp_at(mi, li_hi, &|r| r.amp[0]).words(2),
                sp_at(mi, li_hi, &|r| r.amp[1]).words(2),
                f(sp_at(mi, li_hi, &|r| r.closure0).median, 3),
            ));
        }
        reading.push(format!(
            "**Pounding and amplification** (tables `yielding`, `yielding_pounding`, rows {pga_hi} g): {}. Yielding stories cap the story shear near F_y (1 + b (μ − 1)), so a yielded building's shear cannot be amplified much{}.",
            parts.join("; "),
            match (
                sp_at(0, li_hi, &|r| r.closure0).median,
                sp_at(1, li_hi, &|r| r.closure0).median,
            ) {
                (Some(el), Some(inel)) if inel < el && pounding_n(1, li_hi) < pounding_n(0, li_hi) => {
                    "; and the inelastic buildings need less separation without contact, so fewer records pound"
                }
                _ => "",
            }
        ));
        let mut mu_parts = Vec::new();
        for mi in 0..ms.len() {
            mu_parts.push(format!(
                "{}: {} / {} with pounding, {} / {} without; ratio with / without per record {} / {}",
                mname(mi),
                f(sp_at(mi, li_hi, &|r| r.mu[0]).median, 1),
                f(sp_at(mi, li_hi, &|r| r.mu[1]).median, 1),
                f(sp_at(mi, li_hi, &|r| r.mu0[0]).median, 1),
                f(sp_at(mi, li_hi, &|r| r.mu0[1]).median, 1),
                sp_at(mi, li_hi, &|r| ratio(r, 0)).words(2),
                sp_at(mi, li_hi, &|r| ratio(r, 1)).words(2),
            ));
        }
        reading.push(format!(
            "**Ductility demand** (largest over the stories; for the elastic method its drift over the yield drift, the equal-displacement estimate) of {} / {} at {pga_hi} g, medians: {}.",
            names[0],
            names[1],
            mu_parts.join("; ")
        ));
        let mut dom = Vec::new();
        for q in Quantity::ALL {
            let mine: Vec<&(usize, Quantity, Option<f64>, Option<f64>)> = crossings
                .iter()
                .filter(|c| c.1.short() == q.short())
                .collect();
            let halves: Vec<String> = mine
                .iter()
                .map(|(ri, _, _, x)| {
                    format!(
                        "{} against {}",
                        x.map_or(format!("at no level up to {pga_hi} g"), |x| format!(
                            "from {} g (R = {:.2})",
                            crate::table::trimmed(x, 3),
                            r_of(x)
                        )),
                        d.inelastic[*ri]
                    )
                })
                .collect();
            // The first departures against the reference, with the records named when few.
            let first = mine.first().and_then(|c| c.2);
            let who = first
                .and_then(|x| lv.iter().position(|l| *l == x))
                .map(|li| {
                    let v: Vec<String> = (0..recs.len())
                        .filter(|&i| {
                            q.of(&resp[0][li][i], &resp[1][li][i])
                                .is_some_and(|e| e > d.band)
                        })
                        .map(|i| record_name(&recs[i]))
                        .collect();
                    match v.len() {
                        1 => format!("one record only, {}", v[0]),
                        2 => format!("two records, {} and {}", v[0], v[1]),
                        n => format!("{n} records"),
                    }
                })
                .unwrap_or_default();
            let label = q.label();
            dom.push(format!(
                "{}{}: half the records depart {}; {}",
                label[..1].to_uppercase(),
                &label[1..],
                halves.join(", "),
                first.map_or(format!("no departure up to {pga_hi} g"), |x| format!(
                    "the first departure, at {x} g (R = {:.2}), is on {who}",
                    r_of(x)
                ))
            ));
        }
        reading.push(format!(
            "**Domain of validity** (table `yielding_validity`, figure; departure e > {:.0} %). {}. {}",
            100.0 * d.band,
            dom.join(". "),
            match crossings
                .iter()
                .filter_map(|c| c.3)
                .reduce(f64::min)
            {
                Some(x) => format!(
                    "So the linear modal method is within {:.0} % of the inelastic answer on most records only below {} g, i.e. R = {:.2} (median demand over strength); which records depart follows from their own elastic demand (next paragraph).",
                    100.0 * d.band,
                    crate::table::trimmed(x, 3),
                    r_of(x)
                ),
                None => format!(
                    "The linear modal method stays within {:.0} % of the inelastic answer on most records at every level up to {pga_hi} g.",
                    100.0 * d.band
                ),
            }
        ));
        let checks: Vec<String> = self_summary
            .iter()
            .enumerate()
            .map(|(ri, (_, ea, ed, n_y, n_dep, _))| {
                format!(
                    "against {}: largest departure {} in amplification and {} in peak drift below the strength, {n_dep} of {n_y} pairs above it depart",
                    d.inelastic[ri],
                    e(Some(*ea), 1),
                    e(Some(*ed), 1),
                )
            })
            .collect();
        let (n_el, n_el_pound) = self_summary.first().map_or((0, 0), |s| (s.0, s.5));
        // Where the median elastic roof closure without contact reaches the gap.
        let onset = crossing(
            &lv.iter()
                .enumerate()
                .filter_map(|(li, &x)| sp_at(0, li, &|r| r.closure0).median.map(|c| (x, c)))
                .collect::<Vec<_>>(),
            d.gap,
        );
        reading.push(format!(
            "**The elastic run tells whether it is inside the domain** (table `yielding_selfcheck`). On the {n_el} (record, level) pairs where the elastic run's demand stays below the strength in every story of both buildings (μ_el < 1, with and without pounding; {n_el_pound} of them pound) nothing can yield, so the departures there are integration error and, for the gap element, the error of its contact spring; above the strength most pairs depart by more than {:.0} %. Per inelastic method: {}.{}",
            100.0 * d.band,
            checks.join("; "),
            if n_el_pound == 0 {
                format!(
                    " None of the pairs below the strength pounds: with this strength every elastic run that pounds has reached the strength somewhere (the median elastic roof closure without contact reaches the {} cm gap at {}), so here the modal method's domain of validity holds no pounding case; a stronger pair (a higher `reference_pga`) would pound before it yields.",
                    d.gap * 100.0,
                    onset.map_or(format!("no level up to {pga_hi} g"), |x| format!(
                        "{} g (R = {:.2})",
                        crate::table::trimmed(x, 3),
                        r_of(x)
                    ))
                )
            } else {
                String::new()
            }
        ));
        if d.inelastic.len() > 1 {
            let mut parts = Vec::new();
            for q in [Quantity::Amplification, Quantity::Drift] {
                for ri in 1..d.inelastic.len() {
                    let v: Vec<f64> = (0..lv.len())
                        .flat_map(|li| (0..recs.len()).map(move |i| (li, i)))
                        .filter_map(|(li, i)| q.of(&resp[ri + 1][li][i], &resp[1][li][i]))
                        .collect();
                    let sp = Spread::of(v.iter().copied());
                    parts.push(format!(
                        "{} of {} from {}: median {}, largest {} over {} pairs",
                        q.label(),
                        d.inelastic[ri],
                        d.inelastic[0],
                        e(sp.median, 1),
                        e(v.iter().copied().reduce(f64::max), 1),
                        sp.n
                    ));
                }
            }
            reading.push(format!(
                "**The inelastic methods agree with each other** (same departure measure, every record and level): {}.",
                parts.join("; ")
            ));
        }
        // Literature, qualitative; the comparison numbers are computed here.
        let ref_mi = 1;
        // Per building: the share of the records on which pounding raises the inelastic
        // ductility demand by more than the band, and the median ratio.
        let raised = |b: usize| {
            let v: Vec<f64> = resp[ref_mi][li_hi]
                .iter()
                .filter_map(|r| ratio(r, b))
                .map(|x| x - 1.0)
                .collect();
            share_above(&v, d.band)
        };
        let ((s1, n1), (s2, n2)) = (raised(0), raised(1));
        let (m1, m2) = (&scene.buildings[0], &scene.buildings[1]);
        let lighter = if m1.total_mass() <= m2.total_mass() {
            0
        } else {
            1
        };
        let f1 = |b: &structure::Building| b.modes().ok().map(|m| m.omega[0]);
        let flexible = match (f1(m1), f1(m2)) {
            (Some(a), Some(b)) if a <= b => 0,
            _ => 1,
        };
        let larger = match (s1, s2) {
            (Some(a), Some(b)) if a > b => Some(0),
            (Some(a), Some(b)) if b > a => Some(1),
            _ => None,
        };
        let amp_el = sp_at(0, li_hi, &|r| r.amp[1]).median;
        let amp_in = sp_at(ref_mi, li_hi, &|r| r.amp[1]).median;
        reading.push(format!(
            "**Literature (qualitative).** Anagnostopoulos & Spiliopoulos (1992, Earthquake Eng. Struct. Dyn. 21:289–302), who studied pounding of inelastic lumped-mass buildings in a row, report, as we read them, that pounding changes the ductility demand most for the lighter or more flexible structure, and that inelastic response reduces the amplification the elastic analysis predicts. Here {} is the lighter{} one; at {pga_hi} g pounding raises the inelastic ({}) ductility demand by more than {:.0} % on {} of {n1} records for {} and {} of {n2} for {} (table `yielding_pounding`: ratio with / without), so the larger effect is {}{}. The second tendency {}: the inelastic median top-story amplification of {} is {} against {} elastic. The set-ups differ (contact at every floor, c_r = {}, 15-story shear sticks whose strength follows each building's own elastic demand), so this compares tendencies, not numbers.",
            names[lighter],
            if lighter == flexible {
                " and more flexible"
            } else {
                ""
            },
            d.inelastic[0],
            100.0 * d.band,
            s1.map_or("–".into(), |s| format!("{:.0}", s * n1 as f64)),
            names[0],
            s2.map_or("–".into(), |s| format!("{:.0}", s * n2 as f64)),
            names[1],
            larger.map_or("the same in both".to_string(), |b| format!("in {}", names[b])),
            match larger {
                Some(b) if b == lighter => ", the tendency the paper reports",
                Some(_) => ", not the tendency the paper reports",
                None => "",
            },
            match (amp_in, amp_el) {
                (Some(a), Some(b)) if a < b => "is seen here",
                (Some(_), Some(_)) => "is not seen here",
                _ => "cannot be judged here",
            },
            names[1],
            f(amp_in, 2),
            f(amp_el, 2),
            d.restitution,
        ));
        // Wall times (machine-dependent): all cases with pounding, and those inside the
        // domain (the elastic run below the strength everywhere).
        let inside = |mi: usize| {
            Spread::of((0..lv.len()).flat_map(|li| {
                let resp = &resp;
                (0..recs.len()).filter_map(move |i| {
                    (resp[0][li][i].mu_max()? < 1.0)
                        .then_some(resp[mi][li][i].wall)
                        .flatten()
                })
            }))
        };
        let total = |mi: usize| -> f64 { resp[mi].iter().flatten().filter_map(|r| r.wall).sum() };
        let ms_txt = |x: Option<f64>| x.map_or("–".into(), |x| format!("{:.1} ms", 1e3 * x));
        let times: Vec<String> = (0..ms.len())
            .map(|mi| {
                let ratio = walls[mi].median.zip(walls[0].median).map(|(a, b)| a / b);
                format!(
                    "{} {}{} (inside the domain {}; all {} {:.1} s)",
                    mname(mi),
                    ms_txt(walls[mi].median),
                    if mi > 0 {
                        format!(", {}× the elastic run", f(ratio, 1))
                    } else {
                        String::new()
                    },
                    ms_txt(inside(mi).median),
                    crate::table::count(walls[mi].n, "run", "runs"),
                    total(mi)
                )
            })
            .collect();
        let speedup = (1..ms.len())
            .filter_map(|mi| walls[mi].median.zip(walls[0].median).map(|(a, b)| a / b))
            .reduce(f64::min);
        reading.push(format!(
            "**Cost and what the speed buys** (table `yielding_cpu`; wall times of one run per case, cases side by side on a shared machine: indicative, and the only machine-dependent numbers of this summary). Median wall time per analysis with pounding: {}. Inside the domain of validity the elastic run gives the inelastic answer (previous paragraphs) at {} of the cost, and its own demand over strength says whether it is inside: so it can screen a record set or a parameter sweep ({}× more analyses for the same time), and only the records and levels where its demand exceeds the strength need an inelastic method. Outside the domain its speed buys an answer that is off by more than {:.0} % on {}.",
            times.join("; "),
            speedup.map_or("a fraction".into(), |x| format!("1/{x:.0}")),
            speedup.map_or("–".into(), |x| format!("{x:.0}")),
            100.0 * d.band,
            // The first inelastic method's self-check: departing pairs of those above.
            match (self_summary.first(), d.inelastic.first()) {
                (Some(s), Some(m)) => format!(
                    "{} of the {} (record, level) pairs above the strength (against {m}, table `yielding_selfcheck`)",
                    s.4, s.3
                ),
                _ => "the (record, level) pairs above the strength (table `yielding_selfcheck`)"
                    .into(),
            }
        ));
        if let Some(n) = failures_note(res) {
            reading.push(n);
        }

        strength_t.write(&ctx.dir, "yielding_strength")?;
        resp_t.write(&ctx.dir, "yielding")?;
        val_t.write(&ctx.dir, "yielding_validity")?;
        pound_t.write(&ctx.dir, "yielding_pounding")?;
        self_t.write(&ctx.dir, "yielding_selfcheck")?;
        cpu_t.write(&ctx.dir, "yielding_cpu")?;
        all.write(&ctx.dir, "yielding_all")?;
        // One paragraph per reading.
        let reading: Vec<String> = reading.into_iter().map(|r| format!("{r}\n\n")).collect();
        write_summary(
            ctx,
            &format!(
                "Yielding buildings: the domain of validity of the linear modal method (strength: the median elastic demand at {} g)",
                d.reference_pga
            ),
            &reading,
            &[&val_t, &self_t, &pound_t, &resp_t, &strength_t],
            &[(
                "yielding_validity",
                "Where the elastic momentum method departs by more than the band from the inelastic answer",
            )],
        )
    }
}
