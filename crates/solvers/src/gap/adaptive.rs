//! The adaptive gap-element integrator: Dormand–Prince 5(4) with located contact events.
//!
//! State y = [u (n); v (n); E_input; E_damping; W_contact; impulse_c (one per contact)].
//! The last 3 + n_c components are quadratures integrated with the same stages (they do not
//! enter the error norm), so the energy audit and the impulses are exactly consistent with
//! the integrated motion. Tolerances: rtol = `gap_element.tolerance`, atol = rtol·1e-3 m on
//! displacements and rtol·1e-3 m/s on velocities.
//!
//! Shape: `GapStepper::step` advances by one trial step and reports a `StepOutcome`
//! (rejected, accepted, record point reached, contact closed or opened, story kink); the
//! driver `run_from` owns the loop over the record intervals, the response tracker (peaks,
//! samples, history) and the overlap audit. The contact books (modes, episodes, impacts,
//! impact-rate guard) are the `ledger::ContactLedger` shared with Newmark.
//!
//! Step loop:
//! 1. The step is cut to the next record point (t = i·dt), so the ground acceleration is one
//!    linear piece inside every step, and while a contact is closed to 1/8 of its contact
//!    period 2π/ω_c (ω_c = √(k/m_eff); Hertz: tangent value at the elastic peak).
//! 2. Contact modes (open/closed, approach speed at closure) are frozen during a trial step; a
//!    rejected step changes nothing.
//! 3. After an accepted step each contact's event function g (law.rs) is sampled on the dense
//!    output at θ = ¼, ½, ¾, 1; an interior extremum of δ (δ̇ changing sign between samples,
//!    located by Brent) is checked too, so a closure that opens again inside the step is not
//!    missed; for a closed clamped Kelvin–Voigt contact, the interior minimum of its force
//!    F = kδ + cδ̇ (dF/dt = kδ̇ + cδ̈ changing sign), so an end that the force comes back
//!    from is not missed either (a minimum within F's round-off is not an end), and while
//!    such a contact is open and penetrating, the interior maximum of F. An interior extremum
//!    of δ within δ's round-off (64 ε (|u_l| + |u_r| + gap)) is a graze: no end, no closure.
//!    A contact released
//!    at a root read on its positive side, in a dip of g that ends before θ = ¼, closes at
//!    the dip's far root, not at once. The earliest sign change is located by Brent on the
//!    interpolant; the step is
//!    cut there (state from the dense output), the contact flips, and f is re-evaluated
//!    (FSAL restarts).
//! 4. Peak penetration and peak force of an episode are located on the dense output too
//!    (roots of δ̇ and of dF/dt = F_δ δ̇ + F_δ̇ δ̈).
//! 5. Yielding stories ([`super::stories`]): every stage evaluates the story law from the
//!    state committed at the step start (pure), so a rejected step changes nothing. After
//!    an accepted step the story kinks (a story's drift leaving its elastic range: yield; a
//!    flowing story's drift rate changing sign: unloading) are located on the dense output
//!    before the earliest contact event ([`Stories::locate_kink`]); the step is cut at the
//!    earliest, the stories are committed there and f is re-evaluated (FSAL restarts), so no
//!    step straddles a kink and the method keeps its order. Otherwise the stories are
//!    committed at the end of the accepted part of the step. Peaks of a yielding building:
//!    the interior drift extrema are located (unless the drift's bounds over the step show
//!    that neither drift nor shear can reach its running peak) and the shear there taken
//!    from the law.
//!
//! Cost (issue 10: the paper scene takes one step per record interval, so the time goes
//! into the work per step, about six right-hand sides and the dense output's uses). Every
//! shortcut below gives bit-identical results (the same operations in the same order):
//! - the right-hand side (`Rhs`) works on panels of 4 floors in vector registers (AVX2
//!   where available, through `pulp`; no fused multiply-add), C v column by column;
//! - the dense peaks look first only at the sign of each rate at both ends, and bound the
//!   Hermite extremum before solving for it; the bisections that locate an extremum
//!   (`bisect`) evaluate three levels of midpoints at once;
//! - without a history, the instants before the end update the peaks only.

use crate::closure::Conv;
use structure::Scene;

use super::dopri::{dense_at, Dopri5};
use super::stories::{Kink, Stories};
use super::{audit, output, ContactLedger, Episode, Mode, Segment, System};
use crate::output::EnergyAudit;
use crate::response::ResponseTracker;
use crate::step::StepOutcome;
use crate::{History, Impact, RunOutput, SolverError, Stats};

/// Samples per step for the event search.
const EVENT_SAMPLES: usize = 4;
/// Fraction of the contact period allowed per step while a contact is closed.
const CONTACT_STEP_FRACTION: f64 = 1.0 / 8.0;
/// Root tolerance in θ (fraction of the step).
const THETA_TOL: f64 = 1e-14;

/// Brent on [a, b]; `calls` counts evaluations. Without a sign change returns `a`.
pub(crate) fn locate(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, calls: &mut u64) -> f64 {
    let mut conv = Conv {
        tol: THETA_TOL,
        iterations: 0,
    };
    let g = |x: f64| {
        *calls += 1;
        f(x)
    };
    match roots::find_root_brent(a, b, g, &mut conv) {
        Ok(x) => x.clamp(a, b),
        Err(roots::SearchError::NoBracketing) => a,
        Err(_) => 0.5 * (a + b),
    }
}

/// One building of [`Rhs`], its floors in panels of 4 rows (the last one zero-padded).
#[derive(Debug, Clone)]
struct PanelBlock {
    /// First floor (global index) and number of floors.
    off: usize,
    len: usize,
    /// Per panel: story stiffness k_j and floor mass m_j of its rows (zero past the top).
    k: Vec<[f64; 4]>,
    m: Vec<[f64; 4]>,
    /// The damping matrix in groups of up to [`GROUP`] panels: (panels in the group, data
    /// laid out [column j][panel][row r]) holding `Block::c[j·len + 4p + r]`, the entry the
    /// column sweep of `System::internal` multiplies by v_j for row 4p + r (zero past the
    /// top).
    groups: Vec<(usize, Vec<[f64; 4]>)>,
}

/// Panels of 4 rows whose C v columns are summed together (4 accumulators: 16 rows).
const GROUP: usize = 4;

/// The adaptive integrator's right-hand side, laid out for vector instructions:
///
/// ```text
/// u̇ = v
/// v̇ = M⁻¹ (−f_s(u) − C v − M 1 a_g(t) + Σ_closed F_c (e_right − e_left))
/// Ė_input = −Σ_i m_i a_g v_i,  Ė_damping = vᵀ C v,  Ẇ_contact = Σ_closed F_c δ̇_c
/// İ_c = F_c (closed contacts; 0 when open)
/// ```
///
/// with the contact modes and the committed story state frozen. The same arithmetic as
/// `System::internal` followed by the ground load, the contact forces and M⁻¹, in the same
/// order (bit-identical results): per floor i of a building
/// a_i = (((−s_i) + s_{i+1}) − (C v)_i) − m_i a_g, with the story forces s_j = k_j (u_j −
/// u_{j−1}) (u_{−1} = 0; or the story law's) and s_len = −0 (so the top floor gets −s_top
/// exactly), each (C v)_i summed over the columns j in order from 0 starting from 0; the
/// energy rates summed floor by floor in the same order. The floors of a building are
/// processed in panels of 4 rows held in vector registers (AVX2 where available,
/// [`pulp::Arch`]; no fused multiply-add).
///
/// A panel reads and writes 4 rows even past a building's top floor: the state has at
/// least 2n + 3 components, so the rows read (floor i ≤ n + 2 of u or v) exist, and the
/// rows written past the top land on the next building's first floors (written after) or
/// on the energy rates (written last); they are never used.
#[derive(Debug, Clone)]
pub(crate) struct Rhs {
    arch: pulp::Arch,
    blocks: Vec<PanelBlock>,
    /// Story forces of a yielding building, s_len = −0 (4 rows of padding).
    s: Vec<f64>,
    /// A building's energy-rate products v_i (C v)_i and m_i a_g v_i, per panel.
    pd: Vec<[f64; 4]>,
    pg: Vec<[f64; 4]>,
}

impl Rhs {
    pub(crate) fn new(sys: &System) -> Rhs {
        let mut blocks = Vec::with_capacity(sys.blocks.len());
        let mut panels_max = 0;
        for b in &sys.blocks {
            let (off, len) = (b.off, b.len);
            let panels = len.div_ceil(4);
            panels_max = panels_max.max(panels);
            let quads = |x: &[f64]| -> Vec<[f64; 4]> {
                (0..panels)
                    .map(|p| {
                        std::array::from_fn(|r| {
                            let j = 4 * p + r;
                            if j < len {
                                x[off + j]
                            } else {
                                0.0
                            }
                        })
                    })
                    .collect()
            };
            let mut groups = Vec::new();
            let mut p0 = 0;
            while p0 < panels {
                let g = GROUP.min(panels - p0);
                let mut data = Vec::with_capacity(len * g);
                for j in 0..len {
                    for p in p0..p0 + g {
                        data.push(std::array::from_fn(|r| {
                            let i = 4 * p + r;
                            if i < len {
                                b.c[j * len + i]
                            } else {
                                0.0
                            }
                        }));
                    }
                }
                groups.push((g, data));
                p0 += g;
            }
            blocks.push(PanelBlock {
                off,
                len,
                k: quads(&sys.story_k),
                m: quads(&sys.mass),
                groups,
            });
        }
        Rhs {
            arch: pulp::Arch::new(),
            blocks,
            s: vec![0.0; 4 * panels_max + 4],
            pd: vec![[0.0; 4]; panels_max],
            pg: vec![[0.0; 4]; panels_max],
        }
    }

