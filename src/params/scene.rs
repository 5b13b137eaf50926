//! Scene constants of MODEL.md §1.1 as typed sections, one per problem-file section (SI
//! units, angles in radians).

use serde::{Deserialize, Serialize};

/// `[hand]`: actuator, links and the distal stop.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Hand {
    /// Actuator torque τ (N·m).
    pub tau: f64,
    /// Rod radius w of every link (m).
    pub w: f64,
    /// Finger density ρ_f (kg/m³).
    pub rho_f: f64,
    /// Radius R_open of the virtual cylinder defining the open pose (m).
    pub r_open: f64,
    /// Spring rate k_s added to the preload (N·m/rad).
    pub k_s: f64,
    /// Distal joint stop stiffness (N·m/rad).
    pub k_stop: f64,
    /// Distal joint stop damping factor (s/rad).
    pub c_stop: f64,
}

/// `[object]`: the cylinder and where it is grasped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Object {
    /// Object radius R (m).
    pub radius: f64,
    /// Object length L_c (m).
    pub length: f64,
    /// Object density ρ_c (kg/m³).
    pub density: f64,
    /// Grasp height h_c (m).
    pub grasp_height: f64,
}

impl Object {
    /// Object mass m_c = ρ_c π R² L_c.
    pub fn mass(&self) -> f64 {
        self.density * std::f64::consts::PI * self.radius.powi(2) * self.length
    }
    /// Transverse inertia J_c = m_c (3R² + L_c²)/12.
    pub fn inertia(&self) -> f64 {
        self.mass() * (3.0 * self.radius.powi(2) + self.length.powi(2)) / 12.0
    }
    /// Lever of the tilting impulse k_c = |L_c/2 − h_c|.
    pub fn impulse_lever(&self) -> f64 {
        (self.length / 2.0 - self.grasp_height).abs()
    }
}

/// `[contact]`: the object–phalanx contact law (Hertz–Flores normal force, regularised friction).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactLaw {
    /// Static friction object–phalanx μ_s.
    pub mu_s: f64,
    /// Dynamic friction object–phalanx μ_d.
    pub mu_d: f64,
    /// Static transition velocity v_s (m/s).
    pub v_s: f64,
    /// Dynamic transition velocity v_d (m/s).
    pub v_d: f64,
    /// Restitution coefficient e.
    pub restitution: f64,
    /// Hertz stiffness K (N/m^1.5).
    pub k_contact: f64,
    /// Floor of the captured onset velocity (m/s).
    pub v_min: f64,
    /// Separation hysteresis ε_sep (m).
    pub eps_sep: f64,
}

impl ContactLaw {
    /// Flores damping factor χ = 8(1 − e)/(5e) (D8).
    pub fn chi(&self) -> f64 {
        8.0 * (1.0 - self.restitution) / (5.0 * self.restitution)
    }
}

/// `[environment]`: gravity and the object's other contacts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Environment {
    /// Gravity g (m/s²).
    pub g: f64,
    /// In-plane gravity magnitude g_eq (m/s²).
    pub g_eq: f64,
    /// In-plane gravity direction θ_g (rad).
    pub theta_g: f64,
    /// Object–ground friction μ_g.
    pub mu_g: f64,
    /// Object–palm friction μ_p.
    pub mu_p: f64,
}

/// `[criteria]`: the stage criteria and their grids.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Criteria {
    /// Radii of the closed poses of the singularity sweep (m).
    pub r_sing: Vec<f64>,
    /// Singularity margin (rad).
    pub margin_sing: f64,
    /// Sweep step Δθ (rad).
    pub sweep_step: f64,
    /// Impact criterion translation limit Δx_max (m).
    pub dx_max: f64,
    /// Impact criterion rotation limit θ_max (rad).
    pub theta_max: f64,
    /// Max distal fold at first contact (rad).
    pub fold_max: f64,
    /// Offset grid step Δ_off (m).
    pub offset_step: f64,
    /// Offset grid end off_max (m).
    pub offset_max: f64,
    /// Low-pass time constant of the force criterion T_f (s).
    pub t_filter: f64,
    /// Stability threshold η_stab.
    pub eta_stab: f64,
    /// Maximum simulated time (s).
    pub t_max: f64,
    /// Which static force set defines α and F̃ (MODEL.md §6.5, D22).
    pub force_model: ForceModel,
}

/// The force set that defines the objectives α and F̃ (MODEL.md §6.5, decision D22).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ForceModel {
    /// Friction-mobilised forces f^μ (the thesis's §2.2.1 / §4.2.2 forces; the default).
    #[default]
    Mobilised,
    /// Frictionless forces f⁰ (the v1 definition).
    Frictionless,
}

impl ForceModel {
    /// The problem-file spelling (`mobilised`, `frictionless`).
    pub fn as_str(self) -> &'static str {
        match self {
            ForceModel::Mobilised => "mobilised",
            ForceModel::Frictionless => "frictionless",
        }
    }
}

/// All scene constants of MODEL.md §1.1, section by section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneParams {
    /// `[hand]`.
    pub hand: Hand,
    /// `[object]`.
    pub object: Object,
    /// `[contact]`.
    pub contact: ContactLaw,
    /// `[environment]`.
    pub env: Environment,
    /// `[criteria]`.
    pub criteria: Criteria,
    /// `[scene]` (MODEL.md §14).
    pub setup: super::scene_kind::SceneSetup,
}

/// One object of a robust problem: its cylinder, grasp height and grip torque.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectCase {
    /// Its name (CSV columns `NAME.p_stay`, …).
    pub name: String,
    /// The cylinder and where it is grasped.
    pub object: Object,
    /// The grip torque τ the controller applies to this object (N·m; the spring preload is
    /// sized once, at `[hand] tau`).
    pub tau: f64,
    /// The problem file its cylinder was taken from, as written (None: given inline).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
}
