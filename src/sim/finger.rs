//! The finger ODE of the fixed-object grasp scene (MODEL.md §8): state
//! y = (q11, q21, q̇11, q̇21, F̄_y) — one finger's four mechanical states plus the low-pass
//! filtered hand force of the force criterion (§9.3). With the object fixed and centred,
//! finger 2 is the mirror image of finger 1, so one finger is integrated. The object centre
//! is a field (`centre`), so an offset scene reuses this code.

use crate::math::V2;
use crate::model::contact::{capsule, flores_normal, CapsuleGeom, CapsulePart, FrictionLaw};
use crate::model::dynamics::{gravity_potential, gravity_tree, reduce_tree_force, reduced};
use crate::model::geometry::{Finger, Pose};
use crate::model::kinematics::Kin;
use crate::params::SceneParams;
use crate::sim::integrator::Rhs;
use nalgebra::{Matrix2, SVector, Vector2};

/// State dimension.
pub const NS: usize = 5;
/// State vector.
pub type State = SVector<f64, NS>;

/// Contact memory of one phalanx (§8.5): active between onset and separation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Memory {
    /// Between onset and separation.
    pub active: bool,
    /// Captured onset velocity δ̇⁻ (floored at v_min).
    pub vminus: f64,
}

/// Everything about one phalanx contact at a state.
#[derive(Debug, Clone, Copy)]
pub struct ContactState {
    /// Capsule geometry.
    pub geom: CapsuleGeom,
    /// Contact row a (δ̇ = a q̇_a).
    pub row: Vector2<f64>,
    /// Point Jacobian.
    pub jp: Matrix2<f64>,
    /// Penetration rate δ̇.
    pub delta_dot: f64,
    /// Slip velocity u of the finger point along t_c.
    pub slip: f64,
    /// Normal force magnitude F_n.
    pub normal_force: f64,
    /// Friction force F_t (along t_c, on the finger).
    pub friction_force: f64,
}

/// Full evaluation of the finger at a state.
#[derive(Debug, Clone, Copy)]
pub struct FingerEval {
    /// Linkage pose (q12, q13 not computed: NaN; use `sin_q13`).
    pub pose: Pose,
    /// sin q13 = cross(x12, x22) (parallel singularity at 0).
    pub sin_q13: f64,
    /// Kinematics.
    pub kin: Kin,
    /// Mass matrix.
    pub m: Matrix2<f64>,
    /// Total generalised force minus bias: M q̈ = q_total.
    pub q_total: Vector2<f64>,
    /// Accelerations q̈_a.
    pub qdd: Vector2<f64>,
    /// Proximal (0) and distal (1) contacts.
    pub contacts: [ContactState; 2],
    /// Force of this finger on the object (local frame).
    pub object_force: V2,
    /// θ2.
    pub theta2: f64,
    /// θ̇2.
    pub theta2_dot: f64,
    /// Total energy E = T + V.
    pub energy: f64,
    /// The smooth piece of the right-hand side (see [`Rhs::piece`]).
    pub piece: u64,
}

/// Constants of the finger ODE.
#[derive(Debug, Clone, Copy)]
pub struct FingerOde<'a> {
    /// The finger.
    pub finger: &'a Finger,
    /// Actuator torque τ.
    pub tau: f64,
    /// Spring preload τ_s0.
    pub tau_s0: f64,
    /// Spring rate k_s.
    pub k_s: f64,
    /// Stop stiffness and damping.
    pub k_stop: f64,
    /// Stop damping factor.
    pub c_stop: f64,
    /// Hertz stiffness.
    pub k_contact: f64,
    /// Flores χ.
    pub chi: f64,
    /// Friction law.
    pub friction: FrictionLaw,
    /// Object centre in the finger's local frame.
    pub centre: V2,
    /// R + w.
    pub rw: f64,
    /// Filter time constant T_f.
    pub t_filter: f64,
    /// Scene constants (gravity, contact law).
    pub scene: &'a SceneParams,
    /// Contact memories.
    pub mem: [Memory; 2],
    /// Contacts enabled (false: free finger, for energy tests).
    pub contacts_enabled: bool,
    /// RHS evaluations (counted here so that event location is counted too).
    pub evals: u64,
    /// The full evaluation at the end of the last accepted step (see [`FingerOde::take_accepted`]).
    accepted: Option<(State, FingerEval)>,
}

