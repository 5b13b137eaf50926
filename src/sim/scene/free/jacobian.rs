//! The free scene's Jacobian by blocks. The fingers and the object couple only through
//! their contacts, so a column needs only what its state changes:
//! * a finger state: that finger (its linkage, mass matrix, forces) and its two phalanx
//!   contacts — the other finger's rows and the object's kinematic rows are zero;
//! * the object's position or orientation: every contact (the fingers' evaluations and
//!   mass matrices are kept);
//! * the object's velocities: the contacts' relative velocities and loads only (geometry
//!   kept);
//! * the kinematic rows (q̇ of the fingers, dG/dt = v, dq/dt = ½ ω ⊗ q/|q|): analytic.
//!
//! The other entries are forward differences of the changed contributions with the dense
//! Jacobian's steps (√ε·max(|y_j|, 1e-3)), taken on the other side where the perturbed
//! state leaves the smooth piece of y, as [`fd_jacobian`](crate::sim::fd_jacobian) does.
//! The cost per Jacobian is about 8 finger evaluations and 13 contact sweeps instead of 21
//! full evaluations, and grows linearly with the number of bodies.

use super::contacts::{Body, CapsuleHit, GroundHit};
use super::{FreeScene, St, G0, NC, NF, NG_MAX, Q0, V0, W0};
use crate::sim::contact3d::V3;
use crate::sim::finger::{FingerLinkage, Kink};
use crate::sim::integrate::Piece;
use nalgebra::{Matrix2, Matrix3, SMatrix, Vector2};

/// The Jacobian matrix of the free scene.
pub type FreeJacobian = SMatrix<f64, NF, NF>;

/// One contact's contribution: force and torque (about G) on the object, generalised force
/// on its finger (zero for the palm and the ground), and its piece flags.
#[derive(Debug, Clone, Copy, Default)]
struct Load {
    f: V3,
    t: V3,
    gen: Vector2<f64>,
    loaded: bool,
    clipped: bool,
}

/// Every contact whose memory is set, at one state (the others carry no load and cannot
/// start to: their memory changes only at events).
#[derive(Debug, Clone, Copy)]
struct Loads {
    caps: [Option<CapsuleHit>; 5],
    ground: [Option<GroundHit>; NG_MAX],
    load: [Load; NC],
}

/// Sum of the contributions of contacts `ks`: (force, torque, generalised force on each
/// finger).
fn sum(load: &[Load; NC], ks: std::ops::Range<usize>) -> (V3, V3, [Vector2<f64>; 2]) {
    let (mut f, mut t, mut g) = (V3::zeros(), V3::zeros(), [Vector2::zeros(); 2]);
    for k in ks {
        f += load[k].f;
        t += load[k].t;
        if k < 4 {
            g[k / 2] += load[k].gen;
        }
    }
    (f, t, g)
}

/// Do the flags of contacts `ks` (and of finger `finger`'s kinks) at a perturbed state
/// differ from `piece`'s?
/// One column's perturbed evaluation that stays on the current smooth piece: `eval(dy)`,
/// or `eval(-dy)` when +dy leaves the piece (`left`); the step used and the result, with
/// the evaluations counted in `evals`.
fn on_piece<T>(dy: f64, eval: impl Fn(f64) -> T, left: impl Fn(&T) -> bool, evals: &mut u64) -> (f64, T) {
    *evals += 1;
    let r = eval(dy);
    if !left(&r) {
        return (dy, r);
    }
    *evals += 1;
    (-dy, eval(-dy))
}

fn left_piece(piece: Piece, load: &[Load; NC], ks: std::ops::Range<usize>, finger: Option<(usize, Piece)>) -> bool {
    for k in ks {
        if load[k].loaded != piece.has(12 + 2 * k as u32)
            || (load[k].loaded && load[k].clipped) != piece.has(13 + 2 * k as u32)
        {
            return true;
        }
    }
    if let Some((i, p)) = finger {
        for b in 0..Kink::BITS {
            if p.has(b) != piece.has(b + Kink::BITS * i as u32) {
                return true;
            }
        }
    }
    false
}

