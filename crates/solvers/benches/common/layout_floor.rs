//! The cost floor of a block layout for the momentum method's fast path (issue 10): the
//! fast path's *regular* work on the paper scene, laid out for it, so that the distance
//! between the solver and the speed target can be measured. Shared by the criterion
//! bench `layout_floor` and the example of the same name (instruction counts, and a test
//! that the kernel does the solver's work).
//!
//! Per block of up to [`B`] base steps it
//! 1. propagates every mode over the steps (the solver's own propagators,
//!    [`Problem::full`]), the input and damping works included, storing q and q̇ of every
//!    step time-major;
//! 2. rebuilds each building's floor displacements and velocities u = Φq, u̇ = Φq̇ for
//!    every step of the block (floors and modes padded to 16);
//! 3. samples along time: the running peaks of |u_i| and |V_i| = |k_i (u_i − u_{i−1})|,
//!    the rates' sign changes (where the solver's slow path looks for an interior extremum:
//!    counted, not refined), and the roof contact's δ = u₁ − u₂ − gap (a step with δ ≥ 0,
//!    or whose δ̇ turns from + to − with the cubic Hermite bound of δ over the step ≥ 0, is
//!    counted as one that would need the closed form).
//!
//! It leaves out, on purpose: event location and impacts (the block is never cut at a
//! contact), the slow paths of the peaks and of the overlap audit, the energy envelope and
//! the history. Its answer is the response without contact (with its peaks sampled at the
//! steps), not the solver's: it is a floor, not a solver. Only for scenes of buildings of
//! at most 16 floors with every mode kept and one contact (the paper scene).
use solvers::momentum::modal::{self, StepBlock};
use solvers::momentum::Problem;

/// Steps per block.
const B: usize = 64;
/// Modes per building and floors per building, padded (the paper scene: 15 and 15).
const PM: usize = 16;
const PF: usize = 16;

/// The problem's data in the floor's layout (per building, padded to 16 modes and floors).
pub struct Layout {
    /// Per building, its modes' step coefficients in PM lanes (the solver's [`StepBlock`]).
    coef: Vec<StepBlock<PM>>,
    /// Per building Φ: mode m's floors at [m][0..PF] (zeros past the last floor or mode).
    phi: Vec<[[f64; PF]; PM]>,
    /// Per building the story stiffness per floor (zeros past the last floor).
    k: Vec<[f64; PF]>,
    /// Roof floor of each building (0-based) and the gap of the roof contact.
    roof: [usize; 2],
    gap: f64,
    /// Floors per building.
    floors: Vec<usize>,
}

/// The layout of `p` (built from `scene`); panics on a building of more than 16 floors or
/// modes (the floor is for the paper scene).
pub fn layout(p: &Problem, scene: &structure::Scene) -> Layout {
    let c = &p.full;
    let mut coef = Vec::new();
    let mut phi = Vec::new();
    let mut k = Vec::new();
    for (bm, bd) in p.modal.buildings.iter().zip(&scene.buildings) {
        let r = bm.range.clone();
        assert!(
            r.len() <= PM && bm.n_floors <= PF,
            "the floor takes buildings of at most {PF} floors and {PM} modes"
        );
        coef.push(StepBlock::gather(c, &p.modal.gamma, r.start, r.len()));
        let mut ph = [[0.0; PF]; PM];
        for (m, row) in ph.iter_mut().enumerate().take(r.len()) {
            for (i, x) in row.iter_mut().enumerate().take(bm.n_floors) {
                *x = bm.phi[m * bm.n_floors + i];
            }
        }
        phi.push(ph);
        let mut kk = [0.0; PF];
        kk[..bd.story_stiffness.len()].copy_from_slice(&bd.story_stiffness);
        k.push(kk);
    }
    let ct = &scene.contacts[0];
    Layout {
        coef,
        phi,
        k,
        roof: [ct.left_dof, ct.right_dof],
        gap: ct.gap,
        floors: p.modal.buildings.iter().map(|b| b.n_floors).collect(),
    }
}

/// What one run counted.
#[derive(Debug, Default, Clone)]
pub struct Counts {
    /// Base steps.
    pub steps: usize,
    /// Rate sign changes over the steps (floor displacements and story shears).
    pub turns: usize,
    /// Steps the roof contact would send to the closed form.
    pub closed_form: usize,
    /// Sampled peaks per building: |u_i| (m) and |V_i| (N), floor 1 first.
    pub disp_max: Vec<Vec<f64>>,
    pub shear_max: Vec<Vec<f64>>,
    /// Input plus damping work summed over the modes (a checksum).
    pub work: f64,
}

/// One block's propagation of a building from (x, v) by the solver's own kernel
/// ([`modal::propagate`]): q, q̇ of each step into qs, vs, the works summed per mode.
#[inline(always)]
fn propagate(
    c: &StepBlock<PM>,
    (x, v): (&mut [f64; PM], &mut [f64; PM]),
    ag: (&[f64], &[f64]),
    (qs, vs): (&mut [[f64; PM]], &mut [[f64; PM]]),
    work: &mut [f64; PM],
) {
    for (t, (&a0, &a1)) in ag.0.iter().zip(ag.1).enumerate() {
        let [xn, vn, input, damping] = modal::propagate::<PM>(c, *x, *v, a0, a1);
        for n in 0..PM {
            work[n] += input[n] + damping[n];
        }
        *x = xn;
        *v = vn;
        qs[t] = xn;
        vs[t] = vn;
    }
}

