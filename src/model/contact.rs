//! Object contacts of a phalanx modelled as a capsule against a fixed vertical cylinder
//! (MODEL.md §8.5), the Flores normal law (D8) and the ADAMS-STEP friction law (§8.6).

use crate::math::V2;

/// Which part of a capsule is closest to the object centre.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CapsulePart {
    /// The cap at the segment start (base O21 for the proximal, knuckle O22 for the distal).
    Start,
    /// Along the segment.
    Segment,
    /// The cap at the segment end (knuckle O22 for the proximal, tip for the distal).
    End,
}

/// Closest-point geometry of a capsule [A, A + L x̂] against a circle (centre C).
#[derive(Debug, Clone, Copy)]
pub struct CapsuleGeom {
    /// Penetration δ = R + w − d (> 0 in contact).
    pub delta: f64,
    /// Unit normal y_c, phalanx → object.
    pub normal: V2,
    /// Tangent t_c = (y_c,y, −y_c,x).
    pub tangent: V2,
    /// Material contact point P = N + w y_c.
    pub point: V2,
    /// Clamped abscissa k along the segment.
    pub k: f64,
    /// Which part is closest.
    pub part: CapsulePart,
}

/// Capsule–circle closest-point construction of §8.5. `rw` = R + w.
#[inline]
pub fn capsule(a: V2, xhat: V2, len: f64, c: V2, rw: f64, w: f64) -> CapsuleGeom {
    let k_raw = (c - a).dot(&xhat);
    let (k, part) = if k_raw <= 0.0 {
        (0.0, CapsulePart::Start)
    } else if k_raw >= len {
        (len, CapsulePart::End)
    } else {
        (k_raw, CapsulePart::Segment)
    };
    let n = a + k * xhat;
    let cn = c - n;
    let d = cn.norm();
    // d = 0 would mean the object centre on the phalanx axis: no meaningful normal.
    let normal = if d > 0.0 { cn / d } else { crate::math::perp(xhat) };
    CapsuleGeom { delta: rw - d, normal, tangent: V2::new(normal.y, -normal.x), point: n + w * normal, k, part }
}

/// Flores et al. (2011) normal force F_n = max(0, K δ^{3/2} (1 + χ δ̇/δ̇⁻)) for δ > 0.
#[inline]
pub fn flores_normal(k: f64, chi: f64, delta: f64, delta_dot: f64, vminus: f64) -> f64 {
    if delta <= 0.0 {
        return 0.0;
    }
    let el = k * delta * delta.sqrt();
    (el * (1.0 + chi * delta_dot / vminus)).max(0.0)
}

/// ADAMS STEP: h0 for x ≤ x0, h1 for x ≥ x1, cubic blend s²(3 − 2s) between.
#[inline]
pub fn adams_step(x: f64, x0: f64, h0: f64, x1: f64, h1: f64) -> f64 {
    if x <= x0 {
        h0
    } else if x >= x1 {
        h1
    } else {
        let s = (x - x0) / (x1 - x0);
        h0 + (h1 - h0) * s * s * (3.0 - 2.0 * s)
    }
}

/// Friction coefficients of the regularised law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionLaw {
    /// Static coefficient μ_s.
    pub mu_s: f64,
    /// Dynamic coefficient μ_d.
    pub mu_d: f64,
    /// Static transition velocity v_s.
    pub v_s: f64,
    /// Dynamic transition velocity v_d.
    pub v_d: f64,
}

impl FrictionLaw {
    /// μ̃(u): odd, C¹, 0 at rest, μ_s at |u| = v_s, μ_d for |u| ≥ v_d (§8.6).
    #[inline]
    pub fn mu(&self, u: f64) -> f64 {
        let a = u.abs();
        let m = if a <= self.v_s {
            adams_step(a, -self.v_s, -self.mu_s, self.v_s, self.mu_s)
        } else {
            adams_step(a, self.v_s, self.mu_s, self.v_d, self.mu_d)
        };
        if u < 0.0 {
            -m
        } else {
            m
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friction_shape() {
        let f = FrictionLaw { mu_s: 0.6, mu_d: 0.4, v_s: 5e-3, v_d: 10e-3 };
        assert_eq!(f.mu(0.0), 0.0);
        assert!((f.mu(5e-3) - 0.6).abs() < 1e-15);
        assert!((f.mu(-5e-3) + 0.6).abs() < 1e-15);
        assert!((f.mu(0.02) - 0.4).abs() < 1e-15);
        // slope 1.5 μ_s / v_s at 0
        let h = 1e-9;
        assert!(((f.mu(h) - f.mu(-h)) / (2.0 * h) - 1.5 * 0.6 / 5e-3).abs() < 1e-3);
        // odd and dissipative
        for &u in &[1e-4, 3e-3, 7e-3, 1.0] {
            assert!((f.mu(u) + f.mu(-u)).abs() < 1e-15);
            assert!(f.mu(u) > 0.0);
        }
    }

    #[test]
    fn capsule_parts() {
        let g = capsule(V2::zeros(), V2::new(1.0, 0.0), 1.0, V2::new(0.5, 0.3), 0.35, 0.05);
        assert_eq!(g.part, CapsulePart::Segment);
        assert!((g.delta - 0.05).abs() < 1e-15);
        assert!((g.point - V2::new(0.5, 0.05)).norm() < 1e-15);
        let g = capsule(V2::zeros(), V2::new(1.0, 0.0), 1.0, V2::new(1.3, 0.4), 0.45, 0.05);
        assert_eq!(g.part, CapsulePart::End);
        assert!((g.delta - (0.45 - 0.5)).abs() < 1e-15);
    }
}
