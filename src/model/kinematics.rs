//! First- and second-order kinematics of the five-bar finger (MODEL.md §5.3–5.5, §6.3).

use super::geometry::{Finger, Pose};
use crate::math::{perp, V2};
use nalgebra::{Matrix2, Vector2};

/// First-order kinematics at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kin {
    /// q̇_d = J_d q̇_a (rows q12, q22; columns q11, q21).
    pub jd: Matrix2<f64>,
    /// Ẋ = J_X q̇_a for X = O13.
    pub jx: Matrix2<f64>,
    /// Inverse of the velocity-closure matrix [perp(u1), −perp(u2)] (reused by b_d).
    cinv: Matrix2<f64>,
    u1: V2,
    u2: V2,
    x11: V2,
    x21: V2,
}

impl Kin {
    /// Kinematics at pose `p`; `None` at a singular pose (det of the closure matrix ≈ 0).
    #[inline]
    pub fn new(f: &Finger, p: &Pose) -> Option<Self> {
        let (x11, x21, x12, x22) = (p.x11, p.x21, p.x12, p.x22);
        let u1 = f.l12 * x12;
        let u2 = f.l22 * x22;
        let c = Matrix2::from_columns(&[perp(u1), -perp(u2)]);
        let cinv = crate::math::inv2(&c)?;
        let col_q11 = cinv * (-perp(f.l11 * x11 + u1));
        let col_q21 = cinv * perp(f.l21 * x21 + u2);
        let jd = Matrix2::from_columns(&[col_q11, col_q21]);
        // Ẋ = d/dt (O11 + l11 x11 + u1) = q̇11 perp(l11 x11 + u1) + q̇12 perp(u1)
        let jx = Matrix2::from_columns(&[perp(f.l11 * x11 + u1), V2::zeros()]) + perp(u1) * jd.row(0);
        Some(Kin { jd, jx, cinv, u1, u2, x11, x21 })
    }

    /// J21 (∂q22/∂q11).
    #[inline]
    pub fn j21(&self) -> f64 {
        self.jd[(1, 0)]
    }
    /// J22 (∂q22/∂q21).
    #[inline]
    pub fn j22(&self) -> f64 {
        self.jd[(1, 1)]
    }
    /// Row (J21, J22): θ̇2 = q̇22 = j·q̇_a.
    #[inline]
    pub fn j_row(&self) -> Vector2<f64> {
        Vector2::new(self.jd[(1, 0)], self.jd[(1, 1)])
    }

    /// Second-order term b_d with q̈_d = J_d q̈_a + b_d (MODEL.md §5.4).
    #[inline]
    pub fn bd(&self, f: &Finger, qa_dot: Vector2<f64>) -> Vector2<f64> {
        let qd_dot = self.jd * qa_dot;
        let w1 = qa_dot[0] + qd_dot[0];
        let w2 = qa_dot[1] + qd_dot[1];
        let rhs = qa_dot[0] * qa_dot[0] * f.l11 * self.x11 + w1 * w1 * self.u1
            - qa_dot[1] * qa_dot[1] * f.l21 * self.x21
            - w2 * w2 * self.u2;
        self.cinv * rhs
    }

    /// Phalanx-angle map θ̇ = G q̇_a, G = [[0, 1], [J21, J22]] (MODEL.md §5.5).
    #[inline]
    pub fn g(&self) -> Matrix2<f64> {
        Matrix2::new(0.0, 1.0, self.jd[(1, 0)], self.jd[(1, 1)])
    }

    /// Jacobian of a material point `pt` of body 21 (`distal = false`) or body 22
    /// (`distal = true`): v_P = J_P q̇_a (MODEL.md §6.3).
    #[inline]
    pub fn point_jacobian(&self, f: &Finger, p: &Pose, pt: V2, distal: bool) -> Matrix2<f64> {
        let mut j = Matrix2::from_columns(&[V2::zeros(), perp(pt - f.o21)]);
        if distal {
            j += perp(pt - p.o22) * self.jd.row(1);
        }
        j
    }
}
