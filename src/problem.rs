//! Problem files: the scene (MODEL.md §1.1), the nominal design and the design bounds.
//!
//! A problem file is TOML with the sections `[hand]`, `[object]`, `[contact]`,
//! `[environment]`, `[criteria]`, `[solver]`, `[nominal]` and `[bounds]`. Every key is
//! required and unknown keys are rejected: there are no silent defaults. Errors name the
//! file and the field.

use crate::math::deg;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Error while loading or validating a problem file.
#[derive(Debug, thiserror::Error)]
pub enum ProblemError {
    /// The file could not be read.
    #[error("{file}: cannot read problem file: {err}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The I/O error.
        err: std::io::Error,
    },
    /// TOML syntax error, unknown key, missing key or wrong type.
    #[error("{file}: {message}")]
    Parse {
        /// The file.
        file: PathBuf,
        /// toml's message (contains the line, column and key).
        message: String,
    },
    /// A field has a value outside its physical range.
    #[error("{file}: field `{field}` = {value}: {rule}")]
    Invalid {
        /// The file.
        file: PathBuf,
        /// Dotted field name, e.g. `object.radius`.
        field: String,
        /// The offending value.
        value: String,
        /// What the value must satisfy.
        rule: String,
    },
}

/// Design vector `x = (l21, b, t22, r, p, ψ)` (MODEL.md §1.2). ψ in radians.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Design {
    /// Proximal phalanx length l21 (m).
    pub l21: f64,
    /// Palm length b (m).
    pub b: f64,
    /// Distal phalanx length t22 (m).
    pub t22: f64,
    /// Transmission ratio r = l22/l11.
    pub r: f64,
    /// Ratio p = l11/l21.
    pub p: f64,
    /// Distal angle ψ (rad).
    pub psi: f64,
}

/// Names of the six design variables, in order (ψ given in degrees in files and on the CLI).
pub const DESIGN_NAMES: [&str; 6] = ["l21", "b", "t22", "r", "p", "psi_deg"];

impl Design {
    /// The thesis' nominal design (MODEL.md §1.2).
    pub fn nominal() -> Self {
        Design { l21: 0.0494, b: 0.056, t22: 0.0376, r: 0.46, p: 0.4, psi: deg(129.76) }
    }
    /// As an array in optimiser units (ψ in degrees).
    pub fn to_array(&self) -> [f64; 6] {
        [self.l21, self.b, self.t22, self.r, self.p, self.psi.to_degrees()]
    }
    /// From an array in optimiser units (ψ in degrees).
    pub fn from_array(x: &[f64; 6]) -> Self {
        Design { l21: x[0], b: x[1], t22: x[2], r: x[3], p: x[4], psi: deg(x[5]) }
    }
    /// Total hand length l_hand = b + 2 t22 + 2 l21.
    pub fn l_hand(&self) -> f64 {
        self.b + 2.0 * self.t22 + 2.0 * self.l21
    }
    /// Parse `l21=..,b=..,t22=..,r=..,p=..,psi_deg=..` (all six required, each once).
    pub fn parse_assignments(s: &str) -> Result<Self, String> {
        let mut vals: [Option<f64>; 6] = [None; 6];
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (k, v) = part
                .split_once('=')
                .ok_or_else(|| format!("--design: `{part}` is not of the form name=value"))?;
            let k = k.trim();
            let idx = DESIGN_NAMES.iter().position(|n| *n == k).ok_or_else(|| {
                format!("--design: unknown variable `{k}` (expected one of {})", DESIGN_NAMES.join(", "))
            })?;
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| format!("--design: `{k}` = `{}` is not a number", v.trim()))?;
            if !x.is_finite() {
                return Err(format!("--design: `{k}` = {x} is not finite"));
            }
            if vals[idx].replace(x).is_some() {
                return Err(format!("--design: `{k}` given twice"));
            }
        }
        let mut arr = [0.0; 6];
        for (i, v) in vals.iter().enumerate() {
            arr[i] = v.ok_or_else(|| format!("--design: missing `{}`", DESIGN_NAMES[i]))?;
        }
        Ok(Design::from_array(&arr))
    }
}

/// Scene constants of MODEL.md §1.1 (SI units, angles in radians).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scene {
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
    /// Object radius R (m).
    pub radius: f64,
    /// Object length L_c (m).
    pub length: f64,
    /// Object density ρ_c (kg/m³).
    pub density: f64,
    /// Grasp height h_c (m).
    pub grasp_height: f64,
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
}

impl Scene {
    /// Object mass m_c = ρ_c π R² L_c.
    pub fn object_mass(&self) -> f64 {
        self.density * std::f64::consts::PI * self.radius.powi(2) * self.length
    }
    /// Transverse inertia J_c = m_c (3R² + L_c²)/12.
    pub fn object_inertia(&self) -> f64 {
        self.object_mass() * (3.0 * self.radius.powi(2) + self.length.powi(2)) / 12.0
    }
    /// Lever of the tilting impulse k_c = |L_c/2 − h_c|.
    pub fn impulse_lever(&self) -> f64 {
        (self.length / 2.0 - self.grasp_height).abs()
    }
    /// Flores damping factor χ = 8(1 − e)/(5e) (D8).
    pub fn chi(&self) -> f64 {
        8.0 * (1.0 - self.restitution) / (5.0 * self.restitution)
    }
}

