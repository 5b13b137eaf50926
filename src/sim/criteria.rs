//! Dynamic criteria of MODEL.md §9: impact energy, force margin, stability threshold.

use crate::math::V2;
use crate::params::SceneParams;

/// Impact energies at a contact onset (§9.1).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Impact {
    /// Effective finger mass m_finger = 1/(a M⁻¹ aᵀ).
    pub m_finger: f64,
    /// Onset velocity V = δ̇⁻ (uncapped).
    pub v_impact: f64,
    /// E_cyl = P²/(2 m_cyl).
    pub e_cyl: f64,
    /// E_trans = P²/(2 m_c).
    pub e_trans: f64,
    /// E_rot = P²/(2 m_rot).
    pub e_rot: f64,
    /// min(E_lim,trans, E_lim,rot).
    pub e_lim: f64,
}

/// Energy limits (E_lim,trans, E_lim,rot) of eqs. 3.27, 3.29. E_lim,rot is the rise of the
/// centre of mass tilting about the base edge, m g [(L/2)(cos θ − 1) + R sin θ], at
/// θ = min(θ_max, θ_tip), θ_tip = atan(2R/L): beyond θ_tip the rise falls (the object tips
/// over by itself), so the energy to tilt it past θ_max is the barrier at θ_tip
/// (docs/model.md; eq. 3.29 literally turns negative above 2 θ_tip).
pub fn impact_limits(s: &SceneParams) -> (f64, f64) {
    let mc = s.object.mass();
    let trans = s.env.mu_g * mc * s.env.g * s.criteria.dx_max;
    let (half, r) = (s.object.length / 2.0, s.object.radius);
    let theta = s.criteria.theta_max.min((r / half).atan());
    let rot = mc * s.env.g * (half * (theta.cos() - 1.0) + r * theta.sin());
    (trans, rot)
}

/// Impact energies for a finger of effective mass `m_finger` hitting at `v`.
pub fn impact(s: &SceneParams, m_finger: f64, v: f64) -> Impact {
    let m_c = s.object.mass();
    let kc = s.object.impulse_lever();
    let m_rot = if kc > 0.0 { s.object.inertia() / (kc * kc) } else { f64::INFINITY };
    let m_cyl = if m_rot.is_finite() { m_c * m_rot / (m_c + m_rot) } else { m_c };
    let m_tot = m_finger * m_cyl / (m_finger + m_cyl);
    let p = (1.0 + s.contact.restitution) * m_tot * v;
    let (lt, lr) = impact_limits(s);
    Impact {
        m_finger,
        v_impact: v,
        e_cyl: p * p / (2.0 * m_cyl),
        e_trans: p * p / (2.0 * m_c),
        e_rot: if m_rot.is_finite() { p * p / (2.0 * m_rot) } else { 0.0 },
        e_lim: lt.min(lr),
    }
}

/// R_area = min(μ_g m_c g, R m_c g / h_c) (§9.3).
pub fn r_area(s: &SceneParams) -> f64 {
    let mg = s.object.mass() * s.env.g;
    (s.env.mu_g * mg).min(s.object.radius * mg / s.object.grasp_height)
}

/// Force margin m(F) of §9.3 (≥ 0 = stable).
#[inline]
pub fn force_margin(s: &SceneParams, r_area: f64, f: V2) -> f64 {
    if f.y >= 0.0 {
        r_area - f.norm()
    } else {
        r_area - s.env.mu_p * f.y - f.x.abs()
    }
}

/// U_min = min_i (2/5) K^{−2/3} (f⁰_i)^{5/3} (§9.4).
pub fn u_min(s: &SceneParams, f0: [f64; 2]) -> f64 {
    f0.iter()
        .map(|&f| 0.4 * s.contact.k_contact.powf(-2.0 / 3.0) * f.max(0.0).powf(5.0 / 3.0))
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn margin_continuous_at_fy_zero() {
        let s = crate::params::Problem::from_toml_str(
            &std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap(),
            std::path::Path::new("bottle-1l.toml"),
        )
        .unwrap()
        .scene;
        let ra = r_area(&s);
        let a = force_margin(&s, ra, V2::new(0.7, 1e-12));
        let b = force_margin(&s, ra, V2::new(0.7, -1e-12));
        assert!((a - b).abs() < 1e-9);
        let (lt, lr) = impact_limits(&s);
        assert!((lt - 3.9448e-3).abs() < 1e-7, "{lt}");
        assert!((lr - 6.7345e-3).abs() < 1e-7, "{lr}");
    }

    /// E_lim,rot is the tilt barrier up to θ_max: it grows with θ_max up to the tipping
    /// angle atan(2R/L) and stays at m g (√(R² + L²/4) − L/2) beyond it (eq. 3.29 itself
    /// falls and turns negative there: −0.59 J at 90° for the 1 l bottle).
    #[test]
    fn the_rotation_limit_is_the_barrier_up_to_theta_max() {
        let mut s = crate::params::Problem::from_toml_str(
            &std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap(),
            std::path::Path::new("bottle-1l.toml"),
        )
        .unwrap()
        .scene;
        let (r, half) = (s.object.radius, s.object.length / 2.0);
        let barrier = s.object.mass() * s.env.g * ((r * r + half * half).sqrt() - half);
        let mut last = 0.0;
        for deg in 1..=90 {
            s.criteria.theta_max = f64::from(deg).to_radians();
            let lr = impact_limits(&s).1;
            assert!(lr >= last && lr <= barrier * (1.0 + 1e-12), "{deg}°: {lr} after {last}, barrier {barrier}");
            last = lr;
        }
        assert!((last - barrier).abs() < 1e-12 * barrier, "{last} {barrier}");
    }
}
