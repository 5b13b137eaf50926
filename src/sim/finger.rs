//! One finger's dynamics (MODEL.md §8.1–8.6) against an object it is given: the object
//! centre in the finger's local frame and the contact memories of its two phalanges. A
//! scene places the object and combines the fingers (the centred scene mirrors one finger;
//! an offset scene evaluates two, each with its own centre).

use super::integrate::Piece;
use super::memory::Memory;
use crate::math::V2;
use crate::model::Kin;
use crate::model::{capsule, flores_normal, CapsuleGeom, CapsulePart, FrictionLaw};
use crate::model::{gravity_potential, gravity_tree, reduce_tree_force, reduced};
use crate::model::{Finger, Pose};
use crate::params::SceneParams;
use nalgebra::{Matrix2, Vector2};

/// A kink of one finger's right-hand side: the flags of its smooth [`Piece`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kink {
    /// The distal stop is engaged (φ = −θ2 > 0).
    StopEngaged,
    /// The stop force is clipped at zero by its damping term.
    StopClipped,
    /// Contact `i` (0 proximal, 1 distal) carries a load.
    ContactLoaded(usize),
    /// Contact `i`'s force is clipped at zero by its damping term.
    ContactClipped(usize),
}

impl Kink {
    /// Flags used by one finger (a scene with several fingers offsets finger j's by
    /// `j * Kink::BITS`).
    pub const BITS: u32 = 6;

    /// The flag bit of this kink.
    #[inline(always)]
    pub const fn bit(self) -> u32 {
        match self {
            Kink::StopEngaged => 0,
            Kink::StopClipped => 1,
            Kink::ContactLoaded(i) => 2 + 2 * i as u32,
            Kink::ContactClipped(i) => 3 + 2 * i as u32,
        }
    }
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
    /// The smooth piece of the right-hand side (see [`crate::sim::integrate::Rhs::piece`]).
    pub piece: Piece,
}

impl FingerEval {
    /// True when a knuckle cap (O22, shared by both capsules) carries a contact.
    pub fn knuckle_contact(&self) -> bool {
        (self.contacts[0].geom.part == CapsulePart::End && self.contacts[0].normal_force > 0.0)
            || (self.contacts[1].geom.part == CapsulePart::Start && self.contacts[1].normal_force > 0.0)
    }
}

/// One finger's linkage at a state, without contacts ([`FingerModel::linkage`]): a scene
/// that computes the contacts itself adds their generalised forces to `gf`.
#[derive(Debug, Clone, Copy)]
pub struct FingerLinkage {
    /// Linkage pose (q12, q13 not computed: NaN).
    pub pose: Pose,
    /// Kinematics.
    pub kin: Kin,
    /// Mass matrix.
    pub m: Matrix2<f64>,
    /// Velocity-dependent bias c (M q̈ = gf − c).
    pub c: Vector2<f64>,
    /// Direction of the distal phalanx.
    pub xd: V2,
    /// θ2 (NaN where not needed, see [`FingerModel::evaluate`]).
    pub theta2: f64,
    /// θ̇2.
    pub theta2_dot: f64,
    /// Generalised applied forces: actuator, spring, stop, gravity.
    pub gf: Vector2<f64>,
    /// Potential energy of those (NaN unless `full`).
    pub v: f64,
    /// The smooth piece (stop flags).
    pub piece: Piece,
}

impl FingerLinkage {
    /// sin q13 = cross(x12, x22) (parallel singularity at 0).
    #[inline]
    pub fn sin_q13(&self) -> f64 {
        crate::math::cross(self.pose.x12, self.pose.x22)
    }

    /// Kinetic plus potential energy at rates `qd` (NaN unless evaluated `full`).
    #[inline]
    pub fn energy(&self, qd: Vector2<f64>) -> f64 {
        0.5 * qd.dot(&(self.m * qd)) + self.v
    }
}

/// Constants of one finger's dynamics.
#[derive(Debug, Clone, Copy)]
pub struct FingerModel<'a> {
    /// The finger.
    pub finger: &'a Finger,
    /// Actuator torque τ.
    pub tau: f64,
    /// Spring preload τ_s0.
    pub tau_s0: f64,
    /// Spring rate k_s.
    pub k_s: f64,
    /// Stop stiffness.
    pub k_stop: f64,
    /// Stop damping factor.
    pub c_stop: f64,
    /// Hertz stiffness.
    pub k_contact: f64,
    /// Flores χ.
    pub chi: f64,
    /// Friction law.
    pub friction: FrictionLaw,
    /// R + w.
    pub rw: f64,
    /// SceneParams (gravity).
    pub scene: &'a SceneParams,
}

impl<'a> FingerModel<'a> {
    /// The finger of `scene` with spring preload `tau_s0`.
    pub fn new(finger: &'a Finger, scene: &'a SceneParams, tau_s0: f64) -> Self {
        FingerModel {
            finger,
            tau: scene.hand.tau,
            tau_s0,
            k_s: scene.hand.k_s,
            k_stop: scene.hand.k_stop,
            c_stop: scene.hand.c_stop,
            k_contact: scene.contact.k_contact,
            chi: scene.contact.chi(),
            friction: FrictionLaw {
                mu_s: scene.contact.mu_s,
                mu_d: scene.contact.mu_d,
                v_s: scene.contact.v_s,
                v_d: scene.contact.v_d,
            },
            rw: scene.object.radius + scene.hand.w,
            scene,
        }
    }

