//! Reduced dynamics of one finger in q_a = (q11, q21) (MODEL.md §8.1–8.4, §8.8).

use super::geometry::{Finger, Pose};
use super::kinematics::Kin;
use crate::math::{e, perp, V2};
use crate::params::SceneParams;
use nalgebra::{Matrix2, Vector2, Vector4};

/// Mass matrix and bias of one open chain (eq. 2.49, 2.53–2.54).
#[inline]
#[allow(clippy::too_many_arguments)]
fn chain(
    i1: f64,
    l1: f64,
    m2: f64,
    i2: f64,
    s: V2,
    cs_beta: (f64, f64),
    adot: f64,
    bdot: f64,
) -> (Matrix2<f64>, Vector2<f64>) {
    let (cb, sb) = cs_beta;
    let h = m2 * l1 * (s.x * cb - s.y * sb);
    let g = m2 * l1 * (s.x * sb + s.y * cb);
    let m = Matrix2::new(i1 + i2 + m2 * l1 * l1 + 2.0 * h, i2 + h, i2 + h, i2);
    let c = Vector2::new(-g * (2.0 * adot * bdot + bdot * bdot), g * adot * adot);
    (m, c)
}

/// Mass matrix M(q_a) and bias c(q_a, q̇_a) of the closed chain (MODEL.md §8.2).
#[derive(Debug, Clone, Copy)]
pub struct Reduced {
    /// M = Wᵀ M_t W.
    pub m: Matrix2<f64>,
    /// c = Wᵀ (M_t (0, b_d1, 0, b_d2) + c_t).
    pub c: Vector2<f64>,
}

/// W = ∂q_t/∂q_a as its two non-trivial rows (the J_d rows).
#[inline]
fn reduce4(jd: &Matrix2<f64>, v: Vector4<f64>) -> Vector2<f64> {
    // Wᵀ v with W = [[1,0],[J11,J12],[0,1],[J21,J22]], v = (q11, q12, q21, q22)-indexed.
    Vector2::new(v[0] + jd[(0, 0)] * v[1] + jd[(1, 0)] * v[3], v[2] + jd[(0, 1)] * v[1] + jd[(1, 1)] * v[3])
}

/// Reduced M and c at pose `p` with active rates `qa_dot` (see `reduced_parts`).
#[inline]
pub fn reduced(f: &Finger, p: &Pose, k: &Kin, qa_dot: Vector2<f64>) -> Reduced {
    let cs12 = (p.x11.dot(&p.x12), crate::math::cross(p.x11, p.x12));
    let cs22 = (p.x21.dot(&p.x22), crate::math::cross(p.x21, p.x22));
    reduced_parts(f, cs12, cs22, &k.jd, k.bd(f, qa_dot), qa_dot)
}

/// Reduced M and c from the relative angles' (cos, sin) of q12 and q22, J_d and b_d at
/// active rates `qa_dot`: M = Wᵀ M_t W and c = Wᵀ (M_t (0, b_d1, 0, b_d2) + c_t) with the
/// block structure of W written out (chain 1 has rates (q̇11, J11 q̇11 + J12 q̇21), chain 2
/// (q̇21, J21 q̇11 + J22 q̇21)).
#[inline(always)]
fn reduced_parts(
    f: &Finger,
    cs12: (f64, f64),
    cs22: (f64, f64),
    jd: &Matrix2<f64>,
    bd: Vector2<f64>,
    qa_dot: Vector2<f64>,
) -> Reduced {
    let ms = &f.mass;
    let qd_dot = jd * qa_dot;
    let (m1, c1) = chain(ms.i[0], f.l11, ms.m[1], ms.i[1], V2::new(f.l12 / 2.0, 0.0), cs12, qa_dot[0], qd_dot[0]);
    let (m2, c2) = chain(ms.i[2], f.l21, ms.m[3], ms.i[3], ms.s22, cs22, qa_dot[1], qd_dot[1]);
    let (a1, b1, d1) = (m1[(0, 0)], m1[(0, 1)], m1[(1, 1)]);
    let (a2, b2, d2) = (m2[(0, 0)], m2[(0, 1)], m2[(1, 1)]);
    let (j11, j12, j21, j22) = (jd[(0, 0)], jd[(0, 1)], jd[(1, 0)], jd[(1, 1)]);
    // chain 1: W1 = [[1, 0], [J11, J12]]; chain 2: W2 = [[0, 1], [J21, J22]]
    let e1 = b1 + d1 * j11;
    let e2 = b2 + d2 * j22;
    let m00 = a1 + j11 * (b1 + e1) + d2 * j21 * j21;
    let m01 = e1 * j12 + j21 * e2;
    let m11 = d1 * j12 * j12 + a2 + j22 * (b2 + e2);
    let (f10, f11) = (b1 * bd[0] + c1[0], d1 * bd[0] + c1[1]);
    let (f20, f21) = (b2 * bd[1] + c2[0], d2 * bd[1] + c2[1]);
    Reduced {
        m: Matrix2::new(m00, m01, m01, m11),
        c: Vector2::new(f10 + j11 * f11 + j21 * f21, j12 * f11 + f20 + j22 * f21),
    }
}

