//! The contact rows in mass-scaled physical coordinates, so that the momentum method's
//! impulse code ([`crate::momentum::impulse`]) applies unchanged.
//!
//! With w = M^½ v (and likewise for displacements) the kinetic energy is ½ wᵀw, as ½ q̇ᵀq̇
//! is in mass-normalised modal coordinates. Contact c has the row G_c = e_l − e_r (e_l
//! alone for a wall) in physical coordinates and g_c = M^−½ G_cᵀ in scaled ones:
//!
//! ```text
//! g_c,i = +1/√m_l at the left floor, −1/√m_r at the right floor, 0 elsewhere
//! v_c = g_c·w = u̇_l − u̇_r,   W_ab = g_a·g_b = G_a M⁻¹ G_bᵀ   (Delassus matrix)
//! Δw = −g_c P_c   ⇔   Δv = −M⁻¹ G_cᵀ P_c
//! ```
//!
//! With all modes the modal row is Φᵀ G_cᵀ and Φ Φᵀ = M⁻¹ (mass-normalised shapes), so
//! both W are the same matrix: the impulses are the momentum method's to round-off.

use structure::Scene;

use crate::gap::System;
use crate::momentum::impulse::{solve_checked, ContactGeom};
use crate::SolverError;

/// One [`ContactGeom`] per scene contact, its row `g` over all floors in mass-scaled
/// coordinates (see the module docs).
pub(crate) fn geometry(sys: &System, scene: &Scene) -> Vec<ContactGeom> {
    scene
        .contacts
        .iter()
        .zip(&sys.contacts)
        .map(|(c, cd)| {
            let mut g = vec![0.0; sys.n];
            g[cd.l] = 1.0 / sys.mass[cd.l].sqrt();
            if !cd.wall {
                g[cd.r] -= 1.0 / sys.mass[cd.r].sqrt();
            }
            ContactGeom {
                left: c.left,
                right: c.right,
                left_dof: c.left_dof,
                right_dof: c.right_dof,
                gap: c.gap,
                restitution: c.restitution,
                g,
                m_left: sys.mass[cd.l],
                m_right: if cd.wall {
                    f64::INFINITY
                } else {
                    sys.mass[cd.r]
                },
                wall: cd.wall,
            }
        })
        .collect()
}

/// The inverse of the Delassus matrix of the held contacts `set`, row-major, computed once
/// per change of the held set (the right-hand side applies it at every stage).
pub(crate) fn delassus_inverse(
    geoms: &[ContactGeom],
    set: &[usize],
    time: f64,
) -> Result<Vec<f64>, SolverError> {
    let k = set.len();
    let w = crate::momentum::impulse::delassus(geoms, set);
    let mut inv = vec![0.0; k * k];
    for col in 0..k {
        let mut e = vec![0.0; k];
        e[col] = 1.0;
        let x = solve_checked(w.clone(), e).ok_or_else(|| SolverError::SingularContact {
            time,
            contacts: set.to_vec(),
            context: "holding forces of a persistent-contact phase".into(),
        })?;
        for (row, xv) in x.into_iter().enumerate() {
            inv[row * k + col] = xv;
        }
    }
    Ok(inv)
}

/// Physical → mass-scaled: out_i = √m_i x_i.
pub(crate) fn scale(sys: &System, x: &[f64]) -> Vec<f64> {
    x.iter()
        .zip(&sys.mass)
        .map(|(xi, m)| xi * m.sqrt())
        .collect()
}

/// Mass-scaled → physical, into `x`: x_i = w_i / √m_i.
pub(crate) fn unscale(sys: &System, w: &[f64], x: &mut [f64]) {
    for ((xi, wi), m) in x.iter_mut().zip(w).zip(&sys.mass) {
        *xi = wi / m.sqrt();
    }
}
