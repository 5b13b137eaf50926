//! The free scene's parts, each computed on its own so that the block Jacobian
//! (`jacobian.rs`) can re-evaluate only what a perturbed state changes: the object's
//! kinematics ([`Body`]), one capsule contact's geometry and relative velocity
//! ([`CapsuleHit`]), one ground point's ([`GroundHit`]), and their loads. The right-hand
//! side (`eval_with`) adds them up in a fixed order.

use super::{FreeScene, St, G0, NC, Q0, V0, W0};
use crate::math::V2;
use crate::model::Pose;
use crate::sim::contact3d::{closest_segments, point_force, quat_matrix, V3};
use crate::sim::finger::FingerLinkage;
use nalgebra::{Matrix2, Matrix3, Vector2};

/// The object's kinematics at a state.
#[derive(Debug, Clone, Copy)]
pub(super) struct Body {
    /// Position of G.
    pub g: V3,
    /// Orientation (w, x, y, z), as stored (not normalised).
    pub q: [f64; 4],
    /// Rotation matrix of q/|q|.
    pub rot: Matrix3<f64>,
    /// Velocity of G.
    pub v: V3,
    /// Angular velocity (world).
    pub om: V3,
    /// The axis a.
    pub a: V3,
    /// The axis segment's start G − (L_c/2) a and its direction L_c a.
    pub p0: V3,
    /// L_c a.
    pub d2: V3,
}

/// One capsule contact (0–3 phalanges, 4 palm) against the object's axis segment.
#[derive(Debug, Clone, Copy)]
pub(super) struct CapsuleHit {
    /// Penetration δ.
    pub delta: f64,
    /// δ̇.
    pub dd: f64,
    /// Tangential relative velocity.
    pub u: V3,
    /// Contact normal (from the finger toward the object's axis).
    pub yc: V3,
    /// The object's material point P_o.
    pub po: V3,
    /// Velocity of the finger's material point P_f.
    pub vf: V3,
    /// The finger's point Jacobian at P_f (local frame; zero for the palm).
    pub jm: Matrix2<f64>,
    /// The closest point on the axis was clamped to an end.
    pub rim: bool,
}

/// One ground point of the base rim.
#[derive(Debug, Clone, Copy)]
pub(super) struct GroundHit {
    /// The point relative to G (world).
    pub rk: V3,
    /// Penetration δ.
    pub delta: f64,
    /// Velocity of the point.
    pub vp: V3,
}

/// Mirror factor of finger `i` (finger 2 is finger 1's mirror image in x).
#[inline(always)]
pub(super) fn mirror(i: usize) -> f64 {
    if i == 0 {
        1.0
    } else {
        -1.0
    }
}