/// ½ ∂(ω ⊗ q̂)/∂q (4×4, with q̂ = q/|q|) and ½ ∂(ω ⊗ q̂)/∂ω (4×3).
fn quat_rate_jacobian(q: [f64; 4], om: V3) -> (SMatrix<f64, 4, 4>, SMatrix<f64, 4, 3>) {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let qh = nalgebra::Vector4::new(q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    let (wx, wy, wz) = (om.x, om.y, om.z);
    #[rustfmt::skip]
    let l = SMatrix::<f64, 4, 4>::new(
        0.0, -wx, -wy, -wz,
        wx, 0.0, -wz, wy,
        wy, wz, 0.0, -wx,
        wz, -wy, wx, 0.0,
    );
    let proj = (SMatrix::<f64, 4, 4>::identity() - qh * qh.transpose()) / n;
    #[rustfmt::skip]
    let dw = SMatrix::<f64, 4, 3>::new(
        -qh[1], -qh[2], -qh[3],
        qh[0], qh[3], -qh[2],
        -qh[3], qh[0], qh[1],
        qh[2], -qh[1], qh[0],
    );
    (l * proj * 0.5, dw * 0.5)
}

impl FreeScene<'_> {
    /// The contribution of capsule contact `k` with geometry `h` against the object `b`.
    #[inline(always)]
    fn capsule_contrib(&self, k: usize, h: &CapsuleHit, b: &Body) -> Load {
        if !self.loaded(k, h.delta) {
            return Load::default();
        }
        let (_, on_finger, clipped) = self.capsule_load(k, h);
        let gen = if k < 4 { Self::generalised(k / 2, &h.jm, &on_finger) } else { Vector2::zeros() };
        Load { f: -on_finger, t: -(h.po - b.g).cross(&on_finger), gen, loaded: true, clipped }
    }

    /// The contribution of ground point `k` (contact 5 + k) with geometry `h`.
    #[inline(always)]
    fn ground_contrib(&self, k: usize, h: &GroundHit) -> Load {
        if !self.loaded(5 + k, h.delta) {
            return Load::default();
        }
        let (_, fo, clipped) = self.ground_load(5 + k, h);
        Load { f: fo, t: h.rk.cross(&fo), gen: Vector2::zeros(), loaded: true, clipped }
    }

    /// Does the capsule contact `k` take part (fingers integrated, memory set)?
    #[inline(always)]
    fn capsule_on(&self, k: usize) -> bool {
        (k == 4 || self.setup.fingers) && self.mem[k].active
    }

    /// The capsule contacts of `base` recomputed against the object `b` (fingers `fe` at
    /// rates `qd`), into `load`.
    fn capsules_at(&self, load: &mut [Load; NC], fe: &[FingerLinkage; 2], qd: &[Vector2<f64>; 2], b: &Body) {
        for k in (0..5).filter(|&k| self.capsule_on(k)) {
            let i = (k / 2).min(1);
            load[k] = self.capsule_contrib(k, &self.capsule_hit(k, &fe[i], qd[i], b), b);
        }
    }

    /// Every contact with its memory set, at the object `b` with the fingers `fe` at rates
    /// `qd`.
    fn loads(&self, fe: &[FingerLinkage; 2], qd: &[Vector2<f64>; 2], b: &Body) -> Loads {
        let mut l = Loads { caps: [None; 5], ground: [None; NG_MAX], load: [Load::default(); NC] };
        for k in (0..5).filter(|&k| self.capsule_on(k)) {
            let i = (k / 2).min(1);
            let h = self.capsule_hit(k, &fe[i], qd[i], b);
            l.load[k] = self.capsule_contrib(k, &h, b);
            l.caps[k] = Some(h);
        }
        for k in (0..self.ng).filter(|&k| self.mem[5 + k].active) {
            let h = self.ground_hit(k, b);
            l.load[5 + k] = self.ground_contrib(k, &h);
            l.ground[k] = Some(h);
        }
        l
    }

    /// The loads of `base` (same positions) with the object's velocities of `b`, into
    /// `load` (only the loaded contacts change).
    fn loads_new_velocity(&self, base: &Loads, b: &Body, load: &mut [Load; NC]) {
        for k in 0..5 {
            if let (Some(mut h), true) = (base.caps[k], base.load[k].loaded) {
                h.relative_velocity(b);
                load[k] = self.capsule_contrib(k, &h, b);
            }
        }
        for k in 0..self.ng {
            if let (Some(mut h), true) = (base.ground[k], base.load[5 + k].loaded) {
                h.vp = b.v + b.om.cross(&h.rk);
                load[5 + k] = self.ground_contrib(k, &h);
            }
        }
    }

    /// dω/dt of the object `b` (inverse inertia `i_inv`) under the contact torque `t`
    /// (the push added).
    fn omega_dot(&self, b: &Body, i_inv: &Matrix3<f64>, t: V3) -> V3 {
        let t = match self.push(b) {
            Some((_, tp)) => t + tp,
            None => t,
        };
        i_inv * (t - b.om.cross(&self.inertia_times(b, &b.om)))
    }

    /// The Jacobian at `y` (on the smooth piece `piece`) into `jac`, by blocks; false where
    /// the model is undefined at a state it needs.
    pub(super) fn block_jacobian(&mut self, y: &St, piece: Piece, jac: &mut FreeJacobian) -> bool {
        let Some(n) = self.block_jacobian_into(y, piece, jac) else { return false };
        self.jac_evals += n;
        true
    }

    fn block_jacobian_into(&self, y: &St, piece: Piece, jac: &mut FreeJacobian) -> Option<u64> {
        let sq = f64::EPSILON.sqrt();
        let step = |j: usize| sq * y[j].abs().max(1e-3);
        let mut evals = 0;
        jac.fill(0.0);
        let fe = self.fingers(y, false)?;
        let qd = [self.finger_rates(y, 0), self.finger_rates(y, 1)];
        let b = self.body(y);
        let base = self.loads(&fe, &qd, &b);
        let m_inv = [crate::math::inv2(&fe[0].m)?, crate::math::inv2(&fe[1].m)?];
        let i_inv = self.inertia_inverse(&b);
        let (f0, t0, g0) = sum(&base.load, 0..NC);
        let wdot0 = self.omega_dot(&b, &i_inv, t0);
        // ---- finger columns: that finger and its two phalanges ---------------------------
        if self.setup.fingers {
            for i in 0..2 {
                let o = 4 * i;
                jac[(o, o + 2)] = 1.0;
                jac[(o + 1, o + 3)] = 1.0;
                let ks = 2 * i..2 * i + 2;
                let (fb, tb, gb) = sum(&base.load, ks.clone());
                let qdd0 = m_inv[i] * (fe[i].gf - fe[i].c + gb[i]);
                for j in 0..4 {
                    let mut dy = step(o + j);
                    let mut side = 0;
                    let (col_qdd, df, dt) = loop {
                        let mut yp = *y;
                        yp[o + j] += dy;
                        evals += 1;
                        let qdp = Vector2::new(yp[o + 2], yp[o + 3]);
                        let fp = self.model.linkage(Vector2::new(yp[o], yp[o + 1]), qdp, false)?;
                        let mut load = base.load;
                        for k in ks.clone().filter(|&k| self.capsule_on(k)) {
                            load[k] = self.capsule_contrib(k, &self.capsule_hit(k, &fp, qdp, &b), &b);
                        }
                        if side == 0 && left_piece(piece, &load, ks.clone(), Some((i, fp.piece))) {
                            dy = -dy;
                            side = 1;
                            continue;
                        }
                        let (fk, tk, gk) = sum(&load, ks.clone());
                        let qdd = crate::math::inv2(&fp.m)? * (fp.gf - fp.c + gk[i]);
                        break (qdd - qdd0, fk - fb, tk - tb);
                    };
                    let c = o + j;
                    jac[(o + 2, c)] = col_qdd[0] / dy;
                    jac[(o + 3, c)] = col_qdd[1] / dy;
                    let dw = i_inv * (dt / dy);
                    for r in 0..3 {
                        jac[(V0 + r, c)] = df[r] / dy / self.m;
                        jac[(W0 + r, c)] = dw[r];
                    }
                }
            }
        }
        // ---- object position and orientation: the contacts, fingers kept -----------------
        let (dq_dq, dq_dw) = quat_rate_jacobian(b.q, b.om);
        for j in G0..Q0 + 4 {
            let eval = |dy: f64| {
                let mut yp = *y;
                yp[j] += dy;
                let bp = self.body(&yp);
                let load = if j < G0 + 2 {
                    // G_x, G_y: the ground points' δ and velocities do not change
                    let mut load = base.load;
                    self.capsules_at(&mut load, &fe, &qd, &bp);
                    load
                } else {
                    self.loads(&fe, &qd, &bp).load
                };
                (load, bp)
            };
            let (dy, (load, bp)) = on_piece(step(j), eval, |r| left_piece(piece, &r.0, 0..NC, None), &mut evals);
            let (f1, t1, g1) = sum(&load, 0..NC);
            self.finger_rows(jac, j, &m_inv, &g1, &g0, dy);
            let wdot = if j < Q0 {
                self.omega_dot(&bp, &i_inv, t1)
            } else {
                self.omega_dot(&bp, &self.inertia_inverse(&bp), t1)
            };
            let push_f = |b: &Body| self.push(b).map_or(V3::zeros(), |p| p.0);
            let df = (f1 + push_f(&bp)) - (f0 + push_f(&b));
            for r in 0..3 {
                jac[(V0 + r, j)] = df[r] / self.m / dy;
                jac[(W0 + r, j)] = (wdot[r] - wdot0[r]) / dy;
            }
        }
        for r in 0..4 {
            for c in 0..4 {
                jac[(Q0 + r, Q0 + c)] = dq_dq[(r, c)];
            }
            for c in 0..3 {
                jac[(Q0 + r, W0 + c)] = dq_dw[(r, c)];
            }
        }
        // ---- object velocities: relative velocities and loads only -----------------------
        for r in 0..3 {
            jac[(G0 + r, V0 + r)] = 1.0;
        }
        for j in V0..W0 + 3 {
            let eval = |dy: f64| {
                let mut bp = b;
                if j < W0 {
                    bp.v[j - V0] += dy;
                } else {
                    bp.om[j - W0] += dy;
                }
                let mut load = base.load;
                self.loads_new_velocity(&base, &bp, &mut load);
                (load, bp)
            };
            let (dy, (load, bp)) = on_piece(step(j), eval, |r| left_piece(piece, &r.0, 0..NC, None), &mut evals);
            let (f1, t1, g1) = sum(&load, 0..NC);
            self.finger_rows(jac, j, &m_inv, &g1, &g0, dy);
            let wdot = self.omega_dot(&bp, &i_inv, t1);
            for r in 0..3 {
                jac[(V0 + r, j)] = (f1[r] - f0[r]) / self.m / dy;
                jac[(W0 + r, j)] = (wdot[r] - wdot0[r]) / dy;
            }
        }
        Some(evals)
    }

    /// Column `c` of the fingers' dynamic rows from the generalised contact forces `g1`
    /// (perturbed) and `g0` (base), the fingers' mass matrices unchanged.
    fn finger_rows(
        &self,
        jac: &mut FreeJacobian,
        c: usize,
        m_inv: &[Matrix2<f64>; 2],
        g1: &[Vector2<f64>; 2],
        g0: &[Vector2<f64>; 2],
        dy: f64,
    ) {
        if !self.setup.fingers {
            return;
        }
        for i in 0..2 {
            let d = m_inv[i] * (g1[i] - g0[i]);
            jac[(4 * i + 2, c)] = d[0] / dy;
            jac[(4 * i + 3, c)] = d[1] / dy;
        }
    }
}