impl<'a> FingerOde<'a> {
    /// The finger of the grasp scene closing on the object centred at local (x_c, R).
    pub fn new(finger: &'a Finger, scene: &'a SceneParams, tau_s0: f64, x_c: f64) -> Self {
        FingerOde {
            finger,
            tau: scene.hand.tau,
            tau_s0,
            k_s: scene.hand.k_s,
            k_stop: scene.hand.k_stop,
            c_stop: scene.hand.c_stop,
            k_contact: scene.contact.k_contact,
            chi: scene.contact.chi(),
            friction: FrictionLaw { mu_s: scene.contact.mu_s, mu_d: scene.contact.mu_d, v_s: scene.contact.v_s, v_d: scene.contact.v_d },
            centre: V2::new(x_c, scene.object.radius),
            rw: scene.object.radius + scene.hand.w,
            t_filter: scene.criteria.t_filter,
            scene,
            mem: [Memory::default(); 2],
            contacts_enabled: true,
            evals: 0,
            accepted: None,
        }
    }

    /// Capsule geometry of both phalanges at a pose.
    #[inline]
    pub fn geometry(&self, p: &Pose) -> [CapsuleGeom; 2] {
        let f = self.finger;
        let xd = f.distal_dir(p);
        [
            capsule(f.o21, p.x21, f.l21, self.centre, self.rw, f.w),
            capsule(p.o22, xd, f.t22, self.centre, self.rw, f.w),
        ]
    }

    /// Evaluate the full model at state `y`; `None` where the DGM or kinematics fail.
    #[inline]
    pub fn evaluate(&self, y: &State) -> Option<FingerEval> {
        self.evaluate_with(y, true)
    }

    /// The model at `y`. `full = false` is the right-hand side's lean path: the energy is
    /// NaN and θ2 (one `atan2`) is computed only where a force needs it — a spring rate
    /// k_s ≠ 0, in-plane gravity, or the stop engaged (sin θ2 < 0, equivalent to θ2 < 0 for
    /// θ2 = q22 + ψ with q22 ∈ (−π, π] and ψ > 0); otherwise θ2 is NaN.
    #[inline(always)]
    fn evaluate_with(&self, y: &State, full: bool) -> Option<FingerEval> {
        let f = self.finger;
        let mut pose = f.dgm_fast(y[0], y[1]).ok()?;
        let kin = Kin::new(f, &pose)?;
        let qd = Vector2::new(y[2], y[3]);
        let red = reduced(f, &pose, &kin, qd);
        let j = kin.j_row();
        let xd = f.distal_dir(&pose);
        let gravity = self.scene.env.g_eq != 0.0;
        let theta2 = if full || gravity || self.k_s != 0.0 || crate::math::cross(pose.x21, xd) < 0.0 {
            pose.q22 = pose.q22_from_vectors();
            pose.q22 + f.psi
        } else {
            f64::NAN
        };
        let theta2_dot = j.dot(&qd);
        let mut piece = 0u64;
        // actuator, spring, stop, gravity
        let spring = if self.k_s != 0.0 { self.tau_s0 + self.k_s * theta2 } else { self.tau_s0 };
        let mut q = Vector2::new(self.tau, 0.0) - spring * j;
        let mut v = if full { -self.tau * y[0] + self.tau_s0 * theta2 + 0.5 * self.k_s * theta2 * theta2 } else { f64::NAN };
        let phi = -theta2;
        if phi > 0.0 {
            piece |= 1;
            let damp = 1.0 + self.c_stop * (-theta2_dot);
            if damp <= 0.0 {
                piece |= 2;
            }
            q += (self.k_stop * phi * damp).max(0.0) * j;
            v += 0.5 * self.k_stop * phi * phi;
        }
        if gravity {
            q += reduce_tree_force(&kin, gravity_tree(f, &pose, self.scene));
            if full {
                v += gravity_potential(f, &pose, self.scene);
            }
        }
        let geo = [capsule(f.o21, pose.x21, f.l21, self.centre, self.rw, f.w), capsule(pose.o22, xd, f.t22, self.centre, self.rw, f.w)];
        let mut object_force = V2::zeros();
        let mut contacts = [ContactState {
            geom: geo[0],
            row: Vector2::zeros(),
            jp: Matrix2::zeros(),
            delta_dot: 0.0,
            slip: 0.0,
            normal_force: 0.0,
            friction_force: 0.0,
        }; 2];
        for i in 0..2 {
            let g = geo[i];
            let jp = kin.point_jacobian(f, &pose, g.point, i == 1);
            let vp = jp * qd;
            let c = &mut contacts[i];
            c.geom = g;
            c.jp = jp;
            c.row = jp.transpose() * g.normal;
            c.delta_dot = g.normal.dot(&vp);
            c.slip = g.tangent.dot(&vp);
            if self.contacts_enabled && self.mem[i].active && g.delta > 0.0 {
                piece |= 4 << (2 * i);
                if 1.0 + self.chi * c.delta_dot / self.mem[i].vminus <= 0.0 {
                    piece |= 8 << (2 * i);
                }
                let fnm = flores_normal(self.k_contact, self.chi, g.delta, c.delta_dot, self.mem[i].vminus);
                let ft = -self.friction.mu(c.slip) * fnm;
                let force = -fnm * g.normal + ft * g.tangent;
                q += jp.transpose() * force;
                object_force -= force;
                c.normal_force = fnm;
                c.friction_force = ft;
                if full {
                    v += 0.4 * self.k_contact * g.delta * g.delta * g.delta.sqrt();
                }
            }
        }
        let q_total = q - red.c;
        let minv = red.m.try_inverse()?;
        let qdd = minv * q_total;
        let energy = if full { 0.5 * qd.dot(&(red.m * qd)) + v } else { f64::NAN };
        let sin_q13 = crate::math::cross(pose.x12, pose.x22);
        Some(FingerEval { pose, kin, m: red.m, q_total, qdd, contacts, object_force, theta2, theta2_dot, energy, sin_q13, piece })
    }