/// u = Φq for every step of the block (time-major), two steps at a time (four spill the
/// accumulators).
#[inline(always)]
fn rebuild(phi: &[[f64; PF]; PM], qs: &[[f64; PM]], us: &mut [[f64; PF]]) {
    let n = qs.len();
    let mut t = 0;
    while t + 2 <= n {
        let q: [&[f64; PM]; 2] = std::array::from_fn(|r| &qs[t + r]);
        let mut acc = [[0.0; PF]; 2];
        for m in 0..PM {
            let col = &phi[m];
            for r in 0..2 {
                for i in 0..PF {
                    acc[r][i] = col[i].mul_add(q[r][m], acc[r][i]);
                }
            }
        }
        us[t..t + 2].copy_from_slice(&acc);
        t += 2;
    }
    while t < n {
        let mut a0 = [0.0; PF];
        for m in 0..PM {
            for i in 0..PF {
                a0[i] = phi[m][i].mul_add(qs[t][m], a0[i]);
            }
        }
        us[t] = a0;
        t += 1;
    }
}

/// Peaks and rate sign changes of one building along the block's steps; `prev` the rates of
/// the step before the block. Returns the number of sign changes.
#[inline(always)]
fn sample(
    k: &[f64; PF],
    (us, uds): (&[[f64; PF]], &[[f64; PF]]),
    prev: &mut [f64; PF],
    (dm, sm): (&mut [f64; PF], &mut [f64; PF]),
) -> usize {
    let mut acc = [0.0f64; PF];
    for (u, ud) in us.iter().zip(uds) {
        let shift = |a: &[f64; PF]| -> [f64; PF] {
            std::array::from_fn(|i| if i == 0 { 0.0 } else { a[i - 1] })
        };
        let (below, vbelow, pbelow) = (shift(u), shift(ud), shift(prev));
        for i in 0..PF {
            dm[i] = dm[i].max(u[i].abs());
            sm[i] = sm[i].max((k[i] * (u[i] - below[i])).abs());
            let r0 = k[i] * (prev[i] - pbelow[i]);
            let r1 = k[i] * (ud[i] - vbelow[i]);
            let d_turn = if prev[i] * ud[i] < 0.0 { 1.0 } else { 0.0 };
            let s_turn = if r0 * r1 < 0.0 { 1.0 } else { 0.0 };
            acc[i] += d_turn + s_turn;
        }
        *prev = *ud;
    }
    acc.iter().sum::<f64>() as usize
}

/// One analysis over the whole record (see the module docs), in the widest instruction set.
pub fn run(p: &Problem, l: &Layout) -> Counts {
    struct Op<'a>(&'a Problem, &'a Layout);
    impl pulp::WithSimd for Op<'_> {
        type Output = Counts;
        #[inline(always)]
        fn with_simd<S: pulp::Simd>(self, _: S) -> Counts {
            kernel(self.0, self.1)
        }
    }
    pulp::Arch::new().dispatch(Op(p, l))
}

#[inline(always)]
fn kernel(p: &Problem, l: &Layout) -> Counts {
    let nb = l.coef.len();
    let mut x = vec![[0.0; PM]; nb];
    let mut v = vec![[0.0; PM]; nb];
    let mut work = vec![[0.0; PM]; nb];
    let mut qs = vec![[[0.0; PM]; B]; 2 * nb];
    let mut us = vec![[[0.0; PF]; B]; 2 * nb];
    let mut prev = vec![[0.0; PF]; nb];
    let mut dm = vec![[0.0; PF]; nb];
    let mut sm = vec![[0.0; PF]; nb];
    let mut cnt = Counts::default();
    let (mut d_prev, mut dd_prev) = (-l.gap, 0.0f64);
    let n = p.n_steps;
    let mut j = 0;
    while j < n {
        let e = (j + B).min(n);
        let len = e - j;
        let ag = (&p.ag_start[j..e], &p.ag_end[j..e]);
        for b in 0..nb {
            let (q, rest) = qs.split_at_mut(2 * b + 1);
            let (qx, qv) = (&mut q[2 * b][..len], &mut rest[0][..len]);
            propagate(
                &l.coef[b],
                (&mut x[b], &mut v[b]),
                ag,
                (qx, qv),
                &mut work[b],
            );
            let (u, rest) = us.split_at_mut(2 * b + 1);
            rebuild(&l.phi[b], qx, &mut u[2 * b][..len]);
            rebuild(&l.phi[b], qv, &mut rest[0][..len]);
            cnt.turns += sample(
                &l.k[b],
                (&us[2 * b][..len], &us[2 * b + 1][..len]),
                &mut prev[b],
                (&mut dm[b], &mut sm[b]),
            );
        }
        // The roof contact along the block.
        let (r0, r1) = (l.roof[0], l.roof[1]);
        // A bound of the cubic Hermite interpolant's interior values (the solver's filter).
        let c = 4.0 / 27.0 * p.h;
        for t in 0..len {
            let d = us[0][t][r0] - us[2][t][r1] - l.gap;
            let dd = us[1][t][r0] - us[3][t][r1];
            let reach = d_prev.max(d) + c * (dd_prev.abs() + dd.abs());
            if d >= 0.0 || (dd_prev > 0.0 && dd < 0.0 && reach >= 0.0) {
                cnt.closed_form += 1;
            }
            (d_prev, dd_prev) = (d, dd);
        }
        j = e;
    }
    cnt.steps = n;
    let floors = |a: &[[f64; PF]]| -> Vec<Vec<f64>> {
        a.iter()
            .zip(&l.floors)
            .map(|(x, &n)| x[..n].to_vec())
            .collect()
    };
    cnt.disp_max = floors(&dm);
    cnt.shear_max = floors(&sm);
    cnt.work = work.iter().flatten().sum();
    cnt
}