    /// Evaluates f(t, y) into `o` (module docs of [`Rhs`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn eval(
        &mut self,
        sys: &System,
        stories: &Stories,
        seg: &Segment,
        modes: &[Mode],
        t: f64,
        y: &[f64],
        o: &mut [f64],
    ) {
        struct Op<'r, 'a> {
            rhs: &'r mut Rhs,
            sys: &'a System,
            stories: &'a Stories,
            ag: f64,
            modes: &'a [Mode],
            y: &'a [f64],
            o: &'a mut [f64],
        }
        impl pulp::WithSimd for Op<'_, '_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _: S) {
                self.rhs
                    .eval_body(self.sys, self.stories, self.ag, self.modes, self.y, self.o)
            }
        }
        let arch = self.arch;
        arch.dispatch(Op {
            rhs: self,
            sys,
            stories,
            ag: seg.at(t),
            modes,
            y,
            o,
        });
    }

    #[inline(always)]
    fn eval_body(
        &mut self,
        sys: &System,
        stories: &Stories,
        ag: f64,
        modes: &[Mode],
        y: &[f64],
        o: &mut [f64],
    ) {
        let n = sys.n;
        assert!(y.len() >= 2 * n + 3 && o.len() >= 2 * n + 3);
        // u̇ = v, 4 rows at a time: the rows past n land on the first accelerations, written
        // below.
        let rows = 4 * n.div_ceil(4);
        let (vq, _) = y[n..n + rows].as_chunks::<4>();
        let (oq, _) = o[..rows].as_chunks_mut::<4>();
        for (o, v) in oq.iter_mut().zip(vq) {
            *o = *v;
        }
        let (mut pdamp, mut pin) = (0.0, 0.0);
        for (bi, b) in self.blocks.iter().enumerate() {
            let (off, len) = (b.off, b.len);
            let panels = b.k.len();
            let rows = 4 * panels;
            let (u, _) = y[off..off + rows].as_chunks::<4>();
            let (v, _) = y[n + off..n + off + rows].as_chunks::<4>();
            let (out, _) = o[n + off..n + off + rows].as_chunks_mut::<4>();
            let vcol = &y[n + off..n + off + len];
            // The rows of the last panel: 1 to 4 (its row `top` is the top floor).
            let top = len - 1 - 4 * (panels - 1);
            let yielding = stories.yielding(bi);
            let s = &mut self.s[..rows + 4];
            if yielding {
                let mut below = 0.0;
                for j in 0..len {
                    s[j] = stories.story_force(bi, j, y[off + j] - below).0;
                    below = y[off + j];
                }
                s[len] = -0.0;
            }
            let s: Option<&[f64]> = yielding.then_some(s);
            let mut p0 = 0;
            for (g, data) in &b.groups {
                let io = GroupIo {
                    p0,
                    top: (p0 + g == panels).then_some(top),
                    u,
                    v,
                    vcol,
                    k: &b.k,
                    m: &b.m,
                    s,
                    ag,
                };
                let (out, pd, pg) = (&mut out[..], &mut self.pd[..], &mut self.pg[..]);
                match g {
                    4 => group::<4>(data, &io, out, pd, pg),
                    3 => group::<3>(data, &io, out, pd, pg),
                    2 => group::<2>(data, &io, out, pd, pg),
                    _ => group::<1>(data, &io, out, pd, pg),
                }
                p0 += g;
            }
            // The energy rates floor by floor (the scalar order of `System::internal`).
            let (pd, _) = self.pd.as_flattened().split_at(len);
            let (pg, _) = self.pg.as_flattened().split_at(len);
            for (&d, &g) in pd.iter().zip(pg) {
                pdamp += d;
                pin -= g;
            }
        }
        let (acc, extra) = o[n..].split_at_mut(n);
        let (u, v) = (&y[..n], &y[n..2 * n]);
        let mut pc = 0.0;
        for (ci, c) in sys.contacts.iter().enumerate() {
            let m = modes[ci];
            if m.closed {
                let d = c.rel(u) - c.gap;
                let dd = c.rel(v);
                let f = c.law.force(d, dd, m.v_close);
                c.push_apart(acc, f);
                pc += f * dd;
                extra[3 + ci] = f;
            } else {
                extra[3 + ci] = 0.0;
            }
        }
        let inv_mass = &sys.inv_mass[..n];
        for i in 0..n {
            acc[i] *= inv_mass[i];
        }
        extra[0] = pin;
        extra[1] = pdamp;
        extra[2] = pc;
    }
}

/// The accelerations before M⁻¹ of one panel into `out`, from its C v `c`, its story forces
/// `s0` and those of the rows above `s1` (−0 above the top floor), its floor masses `m` and
/// velocities `v`; and its floors' energy rates v_i (C v)_i into `pd` and m_i a_g v_i into
/// `pg`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn panel(
    c: [f64; 4],
    s0: [f64; 4],
    s1: [f64; 4],
    m: [f64; 4],
    v: [f64; 4],
    ag: f64,
    out: &mut [f64; 4],
    pd: &mut [f64; 4],
    pg: &mut [f64; 4],
) {
    let f: [f64; 4] = std::array::from_fn(|r| m[r] * ag);
    *out = std::array::from_fn(|r| ((-s0[r] + s1[r]) - c[r]) - f[r]);
    *pd = std::array::from_fn(|r| v[r] * c[r]);
    *pg = std::array::from_fn(|r| f[r] * v[r]);
}

/// Story forces k_r (u_r − u_{r−1}) of a panel's rows from their displacements `u`, stiffness
/// `k` and the displacement `below` of the floor under the panel's first row.
#[inline(always)]
fn story_forces(u: [f64; 4], k: [f64; 4], below: f64) -> [f64; 4] {
    let up = [below, u[0], u[1], u[2]];
    std::array::from_fn(|r| k[r] * (u[r] - up[r]))
}

/// The inputs of one group of panels of a building ([`group`]).
struct GroupIo<'a> {
    /// The group's first panel.
    p0: usize,
    /// The row of the building's top floor in the group's last panel, if it holds it.
    top: Option<usize>,
    /// The building's displacements and velocities by panel (rows past the top are read,
    /// never used) and its floors' velocities.
    u: &'a [[f64; 4]],
    v: &'a [[f64; 4]],
    vcol: &'a [f64],
    /// Story stiffness and floor masses by panel.
    k: &'a [[f64; 4]],
    m: &'a [[f64; 4]],
    /// The story forces of a yielding building (s_len = −0, 4 rows of padding); `None` for
    /// a linear one.
    s: Option<&'a [f64]>,
    ag: f64,
}

/// One group of `G` panels ([`PanelBlock::groups`]): C v, the story forces and [`panel`],
/// on arrays of fixed size (unrolled, no bounds checks inside).
#[inline(always)]
fn group<const G: usize>(
    data: &[[f64; 4]],
    io: &GroupIo,
    out: &mut [[f64; 4]],
    pd: &mut [[f64; 4]],
    pg: &mut [[f64; 4]],
) {
    let (p0, panels) = (io.p0, io.u.len());
    let c = cv_panels::<G>(data, io.vcol);
    let r = p0..p0 + G;
    let u: &[[f64; 4]; G] = io.u[r.clone()].try_into().unwrap();
    let v: &[[f64; 4]; G] = io.v[r.clone()].try_into().unwrap();
    let m: &[[f64; 4]; G] = io.m[r.clone()].try_into().unwrap();
    let out: &mut [[f64; 4]; G] = (&mut out[r.clone()]).try_into().unwrap();
    let pd: &mut [[f64; 4]; G] = (&mut pd[r.clone()]).try_into().unwrap();
    let pg: &mut [[f64; 4]; G] = (&mut pg[r.clone()]).try_into().unwrap();
    // Story forces of the group's rows (s0) and of the rows above (s1).
    let (s0, mut s1): ([[f64; 4]; G], [[f64; 4]; G]) = match io.s {
        Some(s) => (
            std::array::from_fn(|q| quad(s, 4 * (p0 + q))),
            std::array::from_fn(|q| quad(s, 4 * (p0 + q) + 1)),
        ),
        None => {
            let k: &[[f64; 4]; G] = io.k[r].try_into().unwrap();
            let below = if p0 == 0 { 0.0 } else { io.u[p0 - 1][3] };
            let s0: [[f64; 4]; G] = std::array::from_fn(|q| {
                let under = if q == 0 { below } else { u[q - 1][3] };
                story_forces(u[q], k[q], under)
            });
            // The story above the group: the next panel's first (the roof: −0).
            let above = if p0 + G < panels {
                let (un, kn) = (io.u[p0 + G][0], io.k[p0 + G][0]);
                kn * (un - u[G - 1][3])
            } else {
                -0.0
            };
            let s1 = std::array::from_fn(|q| {
                let next = if q + 1 < G { s0[q + 1][0] } else { above };
                [s0[q][1], s0[q][2], s0[q][3], next]
            });
            (s0, s1)
        }
    };
    if let Some(top) = io.top {
        // A select rather than a store at a variable row (which would go through memory).
        s1[G - 1] = std::array::from_fn(|r| if r == top { -0.0 } else { s1[G - 1][r] });
    }
    for q in 0..G {
        panel(
            c[q],
            s0[q],
            s1[q],
            m[q],
            v[q],
            io.ag,
            &mut out[q],
            &mut pd[q],
            &mut pg[q],
        );
    }
}

/// Four consecutive entries of `x` from `i`.
#[inline(always)]
fn quad(x: &[f64], i: usize) -> [f64; 4] {
    x[i..i + 4].try_into().unwrap()
}

/// (C v) of the `G` panels of one group ([`PanelBlock::groups`]) from the velocities `v` of
/// the building's floors: each row's sum over the columns in order from 0, starting from 0
/// (the sums of `System::internal`).
#[inline(always)]
fn cv_panels<const G: usize>(data: &[[f64; 4]], v: &[f64]) -> [[f64; 4]; G] {
    let mut acc = [[0.0f64; 4]; G];
    let (data, _) = data.as_chunks::<G>();
    let data = &data[..v.len()];
    let column = |acc: &mut [[f64; 4]; G], c: &[[f64; 4]; G], vj: f64| {
        for g in 0..G {
            for r in 0..4 {
                acc[g][r] += c[g][r] * vj;
            }
        }
    };
    // Two columns per iteration (less loop overhead), the same sums in the same order.
    let (pairs, last) = data.as_chunks::<2>();
    let (vpairs, vlast) = v.as_chunks::<2>();
    for (c, vj) in pairs.iter().zip(vpairs) {
        column(&mut acc, &c[0], vj[0]);
        column(&mut acc, &c[1], vj[1]);
    }
    if let (Some(c), Some(&vj)) = (last.first(), vlast.first()) {
        column(&mut acc, c, vj);
    }
    acc
}

