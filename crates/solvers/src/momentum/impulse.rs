//! Contact geometry in modal coordinates and the impact impulses (paper eqs 19–24).
//!
//! Contact c joins floor i of building L to floor j of building R, or to a rigid wall that
//! moves with the ground (then g_c = (φ_L[i]) alone and v_c is the floor's own velocity
//! relative to the ground). With the dense modal row
//! g_c = (φ_L[i] on L's modes, −φ_R[j] on R's modes), the gap function and the relative
//! (approach) velocity are δ_c = g_c·q − gap and v_c = g_c·q̇. An impulse pair P_c ≥ 0
//! pushes the floors apart: Δq̇ = −g_c P_c, so Δv = −W P with the Delassus matrix
//! W_ab = g_a·g_b (W_cc = Σ_kept φ_L[i]² + Σ_kept φ_R[j]²).
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
pub fn solve_checked(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    let scale = (0..n).map(|k| a[k][k].abs()).fold(0.0, f64::max);
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if !(a[p][k].abs() > 1e-12 * scale) {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        for i in k + 1..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
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
    for c in held {
        if !set.contains(&c) {
            set.push(c);
            target.push(approach(c).max(0.0));
        }
    }
}

/// Non-negative impulses P on `set` with W P = target on the retained contacts (the
/// others get P = 0): solve, drop the most negative, repeat. Returns (contact, P) pairs.
pub fn lcp_impulses(
    contacts: &[ContactGeom],
    set: &[usize],
    target: &[f64],
    time: f64,
) -> Result<Vec<(usize, f64)>, SolverError> {
    let mut active: Vec<usize> = (0..set.len()).collect();
    loop {
        if active.is_empty() {
            return Ok(vec![]);
        }
        let ids: Vec<usize> = active.iter().map(|&k| set[k]).collect();
        let rhs: Vec<f64> = active.iter().map(|&k| target[k]).collect();
        let p = solve_delassus(
            contacts,
            &ids,
            rhs,
            time,
            "impulses of simultaneous closures",
        )?;
        let (worst, pmin) =
            p.iter().enumerate().fold(
                (0, f64::INFINITY),
                |m, (i, &x)| if x < m.1 { (i, x) } else { m },
            );
        if pmin >= 0.0 {
            return Ok(ids.into_iter().zip(p).collect());
        }
        active.remove(worst);
    }
}

/// Applies Δq̇ = −Σ g_c P_c.
pub fn apply(contacts: &[ContactGeom], impulses: &[(usize, f64)], v: &mut [f64]) {
    for &(c, p) in impulses {
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
