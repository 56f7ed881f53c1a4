//! Contact geometry in modal coordinates and the impact impulses (paper eqs 19–24).
//!
//! Contact c joins floor i of building L to floor j of building R, or to a rigid wall that
//! moves with the ground (then g_c = (φ_L\[i\]) alone and v_c is the floor's own velocity
//! relative to the ground). With the dense modal row
//! g_c = (φ_L\[i\] on L's modes, −φ_R\[j\] on R's modes), the gap function and the relative
//! (approach) velocity are δ_c = g_c·q − gap and v_c = g_c·q̇. An impulse pair P_c ≥ 0
//! pushes the floors apart: Δq̇ = −g_c P_c, so Δv = −W P with the Delassus matrix
//! W_ab = g_a·g_b (W_cc = Σ_kept φ_L\[i\]² + Σ_kept φ_R\[j\]²).
//!
//! - `consistent`: W_AA P_A = (1 + e) v_A on the active set A (a small linear
//!   complementarity problem: solve, drop the most negative impulse, repeat). Gives
//!   v⁺ = −e v⁻ exactly and conserves momentum (exactly with all modes).
//! - `paper`: eqs (23)–(24) with the floor masses m_k, m_l (eq. 24 read with l for the
//!   printed i) give the intended floor velocity jumps Δẏ; then Δq̇ = Φᵀ M Δẏ per building.
//!   With all modes and lumped masses this equals `consistent`; with truncated modes the
//!   contact point realises only r_N of the jump.

use structure::Contact;

use crate::SolverError;

use super::modal::Modal;

/// One contact pair in modal form.
#[derive(Debug, Clone)]
pub struct ContactGeom {
    pub left: usize,
    pub right: usize,
    pub left_dof: usize,
    pub right_dof: usize,
    pub gap: f64,
    pub restitution: f64,
    /// Dense modal row g_c (see module docs).
    pub g: Vec<f64>,
    /// Floor masses m_k (left), m_l (right), kg (m_l = ∞ for a wall).
    pub m_left: f64,
    pub m_right: f64,
    /// The right side is a rigid wall ([`Contact::wall`]): `right`/`right_dof` repeat the
    /// left side and are not a second body.
    pub wall: bool,
}

impl ContactGeom {
    pub fn new(modal: &Modal, c: &Contact) -> ContactGeom {
        let gl = modal.floor_row(c.left, c.left_dof);
        // A wall (rigid, moving with the ground) has no modes: g_c is the left row alone,
        // so W_cc = Σ_kept φ_L[i]² and P = (1 + e) v / W_cc (the wall takes the reaction).
        let g = if c.wall {
            gl
        } else {
            let gr = modal.floor_row(c.right, c.right_dof);
            gl.iter().zip(&gr).map(|(a, b)| a - b).collect()
        };
        ContactGeom {
            left: c.left,
            right: c.right,
            left_dof: c.left_dof,
            right_dof: c.right_dof,
            gap: c.gap,
            restitution: c.restitution,
            g,
            m_left: modal.buildings[c.left].masses[c.left_dof],
            m_right: if c.wall {
                f64::INFINITY
            } else {
                modal.buildings[c.right].masses[c.right_dof]
            },
            wall: c.wall,
        }
    }

    /// g·q summed in mode order (as `iter().sum()`), the products by chunks of 4.
    #[inline]
    pub fn dot(&self, q: &[f64]) -> f64 {
        let n = self.g.len().min(q.len());
        let (g, q) = (&self.g[..n], &q[..n]);
        let n4 = n / 4 * 4;
        // The neutral element `Sum` starts from.
        let mut acc: f64 = std::iter::empty::<f64>().sum();
        for (gc, qc) in g[..n4].chunks_exact(4).zip(q[..n4].chunks_exact(4)) {
            let gc: [f64; 4] = gc.try_into().unwrap();
            let qc: [f64; 4] = qc.try_into().unwrap();
            let pr: [f64; 4] = std::array::from_fn(|i| gc[i] * qc[i]);
            for p in pr {
                acc += p;
            }
        }
        for (a, b) in g[n4..].iter().zip(&q[n4..]) {
            acc += a * b;
        }
        acc
    }

