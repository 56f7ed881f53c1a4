//! Story state of the physical-coordinate solvers (gap element, adaptive and Newmark; the
//! impulse stepper): the committed state of every yielding story and the location of the
//! bilinear law's kinks on a step's dense output.
//!
//! A building with `story_law = "bilinear"` ([`structure::model::StoryLaw`]) has in every
//! story j a [`Bilinear`] spring on the drift d_j = u_j − u_{j−1} (u_0 = 0, the ground):
//!
//! ```text
//! V_j = F(d_j; committed state of story j)        (return mapping, story_law.rs)
//! f_int = −Σ_j V_j (e_j − e_{j−1}) − C v           (C: the elastic building's damping matrix)
//! ```
//!
//! Linear buildings keep V_j = k_j d_j on a fast path with exactly today's arithmetic, so a
//! scene without yielding runs as fast and gives bit-identical results.
//!
//! Trial / commit: [`Stories::story_force`] and `System::internal` evaluate the law
//! from the *committed* state and change nothing (the six Dormand–Prince stages, the Newton
//! iterates of a Newmark step and a rejected step are pure trials); a stepper calls
//! [`Stories::commit`] once per accepted step (or located event), with the state it accepts.
//! The answer of a trial from the committed state is exact as long as the drift moves
//! monotonically from the committed drift (return mapping of a linear-hardening law): the
//! adaptive stepper guarantees it by never straddling a kink ([`Stories::locate_kink`]):
//!
//! - **yield**: a story answering elastically ([`Flow::Elastic`]) whose drift leaves its
//!   elastic range [lo, hi] (`Bilinear::elastic_range`): the event function is the signed
//!   distance to the range, g = min(d − lo, hi − d), which turns negative;
//! - **unloading**: a story flowing ([`Flow::Up`] / [`Flow::Down`]) whose drift rate turns
//!   against the flow (ḋ changes sign).
//!
//! Both are found like contact events: sampled at θ = ¼, ½, ¾, 1 of the step on the dense
//! output, an interior drift extremum located too (so an excursion out of the range and
//! back inside one step is caught), then Brent on the interpolant. A drift excursion beyond
//! the range by less than [`RANGE_SLACK`] × yield drift is not cut (it is round-off of the
//! located kink); the law still answers it exactly.
//!
//! The flow flags only steer the event search; the forces always come from the return
//! mapping. After a commit: the story of a located yield kink flows in the direction it left
//! the range (if its drift still moves that way), the story of a located unloading kink is
//! elastic, any other story keeps flowing while its drift rate points out of the range and
//! starts flowing when it sits on the boundary (within the slack) moving out.
//!
//! Energy: the recoverable story energy ½ k₀ (d − u_p)² + ½ α²/H and the hysteretic
//! (dissipated) energy, plastic work less ½ α²/H ([`Bilinear::hysteretic_energy`]), are
//! exact functions of the committed state, so the energy audit closes to the integration
//! error without an extra quadrature.

use structure::model::story_law::Bilinear;
use structure::Scene;

use super::dopri::Dopri5;

/// Drift excursions beyond the elastic range smaller than this fraction of the yield drift
/// F_y/k₀ are not located as yield kinks (dimensionless).
pub const RANGE_SLACK: f64 = 1e-10;

/// Samples per step of the kink search (as for contact events).
const KINK_SAMPLES: usize = 4;

/// What a story's committed state does at the start of the next step (steers the kink
/// search only; forces always come from the return mapping).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    /// Inside the elastic range (or on its boundary moving inside).
    Elastic,
    /// On the upper yield surface with the drift increasing (plastic flow, u_p growing).
    Up,
    /// On the lower yield surface with the drift decreasing.
    Down,
}

/// One yielding story.
#[derive(Debug, Clone)]
pub struct Story {
    /// Index of the building in the scene.
    pub building: usize,
    /// Story number within the building, 0-based (story 1 joins floor 1 to the ground).
    pub story: usize,
    /// Global index (all buildings' floors, building 0 first) of the floor above the story.
    pub floor: usize,
    /// Global index of the floor below; `None` for the first story (the ground, u_0 = 0).
    pub below: Option<usize>,
    /// The spring with its committed state.
    pub spring: Bilinear,
    /// Flow flag of the committed state.
    pub flow: Flow,
}

