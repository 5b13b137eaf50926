//! Compliant static equilibrium of one finger on a fixed object (MODEL.md §8.9).

use super::finger::{FingerEval, FingerModel};
use super::memory::Memory;
use crate::math::V2;
use crate::model::closed_pose;
use crate::params::SceneParams;
use nalgebra::{Matrix2, Vector2};

/// Compliant static equilibrium (§8.9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Equilibrium {
    /// q* = (q11, q21).
    pub q: Vector2<f64>,
    /// V(q*).
    pub v_star: f64,
    /// f*.
    pub fstar: [f64; 2],
}

/// Damped Newton iteration of §8.9 for the finger `model` on the object centred at
/// `centre` (local frame; its x selects the rigid closed pose of §6.1), started at the
/// rigid closed pose pre-penetrated along the contact rows by the static forces `f0`.
pub fn finger_equilibrium(model: &FingerModel, centre: V2, s: &SceneParams, f0: [f64; 2]) -> Option<Equilibrium> {
    let mem = [Memory { active: true, vminus: 1.0 }; 2];
    let f = model.finger;
    let cp = closed_pose(f, s.object.radius, centre.x).ok()?;
    let at =
        |q: Vector2<f64>| -> Option<FingerEval> { model.evaluate(q, Vector2::new(0.0, 0.0), centre, &mem, true, true) };
    let q_rigid = Vector2::new(cp.pose.q11, cp.pose.q21);
    let e0 = at(q_rigid)?;
    let a = Matrix2::from_rows(&[e0.contacts[0].row.transpose(), e0.contacts[1].row.transpose()]);
    let dl = Vector2::new(
        (f0[0].max(0.0) / s.contact.k_contact).powf(2.0 / 3.0),
        (f0[1].max(0.0) / s.contact.k_contact).powf(2.0 / 3.0),
    );
    let mut q = q_rigid + a.try_inverse()? * dl;
    let tol = 1e-9 * s.hand.tau;
    for _ in 0..2000 {
        let r = at(q)?.q_total;
        if r.amax() < tol {
            let ev = at(q)?;
            return Some(Equilibrium {
                q,
                v_star: ev.energy,
                fstar: [ev.contacts[0].normal_force, ev.contacts[1].normal_force],
            });
        }
        let h = 1e-9;
        let mut jac = Matrix2::zeros();
        for j in 0..2 {
            let mut qp = q;
            let mut qm = q;
            qp[j] += h;
            qm[j] -= h;
            jac.set_column(j, &((at(qp)?.q_total - at(qm)?.q_total) / (2.0 * h)));
        }
        let mut dq = -(jac.try_inverse()? * r);
        let m = dq.amax();
        if m > 2e-5 {
            dq *= 2e-5 / m;
        }
        q += dq;
    }
    None
}
