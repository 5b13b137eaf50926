//! Derived geometry, open configuration, direct geometric model and the leg-1 inverse
//! model (MODEL.md §3, §5.1, §5.2), plus the mass properties of §4.

use crate::math::{angle, cross, e, e_fast, perp, wrap, V2};
use crate::params::{Design, SceneParams};
use std::f64::consts::PI;

/// Why a finger cannot be built or posed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GeomError {
    /// A length of the design is ≤ 0 or not finite (stage 0).
    InvalidLength,
    /// k10² ≤ 0: the open pose of §3.2 does not exist.
    NoOpenPose,
    /// The loop cannot be closed (β_k² < 0 or no circle intersection).
    NotMountable,
    /// The pose exists only in the other assembly mode (Γ) or working mode (σ).
    AssemblyModeChange,
}

impl GeomError {
    /// Human-readable reason.
    pub fn reason(self) -> &'static str {
        match self {
            GeomError::InvalidLength => "a length is not positive",
            GeomError::NoOpenPose => "open pose undefined (k10^2 <= 0)",
            GeomError::NotMountable => "linkage not mountable",
            GeomError::AssemblyModeChange => "assembly mode differs from the open pose",
        }
    }
}

/// Mass properties of the four bodies (MODEL.md §4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassProps {
    /// Masses m11, m12, m21, m22 (kg).
    pub m: [f64; 4],
    /// Inertias about the joints I11, I12, I21, I22 (kg·m²).
    pub i: [f64; 4],
    /// COM of body 22 in its frame (x along link 22) (m).
    pub s22: V2,
}

/// One finger's linkage: design, derived lengths, assembly modes, open pose and masses.
/// Everything is in the finger's local frame (MODEL.md §2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Finger {
    /// Actuated link length l11.
    pub l11: f64,
    /// Transmission bar length l12.
    pub l12: f64,
    /// Proximal phalanx length l21.
    pub l21: f64,
    /// Link 22 length l22.
    pub l22: f64,
    /// Distal phalanx length t22.
    pub t22: f64,
    /// Distal angle ψ (rad).
    pub psi: f64,
    /// Rod radius w.
    pub w: f64,
    /// Base joint O11 = O21 = (b/2, 0).
    pub o21: V2,
    /// Assembly mode Γ = ±1.
    pub gamma: f64,
    /// Leg-1 working mode σ = ±1.
    pub sigma: f64,
    /// k10 of eq. 4.3.
    pub k10: f64,
    /// Open pose (q11, q12, q21, q22).
    pub open: Pose,
    /// Mass properties.
    pub mass: MassProps,
    /// (cos ψ, sin ψ).
    pub psi_cs: V2,
}

/// A full linkage pose with its joint points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Actuated angle q11 (absolute).
    pub q11: f64,
    /// Bar angle q12 (relative to link 11); NaN from [`Finger::dgm_fast`].
    pub q12: f64,
    /// Proximal angle q21 (absolute) = θ1.
    pub q21: f64,
    /// Link-22 angle q22 (relative to link 21); NaN from [`Finger::dgm_fast`] (see
    /// [`Pose::q22_from_vectors`]).
    pub q22: f64,
    /// Angle from x12 to x22; NaN from [`Finger::dgm_fast`].
    pub q13: f64,
    /// Joint O12.
    pub o12: V2,
    /// Joint O22.
    pub o22: V2,
    /// Joint O13.
    pub o13: V2,
    /// Unit vectors of links 11, 12, 21, 22 (x_i = e(absolute angle)).
    pub x11: V2,
    /// Unit vector of link 12.
    pub x12: V2,
    /// Unit vector of link 21 (proximal phalanx).
    pub x21: V2,
    /// Unit vector of link 22.
    pub x22: V2,
}

impl Pose {
    /// q22 from the unit vectors, `atan2(x21 × x22, x21 · x22)` (what [`Finger::dgm`] stores).
    #[inline]
    pub fn q22_from_vectors(&self) -> f64 {
        cross(self.x21, self.x22).atan2(self.x21.dot(&self.x22))
    }

    /// Phalanx angles (θ1, θ2) = (q21, q22 + ψ).
    pub fn theta(&self, psi: f64) -> (f64, f64) {
        (self.q21, self.q22 + psi)
    }
}