impl Story {
    /// Drift u_floor − u_below (m) of a per-floor vector `x` (or its rate, m/s, from the
    /// velocities).
    #[inline]
    pub fn drift(&self, x: &[f64]) -> f64 {
        x[self.floor] - self.below.map_or(0.0, |b| x[b])
    }

    /// Slack of the kink search, m: [`RANGE_SLACK`] × F_y/k₀.
    fn slack(&self) -> f64 {
        RANGE_SLACK * self.spring.params.yield_drift()
    }

    /// Signed distance of drift `d` (m) inside the committed elastic range (> 0 inside).
    #[inline]
    fn inside(&self, d: f64) -> f64 {
        let (lo, hi) = self.spring.elastic_range();
        (d - lo).min(hi - d)
    }
}

/// Bounds (min, max) of the drift u_i − u_below (m) over the whole step of `dp` (`i`,
/// `below`: state components of the floor above and below, `None` for the ground). The dense
/// output of a component is the cubic Hermite interpolant H(θ) of its end values and end
/// rates plus r₅ θ²(1−θ)², |r₅ θ²(1−θ)²| ≤ |r₅|/16; the extremes of H on [0, 1] lie at the
/// ends or at the roots of H′ (a quadratic), so [min H − |r₅|/16, max H + |r₅|/16] (widened
/// by a round-off margin) encloses the drift. `None` if anything is not finite.
pub fn drift_bounds(dp: &Dopri5, i: usize, below: Option<usize>) -> Option<(f64, f64)> {
    let comb = |f: &dyn Fn(usize) -> f64| f(i) - below.map_or(0.0, f);
    let y0 = comb(&|k| dp.dense(k, 0.0));
    let y1 = comb(&|k| dp.dense(k, 1.0));
    // End slopes in θ: h·(rate of the dense output).
    let m0 = dp.h * comb(&|k| dp.dense_rate(k, 0.0));
    let m1 = dp.h * comb(&|k| dp.dense_rate(k, 1.0));
    let r5 = comb(&|k| dp.quartic(k)).abs() / 16.0;
    // H(θ) = y0 + c1 θ + c2 θ² + c3 θ³.
    let c1 = m0;
    let c2 = -3.0 * y0 - 2.0 * m0 + 3.0 * y1 - m1;
    let c3 = 2.0 * y0 + m0 - 2.0 * y1 + m1;
    let h_at = |t: f64| y0 + t * (c1 + t * (c2 + t * c3));
    let (mut lo, mut hi) = (y0.min(y1), y0.max(y1));
    // Roots of H′ = c1 + 2 c2 θ + 3 c3 θ² in (0, 1).
    let (qa, qb, qc) = (3.0 * c3, 2.0 * c2, c1);
    let mut roots = [f64::NAN; 2];
    if qa.abs() > 1e-300 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            roots = [(-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa)];
        }
    } else if qb != 0.0 {
        roots[0] = -qc / qb;
    }
    for t in roots {
        if t > 0.0 && t < 1.0 {
            let v = h_at(t);
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let margin = r5 + 1e-12 * (lo.abs() + hi.abs());
    (lo.is_finite() && hi.is_finite() && margin.is_finite()).then_some((lo - margin, hi + margin))
}

/// True when the drift of story `s` provably stays inside the committed elastic range over
/// the whole step of `dp` ([`drift_bounds`]): a cheap pre-check that skips the kink search,
/// conservative, so it never changes a result.
fn stays_inside(s: &Story, dp: &Dopri5, u_off: usize) -> bool {
    let Some((d_lo, d_hi)) = drift_bounds(dp, u_off + s.floor, s.below.map(|b| u_off + b)) else {
        return false;
    };
    let (lo, hi) = s.spring.elastic_range();
    d_hi < hi && d_lo > lo
}

/// Which kink a stepper located.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KinkKind {
    /// The drift leaves the elastic range: plastic flow starts.
    Yield,
    /// The drift rate of a flowing story changes sign: elastic unloading starts.
    Unload,
}

