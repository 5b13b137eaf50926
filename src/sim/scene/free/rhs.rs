//! The free scene's right-hand side: the fingers' linkages, the contact forces (every
//! contact for the full model, only those whose memory is set for the integrator), the
//! object's accelerations, and y'.

use super::contacts::Body;
use super::{Contact3, FreeEval, FreeScene, St, G0, NC, NG_MAX, Q0, V0, W0};
use crate::sim::contact3d::{quat_mul, V3};
use crate::sim::finger::{FingerLinkage, Kink};
use crate::sim::integrate::Piece;
use nalgebra::Vector2;

/// What the forces at a state give (see `FreeScene::forces`).
struct Forces {
    fe: [FingerLinkage; 2],
    b: Body,
    qdd: [Vector2<f64>; 2],
    acc: (V3, V3),
    /// Angular momentum about G.
    l: V3,
    piece: Piece,
}

impl FreeScene<'_> {
    /// The fingers' linkages at `y` (their contact forces are added by the scene).
    #[inline(always)]
    pub(super) fn fingers(&self, y: &St, full: bool) -> Option<[FingerLinkage; 2]> {
        let l0 = self.model.linkage(Vector2::new(y[0], y[1]), self.finger_rates(y, 0), full)?;
        let l1 = self.model.linkage(Vector2::new(y[4], y[5]), self.finger_rates(y, 1), full)?;
        Some([l0, l1])
    }

    /// The forces at `y`: every contact when `ALL` (their states into `c`, their elastic
    /// energy into `v_el`), else only the loaded ones (all a right-hand side needs).
    #[inline(always)]
    fn forces<const ALL: bool>(&self, y: &St, full: bool, c: &mut [Contact3; NC], v_el: &mut f64) -> Option<Forces> {
        let s = self.s;
        let fe = self.fingers(y, full)?;
        let b = self.body(y);
        let mut force = V3::new(0.0, 0.0, -self.m * s.env.g);
        let mut torque = V3::zeros();
        let mut gen = [fe[0].gf - fe[0].c, fe[1].gf - fe[1].c];
        let mut piece = Piece::SMOOTH;
        for i in 0..2 {
            for bit in 0..Kink::BITS {
                if fe[i].piece.has(bit) {
                    piece = piece.with(bit + Kink::BITS * i as u32);
                }
            }
        }
        let kc = s.contact.k_contact;
        // phalanges and palm: capsule (radius w) against the axis segment (radius R)
        for k in 0..5 {
            if k < 4 && !self.setup.fingers {
                c[k].delta = -1.0;
                continue;
            }
            if !ALL && !self.mem[k].active {
                continue;
            }
            let i = (k / 2).min(1);
            let h = self.capsule_hit(k, &fe[i], self.finger_rates(y, i), &b);
            c[k] = Contact3 { delta: h.delta, delta_dot: h.dd, normal: 0.0, rim: h.rim };
            if self.loaded(k, h.delta) {
                let (fnm, on_finger, clipped) = self.capsule_load(k, &h);
                piece = piece.with(12 + 2 * k as u32);
                if clipped {
                    piece = piece.with(13 + 2 * k as u32);
                }
                force -= on_finger;
                torque -= (h.po - b.g).cross(&on_finger);
                c[k].normal = fnm;
                if k < 4 {
                    gen[i] += Self::generalised(i, &h.jm, &on_finger);
                }
                if ALL {
                    *v_el += 0.4 * kc * h.delta * h.delta * h.delta.sqrt();
                }
            }
        }
        // ground points
        let kg = s.setup.ground_k;
        for k in 0..self.ng {
            let ci = 5 + k;
            if !ALL && !self.mem[ci].active {
                continue;
            }
            let h = self.ground_hit(k, &b);
            c[ci] = Contact3 { delta: h.delta, delta_dot: -h.vp.z, normal: 0.0, rim: false };
            if self.loaded(ci, h.delta) {
                let (fnm, fo, clipped) = self.ground_load(ci, &h);
                piece = piece.with(12 + 2 * ci as u32);
                if clipped {
                    piece = piece.with(13 + 2 * ci as u32);
                }
                force += fo;
                torque += h.rk.cross(&fo);
                c[ci].normal = fnm;
                if ALL {
                    *v_el += 0.4 * kg * h.delta * h.delta * h.delta.sqrt();
                }
            }
        }
        for k in self.ng..NG_MAX {
            c[5 + k].delta = -1.0;
        }
        if let Some((fp, tp)) = self.push(&b) {
            force += fp;
            torque += tp;
        }
        let mut qdd = [Vector2::zeros(); 2];
        if self.setup.fingers {
            for i in 0..2 {
                qdd[i] = crate::math::inv2(&fe[i].m)? * gen[i];
            }
        }
        let l = self.inertia_times(&b, &b.om);
        let wdot = self.inertia_inverse_times(&b, &(torque - b.om.cross(&l)));
        Some(Forces { fe, b, qdd, acc: (force / self.m, wdot), l, piece })
    }

    /// The model at `y`.
    #[inline(always)]
    pub(super) fn eval_with(&self, y: &St, full: bool) -> Option<FreeEval> {
        let mut c = [Contact3::default(); NC];
        let mut v_el = 0.0;
        let Forces { fe, b, qdd, acc, l, piece } = self.forces::<true>(y, full, &mut c, &mut v_el)?;
        let (v, om, a) = (b.v, b.om, b.a);
        let e_t = 0.5 * self.m * v.norm_squared();
        let e_r = 0.5 * om.dot(&l);
        let energy = if full {
            fe[0].energy(self.finger_rates(y, 0))
                + fe[1].energy(self.finger_rates(y, 1))
                + e_t
                + e_r
                + self.m * self.s.env.g * b.g.z
                + v_el
        } else {
            f64::NAN
        };
        Some(FreeEval {
            f: fe,
            c,
            qdd,
            acc,
            tilt: a.z.clamp(-1.0, 1.0).acos(),
            e_obj: (e_t, e_r),
            energy,
            piece,
            pos: b.g,
            quat: b.q,
            omega: om,
            axis: a,
        })
    }

    /// The right-hand side at `y` and its piece (the loaded contacts only).
    #[inline(always)]
    pub(super) fn rhs(&self, y: &St) -> Option<(St, Piece)> {
        let mut c = [Contact3::default(); NC];
        let mut v_el = 0.0;
        let f = self.forces::<false>(y, false, &mut c, &mut v_el)?;
        Some((self.deriv_of(y, &f.qdd, &f.acc), f.piece))
    }

    pub(super) fn deriv(&self, y: &St, ev: &FreeEval) -> St {
        self.deriv_of(y, &ev.qdd, &ev.acc)
    }

    /// y' from the fingers' q̈ and the object's dv_G/dt, dω/dt.
    #[inline(always)]
    fn deriv_of(&self, y: &St, qdd: &[Vector2<f64>; 2], acc: &(V3, V3)) -> St {
        let mut d = St::zeros();
        if self.setup.fingers {
            for i in 0..2 {
                let o = 4 * i;
                d[o] = y[o + 2];
                d[o + 1] = y[o + 3];
                d[o + 2] = qdd[i][0];
                d[o + 3] = qdd[i][1];
            }
        }
        let q = [y[Q0], y[Q0 + 1], y[Q0 + 2], y[Q0 + 3]];
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        let qn = [q[0] / n, q[1] / n, q[2] / n, q[3] / n];
        let qd = quat_mul([0.0, y[W0], y[W0 + 1], y[W0 + 2]], qn);
        for j in 0..3 {
            d[G0 + j] = y[V0 + j];
            d[V0 + j] = acc.0[j];
            d[W0 + j] = acc.1[j];
        }
        for j in 0..4 {
            d[Q0 + j] = 0.5 * qd[j];
        }
        d
    }
}