    /// δ = g·q − gap, m.
    #[inline]
    pub fn delta(&self, x: &[f64]) -> f64 {
        self.dot(x) - self.gap
    }

    /// δ as [`Self::delta`] but summed in four interleaved partial sums (vectorises): differs
    /// from it by round-off (≲ 30 ε Σ|g_n q_n|), so only for filters whose margin covers that.
    #[inline(always)]
    pub fn delta_fast(&self, x: &[f64]) -> f64 {
        let n = self.g.len();
        let (g, x) = (&self.g[..n], &x[..n]);
        let n4 = n / 4 * 4;
        let mut acc = [0.0f64; 4];
        for (gc, xc) in g[..n4].chunks_exact(4).zip(x[..n4].chunks_exact(4)) {
            for k in 0..4 {
                acc[k] += gc[k] * xc[k];
            }
        }
        for k in n4..n {
            acc[0] += g[k] * x[k];
        }
        (acc[0] + acc[1]) + (acc[2] + acc[3]) - self.gap
    }
}

/// Delassus matrix of the contacts `set`.
pub fn delassus(contacts: &[ContactGeom], set: &[usize]) -> Vec<Vec<f64>> {
    set.iter()
        .map(|&a| {
            set.iter()
                .map(|&b| contacts[a].dot(&contacts[b].g))
                .collect()
        })
        .collect()
}

/// Solves the small dense system `a x = b` (Gaussian elimination, partial pivoting);
/// `None` when `a` is singular or ill-conditioned: a pivot below 1e-12 of the largest
/// diagonal entry, or a non-finite result.
pub fn solve_checked(a: Vec<Vec<f64>>, b: Vec<f64>) -> Option<Vec<f64>> {
    Factored::new(a)?.solve(b)
}

/// A small dense matrix eliminated once ([`solve_checked`]'s Gaussian elimination with
/// partial pivoting), so that several right-hand sides are solved with the same operations
/// and the same bits as [`solve_checked`] gives each (the held contacts' Delassus matrix,
/// solved for the holding forces at every held trial, changes only with the held set).
#[derive(Debug, Clone)]
pub struct Factored {
    /// The eliminated matrix: its upper triangle, and below the diagonal the multipliers
    /// a_ik / a_kk of step k at \[i\]\[k\] (entries elimination no longer reads).
    lu: Vec<Vec<f64>>,
    /// The row exchanged with row k at step k.
    pivots: Vec<usize>,
}

impl Factored {
    /// Eliminates `a`, or `None` when it is singular or ill-conditioned (a pivot below
    /// 1e-12 of the largest diagonal entry).
    pub fn new(mut a: Vec<Vec<f64>>) -> Option<Factored> {
        let n = a.len();
        let scale = (0..n).map(|k| a[k][k].abs()).fold(0.0, f64::max);
        let mut pivots = Vec::with_capacity(n);
        for k in 0..n {
            let p = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
            if !(a[p][k].abs() > 1e-12 * scale) {
                return None;
            }
            a.swap(k, p);
            pivots.push(p);
            for i in k + 1..n {
                let f = a[i][k] / a[k][k];
                for j in k..n {
                    a[i][j] -= f * a[k][j];
                }
                a[i][k] = f;
            }
        }
        Some(Factored { lu: a, pivots })
    }

    /// The solution x of a x = b, or `None` if it is not finite.
    pub fn solve(&self, mut b: Vec<f64>) -> Option<Vec<f64>> {
        let (a, n) = (&self.lu, self.lu.len());
        // The row exchanges first (later ones moved the stored multipliers with their rows),
        // then each row takes the same subtractions, in the same order, as it did during the
        // elimination.
        for (k, &p) in self.pivots.iter().enumerate() {
            b.swap(k, p);
        }
        for k in 0..n {
            for i in k + 1..n {
                b[i] -= a[i][k] * b[k];
            }
        }
        // Back substitution in place: b[j] holds x_j once row j is done (j > k).
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|j| a[k][j] * b[j]).sum();
            b[k] = (b[k] - s) / a[k][k];
        }
        b.iter().all(|v| v.is_finite()).then_some(b)
    }
}