fn circle_intersections(c0: V2, r0: f64, c1: V2, r1: f64) -> Option<(V2, V2)> {
    let dv = c1 - c0;
    let d = dv.norm();
    if !(d > 0.0) {
        return None;
    }
    let a = (r0 * r0 - r1 * r1 + d * d) / (2.0 * d);
    let h2 = r0 * r0 - a * a;
    if !(h2 >= 0.0) {
        return None;
    }
    let u = dv / d;
    let base = c0 + a * u;
    let h = h2.sqrt();
    Some((base + h * perp(u), base - h * perp(u)))
}

impl Finger {
    /// Build the finger of design `x` in scene `s` (stage 0 and the open pose of stage 1).
    pub fn new(x: &Design, s: &SceneParams) -> Result<Self, GeomError> {
        let l11 = x.p * x.l21;
        let l22 = x.r * l11;
        let lengths = [x.l21, x.b, x.t22, l11, l22];
        if lengths.iter().any(|v| !(v.is_finite() && *v > 0.0)) || !x.psi.is_finite() {
            return Err(GeomError::InvalidLength);
        }
        let w = s.hand.w;
        let ro = s.hand.r_open;
        let k10sq = (x.b / 2.0).powi(2) + ro * ro - (ro + w).powi(2);
        if !(k10sq > 0.0) {
            return Err(GeomError::NoOpenPose);
        }
        let k10 = k10sq.sqrt();
        let q21_0 = PI - (2.0 * ro).atan2(x.b) - (ro + w).atan2(k10);
        let q22_0 = -x.psi;
        let q11_0 = q21_0 - PI / 2.0;
        let o21 = V2::new(x.b / 2.0, 0.0);
        let o12 = o21 + l11 * e(q11_0);
        let o22 = o21 + x.l21 * e(q21_0);
        let o13 = o22 + l22 * e(q21_0 + q22_0);
        let l12 = (o13 - o12).norm();
        if !(l12 > 0.0) {
            return Err(GeomError::NotMountable);
        }
        let c = cross(o12 - o22, o13 - o22);
        let q12_0 = wrap(angle(o13 - o12) - q11_0);
        let gamma = if c >= 0.0 { 1.0 } else { -1.0 };
        let sigma = if q12_0.sin() >= 0.0 { 1.0 } else { -1.0 };
        let open = Pose {
            q11: q11_0,
            q12: q12_0,
            q21: q21_0,
            q22: wrap(q22_0),
            q13: wrap(q21_0 + q22_0 - q11_0 - q12_0),
            o12,
            o22,
            o13,
            x11: e(q11_0),
            x12: (o13 - o12) / l12,
            x21: e(q21_0),
            x22: e(q21_0 + q22_0),
        };
        let lam = s.hand.rho_f * PI * w * w;
        let rod_i = |m: f64, l: f64| m * (w * w / 4.0 + l * l / 3.0);
        let (m11, m12, m21) = (lam * l11, lam * l12, lam * x.l21);
        let m22 = lam * (l22 + x.t22);
        let (sp, cp) = x.psi.sin_cos();
        let s22 = V2::new(
            (lam * l22 * l22 / 2.0 + lam * x.t22 * (x.t22 / 2.0) * cp) / m22,
            lam * x.t22 * (x.t22 / 2.0) * sp / m22,
        );
        let mass = MassProps {
            m: [m11, m12, m21, m22],
            i: [rod_i(m11, l11), rod_i(m12, l12), rod_i(m21, x.l21), rod_i(lam * l22, l22) + rod_i(lam * x.t22, x.t22)],
            s22,
        };
        Ok(Finger {
            l11,
            l12,
            l21: x.l21,
            l22,
            t22: x.t22,
            psi: x.psi,
            w,
            o21,
            gamma,
            sigma,
            k10,
            open,
            mass,
            psi_cs: V2::new(cp, sp),
        })
    }

    /// Direct geometric model (MODEL.md §5.1): pose from the active angles.
    #[inline]
    pub fn dgm(&self, q11: f64, q21: f64) -> Result<Pose, GeomError> {
        self.dgm_with(q11, q21, true)
    }