/// Integrator settings of the grasp simulation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSettings {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance (rad and rad/s).
    pub atol: f64,
    /// Maximum number of accepted + rejected steps before a discard.
    pub max_steps: u64,
}

/// Inclusive design bounds, in optimiser units (ψ in degrees).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Bounds {
    /// Lower bounds.
    pub lo: [f64; 6],
    /// Upper bounds.
    pub hi: [f64; 6],
}

/// A loaded and validated problem.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Problem {
    /// Problem name (from the file).
    pub name: String,
    /// Scene constants.
    pub scene: Scene,
    /// Integrator settings.
    pub solver: SolverSettings,
    /// Nominal design.
    pub nominal: Design,
    /// Design bounds.
    pub bounds: Bounds,
    /// Raw text of the file (hashed into checkpoints).
    #[serde(skip)]
    pub source_text: String,
}

// ---- raw TOML shape -------------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    name: String,
    hand: RawHand,
    object: RawObject,
    contact: RawContact,
    environment: RawEnv,
    criteria: RawCriteria,
    solver: SolverSettings,
    nominal: RawDesign,
    bounds: RawBounds,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHand {
    tau: f64,
    w: f64,
    rho_f: f64,
    r_open: f64,
    k_s: f64,
    k_stop: f64,
    c_stop: f64,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObject {
    radius: f64,
    length: f64,
    density: f64,
    grasp_height: f64,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContact {
    mu_s: f64,
    mu_d: f64,
    v_s: f64,
    v_d: f64,
    restitution: f64,
    k_contact: f64,
    v_min: f64,
    eps_sep: f64,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEnv {
    g: f64,
    g_eq: f64,
    theta_g_deg: f64,
    mu_g: f64,
    mu_p: f64,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCriteria {
    r_sing: Vec<f64>,
    margin_sing_deg: f64,
    sweep_step_deg: f64,
    dx_max: f64,
    theta_max_deg: f64,
    fold_max_deg: f64,
    offset_step: f64,
    offset_max: f64,
    t_filter: f64,
    eta_stab: f64,
    t_max: f64,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDesign {
    l21: f64,
    b: f64,
    t22: f64,
    r: f64,
    p: f64,
    psi_deg: f64,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBounds {
    l21: [f64; 2],
    b: [f64; 2],
    t22: [f64; 2],
    r: [f64; 2],
    p: [f64; 2],
    psi_deg: [f64; 2],
}

/// Physical range a field must lie in.
#[derive(Clone, Copy)]
enum Rule {
    Positive,
    NonNegative,
    Finite,
    /// Open-closed interval (lo, hi].
    In(f64, f64),
}

struct Checker<'a> {
    file: &'a Path,
}

impl Checker<'_> {
    fn check(&self, field: &str, v: f64, rule: Rule) -> Result<f64, ProblemError> {
        let bad = |rule: String| ProblemError::Invalid {
            file: self.file.to_path_buf(),
            field: field.to_string(),
            value: format!("{v}"),
            rule,
        };
        if !v.is_finite() {
            return Err(bad("must be a finite number".into()));
        }
        match rule {
            Rule::Positive if v <= 0.0 => Err(bad("must be > 0".into())),
            Rule::NonNegative if v < 0.0 => Err(bad("must be >= 0".into())),
            Rule::In(lo, hi) if !(v > lo && v <= hi) => Err(bad(format!("must lie in ({lo}, {hi}]"))),
            _ => Ok(v),
        }
    }
    fn fail(&self, field: &str, value: String, rule: &str) -> ProblemError {
        ProblemError::Invalid { file: self.file.to_path_buf(), field: field.into(), value, rule: rule.into() }
    }
}

impl Problem {
    /// Load and validate a problem file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ProblemError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path)
            .map_err(|err| ProblemError::Io { file: path.to_path_buf(), err })?;
        Self::from_toml_str(&text, path)
    }

    /// Parse and validate problem text; `path` is used in error messages only.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Self, ProblemError> {
        let raw: RawFile = toml::from_str(text)
            .map_err(|e| ProblemError::Parse { file: path.to_path_buf(), message: e.to_string().trim_end().to_string() })?;
        let c = Checker { file: path };
        use Rule::*;
        let h = &raw.hand;
        let o = &raw.object;
        let k = &raw.contact;
        let en = &raw.environment;
        let cr = &raw.criteria;
        let scene = Scene {
            tau: c.check("hand.tau", h.tau, Positive)?,
            w: c.check("hand.w", h.w, Positive)?,
            rho_f: c.check("hand.rho_f", h.rho_f, Positive)?,
            r_open: c.check("hand.r_open", h.r_open, Positive)?,
            k_s: c.check("hand.k_s", h.k_s, NonNegative)?,
            k_stop: c.check("hand.k_stop", h.k_stop, Positive)?,
            c_stop: c.check("hand.c_stop", h.c_stop, NonNegative)?,
            radius: c.check("object.radius", o.radius, Positive)?,
            length: c.check("object.length", o.length, Positive)?,
            density: c.check("object.density", o.density, Positive)?,
            grasp_height: c.check("object.grasp_height", o.grasp_height, Positive)?,
            mu_s: c.check("contact.mu_s", k.mu_s, Positive)?,
            mu_d: c.check("contact.mu_d", k.mu_d, Positive)?,
            v_s: c.check("contact.v_s", k.v_s, Positive)?,
            v_d: c.check("contact.v_d", k.v_d, Positive)?,
            restitution: c.check("contact.restitution", k.restitution, In(0.0, 1.0))?,
            k_contact: c.check("contact.k_contact", k.k_contact, Positive)?,
            v_min: c.check("contact.v_min", k.v_min, Positive)?,
            eps_sep: c.check("contact.eps_sep", k.eps_sep, Positive)?,
            g: c.check("environment.g", en.g, NonNegative)?,
            g_eq: c.check("environment.g_eq", en.g_eq, NonNegative)?,
            theta_g: deg(c.check("environment.theta_g_deg", en.theta_g_deg, Finite)?),
            mu_g: c.check("environment.mu_g", en.mu_g, Positive)?,
            mu_p: c.check("environment.mu_p", en.mu_p, NonNegative)?,
            r_sing: cr
                .r_sing
                .iter()
                .enumerate()
                .map(|(i, &r)| c.check(&format!("criteria.r_sing[{i}]"), r, Positive))
                .collect::<Result<_, _>>()?,
            margin_sing: deg(c.check("criteria.margin_sing_deg", cr.margin_sing_deg, In(0.0, 90.0))?),
            sweep_step: deg(c.check("criteria.sweep_step_deg", cr.sweep_step_deg, In(0.0, 45.0))?),
            dx_max: c.check("criteria.dx_max", cr.dx_max, Positive)?,
            theta_max: deg(c.check("criteria.theta_max_deg", cr.theta_max_deg, In(0.0, 90.0))?),
            fold_max: deg(c.check("criteria.fold_max_deg", cr.fold_max_deg, In(0.0, 180.0))?),
            offset_step: c.check("criteria.offset_step", cr.offset_step, Positive)?,
            offset_max: c.check("criteria.offset_max", cr.offset_max, NonNegative)?,
            t_filter: c.check("criteria.t_filter", cr.t_filter, Positive)?,
            eta_stab: c.check("criteria.eta_stab", cr.eta_stab, In(0.0, 1.0))?,
            t_max: c.check("criteria.t_max", cr.t_max, Positive)?,
        };
        if cr.r_sing.is_empty() {
            return Err(c.fail("criteria.r_sing", "[]".into(), "must list at least one radius"));
        }
        if scene.v_d <= scene.v_s {
            return Err(c.fail("contact.v_d", format!("{}", scene.v_d), "must be > contact.v_s"));
        }
        if scene.offset_max / scene.offset_step > 1e5 {
            return Err(c.fail("criteria.offset_step", format!("{}", scene.offset_step), "gives more than 1e5 offsets"));
        }
        let s = &raw.solver;
        c.check("solver.rtol", s.rtol, In(0.0, 1.0))?;
        c.check("solver.atol", s.atol, Positive)?;
        if s.max_steps == 0 {
            return Err(c.fail("solver.max_steps", "0".into(), "must be >= 1"));
        }
        let n = &raw.nominal;
        let nominal = Design {
            l21: c.check("nominal.l21", n.l21, Positive)?,
            b: c.check("nominal.b", n.b, Positive)?,
            t22: c.check("nominal.t22", n.t22, Positive)?,
            r: c.check("nominal.r", n.r, Positive)?,
            p: c.check("nominal.p", n.p, Positive)?,
            psi: deg(c.check("nominal.psi_deg", n.psi_deg, Finite)?),
        };
        let b = &raw.bounds;
        let pairs = [b.l21, b.b, b.t22, b.r, b.p, b.psi_deg];
        let mut lo = [0.0; 6];
        let mut hi = [0.0; 6];
        for (i, pr) in pairs.iter().enumerate() {
            let name = format!("bounds.{}", DESIGN_NAMES[i]);
            let rule = if i == 5 { Finite } else { Positive };
            lo[i] = c.check(&name, pr[0], rule)?;
            hi[i] = c.check(&name, pr[1], rule)?;
            if lo[i] >= hi[i] {
                return Err(c.fail(&name, format!("[{}, {}]", pr[0], pr[1]), "lower bound must be < upper bound"));
            }
        }
        Ok(Problem {
            name: raw.name,
            scene,
            solver: raw.solver,
            nominal,
            bounds: Bounds { lo, hi },
            source_text: text.to_string(),
        })
    }
}