/// Solves W x = b for the Delassus matrix W of `set`, or says that it is singular or
/// ill-conditioned (two contacts on the same floor pair, for instance): never a silent zero.
pub fn solve_delassus(
    contacts: &[ContactGeom],
    set: &[usize],
    b: Vec<f64>,
    time: f64,
    what: &str,
) -> Result<Vec<f64>, SolverError> {
    solve_checked(delassus(contacts, set), b).ok_or_else(|| SolverError::SingularContact {
        time,
        contacts: set.to_vec(),
        context: what.to_string(),
    })
}

/// Adds the contacts `held` (those not already in `set`) to an impact's LCP as perfectly
/// plastic participants: target v⁺ = 0 where they approach (`approach(c)` > 0, m/s), no
/// impulse otherwise. Shared by the momentum and impulse methods (`Stepper::impact`).
pub fn add_plastic(
    set: &mut Vec<usize>,
    target: &mut Vec<f64>,
    held: impl IntoIterator<Item = usize>,
    approach: impl Fn(usize) -> f64,
) {
    add_participants(set, target, held, |c| approach(c).max(0.0));
}

/// Appends the contacts `extra` not already in `set`, each with target `target_of(c)`.
fn add_participants(
    set: &mut Vec<usize>,
    target: &mut Vec<f64>,
    extra: impl IntoIterator<Item = usize>,
    target_of: impl Fn(usize) -> f64,
) {
    for c in extra {
        if !set.contains(&c) {
            set.push(c);
            target.push(target_of(c));
        }
    }
}

/// The impulses of an impact: the frictionless complementarity problem over `set`,
///
/// ```text
/// P ≥ 0,   w = W P − target ≥ 0,   P·w = 0,
/// ```
///
/// with W the Delassus matrix of `set` and `target` the least reduction of each contact's
/// approach speed (m/s): (1 + e) v⁻ for an impacting contact, its approach speed for a held
/// one (plastic), and v⁻ itself (≤ 0: it may be pushed that far before it needs an impulse)
/// for a touching neighbour, one with its gap within the round-off band. A contact with P > 0
/// leaves at exactly its target; one with P = 0 leaves slower than it.
///
/// Active set (Murty's least-index principal pivoting, finite for the positive definite W
/// of independent contacts): the first `n_active` entries of `set` start active; solve
/// W_AA P_A = target_A, then flip the first contact (in `set` order) that is infeasible, an
/// active one with P < 0 or an inactive one with w below −1e-9 of the largest |target|
/// (round-off), and repeat. The solution is unique, and the impulses are those of the final
/// active set solved in `set` order: where the drop-only loop of the releases before found it
/// (no touching neighbours, no inactive contact left approaching), the same bits. The pivots
/// on inactive contacts resolve in one problem what that loop left to a sequence of impacts
/// at one instant (a contact pushed into approach by its neighbour's impulse). Returns
/// (contact, P) pairs of the active set.
pub fn lcp_impulses(
    contacts: &[ContactGeom],
    set: &[usize],
    target: &[f64],
    n_active: usize,
    time: f64,
) -> Result<Vec<(usize, f64)>, SolverError> {
    let n = set.len();
    let mut active = vec![false; n];
    active[..n_active.min(n)].iter_mut().for_each(|a| *a = true);
    let tol = 1e-9 * target.iter().fold(0.0_f64, |m, t| m.max(t.abs()));
    // W of the whole set once; each pivot solves its active block (the same entries, so the
    // same bits, as `solve_delassus` on the active contacts).
    let w = delassus(contacts, set);
    // Pivots: a handful for problems of this size; the bound only guards against a singular
    // W that slipped through the solve's pivot test.
    let limit = 1usize << n.min(16);
    for _ in 0..=limit {
        let on: Vec<usize> = (0..n).filter(|&k| active[k]).collect();
        let p = if on.is_empty() {
            vec![]
        } else {
            let block = on.iter().map(|&a| on.iter().map(|&b| w[a][b]).collect());
            let rhs = on.iter().map(|&k| target[k]).collect();
            solve_checked(block.collect(), rhs).ok_or_else(|| SolverError::SingularContact {
                time,
                contacts: on.iter().map(|&k| set[k]).collect(),
                context: "impulses of simultaneous closures".to_string(),
            })?
        };
        let mut pk = p.iter();
        let flip = (0..n).find(|&k| {
            if active[k] {
                *pk.next().unwrap() < 0.0
            } else {
                let wp: f64 = on.iter().zip(&p).map(|(&a, &pa)| w[k][a] * pa).sum();
                wp - target[k] < -tol
            }
        });
        match flip {
            None => return Ok(on.into_iter().map(|k| set[k]).zip(p).collect()),
            Some(k) => active[k] = !active[k],
        }
    }
    Err(SolverError::SingularContact {
        time,
        contacts: set.to_vec(),
        context: format!(
            "impulses of simultaneous closures: no complementary impulses after {limit} pivots"
        ),
    })
}