/// Observes the state `y` for peaks and, when a history is kept, for its next sample (with
/// the contact forces of the closed contacts).
fn observe(
    sys: &System,
    stories: &Stories,
    tracker: &mut ResponseTracker,
    modes: &[Mode],
    y: &[f64],
    history: bool,
) {
    let n = sys.n;
    if !history {
        sys.observe(stories, tracker, &y[..n]);
        return;
    }
    let (u, v) = (&y[..n], &y[n..2 * n]);
    let forces: Vec<f64> = sys
        .contacts
        .iter()
        .zip(modes)
        .map(|(c, m)| {
            if m.closed {
                c.law.force(c.rel(u) - c.gap, c.rel(v), m.v_close)
            } else {
                0.0
            }
        })
        .collect();
    sys.observe_sample(stories, tracker, u, v, &forces);
}

/// δ, δ̇, δ̈ of contact `c` on the dense output.
#[inline]
/// (δ, δ̇) of a contact from the dense output at θ; `r = None` for a wall (u_r ≡ 0).
pub(crate) fn kin(
    dp: &Dopri5,
    n: usize,
    l: usize,
    r: Option<usize>,
    gap: f64,
    th: f64,
) -> (f64, f64) {
    match r {
        Some(r) => (
            dp.dense(l, th) - dp.dense(r, th) - gap,
            dp.dense(n + l, th) - dp.dense(n + r, th),
        ),
        None => (dp.dense(l, th) - gap, dp.dense(n + l, th)),
    }
}

/// [`kin`] at the event samples θ = j/[`EVENT_SAMPLES`], j = 0 … [`EVENT_SAMPLES`] (the same
/// values), all at once: the dense output's coefficients read once, the samples
/// independent of each other.
fn kin_samples(
    dp: &Dopri5,
    n: usize,
    l: usize,
    r: Option<usize>,
    gap: f64,
) -> [(f64, f64); EVENT_SAMPLES + 1] {
    let th: [f64; EVENT_SAMPLES + 1] = std::array::from_fn(|j| j as f64 / EVENT_SAMPLES as f64);
    let (cl, cvl) = (dp.coefficients(l), dp.coefficients(n + l));
    match r {
        Some(r) => {
            let (cr, cvr) = (dp.coefficients(r), dp.coefficients(n + r));
            std::array::from_fn(|j| {
                (
                    dense_at(&cl, th[j]) - dense_at(&cr, th[j]) - gap,
                    dense_at(&cvl, th[j]) - dense_at(&cvr, th[j]),
                )
            })
        }
        None => std::array::from_fn(|j| (dense_at(&cl, th[j]) - gap, dense_at(&cvl, th[j]))),
    }
}

pub(crate) fn run(
    scene: &Scene,
    sys: &System,
    history: Option<&mut History>,
) -> Result<RunOutput, SolverError> {
    run_from(scene, sys, history, None)
}

/// The accepted part of a step, shown to the driver before the state moves on (continuous
/// peaks, overlap audit).
pub(crate) struct DenseStep<'a> {
    /// The step's dense output.
    pub dp: &'a Dopri5,
    /// Story state committed at the step start.
    pub stories: &'a Stories,
    /// Start of the step, s.
    pub t: f64,
    /// State at the step start.
    pub y0: &'a [f64],
    /// State at θ = `th_end`.
    pub y1: &'a [f64],
    /// Fraction of the step taken, (0, 1].
    pub th_end: f64,
}

/// The adaptive gap-element integrator between two calls of [`GapStepper::step`]: the
/// Dormand–Prince state (y, t, next step h, FSAL stage), the record piece of the ground
/// motion, the contact ledger with the step caps of the closed contacts, the committed
/// story state and the statistics. It knows nothing of peaks, histories or record points
/// other than the one it is told to stop at.
pub(crate) struct GapStepper<'a> {
    sys: &'a System,
    rhs: Rhs,
    dp: Dopri5,
    y: Vec<f64>,
    t: f64,
    h: f64,
    seg: Segment,
    ledger: ContactLedger,
    stories: Stories,
    /// Step cap of each closed contact (1/8 of its contact period), s; ∞ when open.
    caps: Vec<f64>,
    stats: Stats,
    rejected_before: bool,
    total_steps: u64,
    /// Stops a run whose steps no longer advance time ([`crate::step::Progress`]).
    progress: crate::step::Progress,
    max_steps: u64,
    scratch: Vec<f64>,
    y_end: Vec<f64>,
    /// Initial energy (mechanical + stored in closed contacts), J.
    initial: f64,
    /// Energy stored in the contacts closed at t = 0, J.
    stored0: f64,
}

/// Contact `ci` closing at `t` in the state `y`: its approach speed δ̇⁻ and episode (for the
/// ledger); sets its step cap.
fn closing(sys: &System, ci: usize, t: f64, y: &[f64], caps: &mut [f64]) -> (f64, Episode) {
    let n = sys.n;
    let c = &sys.contacts[ci];
    let d = c.rel(&y[..n]) - c.gap;
    let dd = c.rel(&y[n..2 * n]);
    caps[ci] = CONTACT_STEP_FRACTION * 2.0 * std::f64::consts::PI / c.law.contact_omega(dd);
    let episode = Episode {
        t_close: t,
        v_before: dd,
        impulse0: y[2 * n + 3 + ci],
        peak_force: c.law.force(d, dd, dd).max(0.0),
        max_pen: d.max(0.0),
    };
    (dd, episode)
}

impl<'a> GapStepper<'a> {
    /// The initial state of `sys` (contacts already closed at t = 0 open their episodes),
    /// the first stage and the first trial step: `first_step` (s) when given, otherwise
    /// Hairer's starting step, at most up to the first record point `t_bp` (s).
    fn new(scene: &Scene, sys: &'a System, first_step: Option<f64>, t_bp: f64) -> Self {
        let n = sys.n;
        let nc = sys.contacts.len();
        let dim = 2 * n + 3 + nc;
        let tol = scene.gap_element.tolerance;
        let mut dp = Dopri5::new(dim, 2 * n, tol, vec![tol * 1e-3; 2 * n]);
        let limits = &scene.limits;

        let mut y = vec![0.0; dim];
        y[..n].copy_from_slice(&sys.u0);
        y[n..2 * n].copy_from_slice(&sys.v0);
        let mut ledger = ContactLedger::new(nc, limits.max_impact_rate);
        let mut stories = sys.stories();
        let mut caps = vec![f64::INFINITY; nc];
        let mut stats = Stats {
            min_step: f64::INFINITY,
            ..Stats::default()
        };
        for (ci, c) in sys.contacts.iter().enumerate() {
            let d = c.rel(&y[..n]) - c.gap;
            let dd = c.rel(&y[n..2 * n]);
            if c.law.event(d, dd) > 0.0 {
                let (dd, episode) = closing(sys, ci, 0.0, &y, &mut caps);
                ledger.close(ci, dd, episode);
                stats.impacts += 1;
            }
        }
        let stored0 = sys.stored(&y, |i| ledger.closed(i));
        stories.start(&y[..n], &y[n..2 * n]);
        let initial = sys.mech_energy(&stories, &y[..n], &y[n..2 * n]) + stored0;

        let seg = sys.segment(0);
        let t = 0.0f64;
        let mut rhs = Rhs::new(sys);
        rhs.eval(sys, &stories, &seg, ledger.modes(), t, &y, &mut dp.k[0]);
        stats.rhs_evaluations += 1;
        let h = {
            let modes = ledger.modes();
            let mut f = |tt: f64, yy: &[f64], o: &mut [f64]| {
                rhs.eval(sys, &stories, &seg, modes, tt, yy, o)
            };
            let cap0 = caps.iter().cloned().fold(f64::INFINITY, f64::min);
            match first_step {
                Some(h0) => h0,
                None => dp.initial_step(&mut f, t, &y.clone(), (t_bp - t).min(cap0)),
            }
        };
        stats.rhs_evaluations += 1;
        GapStepper {
            sys,
            rhs,
            dp,
            y,
            t,
            h,
            seg,
            ledger,
            stories,
            caps,
            stats,
            rejected_before: false,
            total_steps: 0,
            progress: crate::step::Progress::default(),
            max_steps: limits.max_steps,
            scratch: vec![0.0; dim],
            y_end: vec![0.0; dim],
            initial,
            stored0,
        }
    }

    /// Time, s.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Floor displacements, m.
    pub fn u(&self) -> &[f64] {
        &self.y[..self.sys.n]
    }

    /// Observes the current state for the peaks only: an instant that is neither a history
    /// sample nor the end of the analysis (whose displacements give the residual drift).
    fn observe_peaks(&self, tracker: &mut ResponseTracker) {
        self.sys
            .observe_all_peaks(&self.stories, tracker, &self.y[..self.sys.n]);
    }

    /// Observes the current state for peaks and, when a history is kept, for its next
    /// sample.
    fn observe(&self, tracker: &mut ResponseTracker, history: bool) {
        observe(
            self.sys,
            &self.stories,
            tracker,
            self.ledger.modes(),
            &self.y,
            history,
        );
    }