    /// The full evaluation the integrator made at the end of its last accepted step, if
    /// that step ended at `y` (saves the driver a second evaluation per step).
    #[inline]
    pub fn take_accepted(&mut self, y: &State) -> Option<FingerEval> {
        match self.accepted.take() {
            Some((ya, ev)) if ya == *y => Some(ev),
            _ => None,
        }
    }

    /// Time derivative from a full evaluation (hand force F_hand,y = 2 × finger-1 force).
    #[inline]
    pub fn derivative(&self, y: &State, ev: &FingerEval) -> State {
        let hand_y = 2.0 * ev.object_force.y;
        State::from([y[2], y[3], ev.qdd[0], ev.qdd[1], (hand_y - y[4]) / self.t_filter])
    }

    /// True when a knuckle cap (O22, shared by both capsules) carries a contact.
    pub fn knuckle_contact(ev: &FingerEval) -> bool {
        (ev.contacts[0].geom.part == CapsulePart::End && ev.contacts[0].normal_force > 0.0)
            || (ev.contacts[1].geom.part == CapsulePart::Start && ev.contacts[1].normal_force > 0.0)
    }
}

impl Rhs<NS> for FingerOde<'_> {
    #[inline]
    fn eval(&mut self, _t: f64, y: &State) -> Option<State> {
        self.evals += 1;
        let ev = self.evaluate_with(y, false)?;
        Some(self.derivative(y, &ev))
    }

    /// Smooth piece: bit 0 stop engaged, bit 1 stop force clipped, bits 2+2i contact i
    /// loaded, bits 3+2i its force clipped by the damping term.
    fn piece(&self, y: &State) -> u64 {
        self.evaluate_with(y, false).map_or(u64::MAX, |ev| ev.piece)
    }

    #[inline]
    fn eval_piece(&mut self, _t: f64, y: &State) -> Option<(State, u64)> {
        self.evals += 1;
        let ev = self.evaluate_with(y, false)?;
        Some((self.derivative(y, &ev), ev.piece))
    }

    /// The full evaluation (its forces equal the lean one's), kept for the driver.
    fn eval_accepted(&mut self, _t: f64, y: &State) -> Option<(State, u64)> {
        self.evals += 1;
        let ev = self.evaluate_with(y, true)?;
        let out = (self.derivative(y, &ev), ev.piece);
        self.accepted = Some((*y, ev));
        Some(out)
    }
}