/// Mass matrix only (rates zero).
#[inline]
pub fn mass_matrix(f: &Finger, p: &Pose, k: &Kin) -> Matrix2<f64> {
    reduced(f, p, k, Vector2::zeros()).m
}

/// Tree generalised gravity force Q_t = −∂V_g/∂q_t (MODEL.md §8.3), indexed (q11, q12, q21, q22).
#[inline]
pub fn gravity_tree(f: &Finger, p: &Pose, s: &SceneParams) -> Vector4<f64> {
    if s.env.g_eq == 0.0 {
        return Vector4::zeros();
    }
    let gv = s.env.g_eq * e(s.env.theta_g);
    let ms = &f.mass;
    let (x11, x12, x21) = (p.x11, p.x12, p.x21);
    let rs22 = nalgebra::Rotation2::new(p.q21 + p.q22) * ms.s22;
    let g11 = ms.m[0] * gv.dot(&perp(0.5 * f.l11 * x11));
    let g12a = ms.m[1] * gv.dot(&perp(f.l11 * x11 + 0.5 * f.l12 * x12));
    let g12b = ms.m[1] * gv.dot(&perp(0.5 * f.l12 * x12));
    let g21 = ms.m[2] * gv.dot(&perp(0.5 * f.l21 * x21));
    let g22a = ms.m[3] * gv.dot(&perp(f.l21 * x21 + rs22));
    let g22b = ms.m[3] * gv.dot(&perp(rs22));
    Vector4::new(g11 + g12a, g12b, g21 + g22a, g22b)
}

/// Gravity potential V_g = −Σ m_k g·r_Sk (MODEL.md §8.3).
pub fn gravity_potential(f: &Finger, p: &Pose, s: &SceneParams) -> f64 {
    if s.env.g_eq == 0.0 {
        return 0.0;
    }
    let gv = s.env.g_eq * e(s.env.theta_g);
    let ms = &f.mass;
    let r11 = f.o21 + 0.5 * f.l11 * e(p.q11);
    let r12 = p.o12 + 0.5 * f.l12 * p.x12;
    let r21 = f.o21 + 0.5 * f.l21 * e(p.q21);
    let r22 = p.o22 + nalgebra::Rotation2::new(p.q21 + p.q22) * ms.s22;
    -(ms.m[0] * gv.dot(&r11) + ms.m[1] * gv.dot(&r12) + ms.m[2] * gv.dot(&r21) + ms.m[3] * gv.dot(&r22))
}

/// Reduce a tree generalised force to q_a: Wᵀ Q_t.
#[inline]
pub fn reduce_tree_force(k: &Kin, q: Vector4<f64>) -> Vector2<f64> {
    reduce4(&k.jd, q)
}

/// Body-by-body kinetic energy Σ ½ m v_S² + ½ I_S ω² from DGM velocities (used to test
/// the reduced M; MODEL.md §8.2 identity). `qa_dot` are the active rates.
pub fn kinetic_energy_bodies(f: &Finger, p: &Pose, k: &Kin, qa_dot: Vector2<f64>) -> f64 {
    let ms = &f.mass;
    let w = f.w;
    let qd = k.jd * qa_dot;
    let (w11, w12, w21, w22) = (qa_dot[0], qa_dot[0] + qd[0], qa_dot[1], qa_dot[1] + qd[1]);
    let x11 = e(p.q11);
    let x21 = e(p.q21);
    let x12 = p.x12;
    // COM velocities: v = ω × r relative to moving joints
    let v_o12 = w11 * perp(f.l11 * x11);
    let v_o22 = w21 * perp(f.l21 * x21);
    let v11 = w11 * perp(0.5 * f.l11 * x11);
    let v12 = v_o12 + w12 * perp(0.5 * f.l12 * x12);
    let v21 = w21 * perp(0.5 * f.l21 * x21);
    let rs22 = nalgebra::Rotation2::new(p.q21 + p.q22) * ms.s22;
    let v22 = v_o22 + w22 * perp(rs22);
    // Central inertias: rods I_S = m (w²/4 + l²/12); body 22 by parallel axis from its joint.
    let ic = |m: f64, l: f64| m * (w * w / 4.0 + l * l / 12.0);
    let i22s = ms.i[3] - ms.m[3] * ms.s22.norm_squared();
    0.5 * (ms.m[0] * v11.norm_squared() + ic(ms.m[0], f.l11) * w11 * w11)
        + 0.5 * (ms.m[1] * v12.norm_squared() + ic(ms.m[1], f.l12) * w12 * w12)
        + 0.5 * (ms.m[2] * v21.norm_squared() + ic(ms.m[2], f.l21) * w21 * w21)
        + 0.5 * (ms.m[3] * v22.norm_squared() + i22s * w22 * w22)
}