/// Adds the contacts `touching` (those not already in `set`) to an impact's problem as
/// touching neighbours: target v⁻ (m/s, `approach(c)`), which may be negative (see
/// [`lcp_impulses`]; they start inactive, after the others).
pub fn add_touching(
    set: &mut Vec<usize>,
    target: &mut Vec<f64>,
    touching: impl IntoIterator<Item = usize>,
    approach: impl Fn(usize) -> f64,
) {
    add_participants(set, target, touching, approach);
}

/// Applies Δq̇ = −Σ g_c P_c.
pub fn apply(contacts: &[ContactGeom], impulses: &[(usize, f64)], v: &mut [f64]) {
    apply_set(contacts, impulses.iter().copied(), v);
}

/// [`apply`] of the pairs (contact, impulse) `impulses` yields, in its order (the same
/// operations: no list of pairs is built).
pub fn apply_set(
    contacts: &[ContactGeom],
    impulses: impl IntoIterator<Item = (usize, f64)>,
    v: &mut [f64],
) {
    for (c, p) in impulses {
        for (vn, gn) in v.iter_mut().zip(&contacts[c].g) {
            *vn -= gn * p;
        }
    }
}

/// The paper's impulse (eqs 23–24) for each contact of `set` from the pre-impact modal
/// velocities `v`: applies Δq̇ = Φᵀ M Δẏ and returns the intended impulse m_k |Δẏ_k| per contact.
pub fn apply_paper(
    modal: &Modal,
    contacts: &[ContactGeom],
    set: &[usize],
    v: &mut [f64],
) -> Vec<(usize, f64)> {
    let v_before = v.to_vec();
    let mut out = Vec::new();
    for &c in set {
        let ct = &contacts[c];
        let rl = modal.floor_row(ct.left, ct.left_dof);
        let rr = modal.floor_row(ct.right, ct.right_dof);
        // Floor velocities before (k = left floor, l = right floor).
        let yk: f64 = rl.iter().zip(&v_before).map(|(a, b)| a * b).sum();
        let yl: f64 = rr.iter().zip(&v_before).map(|(a, b)| a * b).sum();
        let (mk, ml, e) = (ct.m_left, ct.m_right, ct.restitution);
        let (dyk, dyl) = if ct.wall {
            // m_l → ∞ with ẏ_l = 0 (the wall): eq (24) gives ẏ_k⁺ = −e ẏ_k.
            (-(1.0 + e) * yk, 0.0)
        } else {
            // eq (23): ẏ_l⁺; eq (24) (l for the printed i): ẏ_k⁺.
            let yl_after = (ml * yl + mk * yk - e * mk * (yl - yk)) / (ml + mk);
            let yk_after = (mk * yk + ml * yl + e * ml * (yl - yk)) / (ml + mk);
            (yk_after - yk, yl_after - yl)
        };
        // Δq̇ = Φᵀ M Δẏ: only the contact floor is nonzero.
        for n in 0..v.len() {
            v[n] += rl[n] * mk * dyk;
            if !ct.wall {
                v[n] += rr[n] * ml * dyl;
            }
        }
        out.push((c, (mk * dyk).abs()));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three unit masses in a row (mass-scaled rows g: A − B and B − C), the first contact
    /// approaching at 1 m/s with e = 1, the second touching.
    fn chain() -> Vec<ContactGeom> {
        let geom = |g: Vec<f64>| ContactGeom {
            left: 0,
            right: 0,
            left_dof: 0,
            right_dof: 0,
            gap: 0.0,
            restitution: 1.0,
            g,
            m_left: 1.0,
            m_right: 1.0,
            wall: false,
        };
        vec![geom(vec![1.0, -1.0, 0.0]), geom(vec![0.0, 1.0, -1.0])]
    }

    /// The impulse on A − B alone (P = 2/W = 1) would push B into C at 0.9 m/s, a second
    /// impact at the same instant: with B − C as a touching neighbour (separating at 0.1 m/s)
    /// the problem is solved at once, W P = (2, −0.1): P = (1.3, 0.6), A − B leaves at −1 m/s
    /// (restitution exact) and B − C at 0 (its target: touching, not approaching).
    #[test]
    fn a_touching_neighbour_pushed_into_approach_takes_an_impulse() {
        let c = chain();
        let (v0, v1) = (1.0, -0.1);
        let p = lcp_impulses(&c, &[0, 1], &[2.0 * v0, v1], 1, 0.0).unwrap();
        assert_eq!(p.len(), 2);
        assert!(
            (p[0].1 - 1.3).abs() < 1e-15 && (p[1].1 - 0.6).abs() < 1e-15,
            "{p:?}"
        );
        let w = |a: usize, b: usize| c[a].dot(&c[b].g);
        let after0 = v0 - (w(0, 0) * p[0].1 + w(0, 1) * p[1].1);
        let after1 = v1 - (w(1, 0) * p[0].1 + w(1, 1) * p[1].1);
        assert!(
            (after0 + 1.0).abs() < 1e-15 && after1.abs() < 1e-15,
            "{after0} {after1}"
        );
    }

    /// A neighbour separating fast enough (2 m/s) takes no impulse: the answer is the impact's
    /// alone, bit for bit the solve of the impacting contact.
    #[test]
    fn a_neighbour_that_stays_apart_changes_nothing() {
        let c = chain();
        let p = lcp_impulses(&c, &[0, 1], &[2.0, -2.0], 1, 0.0).unwrap();
        let alone = solve_delassus(&c, &[0], vec![2.0], 0.0, "").unwrap();
        assert_eq!(p, vec![(0, alone[0])]);
        // All active at the start (the drop-only loop's start) gives the same.
        assert_eq!(lcp_impulses(&c, &[0, 1], &[2.0, -2.0], 2, 0.0).unwrap(), p);
    }

    /// One elimination solves several right-hand sides: a system that needs row exchanges
    /// (a zero leading pivot) against its exact solutions, the same matrix refused when
    /// singular.
    #[test]
    fn an_eliminated_matrix_solves_each_right_hand_side() {
        let a = vec![
            vec![0.0, 2.0, 1.0],
            vec![1.0, 1.0, 0.0],
            vec![3.0, 0.0, 1.0],
        ];
        let f = Factored::new(a.clone()).unwrap();
        for x in [[1.0, 2.0, 3.0], [-0.5, 0.25, 4.0]] {
            let b: Vec<f64> = a
                .iter()
                .map(|r| r.iter().zip(&x).map(|(p, q)| p * q).sum())
                .collect();
            let got = f.solve(b.clone()).unwrap();
            for (g, w) in got.iter().zip(&x) {
                assert!(
                    (g - w).abs() <= 8.0 * f64::EPSILON * w.abs().max(1.0),
                    "{got:?} vs {x:?}"
                );
            }
            assert_eq!(Some(got), solve_checked(a.clone(), b));
        }
        let singular = vec![vec![1.0, 2.0], vec![2.0, 4.0]];
        assert!(Factored::new(singular).is_none());
    }
}