/// A located kink: θ ∈ (0, 1] of the step, the story (index into [`Stories::stories`]) and
/// its kind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kink {
    pub theta: f64,
    pub story: usize,
    pub kind: KinkKind,
}

/// The committed state of every yielding story of every building (empty for a scene of
/// linear buildings: every method on it is then a no-op).
#[derive(Debug, Clone, Default)]
pub struct Stories {
    /// The yielding stories, building by building, story 1 first.
    pub stories: Vec<Story>,
    /// Per building: index in `stories` of its first story, `None` for a linear building.
    first: Vec<Option<usize>>,
    /// Hysteretic energy of each story at the start of the analysis, J (see
    /// [`Stories::start`]; empty before).
    h0: Vec<f64>,
}

impl Stories {
    /// Virgin springs (no plastic drift, no back force) for the yielding buildings of
    /// `scene`; `offsets[b]` is the global index of building b's first floor.
    pub fn new(scene: &Scene, offsets: &[usize]) -> Stories {
        let mut stories = Vec::new();
        let mut first = Vec::with_capacity(scene.buildings.len());
        for (bi, b) in scene.buildings.iter().enumerate() {
            match b.story_law.bilinear_params(&b.story_stiffness) {
                None => first.push(None),
                Some(params) => {
                    first.push(Some(stories.len()));
                    for (j, p) in params.into_iter().enumerate() {
                        let floor = offsets[bi] + j;
                        stories.push(Story {
                            building: bi,
                            story: j,
                            floor,
                            below: (j > 0).then(|| floor - 1),
                            spring: Bilinear::new(p),
                            flow: Flow::Elastic,
                        });
                    }
                }
            }
        }
        Stories {
            stories,
            first,
            h0: Vec::new(),
        }
    }

    /// Commits the initial state (displacements `u0`, m, velocities `v0`, m/s, global) before
    /// the first step. An initial drift beyond the yield drift puts the virgin spring on its
    /// hardening branch there (the plastic drift it implies is history before t = 0: its
    /// dissipation is not counted in [`Self::hysteretic_energy`], and the initial energy is
    /// the recoverable energy of the committed state). Without it, every trial of the first
    /// step would start from the virgin state, wrong if the drift then moves back.
    pub fn start(&mut self, u0: &[f64], v0: &[f64]) {
        self.commit(u0, v0, None);
        self.h0 = self
            .stories
            .iter()
            .map(|s| s.spring.hysteretic_energy())
            .collect();
    }

    /// Hysteretic energy of story `k` since [`Self::start`], J.
    fn story_hysteretic(&self, k: usize) -> f64 {
        self.stories[k].spring.hysteretic_energy() - self.h0.get(k).copied().unwrap_or(0.0)
    }