impl FreeScene<'_> {
    /// The object's kinematics at `y`.
    #[inline(always)]
    pub(super) fn body(&self, y: &St) -> Body {
        let lc = self.s.object.length;
        let g = V3::new(y[G0], y[G0 + 1], y[G0 + 2]);
        let q = [y[Q0], y[Q0 + 1], y[Q0 + 2], y[Q0 + 3]];
        let rot = quat_matrix(q);
        let v = V3::new(y[V0], y[V0 + 1], y[V0 + 2]);
        let om = V3::new(y[W0], y[W0 + 1], y[W0 + 2]);
        let a = rot.column(2).into_owned();
        Body { g, q, rot, v, om, a, p0: g - a * (lc / 2.0), d2: a * lc }
    }

    /// The rates of finger `i` at `y` (zero when the fingers are not integrated).
    #[inline(always)]
    pub(super) fn finger_rates(&self, y: &St, i: usize) -> Vector2<f64> {
        if self.setup.fingers {
            Vector2::new(y[4 * i + 2], y[4 * i + 3])
        } else {
            Vector2::zeros()
        }
    }

    /// Capsule contact `k` (0–3: phalanx k % 2 of finger k / 2, with that finger's
    /// evaluation `fe` and rates `qd`; 4: the palm, `fe` unused) against the object `b`.
    #[inline(always)]
    pub(super) fn capsule_hit(&self, k: usize, fe: &FingerLinkage, qd: Vector2<f64>, b: &Body) -> CapsuleHit {
        let (r, w) = (self.s.object.radius, self.s.hand.w);
        let f = self.model.finger;
        let seg = if k < 4 { self.phalanx_segment(k, &fe.pose, fe.xd) } else { self.palm_segment() };
        let (n, qa, clamped) = Self::closest(seg, b);
        let dv = qa - n;
        let d = dv.norm();
        let yc = dv / d;
        let delta = r + w - d;
        let pf = n + yc * w;
        let po = qa - yc * r;
        let (vf, jm) = if k < 4 {
            let mx = mirror(k / 2);
            let pl = V2::new(mx * pf.x, pf.y);
            let jm = fe.kin.point_jacobian(f, &fe.pose, pl, k % 2 == 1);
            let vl = jm * qd;
            (V3::new(mx * vl.x, vl.y, 0.0), jm)
        } else {
            (V3::zeros(), Matrix2::zeros())
        };
        let mut h = CapsuleHit { delta, dd: 0.0, u: V3::zeros(), yc, po, vf, jm, rim: clamped };
        h.relative_velocity(b);
        h
    }

    /// The axis segment (start, start to end) of phalanx contact `k` (0–3: phalanx k % 2 of
    /// finger k / 2, at that finger's pose `p` with distal direction `xd`).
    #[inline(always)]
    fn phalanx_segment(&self, k: usize, p: &Pose, xd: V2) -> (V3, V3) {
        let f = self.model.finger;
        let (i, j) = (k / 2, k % 2);
        let mx = mirror(i);
        let (start, dir, len) = if j == 0 { (f.o21, p.x21, f.l21) } else { (p.o22, xd, f.t22) };
        (V3::new(mx * start.x, start.y, 0.0), V3::new(mx * dir.x * len, dir.y * len, 0.0))
    }

    /// The palm's axis segment (contact 4).
    #[inline(always)]
    fn palm_segment(&self) -> (V3, V3) {
        let hb = self.model.finger.o21.x;
        (V3::new(-hb, -self.s.hand.w, 0.0), V3::new(2.0 * hb, 0.0, 0.0))
    }

    /// The closest points of a capsule's axis segment `(a3, b3)` and the object's axis:
    /// (the capsule's point, the object's, whether the object's was clamped to an end).
    #[inline(always)]
    fn closest((a3, b3): (V3, V3), b: &Body) -> (V3, V3, bool) {
        let (sp, tp, clamped) = closest_segments(a3, b3, b.p0, b.d2);
        (a3 + b3 * sp, b.p0 + b.d2 * tp, clamped)
    }

    /// Event function `i` alone at `y` (`Scene::event_value`), in the arithmetic of
    /// `eval_with` and `event_values`: a contact from its geometry only (a phalanx from its
    /// finger's DGM, a ground point from the object's pose), the singularity and the stop
    /// from the DGM; no kinematics, forces or energies.
    pub(super) fn event_value_at(&self, i: usize, y: &St) -> Option<f64> {
        let f = self.model.finger;
        let pose = |j: usize| f.dgm_fast(y[4 * j], y[4 * j + 1]).ok();
        let fingers = if self.setup.fingers { 1.0 } else { f64::NAN };
        if i >= NC {
            let p = pose((i - NC) % 2)?;
            return Some(if i < NC + 2 {
                (crate::math::cross(p.x12, p.x22).abs() - 1e-3) * fingers
            } else {
                (p.q22_from_vectors() + f.psi) * fingers
            });
        }
        let (r, w) = (self.s.object.radius, self.s.hand.w);
        let delta = if i < 4 && !self.setup.fingers {
            -1.0
        } else if i < 4 {
            let p = pose(i / 2)?;
            let (n, qa, _) = Self::closest(self.phalanx_segment(i, &p, f.distal_dir(&p)), &self.body(y));
            r + w - (qa - n).norm()
        } else if i == 4 {
            let (n, qa, _) = Self::closest(self.palm_segment(), &self.body(y));
            r + w - (qa - n).norm()
        } else if i - 5 < self.ng {
            self.ground_hit(i - 5, &self.body(y)).delta
        } else {
            -1.0
        };
        Some(self.mem[i].event_value(delta, self.s.contact.eps_sep))
    }

    /// Is contact `k` loaded at penetration `delta` (memory set, δ > 0)?
    #[inline(always)]
    pub(super) fn loaded(&self, k: usize, delta: f64) -> bool {
        self.mem[k].active && delta > 0.0
    }

    /// The load of a loaded capsule contact `k`: (F_n, the force on the finger, whether
    /// the damping clips F_n at zero).
    #[inline(always)]
    pub(super) fn capsule_load(&self, k: usize, h: &CapsuleHit) -> (f64, V3, bool) {
        let law = if k < 4 { &self.model.friction } else { &self.law_palm };
        let kc = self.s.contact.k_contact;
        let (fnm, ft) = point_force(kc, self.chi, law, h.delta, h.dd, self.mem[k].vminus, h.u);
        let clipped = 1.0 + self.chi * h.dd / self.mem[k].vminus <= 0.0;
        (fnm, ft - h.yc * fnm, clipped)
    }

    /// Generalised force on finger `i` of a force `on_finger` at a contact with point
    /// Jacobian `jm`.
    #[inline(always)]
    pub(super) fn generalised(i: usize, jm: &Matrix2<f64>, on_finger: &V3) -> Vector2<f64> {
        jm.transpose() * Vector2::new(mirror(i) * on_finger.x, on_finger.y)
    }

    /// Ground point `k` of the object `b`.
    #[inline(always)]
    pub(super) fn ground_hit(&self, k: usize, b: &Body) -> GroundHit {
        let zg = -self.s.object.grasp_height;
        let rk = b.rot * self.rim_body[k];
        let delta = zg - (b.g.z + rk.z);
        let vp = b.v + b.om.cross(&rk);
        GroundHit { rk, delta, vp }
    }

    /// The load of a loaded ground point `ci` (contact index, 5..): (F_n, the force on the
    /// object, whether the damping clips F_n at zero).
    #[inline(always)]
    pub(super) fn ground_load(&self, ci: usize, h: &GroundHit) -> (f64, V3, bool) {
        let kg = self.s.setup.ground_k;
        let dd = -h.vp.z;
        let (fnm, ft) =
            point_force(kg, self.chi, &self.law_ground, h.delta, dd, self.mem[ci].vminus, V3::new(h.vp.x, h.vp.y, 0.0));
        let clipped = 1.0 + self.chi * dd / self.mem[ci].vminus <= 0.0;
        (fnm, ft + V3::new(0.0, 0.0, fnm), clipped)
    }

    /// The test-only push of §14.5.5 on the object `b`: (force, torque about G).
    #[inline(always)]
    pub(super) fn push(&self, b: &Body) -> Option<(V3, V3)> {
        if self.setup.push_x != 0.0 && b.a.z.abs() > 1e-12 {
            let fp = V3::new(self.setup.push_x, 0.0, 0.0);
            let lever = b.a * (-b.g.z / b.a.z);
            Some((fp, lever.cross(&fp)))
        } else {
            None
        }
    }

    /// The inverse of the object's world inertia tensor: the cylinder is axisymmetric (J_c
    /// about every transverse axis, J_a about its axis a), so I = J_c·1 + (J_a − J_c) a aᵀ
    /// and I⁻¹ = 1/J_c·1 + (1/J_a − 1/J_c) a aᵀ.
    #[inline(always)]
    pub(super) fn inertia_inverse(&self, b: &Body) -> Matrix3<f64> {
        let (jt, ja) = self.axisymmetric();
        Matrix3::from_diagonal_element(1.0 / jt) + b.a * b.a.transpose() * (1.0 / ja - 1.0 / jt)
    }

    /// I v without forming I.
    #[inline(always)]
    pub(super) fn inertia_times(&self, b: &Body, v: &V3) -> V3 {
        let (jt, ja) = self.axisymmetric();
        v * jt + b.a * ((ja - jt) * b.a.dot(v))
    }

    /// I⁻¹ v without forming I⁻¹.
    #[inline(always)]
    pub(super) fn inertia_inverse_times(&self, b: &Body, v: &V3) -> V3 {
        let (jt, ja) = self.axisymmetric();
        v * (1.0 / jt) + b.a * ((1.0 / ja - 1.0 / jt) * b.a.dot(v))
    }

    /// (J_c, J_a): the body-frame inertia is diag(J_c, J_c, J_a).
    #[inline(always)]
    fn axisymmetric(&self) -> (f64, f64) {
        debug_assert_eq!(self.j_body.x, self.j_body.y);
        (self.j_body.x, self.j_body.z)
    }
}

impl CapsuleHit {
    /// δ̇ and u from the (fixed) geometry and the object's velocities.
    #[inline(always)]
    pub(super) fn relative_velocity(&mut self, b: &Body) {
        let vo = b.v + b.om.cross(&(self.po - b.g));
        let rel = self.vf - vo;
        self.dd = self.yc.dot(&rel);
        self.u = rel - self.yc * self.dd;
    }
}
