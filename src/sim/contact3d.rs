//! Contacts of the free scene in 3-D (MODEL.md §14.2): closest points of two segments
//! (capsule–capsule and capsule–cylinder-axis), the Hertz–Flores normal law with its
//! memory, and the friction law of §8.6 generalised to the tangent plane.

use crate::model::{flores_normal, FrictionLaw};
use nalgebra::Vector3;

/// A 3-D vector.
pub type V3 = Vector3<f64>;

/// Closest points of the segments p1 + s d1 (s ∈ [0, 1]) and p2 + t d2 (t ∈ [0, 1]):
/// (s, t, whether t was clamped to an end of the second segment).
pub fn closest_segments(p1: V3, d1: V3, p2: V3, d2: V3) -> (f64, f64, bool) {
    let r = p1 - p2;
    let (a, e, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    let c = d1.dot(&r);
    let b = d1.dot(&d2);
    let denom = a * e - b * b;
    let mut s = if denom > 1e-14 * a * e { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
    let mut t = (b * s + f) / e;
    let mut clamped = false;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
        clamped = true;
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
        clamped = true;
    }
    (s, t, clamped)
}

/// The force of one point contact: normal magnitude and the tangential force vector, for
/// penetration `delta`, its rate `delta_dot`, the tangential relative velocity `u` (of the
/// body the force acts on, relative to the other) and the onset velocity `vminus`.
/// Returns (F_n, F_t) with F_t = −μ̃(|u|) F_n u/|u| (0 at u = 0).
#[inline]
pub fn point_force(k: f64, chi: f64, law: &FrictionLaw, delta: f64, delta_dot: f64, vminus: f64, u: V3) -> (f64, V3) {
    let fnm = flores_normal(k, chi, delta, delta_dot, vminus);
    let a = u.norm();
    let ft = if a > 0.0 { u * (-law.mu(a) * fnm / a) } else { V3::zeros() };
    (fnm, ft)
}

/// Hamilton product p ⊗ q of quaternions stored (w, x, y, z).
#[inline]
pub fn quat_mul(p: [f64; 4], q: [f64; 4]) -> [f64; 4] {
    [
        p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3],
        p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2],
        p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1],
        p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0],
    ]
}

/// The rotation matrix of the unit quaternion (w, x, y, z) (normalised here).
#[inline]
pub fn quat_matrix(q: [f64; 4]) -> nalgebra::Matrix3<f64> {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (w, x, y, z) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    nalgebra::Matrix3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Segment closest points against brute-force sampling; a rotation of 90° about z maps
    /// x to y.
    #[test]
    fn closest_points_and_rotation() {
        let (p1, d1) = (V3::new(0.0, 0.0, 0.0), V3::new(1.0, 0.0, 0.0));
        let (p2, d2) = (V3::new(0.3, 1.0, -0.5), V3::new(0.0, 0.0, 1.0));
        let (s, t, cl) = closest_segments(p1, d1, p2, d2);
        assert!((s - 0.3).abs() < 1e-15 && (t - 0.5).abs() < 1e-15 && !cl);
        let (_, t, cl) = closest_segments(p1, d1, V3::new(0.3, 1.0, 0.5), d2);
        assert!(t == 0.0 && cl);
        let h = std::f64::consts::FRAC_PI_4;
        let m = quat_matrix([h.cos(), 0.0, 0.0, h.sin()]);
        assert!((m * V3::x() - V3::y()).norm() < 1e-15);
    }
}