    /// Capsule geometry of both phalanges at a pose against the object centred at `centre`
    /// (local frame).
    #[inline]
    pub fn geometry(&self, p: &Pose, centre: V2) -> [CapsuleGeom; 2] {
        let xd = self.finger.distal_dir(p);
        [self.phalanx(p, xd, centre, 0), self.phalanx(p, xd, centre, 1)]
    }

    /// Capsule geometry of phalanx `i` (0 proximal, 1 distal, of direction `xd`) at pose `p`
    /// against the object centred at `centre` (local frame).
    #[inline(always)]
    pub fn phalanx(&self, p: &Pose, xd: V2, centre: V2, i: usize) -> CapsuleGeom {
        let f = self.finger;
        if i == 0 {
            capsule(f.o21, p.x21, f.l21, centre, self.rw, f.w)
        } else {
            capsule(p.o22, xd, f.t22, centre, self.rw, f.w)
        }
    }

    /// The linkage part of [`FingerModel::evaluate`] (everything but the contacts) at joint
    /// angles `q` and rates `qd`; `None` where the DGM or kinematics fail. `full` as there.
    #[inline(always)]
    pub fn linkage(&self, q: Vector2<f64>, qd: Vector2<f64>, full: bool) -> Option<FingerLinkage> {
        let f = self.finger;
        let mut pose = f.dgm_fast(q[0], q[1]).ok()?;
        let kin = Kin::new(f, &pose)?;
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
        let mut piece = Piece::SMOOTH;
        // actuator, spring, stop, gravity
        let spring = if self.k_s != 0.0 { self.tau_s0 + self.k_s * theta2 } else { self.tau_s0 };
        let mut gf = Vector2::new(self.tau, 0.0) - spring * j;
        let mut v =
            if full { -self.tau * q[0] + self.tau_s0 * theta2 + 0.5 * self.k_s * theta2 * theta2 } else { f64::NAN };
        let phi = -theta2;
        if phi > 0.0 {
            piece = piece.with(Kink::StopEngaged.bit());
            let damp = 1.0 + self.c_stop * (-theta2_dot);
            if damp <= 0.0 {
                piece = piece.with(Kink::StopClipped.bit());
            }
            gf += (self.k_stop * phi * damp).max(0.0) * j;
            v += 0.5 * self.k_stop * phi * phi;
        }
        if gravity {
            gf += reduce_tree_force(&kin, gravity_tree(f, &pose, self.scene));
            if full {
                v += gravity_potential(f, &pose, self.scene);
            }
        }
        Some(FingerLinkage { pose, kin, m: red.m, c: red.c, xd, theta2, theta2_dot, gf, v, piece })
    }

    /// The model at joint angles `q` = (q11, q21) and rates `qd` against the object
    /// centred at `centre` (local frame) with contact memories `mem` (`touch = false`:
    /// the phalanges pass through the object); `None` where the DGM or kinematics fail.
    /// `full = false` is a right-hand side's lean path: the energy is NaN and θ2 (one
    /// `atan2`) is computed only where a force needs it — a spring rate k_s ≠ 0, in-plane
    /// gravity, or the stop engaged (sin θ2 < 0, equivalent to θ2 < 0 for θ2 = q22 + ψ with
    /// q22 ∈ (−π, π] and ψ > 0); otherwise θ2 is NaN.
    #[inline(always)]
    pub fn evaluate(
        &self,
        q: Vector2<f64>,
        qd: Vector2<f64>,
        centre: V2,
        mem: &[Memory; 2],
        touch: bool,
        full: bool,
    ) -> Option<FingerEval> {
        let f = self.finger;
        let FingerLinkage { pose, kin, m, c: bias, xd, theta2, theta2_dot, mut gf, mut v, mut piece } =
            self.linkage(q, qd, full)?;
        let geo = [self.phalanx(&pose, xd, centre, 0), self.phalanx(&pose, xd, centre, 1)];
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
            if touch && mem[i].active && g.delta > 0.0 {
                piece = piece.with(Kink::ContactLoaded(i).bit());
                if 1.0 + self.chi * c.delta_dot / mem[i].vminus <= 0.0 {
                    piece = piece.with(Kink::ContactClipped(i).bit());
                }
                let fnm = flores_normal(self.k_contact, self.chi, g.delta, c.delta_dot, mem[i].vminus);
                let ft = -self.friction.mu(c.slip) * fnm;
                let force = -fnm * g.normal + ft * g.tangent;
                gf += jp.transpose() * force;
                object_force -= force;
                c.normal_force = fnm;
                c.friction_force = ft;
                if full {
                    v += 0.4 * self.k_contact * g.delta * g.delta * g.delta.sqrt();
                }
            }
        }
        let q_total = gf - bias;
        let minv = crate::math::inv2(&m)?;
        let qdd = minv * q_total;
        let energy = if full { 0.5 * qd.dot(&(m * qd)) + v } else { f64::NAN };
        let sin_q13 = crate::math::cross(pose.x12, pose.x22);
        Some(FingerEval {
            pose,
            kin,
            m,
            q_total,
            qdd,
            contacts,
            object_force,
            theta2,
            theta2_dot,
            energy,
            sin_q13,
            piece,
        })
    }
}