    /// DGM for the simulator's right-hand side: as [`Finger::dgm`] but the angles q12, q22
    /// and q13 are left NaN (no `atan2`) and sin/cos come from
    /// [`crate::math::sin_cos_fast`]; sin q13 is `cross(x12, x22)`, q22 is
    /// [`Pose::q22_from_vectors`].
    #[inline]
    pub fn dgm_fast(&self, q11: f64, q21: f64) -> Result<Pose, GeomError> {
        self.dgm_with(q11, q21, false)
    }

    #[inline(always)]
    fn dgm_with(&self, q11: f64, q21: f64, all_angles: bool) -> Result<Pose, GeomError> {
        let (x11, x21) = if all_angles { (e(q11), e(q21)) } else { (e_fast(q11), e_fast(q21)) };
        let o12 = self.o21 + self.l11 * x11;
        let o22 = self.o21 + self.l21 * x21;
        let v = o12 - o22;
        let d2 = v.norm_squared();
        if !(d2 > 0.0) {
            return Err(GeomError::NotMountable);
        }
        let r1sq = self.l12 * self.l12 / d2;
        let r2sq = self.l22 * self.l22 / d2;
        let ak = 0.5 * (1.0 - r1sq + r2sq);
        let bk2 = r2sq - ak * ak;
        if !(bk2 >= 0.0) {
            return Err(GeomError::NotMountable);
        }
        let o13 = o22 + ak * v + self.gamma * bk2.sqrt() * perp(v);
        let x12 = (o13 - o12) / self.l12;
        let x22 = (o13 - o22) / self.l22;
        let (q12, q22, q13) = if all_angles {
            let q22 = cross(x21, x22).atan2(x21.dot(&x22));
            let q12 = cross(x11, x12).atan2(x11.dot(&x12));
            (q12, q22, wrap(q21 + q22 - q11 - q12))
        } else {
            (f64::NAN, f64::NAN, f64::NAN)
        };
        Ok(Pose { q11, q12, q21, q22, q13, o12, o22, o13, x11, x12, x21, x22 })
    }

    /// Inverse model of leg 1 (MODEL.md §5.2): pose from the phalanx angles (θ1, θ2),
    /// with the working mode σ and the DGM check of the assembly mode Γ.
    pub fn ik(&self, theta1: f64, theta2: f64) -> Result<Pose, GeomError> {
        let q21 = theta1;
        let q22 = theta2 - self.psi;
        let o22 = self.o21 + self.l21 * e(q21);
        let o13 = o22 + self.l22 * e(q21 + q22);
        let (pa, pb) = circle_intersections(self.o21, self.l11, o13, self.l12).ok_or(GeomError::NotMountable)?;
        // q12 is the angle from x11 to x12; sin q12 = cross(x11, x12).
        let sin_q12 = |o12: V2| cross(o12 - self.o21, o13 - o12);
        let o12 = if sin_q12(pa) * self.sigma >= sin_q12(pb) * self.sigma { pa } else { pb };
        if sin_q12(o12) * self.sigma < 0.0 {
            return Err(GeomError::AssemblyModeChange);
        }
        let q11 = angle(o12 - self.o21);
        let pose = self.dgm(q11, q21).map_err(|_| GeomError::AssemblyModeChange)?;
        if wrap(pose.q22 - q22).abs() > 1e-9 {
            return Err(GeomError::AssemblyModeChange);
        }
        Ok(pose)
    }

    /// Distal phalanx tip in local coordinates at pose `p`.
    pub fn tip(&self, p: &Pose) -> V2 {
        p.o22 + self.t22 * self.distal_dir(p)
    }

    /// Direction x_d of the distal phalanx at pose `p` (x22 rotated by ψ).
    #[inline]
    pub fn distal_dir(&self, p: &Pose) -> V2 {
        let (c, s) = (self.psi_cs.x, self.psi_cs.y);
        V2::new(c * p.x22.x - s * p.x22.y, s * p.x22.x + c * p.x22.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circles() {
        let (a, b) = circle_intersections(V2::zeros(), 1.0, V2::new(1.0, 0.0), 1.0).unwrap();
        assert!((a - V2::new(0.5, 0.75f64.sqrt())).norm() < 1e-15);
        assert!((b - V2::new(0.5, -0.75f64.sqrt())).norm() < 1e-15);
        assert!(circle_intersections(V2::zeros(), 1.0, V2::new(3.0, 0.0), 1.0).is_none());
    }
}