    /// One trial step of at most the next step size, cut to the closed contacts' caps and
    /// landing on the record point `t_bp` (s) when within 1 %. When accepted, the contact
    /// events and story kinks are located and the step is cut at the earliest one;
    /// `on_dense` sees the part taken before the state moves on; the contact or the stories
    /// change state there and the FSAL stage restarts. Errors: step budget, step-size
    /// underflow or a non-finite trial state, the impact-rate guard.
    fn step(
        &mut self,
        t_bp: f64,
        on_dense: &mut dyn FnMut(&DenseStep),
    ) -> Result<StepOutcome, SolverError> {
        let sys = self.sys;
        let n = sys.n;
        let nc = sys.contacts.len();
        let imp0 = 2 * n + 3;
        let GapStepper {
            rhs,
            dp,
            y,
            ledger,
            stories,
            caps,
            stats,
            seg,
            scratch,
            y_end,
            ..
        } = self;
        let mut t = self.t;
        let cap = caps
            .iter()
            .zip(ledger.modes())
            .filter(|(_, m)| m.closed)
            .map(|(c, _)| *c)
            .fold(f64::INFINITY, f64::min);
        let mut hs = self.h.min(cap);
        let mut land = false;
        if t + 1.01 * hs >= t_bp {
            hs = t_bp - t;
            land = true;
        }
        self.total_steps += 1;
        if self.total_steps > self.max_steps {
            let closed: Vec<usize> = (0..nc).filter(|&i| ledger.closed(i)).collect();
            return Err(SolverError::StepBudget {
                time: t,
                steps: self.total_steps - 1,
                limit: self.max_steps,
                context: format!("next step {hs:.3e} s, closed contacts: {closed:?}"),
            });
        }
        self.progress.check(t, self.total_steps)?;
        let err = {
            let modes = ledger.modes();
            let stories: &Stories = stories;
            let seg: &Segment = seg;
            let mut f =
                |tt: f64, yy: &[f64], o: &mut [f64]| rhs.eval(sys, stories, seg, modes, tt, yy, o);
            dp.try_step(&mut f, t, y, hs)
        };
        stats.rhs_evaluations += 6;
        let (ok, hnew) = dp.control(err, hs, self.rejected_before);
        if !ok {
            stats.rejected_steps += 1;
            self.rejected_before = true;
            self.h = hnew;
            let h = hnew;
            let hmin = 1e-14 * (1.0 + t);
            if h < hmin {
                let closed: Vec<usize> = (0..nc).filter(|&i| ledger.closed(i)).collect();
                if err.is_nan() {
                    return Err(SolverError::NonFinite {
                        time: t,
                        context: format!("the trial step of {hs:.3e} s produced a non-finite state (closed contacts: {closed:?})"),
                    });
                }
                return Err(SolverError::StepSizeUnderflow {
                    time: t,
                    step: h,
                    min_step: hmin,
                    context: format!(
                        "error norm {err:.3e} after {} rejections; closed contacts: {closed:?}",
                        stats.rejected_steps
                    ),
                });
            }
            return Ok(StepOutcome::Rejected);
        }
        self.rejected_before = false;
        dp.prepare_dense(t, y, hs);
        let dp: &Dopri5 = dp;

        // --- event search -------------------------------------------------------------
        let event = earliest_event(sys, ledger, dp, &mut stats.root_iterations);

        // --- kinks of yielding stories before the earliest contact event ------------------
        let kink: Option<Kink> = if stories.is_empty() {
            None
        } else {
            stories.locate_kink(
                dp,
                0,
                n,
                event.map_or(1.0, |(th, _)| th),
                &mut stats.root_iterations,
            )
        };
        let th_cut = kink.map(|k| k.theta).or(event.map(|(th, _)| th));

        // --- peaks of closed contacts over the part of the step actually taken -----------
        episode_peaks(
            sys,
            ledger,
            dp,
            th_cut.unwrap_or(1.0),
            &mut stats.root_iterations,
        );

        let t_old = t;
        // The accepted part of the step, shown to the driver before the state moves on
        // (the step's start state is still in `y`).
        let th_end = th_cut.map_or(1.0, |th| th.min(1.0));
        let y1: &[f64] = if th_end < 1.0 {
            dp.dense_all(th_end, y_end);
            y_end
        } else {
            &dp.y1
        };
        on_dense(&DenseStep {
            dp,
            stories,
            t,
            y0: y,
            y1,
            th_end,
        });
        let outcome;
        if let Some(k) = kink {
            // A story kink before any contact event: cut the step there and commit.
            dp.dense_all(k.theta, scratch);
            y.copy_from_slice(scratch);
            t += k.theta * hs;
            stories.commit(&y[..n], &y[n..2 * n], Some(&k));
            stats.story_kinks += 1;
            rhs.eval(sys, stories, seg, ledger.modes(), t, y, &mut self.dp.k[0]);
            stats.rhs_evaluations += 1;
            outcome = StepOutcome::StoryKink {
                breakpoint: land && t == t_bp,
            };
        } else {
            match event {
                Some((th, ci)) => {
                    dp.dense_all(th, scratch);
                    y.copy_from_slice(scratch);
                    t = if th >= 1.0 { t + hs } else { t + th * hs };
                    if land && th >= 1.0 {
                        t = t_bp;
                    }
                    let breakpoint = land && t == t_bp;
                    let c = &sys.contacts[ci];
                    if ledger.closed(ci) {
                        let dd = c.rel(&y[n..2 * n]);
                        ledger.open(ci, t, dd, y[imp0 + ci]);
                        caps[ci] = f64::INFINITY;
                        outcome = StepOutcome::ContactOpened {
                            contact: ci,
                            breakpoint,
                        };
                    } else {
                        let (dd, episode) = closing(sys, ci, t, y, caps);
                        stats.impacts += 1;
                        ledger.close_at(ci, t, dd, episode)?;
                        outcome = StepOutcome::ContactClosed {
                            contact: ci,
                            breakpoint,
                        };
                    }
                    stats.events += 1;
                    stories.commit(&y[..n], &y[n..2 * n], None);
                    rhs.eval(sys, stories, seg, ledger.modes(), t, y, &mut self.dp.k[0]);
                    stats.rhs_evaluations += 1;
                }
                None => {
                    self.dp.accept_swap(y);
                    t = if land { t_bp } else { t + hs };
                    stories.commit(&y[..n], &y[n..2 * n], None);
                    outcome = if land && t == t_bp {
                        StepOutcome::Breakpoint
                    } else {
                        StepOutcome::Accepted
                    };
                }
            }
        }
        let taken = t - t_old;
        if taken > 0.0 {
            stats.min_step = stats.min_step.min(taken);
        }
        stats.max_step = stats.max_step.max(taken);
        stats.steps += 1;
        self.h = hnew;
        self.t = t;
        Ok(outcome)
    }

    /// Enters the record interval whose ground-motion piece is `next`, at the record point
    /// reached. The excitation is continuous at a record point except where the record ends
    /// (a jump to zero): only then does FSAL restart with the new piece.
    fn enter_segment(&mut self, next: Segment) {
        let t = self.t;
        let (a_new, a_old) = (next.at(t), self.seg.at(t));
        let jump = (a_new - a_old).abs() > 1e-9 * (a_new.abs() + a_old.abs());
        self.seg = next;
        if jump {
            self.rhs.eval(
                self.sys,
                &self.stories,
                &self.seg,
                self.ledger.modes(),
                t,
                &self.y,
                &mut self.dp.k[0],
            );
            self.stats.rhs_evaluations += 1;
        }
    }

    /// Ends the run: the impacts (episodes still open reported up to the end), the energy
    /// audit, the statistics and the story state.
    fn finish(self) -> (Vec<Impact>, EnergyAudit, Stats, Stories) {
        let sys = self.sys;
        let n = sys.n;
        let (e_in, e_damp, e_work, imp0) = (2 * n, 2 * n + 1, 2 * n + 2, 2 * n + 3);
        let y = &self.y;
        let mut stats = self.stats;
        if stats.min_step == f64::INFINITY {
            stats.min_step = 0.0;
        }
        let stored_t = sys.stored(y, |i| self.ledger.closed(i));
        let energy = audit(
            self.initial,
            y[e_in],
            y[e_damp],
            y[e_work],
            self.stored0,
            sys.mech_energy(&self.stories, &y[..n], &y[n..2 * n]),
            stored_t,
            self.stories.hysteretic_energy(),
        );
        // Episodes still open at the end are reported up to the end of the analysis.
        let impacts = self.ledger.finish(self.t, |ci| {
            (sys.contacts[ci].rel(&y[n..2 * n]), y[imp0 + ci])
        });
        (impacts, energy, stats, self.stories)
    }
}