    /// True when no building yields (the linear fast path everywhere).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.stories.is_empty()
    }

    /// True when building `b` has yielding stories.
    #[inline]
    pub fn yielding(&self, b: usize) -> bool {
        self.first.get(b).is_some_and(|f| f.is_some())
    }

    /// The stories of building `b` (empty for a linear building).
    pub fn of_building(&self, b: usize) -> &[Story] {
        match self.first.get(b).copied().flatten() {
            Some(f) => {
                let end = self.stories[f..]
                    .iter()
                    .position(|s| s.building != b)
                    .map_or(self.stories.len(), |p| f + p);
                &self.stories[f..end]
            }
            None => &[],
        }
    }

    /// Index in [`Self::stories`] of story `j` (0-based) of building `b`, if it yields.
    #[inline]
    pub fn index(&self, b: usize, j: usize) -> Option<usize> {
        self.first.get(b).copied().flatten().map(|f| f + j)
    }

    /// Shear (N) and consistent tangent (N/m) of story `j` of yielding building `b` at drift
    /// `d` (m), from the committed state (pure).
    #[inline]
    pub fn story_force(&self, b: usize, j: usize, d: f64) -> (f64, f64) {
        let f = self.first[b].expect("story_force on a linear building");
        let spring = &self.stories[f + j].spring;
        // The elastic answer first (the common case, the same arithmetic as
        // `Bilinear::evaluate`), the return mapping only beyond the range.
        let (p, c) = (&spring.params, spring.state());
        let f_trial = p.stiffness * (d - c.plastic_drift);
        if (f_trial - c.back_force).abs() <= p.yield_shear {
            return (f_trial, p.stiffness);
        }
        let t = spring.evaluate(d);
        (t.force, t.tangent)
    }

    /// Story shears (N) of yielding building `b` from its floor displacements `u` (m,
    /// building-local, floor 1 first), from the committed state (pure).
    pub fn shears(&self, b: usize, u: &[f64], out: &mut [f64]) {
        let f = self.first[b].expect("shears on a linear building");
        let mut below = 0.0;
        for (j, o) in out.iter_mut().enumerate().take(u.len()) {
            *o = self.stories[f + j].spring.evaluate(u[j] - below).force;
            below = u[j];
        }
    }

    /// Commits every story at the accepted displacements `u` (m) and velocities `v` (m/s)
    /// (global per-floor vectors), `kink` the kink located at this state, if any, and
    /// updates the flow flags (module docs). Call once per accepted step or event, never for
    /// a trial.
    pub fn commit(&mut self, u: &[f64], v: &[f64], kink: Option<&Kink>) {
        for (k, s) in self.stories.iter_mut().enumerate() {
            let d = s.drift(u);
            let r = s.drift(v);
            s.spring.trial(d);
            s.spring.commit();
            let (lo, hi) = s.spring.elastic_range();
            let eps = s.slack();
            s.flow = match kink.filter(|e| e.story == k).map(|e| e.kind) {
                Some(KinkKind::Yield) => {
                    if d > 0.5 * (lo + hi) {
                        if r > 0.0 {
                            Flow::Up
                        } else {
                            Flow::Elastic
                        }
                    } else if r < 0.0 {
                        Flow::Down
                    } else {
                        Flow::Elastic
                    }
                }
                Some(KinkKind::Unload) => Flow::Elastic,
                None => match s.flow {
                    Flow::Up if r > 0.0 => Flow::Up,
                    Flow::Down if r < 0.0 => Flow::Down,
                    Flow::Up | Flow::Down => Flow::Elastic,
                    Flow::Elastic => {
                        if hi - d <= eps && r > 0.0 {
                            Flow::Up
                        } else if d - lo <= eps && r < 0.0 {
                            Flow::Down
                        } else {
                            Flow::Elastic
                        }
                    }
                },
            };
        }
    }

    /// The earliest kink of any yielding story in θ ∈ (0, `th_max`) of the step whose dense
    /// output `dp` holds (after [`Dopri5::prepare_dense`]); `u_off + i` and `v_off + i` are
    /// the components of floor i's displacement and velocity in the stepper's state.
    /// `calls` counts the interpolant evaluations of the root finder. `None`: the step
    /// (up to `th_max`) crosses no kink. Pure: the committed state is only read.
    pub fn locate_kink(
        &self,
        dp: &Dopri5,
        u_off: usize,
        v_off: usize,
        th_max: f64,
        calls: &mut u64,
    ) -> Option<Kink> {
        let mut best: Option<Kink> = None;
        for (k, s) in self.stories.iter().enumerate() {
            let limit = best.map_or(th_max, |b| b.theta);
            let d_at = |th: f64| {
                dp.dense(u_off + s.floor, th) - s.below.map_or(0.0, |b| dp.dense(u_off + b, th))
            };
            let r_at = |th: f64| {
                dp.dense(v_off + s.floor, th) - s.below.map_or(0.0, |b| dp.dense(v_off + b, th))
            };
            let found = match s.flow {
                Flow::Elastic if stays_inside(s, dp, u_off) => None,
                Flow::Elastic => {
                    let eps = s.slack();
                    let g_at = |th: f64| s.inside(d_at(th));
                    let (mut th_a, mut g_a, mut r_a) = (0.0, g_at(0.0), r_at(0.0));
                    let mut bracket = None;
                    for j in 1..=KINK_SAMPLES {
                        if th_a >= limit {
                            break;
                        }
                        let th_b = j as f64 / KINK_SAMPLES as f64;
                        let (g_b, r_b) = (g_at(th_b), r_at(th_b));
                        if g_b < -eps {
                            bracket = Some((th_a, th_b, g_a));
                        } else if r_a * r_b < 0.0 {
                            let tm = super::adaptive::locate(r_at, th_a, th_b, calls);
                            if g_at(tm) < -eps {
                                bracket = Some((th_a, tm, g_a));
                            }
                        }
                        if bracket.is_some() {
                            break;
                        }
                        (th_a, g_a, r_a) = (th_b, g_b, r_b);
                    }
                    match bracket {
                        // Already on the boundary at the step start and moving out: the
                        // kink is the step start itself (a zero-length cut is no cut); the
                        // law answers the flow exactly and the commit sets the flag.
                        Some((a, _, ga)) if a == 0.0 && ga <= 0.0 => None,
                        Some((a, b, _)) => {
                            Some((super::adaptive::locate(g_at, a, b, calls), KinkKind::Yield))
                        }
                        None => None,
                    }
                }
                Flow::Up | Flow::Down => {
                    let dir = if s.flow == Flow::Up { 1.0 } else { -1.0 };
                    let mut th_a = 0.0;
                    let mut found = None;
                    for j in 1..=KINK_SAMPLES {
                        if th_a >= limit {
                            break;
                        }
                        let th_b = j as f64 / KINK_SAMPLES as f64;
                        if dir * r_at(th_b) <= 0.0 {
                            found = Some((
                                super::adaptive::locate(r_at, th_a, th_b, calls),
                                KinkKind::Unload,
                            ));
                            break;
                        }
                        th_a = th_b;
                    }
                    found
                }
            };
            if let Some((theta, kind)) = found {
                if theta > 0.0 && theta < limit {
                    best = Some(Kink {
                        theta,
                        story: k,
                        kind,
                    });
                }
            }
        }
        best
    }

    /// Recoverable energy of the yielding stories at displacements `u` (m, global): Σ ½ k₀
    /// (d − u_p)² + ½ α²/H with the committed state, J.
    pub fn recoverable_energy(&self, u: &[f64]) -> f64 {
        self.stories
            .iter()
            .map(|s| {
                let e = s.drift(u) - s.spring.state().plastic_drift;
                0.5 * s.spring.params.stiffness * e * e + s.spring.hardening_energy()
            })
            .sum()
    }

    /// Energy dissipated by yielding since the start (plastic work less the hardening energy
    /// still stored), all stories, J.
    pub fn hysteretic_energy(&self) -> f64 {
        if self.stories.is_empty() {
            return 0.0;
        }
        (0..self.stories.len())
            .map(|k| self.story_hysteretic(k))
            .sum()
    }

    /// Hysteretic energy of building `b`, J; `None` for a linear building.
    pub fn building_hysteretic_energy(&self, b: usize) -> Option<f64> {
        let f = self.first.get(b).copied().flatten()?;
        let n = self.of_building(b).len();
        Some((f..f + n).map(|k| self.story_hysteretic(k)).sum())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use structure::model::StoryLaw;
    use structure::testing::free_scene;
    use structure::Building;

    /// One story, k₀ = 1 N/m, yield shear `fy` N (u_y = fy m), b = 0.1, on a unit mass.
    fn one_story(fy: f64) -> Stories {
        let mut b = Building::new("s", vec![1.0], vec![1.0], 0.0);
        b.story_law = StoryLaw::Bilinear {
            yield_shear: vec![fy],
            hardening_ratio: 0.1,
        };
        Stories::new(&free_scene(vec![b], vec![], 1.0), &[0])
    }

    /// The dense output of one step of u'' = −u from (sin t0, cos t0) over [t0, t0 + h]
    /// (its interpolant is within ~1e-4 of sin t for h ≤ 1, less accurate for longer steps).
    fn harmonic_step(t0: f64, h: f64) -> Dopri5 {
        let mut dp = Dopri5::new(2, 2, 1e-12, vec![1e-15; 2]);
        let mut f = |_t: f64, y: &[f64], o: &mut [f64]| {
            o[0] = y[1];
            o[1] = -y[0];
        };
        let y = [t0.sin(), t0.cos()];
        f(t0, &y, &mut dp.k[0]);
        dp.try_step(&mut f, t0, &y, h);
        dp.prepare_dense(t0, &y, h);
        dp
    }

    #[test]
    fn yield_and_unloading_kinks_are_located_on_the_dense_output() {
        let mut st = one_story(0.5);
        let mut calls = 0;
        // Drift sin t leaves the elastic range [−0.5, 0.5] at t = asin(0.5) = π/6: on the
        // interpolant to the root tolerance, on sin t to the interpolant's accuracy.
        let h = 0.8;
        let dp = harmonic_step(0.0, h);
        let k = st.locate_kink(&dp, 0, 1, 1.0, &mut calls).unwrap();
        assert_eq!((k.story, k.kind), (0, KinkKind::Yield));
        assert!((dp.dense(0, k.theta) - 0.5).abs() < 1e-12);
        assert!((k.theta * h - std::f64::consts::FRAC_PI_6).abs() < 1e-3);
        // Not before an earlier event.
        assert!(st.locate_kink(&dp, 0, 1, 0.5, &mut calls).is_none());
        // Commit there: the story flows up.
        let (u, v) = ([dp.dense(0, k.theta)], [dp.dense(1, k.theta)]);
        st.commit(&u, &v, Some(&k));
        assert_eq!(st.stories[0].flow, Flow::Up);
        // Committed further up the flow at t = 1.2; the next step flows until the drift
        // rate cos t vanishes at π/2: unloading.
        st.commit(&[1.2f64.sin()], &[1.2f64.cos()], None);
        assert_eq!(st.stories[0].flow, Flow::Up);
        let dp = harmonic_step(1.2, h);
        let before = st.stories[0].spring.state();
        let k = st.locate_kink(&dp, 0, 1, 1.0, &mut calls).unwrap();
        assert_eq!(k.kind, KinkKind::Unload);
        assert!(dp.dense(1, k.theta).abs() < 1e-12);
        assert!((1.2 + k.theta * h - std::f64::consts::FRAC_PI_2).abs() < 1e-3);
        // The search is pure; the commit at the kink makes the story elastic again, its
        // range ending at the peak drift, 2 F_y/k₀ wide.
        assert_eq!(st.stories[0].spring.state(), before);
        let peak = dp.dense(0, k.theta);
        st.commit(&[peak], &[dp.dense(1, k.theta)], Some(&k));
        assert_eq!(st.stories[0].flow, Flow::Elastic);
        let (lo, hi) = st.stories[0].spring.elastic_range();
        assert!(
            (hi - peak).abs() < 1e-12 && (hi - lo - 1.0).abs() < 1e-12,
            "{lo} {hi}"
        );
        assert!(st.hysteretic_energy() > 0.0);
        // Unloading from there stays elastic for the next step: no kink.
        let dp = harmonic_step(std::f64::consts::FRAC_PI_2, 0.5);
        assert!(st.locate_kink(&dp, 0, 1, 1.0, &mut calls).is_none());
    }

    #[test]
    fn an_excursion_out_of_the_range_and_back_between_samples_is_caught() {
        // u_y = 0.995: the drift sin t over a step of 1.2 whose samples straddle π/2 at
        // ±0.15 (sin = 0.9888) is inside the range at every sample but peaks at 1: the
        // interior extremum is checked and the crossing of 0.995 before it located.
        let st = one_story(0.995);
        let mut calls = 0;
        let h = 1.2;
        let t0 = std::f64::consts::FRAC_PI_2 - 0.15 - 0.3;
        let dp = harmonic_step(t0, h);
        for j in 0..=4 {
            assert!(dp.dense(0, j as f64 / 4.0) < 0.995, "sample {j} inside");
        }
        let k = st.locate_kink(&dp, 0, 1, 1.0, &mut calls).unwrap();
        assert_eq!(k.kind, KinkKind::Yield);
        assert!((dp.dense(0, k.theta) - 0.995).abs() < 1e-12);
        assert!(dp.dense(1, k.theta) > 0.0, "the crossing on the way up");
        assert!((t0 + k.theta * h - 0.995f64.asin()).abs() < 1e-2);
    }
}