/// The earliest contact event of the accepted step on its dense output: (θ, contact). Each
/// contact's event function g is sampled at θ = ¼, ½, ¾, 1 (with the interior extremum of δ
/// checked between samples, so a closure that opens again inside the step is not missed,
/// and for a clamped Kelvin–Voigt contact the interior extremum of its force: a minimum
/// while closed, a maximum while open and penetrating) and the first sign change located by
/// Brent. An interior extremum within the round-off of its function (of F, or of δ) is a
/// graze, not an event. `calls` counts the root-finder evaluations.
fn earliest_event(
    sys: &System,
    ledger: &ContactLedger,
    dp: &Dopri5,
    calls: &mut u64,
) -> Option<(f64, usize)> {
    let n = sys.n;
    let mut event: Option<(f64, usize)> = None;
    for (ci, c) in sys.contacts.iter().enumerate() {
        let closed = ledger.closed(ci);
        let law = &c.law;
        let (l, r, gap) = (c.l, (!c.wall).then_some(c.r), c.gap);
        let g_at = |th: f64| {
            let (d, dd) = kin(dp, n, l, r, gap, th);
            law.event(d, dd)
        };
        // A closed clamped Kelvin–Voigt contact: its force rate is read at every sample (an
        // open one's only where it penetrates at a sample).
        let ends_on_force = closed && law.force_event();
        // dF/dt = kδ̇ + cδ̈ (δ̈ from the dense output's derivative).
        let force_rate = |th: f64| {
            let (_, dd) = kin(dp, n, l, r, gap, th);
            let ddd = dp.dense_rate(n + l, th) - r.map_or(0.0, |r| dp.dense_rate(n + r, th));
            law.k * dd + law.c * ddd
        };
        // The round-off of F = kδ + cδ̇ computed from the floors' states (δ = u_l − u_r −
        // gap): 64 ε of its terms. A dip of F no deeper than this is a grazing minimum at
        // F ≈ 0, not an end (read as one, it ends and re-closes the contact in steps of
        // 1e-14 s: measured on the stiffness study, k = 3.16e12 N/m).
        let force_noise = |th: f64| {
            let (ul, vl) = (dp.dense(l, th).abs(), dp.dense(n + l, th).abs());
            let (ur, vr) = r.map_or((0.0, 0.0), |r| {
                (dp.dense(r, th).abs(), dp.dense(n + r, th).abs())
            });
            64.0 * f64::EPSILON * (law.k * (ul + ur + gap) + law.c * (vl + vr))
        };
        // The round-off of δ = u_l − u_r − gap, in the same measure: an interior extremum of
        // δ no further from 0 than this is a graze, neither an end nor a closure.
        let delta_noise = |th: f64| {
            let ur = r.map_or(0.0, |r| dp.dense(r, th).abs());
            64.0 * f64::EPSILON * (dp.dense(l, th).abs() + ur + gap)
        };
        // The round-off of g itself (F's for the clamped law, δ's otherwise).
        let g_noise = |th: f64| {
            if law.force_event() {
                force_noise(th)
            } else {
                delta_noise(th)
            }
        };
        let samples = kin_samples(dp, n, l, r, gap);
        let (mut d_a, mut dd_a) = samples[0];
        // dF/dt at θ_a where it was read (at every sample while closed), NaN elsewhere.
        let mut fr_a = if ends_on_force {
            force_rate(0.0)
        } else {
            f64::NAN
        };
        let mut th_a = 0.0;
        let mut bracket: Option<(f64, f64)> = None;
        for (j, &(d_b, dd_b)) in samples.iter().enumerate().skip(1) {
            let th_b = j as f64 / EVENT_SAMPLES as f64;
            if let Some((te, _)) = event {
                if th_a >= te {
                    break;
                }
            }
            let g_b = law.event(d_b, dd_b);
            let mut fr_b = f64::NAN;
            if !closed {
                if g_b > 0.0 {
                    bracket = Some((th_a, th_b));
                    if th_a == 0.0 && g_at(0.0) >= 0.0 {
                        // Released at the root of g (F for the clamped law, δ otherwise),
                        // read on its positive side, inside a dip that ends before the first
                        // sample: the closure is the dip's far root, after its minimum
                        // (without a minimum below 0 the contact closes again at once).
                        let rate = |th: f64| {
                            if law.force_event() {
                                force_rate(th)
                            } else {
                                kin(dp, n, l, r, gap, th).1
                            }
                        };
                        if rate(0.0) < 0.0 && rate(th_b) > 0.0 {
                            let tm = locate(rate, 0.0, th_b, calls);
                            if g_at(tm) < -g_noise(tm) {
                                bracket = Some((tm, th_b));
                            }
                        }
                    }
                } else if dd_a > 0.0 && dd_b < 0.0 {
                    let tm = locate(|th| kin(dp, n, l, r, gap, th).1, th_a, th_b, calls);
                    let (d, dd) = kin(dp, n, l, r, gap, tm);
                    if law.event(d, dd) > 0.0 && d > delta_noise(tm) {
                        bracket = Some((th_a, tm));
                    }
                }
                if bracket.is_none() && law.force_event() && (d_a > 0.0 || d_b > 0.0) {
                    // Released while still penetrating (the clamped law ends at F = 0, δ >
                    // 0): F rising at one sample and falling at the next has a maximum
                    // between them, a closure (F > 0 there, beyond its round-off, δ > 0)
                    // that ends again before the next sample.
                    let fa = if fr_a.is_nan() {
                        force_rate(th_a)
                    } else {
                        fr_a
                    };
                    fr_b = force_rate(th_b);
                    let fb = fr_b;
                    if fa > 0.0 && fb < 0.0 {
                        let tm = locate(force_rate, th_a, th_b, calls);
                        let (d, dd) = kin(dp, n, l, r, gap, tm);
                        if d > 0.0 && law.k * d + law.c * dd > force_noise(tm) {
                            bracket = Some((th_a, tm));
                        }
                    }
                }
            } else if g_b < 0.0 {
                bracket = Some((th_a, th_b));
            } else if ends_on_force {
                // F = kδ + cδ̇ falling at one sample and rising at the next has a minimum
                // between them: an end (F < 0 there) that the force came back from.
                fr_b = force_rate(th_b);
                if fr_a < 0.0 && fr_b > 0.0 {
                    let tm = locate(force_rate, th_a, th_b, calls);
                    let (d, dd) = kin(dp, n, l, r, gap, tm);
                    if d < 0.0 || law.k * d + law.c * dd < -force_noise(tm) {
                        bracket = Some((th_a, tm));
                    }
                }
            } else if dd_a < 0.0 && dd_b > 0.0 {
                let tm = locate(|th| kin(dp, n, l, r, gap, th).1, th_a, th_b, calls);
                if g_at(tm) < -delta_noise(tm) {
                    bracket = Some((th_a, tm));
                }
            }
            if bracket.is_some() {
                break;
            }
            th_a = th_b;
            d_a = d_b;
            dd_a = dd_b;
            fr_a = fr_b;
        }
        if let Some((a, b)) = bracket {
            let th = locate(g_at, a, b, calls);
            if event.is_none_or(|(te, _)| th < te) {
                event = Some((th, ci));
            }
        }
    }

    event
}

/// Raises the peaks (penetration δ, force) of the closed contacts' episodes over θ ∈ [0,
/// `th_end`] of the accepted step: at the samples and at the located roots of δ̇ and of
/// dF/dt = F_δ δ̇ + F_δ̇ δ̈ on the dense output.
fn episode_peaks(
    sys: &System,
    ledger: &mut ContactLedger,
    dp: &Dopri5,
    th_end: f64,
    calls: &mut u64,
) {
    let n = sys.n;
    for (ci, c) in sys.contacts.iter().enumerate() {
        if !ledger.closed(ci) {
            continue;
        }
        let (l, r, gap, law, vc) = (
            c.l,
            (!c.wall).then_some(c.r),
            c.gap,
            &c.law,
            ledger.v_close(ci),
        );
        let ep = ledger.episode_mut(ci);
        let force_rate = |th: f64| {
            let (d, dd) = kin(dp, n, l, r, gap, th);
            let ddd = dp.dense_rate(n + l, th) - r.map_or(0.0, |r| dp.dense_rate(n + r, th));
            let (kd, kv) = law.tangent(d, dd, vc);
            kd * dd + kv * ddd
        };
        let mut th_a = 0.0;
        let (_, mut dd_a) = kin(dp, n, l, r, gap, 0.0);
        let mut fr_a = force_rate(0.0);
        for j in 1..=EVENT_SAMPLES {
            let th_b = th_end * j as f64 / EVENT_SAMPLES as f64;
            let (d_b, dd_b) = kin(dp, n, l, r, gap, th_b);
            ep.max_pen = ep.max_pen.max(d_b);
            ep.peak_force = ep.peak_force.max(law.force(d_b, dd_b, vc));
            if dd_a > 0.0 && dd_b <= 0.0 {
                let tm = locate(|th| kin(dp, n, l, r, gap, th).1, th_a, th_b, calls);
                let (d, dd) = kin(dp, n, l, r, gap, tm);
                ep.max_pen = ep.max_pen.max(d);
                ep.peak_force = ep.peak_force.max(law.force(d, dd, vc));
            }
            let fr_b = force_rate(th_b);
            if law.kind != structure::scene::ContactLaw::Linear && fr_a > 0.0 && fr_b <= 0.0 {
                let tm = locate(force_rate, th_a, th_b, calls);
                let (d, dd) = kin(dp, n, l, r, gap, tm);
                ep.peak_force = ep.peak_force.max(law.force(d, dd, vc));
            }
            th_a = th_b;
            dd_a = dd_b;
            fr_a = fr_b;
        }
    }
}

/// [`run`] with the first trial step `first_step` (s) instead of Hairer's starting step when
/// given (for tests of the step control, e.g. a first step rejected on purpose).
///
/// The driver: owns the loop over the record intervals, the response tracker (continuous
/// peaks from each accepted step's dense output, samples at record points and events), the
/// history and the overlap audit; the [`GapStepper`] does the integration.
pub(crate) fn run_from(
    scene: &Scene,
    sys: &System,
    mut history: Option<&mut History>,
    first_step: Option<f64>,
) -> Result<RunOutput, SolverError> {
    let duration = scene.duration;
    let n_int = sys.n_intervals(duration);
    let bp = |i: usize| sys.interval_end(i, duration);
    let mut stepper = GapStepper::new(scene, sys, first_step, bp(0));
    let keep = history.is_some();
    let mut obs = DenseObserver::new(scene, sys);
    obs.start(
        sys,
        stepper.u(),
        |t| stepper.observe(t, keep),
        history.as_deref_mut(),
    );

    let mut interval = 0usize;
    while interval < n_int {
        let outcome = stepper.step(bp(interval), &mut |s: &DenseStep| obs.dense(sys, s))?;
        let tracker = &mut obs.tracker;
        // Without a history, an instant before the end updates the peaks only.
        let observe = |stepper: &GapStepper, tracker: &mut ResponseTracker, last: bool| {
            if keep || last {
                stepper.observe(tracker, keep);
            } else {
                stepper.observe_peaks(tracker);
            }
        };
        match outcome {
            StepOutcome::Rejected => continue,
            StepOutcome::Accepted | StepOutcome::Breakpoint => {}
            StepOutcome::StoryKink { .. } => {
                observe(&stepper, tracker, false);
                tracker.sample(stepper.t(), history.as_deref_mut());
            }
            StepOutcome::ContactClosed { breakpoint, .. }
            | StepOutcome::ContactOpened { breakpoint, .. } => {
                observe(&stepper, tracker, false);
                if !breakpoint {
                    tracker.sample(stepper.t(), history.as_deref_mut());
                }
            }
            StepOutcome::Impact { .. }
            | StepOutcome::Released { .. }
            | StepOutcome::ContactsChanged { .. }
            | StepOutcome::Finished => unreachable!("not an outcome of the adaptive stepper"),
        }
        if outcome.at_breakpoint() {
            observe(&stepper, tracker, interval + 1 == n_int);
            tracker.sample(stepper.t(), history.as_deref_mut());
            interval += 1;
            if interval < n_int {
                stepper.enter_segment(sys.segment(interval));
            }
        }
    }

    let (impacts, energy, stats, stories) = stepper.finish();
    Ok(output(
        sys,
        scene,
        &stories,
        obs.tracker.finish(),
        impacts,
        energy,
        stats,
        obs.overlaps,
    ))
}

/// [`crate::response::bisect`] with the same result, faster: the sign change of `f` in
/// [lo, hi] by 60 bisections, each halving [lo, hi] at mid = 0.5 (lo + hi) and keeping
/// [mid, hi] when f(mid) f(lo) > 0, else [lo, mid]. Three levels at a time: the midpoints
/// of the next three levels (1 + 2 + 4, with the same operands in the same order) are
/// evaluated together, off the chain of dependent decisions, and the walk down the three
/// levels (the same choices as the plain loop) is index arithmetic without branches. It
/// stops once three bisections leave [lo, hi] unchanged: every later one would too (each
/// is a function of [lo, hi] alone).
#[inline]
pub(crate) fn bisect(f: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    // 60 bisections: 20 rounds of 3 levels.
    const ROUNDS: usize = 20;
    let (mut lo, mut hi) = (lo, hi);
    let flo = f(lo);
    for _ in 0..ROUNDS {
        // The tree of the round: node k (1 ≤ k < 16) is the interval [los[k], his[k]]
        // with midpoint mids[k] (k < 8); its children are 2k ([lo, mid], taken when
        // f(mid) f(lo) ≤ 0) and 2k + 1 ([mid, hi]).
        let (mut los, mut his, mut mids) = ([lo; 16], [hi; 16], [0.0; 8]);
        for k in 1..8 {
            mids[k] = 0.5 * (los[k] + his[k]);
            (los[2 * k], his[2 * k]) = (los[k], mids[k]);
            (los[2 * k + 1], his[2 * k + 1]) = (mids[k], his[k]);
        }
        mids[0] = mids[1];
        let up: [usize; 8] = std::array::from_fn(|k| usize::from(f(mids[k]) * flo > 0.0));
        let c1 = 2 + up[1];
        let c2 = 2 * c1 + up[c1];
        let c3 = 2 * c2 + up[c2];
        if los[c3] == lo && his[c3] == hi {
            break;
        }
        (lo, hi) = (los[c3], his[c3]);
    }
    0.5 * (lo + hi)
}

/// `if c { a } else { b }` by bit masks, which compiles without a branch.
#[inline(always)]
fn select(c: bool, a: f64, b: f64) -> f64 {
    let m = u64::from(c).wrapping_neg();
    f64::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// What the drivers of the adaptive gap element and of the impulse method observe on every
/// accepted step's dense output: the continuous peaks ([`dense_peaks`]) and the overlap maxima
/// ([`overlaps_over`], on the pairs' state components found once per run).
pub(crate) struct DenseObserver {
    pub tracker: ResponseTracker,
    pub overlaps: crate::overlap::OverlapTracker,
    /// (u_left, u_right) state components of every audited pair.
    dofs: Vec<(usize, usize)>,
    scratch: Vec<f64>,
}

impl DenseObserver {
    /// Observes the initial state: displacements `u` for the overlap audit, `observe` for
    /// the tracker, then the first history row (t = 0).
    pub fn start(
        &mut self,
        sys: &System,
        u: &[f64],
        observe: impl FnOnce(&mut ResponseTracker),
        history: Option<&mut History>,
    ) {
        sys.observe_overlaps(&mut self.overlaps, 0.0, u);
        observe(&mut self.tracker);
        self.tracker.sample(0.0, history);
    }

    pub fn new(scene: &Scene, sys: &System) -> Self {
        let overlaps = crate::overlap::OverlapTracker::new(scene);
        let dofs = overlaps
            .pairs
            .iter()
            .map(|p| {
                (
                    sys.blocks[p.left].off + p.left_dof,
                    sys.blocks[p.right].off + p.right_dof,
                )
            })
            .collect();
        DenseObserver {
            tracker: ResponseTracker::new(scene),
            overlaps,
            dofs,
            scratch: vec![0.0; sys.n],
        }
    }

    /// Observes the accepted step `s`.
    #[inline(always)]
    pub fn dense(&mut self, sys: &System, s: &DenseStep) {
        dense_peaks(
            sys,
            s.stories,
            s.dp,
            s.y0,
            s.y1,
            s.th_end,
            &mut self.tracker,
            &mut self.scratch,
        );
        if !self.overlaps.is_empty() {
            let best = (&mut self.overlaps.max[..], &mut self.overlaps.time[..]);
            let dofs = self.dofs.iter().copied();
            overlaps_over(sys.n, dofs, s.dp, s.t, s.y0, s.y1, s.th_end, best);
        }
    }
}

/// The overlap audit over an accepted step (issue 11, [`crate::overlap`]): u_left − u_right
/// of every audited pair at the end of the part taken (θ = `th_end`, state `y1`) and, when
/// its rate turns from + to − over the step, at the interior maximum, located as in
/// [`dense_peaks`] (Hermite estimate plus the |r₅|/16 slack against the running maximum,
/// then bisection on the rate of the dense output). `t` is the step's start, s; `dofs` the
/// pairs' state components (u_left, u_right) in order ([`DenseObserver`] finds them once per
/// run); `best` the running maxima and their instants (`OverlapTracker::max`, `time`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn overlaps_over(
    n: usize,
    dofs: impl IntoIterator<Item = (usize, usize)>,
    dp: &Dopri5,
    t: f64,
    y: &[f64],
    y1: &[f64],
    th_end: f64,
    best: (&mut [f64], &mut [f64]),
) {
    let len = th_end * dp.h;
    if len <= 0.0 {
        return;
    }
    let (u0, v0, u1, v1) = (&y[..n], &y[n..2 * n], &y1[..n], &y1[n..2 * n]);
    let (max, time) = best;
    for ((max, time), (l, r)) in max.iter_mut().zip(time.iter_mut()).zip(dofs) {
        let (yd0, ye, yde) = (v0[l] - v0[r], u1[l] - u1[r], v1[l] - v1[r]);
        // `OverlapTracker::offer` without a branch (a new maximum comes unpredictably).
        let higher = ye > *max;
        *max = select(higher, ye, *max);
        *time = select(higher, t + len, *time);
        // A maximum inside: the rate turns from + to − (`hermite_extremum` asks for the
        // sign change too); rarely.
        if (yd0 > 0.0) & (yd0 * yde < 0.0) {
            let y0 = u0[l] - u0[r];
            overlap_between(n, dp, t, len, th_end, l, r, [y0, yd0, ye, yde], (max, time));
        }
    }
}

/// The interior maximum of a pair of [`overlaps_over`] (components `l`, `r`), its rate
/// turning from + to − over the step: (u, u̇) at both ends in `ends`; `best` its running
/// maximum and instant (as `OverlapTracker::offer` updates them).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn overlap_between(
    n: usize,
    dp: &Dopri5,
    t: f64,
    len: f64,
    th_end: f64,
    l: usize,
    r: usize,
    ends: [f64; 4],
    best: (&mut f64, &mut f64),
) {
    let [y0, yd0, ye, yde] = ends;
    let Some((_, h)) = crate::response::hermite_extremum(y0, yd0, ye, yde, len) else {
        return;
    };
    let slack = if th_end < 1.0 {
        f64::INFINITY
    } else {
        (dp.quartic(l) - dp.quartic(r)).abs() / 16.0
    };
    let (max, time) = best;
    if h + slack < *max {
        return;
    }
    let (cl, cr) = (dp.coefficients(n + l), dp.coefficients(n + r));
    let rate = |th: f64| dense_at(&cl, th) - dense_at(&cr, th);
    let th = bisect(rate, 0.0, th_end);
    let rel = dp.dense(l, th) - dp.dense(r, th);
    if rel > *max {
        (*max, *time) = (rel, t + th * dp.h);
    }
}

/// Peaks between the ends of an accepted step (issue 10): for every floor displacement and
/// story shear of every building, a sign change of its rate between the step start (`y`) and
/// θ = `th_end` (state `y1`) means an interior extremum. Over a whole step the dense output is
/// the cubic Hermite interpolant of the end values and rates plus r₅ θ²(1−θ)², so the
/// Hermite estimate H is within |r₅|/16 of it: when |H| + |r₅|/16 reaches the running peak
/// (always, for a step cut short by an event) the extremum is located by bisection on the
/// rate of the dense output, and the building's floors there update the peaks. The dense
/// output is the error-controlled interpolant of the step, so the peaks carry the
/// integration tolerance, as the solution does.
///
/// Most quantities have no interior extremum in a step: a first pass over the floors only
/// compares the signs of the rates at both ends (the rates computed as below), and the
/// quantities whose rate changes sign are then examined one by one, in the same order.
#[allow(clippy::too_many_arguments)]
pub(crate) fn dense_peaks(
    sys: &System,
    stories: &Stories,
    dp: &Dopri5,
    y: &[f64],
    y1: &[f64],
    th_end: f64,
    tracker: &mut ResponseTracker,
    scratch: &mut [f64],
) {
    let n = sys.n;
    let len = th_end * dp.h;
    if !(len > 0.0) {
        return;
    }
    let (v0, v1) = (&y[n..2 * n], &y1[n..2 * n]);
    for (bi, b) in sys.blocks.iter().enumerate() {
        let yielding = stories.yielding(bi);
        let (v0, v1) = (&v0[b.off..b.off + b.len], &v1[b.off..b.off + b.len]);
        let k = &sys.story_k[b.off..b.off + b.len];
        // Each floor's rate v_j and its story's rate sc·(v_j − v_{j−1}) (sc: k_j, or 1 for
        // a yielding building's drift; v_{−1} = 0, and x − 0 = x exactly) at both ends; a
        // sign change sends the quantity to `peak_between`, the floor's first.
        let (mut below0, mut below1) = (0.0, 0.0);
        for j in 0..b.len {
            let (a0, a1) = (v0[j], v1[j]);
            let sc = if yielding { 1.0 } else { k[j] };
            let (r0, r1) = (sc * (a0 - below0), sc * (a1 - below1));
            let (floor, story) = (a0 * a1 < 0.0, r0 * r1 < 0.0);
            if floor | story {
                for (turns, story) in [(floor, false), (story, true)] {
                    if turns {
                        peak_between(
                            sys, stories, dp, y, y1, th_end, tracker, scratch, bi, j, story,
                        );
                    }
                }
            }
            (below0, below1) = (a0, a1);
        }
    }
}

/// [`dense_peaks`] for one quantity of building `bi`, floor `j`: its displacement, or its
/// story's shear when `story`.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn peak_between(
    sys: &System,
    stories: &Stories,
    dp: &Dopri5,
    y: &[f64],
    y1: &[f64],
    th_end: f64,
    tracker: &mut ResponseTracker,
    scratch: &mut [f64],
    bi: usize,
    j: usize,
    story: bool,
) {
    let n = sys.n;
    let len = th_end * dp.h;
    let b = &sys.blocks[bi];
    let yielding = stories.yielding(bi);
    let i = b.off + j;
    let below = if story && j > 0 { Some(i - 1) } else { None };
    // A yielding story: its drift (the law's shear is monotone in the drift along
    // a branch and the step crosses no kink, so the shear's extremes lie at the
    // drift's); an interior extremum is located unless the bounds of the drift
    // over the step ([`super::stories::drift_bounds`]) show that neither the
    // drift nor the law's shear there can reach its running peak (a smaller drift
    // may carry a larger shear once the story has yielded).
    let sc = if story && !yielding {
        sys.story_k[i]
    } else {
        1.0
    };
    let comb = |u: &[f64], off: usize| sc * (u[off + i] - below.map_or(0.0, |l| u[off + l]));
    let (y0, yd0, ye, yde) = (comb(y, 0), comb(y, n), comb(y1, 0), comb(y1, n));
    // The caller saw yd0·yde < 0 (and len > 0): there is a Hermite extremum H.
    if story && yielding {
        if th_end >= 1.0 {
            // The law's shear is monotone in the drift (tangent k₀ or b k₀ ≥ 0), so
            // over the step it lies between its values at the drift's bounds.
            if let Some((lo, hi)) = super::stories::drift_bounds(dp, i, below) {
                let (v_lo, v_hi) = (
                    stories.story_force(bi, j, lo).0,
                    stories.story_force(bi, j, hi).0,
                );
                if v_lo.abs().max(v_hi.abs()) < tracker.peak(bi, j).0
                    && lo.abs().max(hi.abs()) < tracker.peak_drift(bi, j)
                {
                    return;
                }
            }
        }
    } else {
        let (vmax, dmax) = tracker.peak(bi, j);
        let peak = if story { vmax } else { dmax };
        let slack = if th_end < 1.0 {
            f64::INFINITY
        } else {
            sc * (dp.quartic(i) - below.map_or(0.0, |l| dp.quartic(l))).abs() / 16.0
        };
        // First a bound of |H| without solving for the extremum: H = h₀₀ y0 + h₀₁ ye +
        // h₁₀ m0 + h₁₁ me with h₀₀, h₀₁ ≥ 0 summing to 1 and |h₁₀|, |h₁₁| ≤ 4/27 on
        // [0, 1] (m = rate·len), so |H| ≤ max(|y0|, |ye|) + 4/27 (|m0| + |me|); 1e-12 of
        // the sum of the magnitudes covers the round-off of `hermite_extremum`'s value
        // many times over. Below the peak, that value would be too: the same decision.
        let (m0, me) = (yd0 * len, yde * len);
        let size = y0.abs() + ye.abs() + m0.abs() + me.abs();
        let bound = y0.abs().max(ye.abs()) + 4.0 / 27.0 * (m0.abs() + me.abs()) + 1e-12 * size;
        if bound + slack < peak {
            return;
        }
        let Some((_, h)) = crate::response::hermite_extremum(y0, yd0, ye, yde, len) else {
            return;
        };
        if h.abs() + slack < peak {
            return;
        }
    }
    let ci = dp.coefficients(n + i);
    let th = match below {
        Some(l) => {
            let cl = dp.coefficients(n + l);
            bisect(
                |th| sc * (dense_at(&ci, th) - dense_at(&cl, th)),
                0.0,
                th_end,
            )
        }
        // x − 0 = x exactly: the first story's rate (and a floor's) needs no second term.
        None => bisect(|th| sc * dense_at(&ci, th), 0.0, th_end),
    };
    for m in b.off..b.off + b.len {
        scratch[m] = dp.dense(m, th);
    }
    sys.observe_peaks(stories, tracker, bi, &scratch[b.off..b.off + b.len]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pair of the event tests below: two 1 t masses, k = 1e9 N/m, c_r = 0.65, `law`.
    fn pair(law: structure::scene::ContactLaw) -> System {
        let mut scene =
            structure::testing::two_oscillators(1e3, 1e-6, 1e3, 1e-6, 1.0, 0.01, 0.65, 1.0);
        scene.gap_element.law = law;
        scene.gap_element.stiffness = 1e9;
        System::new(&scene).unwrap()
    }

    /// The clamped Kelvin–Voigt pair.
    fn kelvin_voigt_pair() -> System {
        let sys = pair(structure::scene::ContactLaw::KelvinVoigt);
        assert!(sys.contacts[0].law.force_event());
        sys
    }

    /// One step of length `h` (s) from t = 0 in which the left mass of `sys` moves with
    /// δ(t) = d0 + v0 t + a0 t²/2 + j t³/6 (the right one at rest): a cubic, which the dense
    /// output reproduces to round-off.
    fn step(sys: &System, h: f64, [d0, v0, a0, j]: [f64; 4]) -> Dopri5 {
        let y0 = [sys.contacts[0].gap + d0, 0.0, v0, 0.0];
        let mut f = |t: f64, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[2];
            dy[1] = y[3];
            dy[2] = a0 + j * t;
            dy[3] = 0.0;
        };
        let mut dp = Dopri5::new(4, 2, 1e-8, vec![1e-11; 2]);
        f(0.0, &y0, &mut dp.k[0]);
        assert!(dp.try_step(&mut f, 0.0, &y0, h).is_finite());
        dp.prepare_dense(0.0, &y0, h);
        dp
    }

    /// The constant-acceleration dip of the clamped pair `sys`: a = 10 m/s², h = 1/ω_c, and
    /// F(t) = A + B t + C t² = C (t − t*)² + F_min with C = k a/2 (A = kδ0 + c v0, B = k v0 +
    /// c a), its minimum F_min = `f_min(C h²)` at t* = `frac` h.
    fn dip(sys: &System, frac: f64, f_min: impl Fn(f64) -> f64) -> Dopri5 {
        let law = &sys.contacts[0].law;
        let (k, c) = (law.k, law.c);
        let h = (law.m_eff / k).sqrt();
        let a = 10.0;
        let cc = 0.5 * k * a;
        let v0 = -a * (frac * h + c / k);
        let b = k * v0 + c * a;
        let d0 = (f_min(cc * h * h) + b * b / (4.0 * cc) - c * v0) / k;
        step(sys, h, [d0, v0, a, 0.0])
    }

    /// (δ, δ̇, F = kδ + cδ̇) of the pair's contact on the dense output at θ.
    fn kelvin_voigt_force(sys: &System, dp: &Dopri5, th: f64) -> (f64, f64, f64) {
        let c = &sys.contacts[0];
        let (d, dd) = kin(dp, sys.n, 0, Some(1), c.gap, th);
        (d, dd, c.law.k * d + c.law.c * dd)
    }

    /// A closed clamped Kelvin–Voigt contact whose force F = kδ + cδ̇ dips below 0 between
    /// two event samples and comes back (positive at θ = 0, ¼, ½, ¾, 1; the contact still
    /// penetrating throughout) ends inside the step, at F's first root, located between the
    /// samples by the turn of dF/dt (the measured misses of 2026-11-29 in the stiffness study:
    /// −413 N and −248 N inside a step). Constant acceleration a: F(t) = C (t − t*)² + F_min,
    /// C = k a/2, F_min = −C h²/100, so F(t* ± h/8) = C (1/64 − 1/100) h² > 0 and F's first
    /// root is t* − h/10. With h = 1/ω_c, c/k = 2ξ/ω_c = 0.27 h keeps δ > 0 at F's minimum.
    #[test]
    fn a_clamped_kelvin_voigt_end_between_samples_is_found() {
        let sys = kelvin_voigt_pair();
        for frac in [0.375, 0.625, 0.875, 0.125] {
            let dp = dip(&sys, frac, |ch2| -0.01 * ch2);
            for j in 0..=EVENT_SAMPLES {
                let th = j as f64 / EVENT_SAMPLES as f64;
                let (d, _, f) = kelvin_voigt_force(&sys, &dp, th);
                assert!(f > 0.0 && d > 0.0, "F = {f}, δ = {d} at θ = {th}");
            }
            let (d, _, f) = kelvin_voigt_force(&sys, &dp, frac);
            assert!(f < 0.0 && d > 0.0, "F = {f}, δ = {d} at the minimum");
            let mut ledger = ContactLedger::new(1, 1e9);
            ledger.close(0, 1.0, Episode::default());
            let mut calls = 0;
            let (th, ci) = earliest_event(&sys, &ledger, &dp, &mut calls)
                .unwrap_or_else(|| panic!("the end near θ = {frac} was missed"));
            assert_eq!(ci, 0);
            let th_root = frac - 0.1;
            assert!((th - th_root).abs() < 1e-9, "θ = {th} against {th_root}");
        }
    }

    /// The reverse: an open clamped Kelvin–Voigt contact, penetrating and separating
    /// throughout (δ > 0 and δ̇ < 0, so δ has no turn to find), whose force F = kδ + cδ̇ is
    /// negative at the five samples and positive between two of them closes there, at F's
    /// first root. F is the cubic F̂ = ε − Q x² + R x³ (x = s − s*, s = t/h; ε = 0.01, Q = 10,
    /// R = −10, in units of k × 1 µm) with h = c/k, and δ̂ = F̂ − F̂′ + F̂″ − F̂‴ (derivatives
    /// in s) the cubic with kδ + cδ̇ = F.
    #[test]
    fn a_clamped_kelvin_voigt_closure_between_samples_is_found() {
        let (eps, q, r, len) = (0.01, 10.0, -10.0, 1e-6);
        let sys = kelvin_voigt_pair();
        let h = sys.contacts[0].law.c / sys.contacts[0].law.k;
        for s_star in [0.375, 0.625, 0.875, 0.125] {
            let f_hat = |s: f64| {
                let x = s - s_star;
                eps - q * x * x + r * x * x * x
            };
            // F̂ and its derivatives at s = 0, then δ̂'s, then δ's in SI.
            let x0 = -s_star;
            let f = [
                f_hat(0.0),
                -2.0 * q * x0 + 3.0 * r * x0 * x0,
                -2.0 * q + 6.0 * r * x0,
                6.0 * r,
            ];
            let dh = [
                f[0] - f[1] + f[2] - f[3],
                f[1] - f[2] + f[3],
                f[2] - f[3],
                f[3],
            ];
            let y = [
                dh[0] * len,
                dh[1] * len / h,
                dh[2] * len / (h * h),
                dh[3] * len / h.powi(3),
            ];
            let dp = step(&sys, h, y);
            for j in 0..=64 {
                let th = j as f64 / 64.0;
                let (d, dd, f) = kelvin_voigt_force(&sys, &dp, th);
                assert!(d > 0.0 && dd < 0.0, "δ = {d}, δ̇ = {dd} at θ = {th}");
                assert!(j % 16 != 0 || f < 0.0, "F = {f} at θ = {th}");
            }
            assert!(kelvin_voigt_force(&sys, &dp, s_star).2 > 0.0);
            let ledger = ContactLedger::new(1, 1e9);
            let mut calls = 0;
            let (th, ci) = earliest_event(&sys, &ledger, &dp, &mut calls)
                .unwrap_or_else(|| panic!("the closure near θ = {s_star} was missed"));
            assert_eq!(ci, 0);
            // F̂'s first root, bisected on the exact cubic.
            let (mut lo, mut hi) = (s_star - 0.125, s_star);
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if f_hat(mid) < 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            assert!((th - lo).abs() < 1e-9, "θ = {th} against {lo}");
        }
    }

    /// Two edges of the clamped Kelvin–Voigt event search, on the constant-acceleration step
    /// of [`dip`] (F(t) = C (t − t*)² + F_min):
    /// - a closed contact whose F dips to −1e-8 N between samples, within F's round-off
    ///   (64 ε of its terms, 2.8e-7 N here), does not end: read as an end, such a grazing
    ///   minimum ended and closed the contact every 6e-14 s in the stiffness study;
    /// - an open contact released at F's root read on its positive side (F(0) ≥ 0) in a dip
    ///   that ends before the first sample closes at the dip's far root, not at θ = 0; so
    ///   does a contact of the linear law in a dip of δ.
    #[test]
    fn grazing_minima_and_dips_after_a_release_are_read_as_such() {
        let sys = kelvin_voigt_pair();
        let mut calls = 0;
        let dp = dip(&sys, 0.375, |_| -1e-8);
        assert!(kelvin_voigt_force(&sys, &dp, 0.375).2 < 0.0);
        let mut ledger = ContactLedger::new(1, 1e9);
        ledger.close(0, 1.0, Episode::default());
        assert_eq!(earliest_event(&sys, &ledger, &dp, &mut calls), None);

        let dp = dip(&sys, 0.1, |ch2| -0.005 * ch2);
        for th in [0.0, 0.25] {
            assert!(kelvin_voigt_force(&sys, &dp, th).2 > 0.0);
        }
        let ledger = ContactLedger::new(1, 1e9);
        let (th, _) = earliest_event(&sys, &ledger, &dp, &mut calls).unwrap();
        let far = 0.1 + 0.005f64.sqrt();
        assert!((th - far).abs() < 1e-9, "θ = {th} against {far}");

        // The same for the linear law, whose event is δ: δ(t) = (a/2)(t − 0.1 h)² − δ_m with
        // δ(0) = (a/2)(0.01 − 0.005) h² > 0 and δ(h/4) > 0, the far root at (0.1 + √0.005) h.
        // a = 10 m/s² and h = 1/ω_c, as in the dip.
        let sys = pair(structure::scene::ContactLaw::Linear);
        let h = (sys.contacts[0].law.m_eff / sys.contacts[0].law.k).sqrt();
        let (a, t_m) = (10.0, 0.1 * h);
        let d_m = 0.005 * 0.5 * a * h * h;
        let y = [0.5 * a * t_m * t_m - d_m, -a * t_m, a, 0.0];
        let dp = step(&sys, h, y);
        let gap = sys.contacts[0].gap;
        for th in [0.0, 0.25] {
            assert!(kin(&dp, sys.n, 0, Some(1), gap, th).0 > 0.0);
        }
        assert!(kin(&dp, sys.n, 0, Some(1), gap, 0.1).0 < 0.0);
        let (th, _) = earliest_event(&sys, &ledger, &dp, &mut calls).unwrap();
        assert!(
            (th - far).abs() < 1e-9,
            "linear law: θ = {th} against {far}"
        );
    }

    /// The δ event of the linear law has a round-off floor, as the clamped law's force has:
    /// with the pair's u_l ≈ gap = 1 cm, δ = u_l − u_r − gap is known to 64 ε (|u_l| + |u_r| +
    /// gap) ≈ 2.8e-16 m. On the constant-acceleration step δ(t) = ±((a/2)(t − t*)² − δ_m)
    /// (a = 10 m/s², h = 1/ω_c, t* = 3h/8, so δ has the sign of ∓δ_m only within 6e-5 h of t*
    /// and the opposite one at the samples):
    /// - a closed contact whose δ dips to −1e-16 m is not ended by it, one that dips to
    ///   −1e-14 m ends at the dip's first root;
    /// - an open contact whose δ rises to +1e-16 m is not closed by it, one that rises to
    ///   +1e-14 m closes at the first root;
    /// - a contact released at δ's root, read on its positive side, in a dip to −1e-16 m that
    ///   ends before the first sample closes again at once (at −1e-14 m: at the far root).
    #[test]
    fn grazing_extrema_of_delta_are_no_events() {
        let sys = pair(structure::scene::ContactLaw::Linear);
        let gap = sys.contacts[0].gap;
        let h = (sys.contacts[0].law.m_eff / sys.contacts[0].law.k).sqrt();
        let a = 10.0;
        // δ(t) = sign ((a/2)(t − t*)² − d_m) as [δ0, δ̇0, δ̈, 0].
        let parabola = |sign: f64, frac: f64, d_m: f64| {
            let t_s = frac * h;
            [
                sign * (0.5 * a * t_s * t_s - d_m),
                -sign * a * t_s,
                sign * a,
                0.0,
            ]
        };
        let delta = |dp: &Dopri5, th: f64| kin(dp, sys.n, 0, Some(1), gap, th).0;
        let mut closed = ContactLedger::new(1, 1e9);
        closed.close(0, 1.0, Episode::default());
        let open = ContactLedger::new(1, 1e9);
        let mut calls = 0;
        for (sign, ledger) in [(1.0, &closed), (-1.0, &open)] {
            for d_m in [1e-16, 1e-14] {
                let dp = step(&sys, h, parabola(sign, 0.375, d_m));
                for j in 0..=EVENT_SAMPLES {
                    let th = j as f64 / EVENT_SAMPLES as f64;
                    assert!(sign * delta(&dp, th) > 0.0, "δ at θ = {th}");
                }
                assert!(sign * delta(&dp, 0.375) < 0.0, "δ at the extremum");
                let event = earliest_event(&sys, ledger, &dp, &mut calls);
                if d_m < 1e-15 {
                    assert_eq!(event, None, "a graze of {d_m} m (sign {sign})");
                } else {
                    let (th, _) = event.expect("an extremum beyond round-off");
                    let root = 0.375 - (2.0 * d_m / a).sqrt() / h;
                    assert!((th - root).abs() < 1e-9, "θ = {th} against {root}");
                }
            }
        }
        for d_m in [1e-16, 1e-14] {
            // The dip's minimum at 0.1 h, δ(0) = (a/2)(0.1 h)² − d_m > 0.
            let dp = step(&sys, h, parabola(1.0, 0.1, d_m));
            assert!(delta(&dp, 0.0) > 0.0 && delta(&dp, 0.1) < 0.0);
            let (th, _) = earliest_event(&sys, &open, &dp, &mut calls).unwrap();
            let far = if d_m < 1e-15 {
                0.0
            } else {
                0.1 + (2.0 * d_m / a).sqrt() / h
            };
            assert!((th - far).abs() < 1e-9, "θ = {th} against {far}");
        }
    }

    /// The three-level bisection picks exactly the point of the plain one, also for a rate
    /// with several sign changes, with round-off noise near its root, on a step cut short,
    /// or with the root at an end.
    #[test]
    fn bisect_is_the_plain_bisection() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rand = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for case in 0..2000 {
            let (a, b, c, d) = (rand() - 0.5, rand() - 0.5, rand() - 0.5, rand() - 0.5);
            let hi = if case % 3 == 0 { rand() } else { 1.0 };
            let f = |t: f64| {
                let p = a + t * (b + t * (c + t * d));
                match case % 4 {
                    0 => p,
                    // Round-off noise: 1 − (1 − p·1e-17) is not p·1e-17.
                    1 => 1.0 - (1.0 - p * 1e-17),
                    2 => (13.0 * t).sin() * p,
                    _ => (t - 0.25 * hi).max(0.0) * p,
                }
            };
            assert_eq!(
                bisect(f, 0.0, hi).to_bits(),
                crate::response::bisect(f, 0.0, hi).to_bits(),
                "case {case}"
            );
        }
    }
}
