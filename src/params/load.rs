//! Problem files: TOML with the sections `[hand]`, `[object]`, `[contact]`,
//! `[environment]`, `[criteria]`, `[scene]`, `[solver]`, `[nominal]` and `[bounds]`. Every key is
//! required but `solver.method` (absent: the default method, [`Method::PROBLEM_DEFAULT`]; it
//! was RADAU5 before session 38) and unknown keys are rejected. Errors name the file and the field.

use super::checker::Checker;
use super::design::{Bounds, Design, DESIGN_NAMES};
use super::limits::{MAX_FILE_BYTES, MAX_R_SING};
use super::method::Method;
use super::robust::Robust;
use super::robust_load::RawRobust;
use super::scene::{ContactLaw, Criteria, Environment, ForceModel, Hand, Object, SceneParams};
use super::scene_kind::{SceneChoice, SceneKind, SceneSetup};
use crate::error::{Error, Result};
use crate::math::deg;
use serde::{Deserialize, Serialize};
use std::io::Read;
use std::path::Path;

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
    /// Integration method (`solver.method`; absent: [`Method::PROBLEM_DEFAULT`]). Left out when
    /// serialised as RADAU5, the type's default.
    #[serde(default, skip_serializing_if = "Method::is_default")]
    pub method: Method,
    /// The file names `solver.method` (false: `method` is the default, whose tolerances the
    /// simulator scales, `sim::Scaling::DEFAULT`; a resumed run of a problem without the key
    /// takes the method its checkpoint records, [`Problem::with_run_method`]).
    #[serde(skip)]
    pub method_named: bool,
}

/// A loaded and validated problem.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Problem {
    /// Problem name (from the file).
    pub name: String,
    /// Scene constants, section by section.
    pub scene: SceneParams,
    /// Integrator settings.
    pub solver: SolverSettings,
    /// Nominal design.
    pub nominal: Design,
    /// Design bounds.
    pub bounds: Bounds,
    /// `[robust]`: several objects and the uncertainty of the grasp (None: one object, the
    /// nominal inputs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robust: Option<Robust>,
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
    scene: RawScene,
    solver: RawSolver,
    nominal: RawDesign,
    bounds: RawBounds,
    #[serde(default)]
    robust: Option<RawRobust>,
}

/// `[solver]` as written: `max_steps` a number, so that `1e8` (the limit as the docs write
/// it) is read like `100000000` and checked as a whole number in its range.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    rtol: f64,
    atol: f64,
    max_steps: f64,
    /// Optional: absent is the default method (RADAU5 before session 38; a run folder of
    /// then resumes with it, [`Problem::with_run_method`]).
    #[serde(default)]
    method: Option<String>,
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
    force_model: String,
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    kind: String,
    x_off: f64,
    t_obs: f64,
    ground_points: f64,
    ground_k: f64,
    ground_v_s: f64,
    ground_v_d: f64,
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
    l21: Vec<f64>,
    b: Vec<f64>,
    t22: Vec<f64>,
    r: Vec<f64>,
    p: Vec<f64>,
    psi_deg: Vec<f64>,
}

/// A struct of checked values whose fields have the raw section's names: field `f` is
/// `c.check("SECTION.f", raw.f)?` (the limit of `SECTION.f`, the error naming it).
macro_rules! checked {
    ($c:expr, $section:literal, $raw:expr, $ty:ident { $($f:ident),* $(,)? }) => {
        $ty { $($f: $c.check(concat!($section, ".", stringify!($f)), $raw.$f)?,)* }
    };
}

impl Problem {
    /// This problem as a run resumes it whose checkpoint records the method `recorded` (its
    /// options' `method`; None: RADAU5, the method of a checkpoint that names none): where the
    /// file names no `solver.method`, the run keeps the method it started with (a run folder
    /// of a gripopt before session 38 ran RADAU5 there, not today's default). A file that
    /// names its method keeps it.
    pub fn with_run_method(mut self, recorded: Option<Method>) -> Self {
        if !self.solver.method_named {
            self.solver.method = recorded.unwrap_or_default();
        }
        self
    }

    /// The files the problem read besides itself: the robust objects' `file = "…"`, each
    /// resolved against the folder of `problem_path` (the file it was loaded from), as the
    /// loader reads them. Outputs must never replace them (`gripopt::check_output_file`).
    pub fn object_files(&self, problem_path: &Path) -> Vec<std::path::PathBuf> {
        let folder = problem_path.parent().unwrap_or(Path::new("."));
        self.robust.iter().flat_map(|r| &r.objects).filter_map(|o| o.file.as_ref()).map(|f| folder.join(f)).collect()
    }

    /// A run folder keeps only its problem.toml, hashed: a robust object taken from another
    /// file (`file = "…"`) could change under a run unnoticed (resume, replay and verify would
    /// read the edited file) and would be missing where the folder is moved. A run's problem
    /// must therefore give every object inline; the error names `path` and the field.
    pub fn check_self_contained(&self, path: &Path) -> Result<()> {
        let objects = self.robust.iter().flat_map(|r| r.objects.iter().enumerate());
        for (i, o) in objects {
            if let Some(f) = &o.file {
                return Err(Error::InvalidField {
                    file: path.to_path_buf(),
                    field: format!("robust.objects[{i}].file"),
                    value: format!("{f:?}"),
                    rule: format!("a run (optimise, resume) needs every object inline: a run folder keeps only problem.toml, so an object file could change under the run unnoticed; copy {f}'s [object] values (radius, length, density, grasp_height) into this object instead of `file`"),
                });
            }
        }
        Ok(())
    }

    /// Load and validate a problem file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let io = |err| Error::io(path, "cannot read problem file", err);
        let file = crate::fsutil::open_regular(path).map_err(io)?;
        let mut bytes = Vec::new();
        file.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes).map_err(io)?;
        if bytes.len() as u64 > MAX_FILE_BYTES {
            return Err(Error::InvalidField {
                file: path.to_path_buf(),
                field: "(the whole file)".into(),
                value: format!("more than {MAX_FILE_BYTES} bytes"),
                rule: "a problem file is a few kB of TOML".into(),
            });
        }
        let text = String::from_utf8(bytes)
            .map_err(|e| io(std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not UTF-8 text ({e})"))))?;
        Self::from_toml_str(&text, path)
    }

    /// Parse and validate problem text; `path` is used in error messages only.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Self> {
        let raw: RawFile = toml::from_str(text)
            .map_err(|e| {
                // what toml echoes of the file (a line of 800 kB) cut to a readable length
                let mut message = crate::error::cap_lines(e.to_string().trim_end(), 200);
                if message.contains("missing field `force_model`") {
                    // files written before MODEL.md v2 (D22), e.g. the copy in an older run folder
                    message.push_str("\n(problem files from before MODEL.md v2 lack `criteria.force_model`: add `force_model = \"frictionless\"` to reproduce a run as it was computed, or \"mobilised\" for the thesis's forces, D22)");
                }
                Error::ProblemParse { file: path.to_path_buf(), message, source: Box::new(e) }
            })?;
        let c = Checker { file: path };
        let h = &raw.hand;
        let o = &raw.object;
        let k = &raw.contact;
        let en = &raw.environment;
        let cr = &raw.criteria;
        let sc = &raw.scene;
        let setup = SceneSetup {
            kind: sc.kind.parse::<SceneKind>().map_err(|()| {
                c.fail(
                    "scene.kind",
                    format!("{:?}", sc.kind),
                    "must be \"centred\", \"offset\" or \"free\" (MODEL.md §14)",
                )
            })?,
            x_off: c.check("scene.x_off", sc.x_off)?,
            t_obs: c.check("scene.t_obs", sc.t_obs)?,
            ground_points: c.whole("scene.ground_points", sc.ground_points)? as usize,
            ground_k: c.check("scene.ground_k", sc.ground_k)?,
            ground_v_s: c.check("scene.ground_v_s", sc.ground_v_s)?,
            ground_v_d: c.check("scene.ground_v_d", sc.ground_v_d)?,
        };
        if setup.ground_v_d <= setup.ground_v_s {
            return Err(c.fail("scene.ground_v_d", format!("{}", setup.ground_v_d), "must be > scene.ground_v_s"));
        }
        let scene = SceneParams {
            setup,
            hand: checked!(c, "hand", h, Hand { tau, w, rho_f, r_open, k_s, k_stop, c_stop }),
            object: checked!(c, "object", o, Object { radius, length, density, grasp_height }),
            contact: checked!(
                c,
                "contact",
                k,
                ContactLaw { mu_s, mu_d, v_s, v_d, restitution, k_contact, v_min, eps_sep }
            ),
            env: Environment {
                g: c.check("environment.g", en.g)?,
                g_eq: c.check("environment.g_eq", en.g_eq)?,
                theta_g: deg(c.check("environment.theta_g_deg", en.theta_g_deg)?),
                mu_g: c.check("environment.mu_g", en.mu_g)?,
                mu_p: c.check("environment.mu_p", en.mu_p)?,
            },
            criteria: Criteria {
                r_sing: cr
                    .r_sing
                    .iter()
                    .enumerate()
                    .map(|(i, &r)| c.check(&format!("criteria.r_sing[{i}]"), r))
                    .collect::<Result<_, _>>()?,
                margin_sing: deg(c.check("criteria.margin_sing_deg", cr.margin_sing_deg)?),
                sweep_step: deg(c.check("criteria.sweep_step_deg", cr.sweep_step_deg)?),
                dx_max: c.check("criteria.dx_max", cr.dx_max)?,
                theta_max: deg(c.check("criteria.theta_max_deg", cr.theta_max_deg)?),
                fold_max: deg(c.check("criteria.fold_max_deg", cr.fold_max_deg)?),
                offset_step: c.check("criteria.offset_step", cr.offset_step)?,
                offset_max: c.check("criteria.offset_max", cr.offset_max)?,
                t_filter: c.check("criteria.t_filter", cr.t_filter)?,
                eta_stab: c.check("criteria.eta_stab", cr.eta_stab)?,
                t_max: c.check("criteria.t_max", cr.t_max)?,
                force_model: match cr.force_model.as_str() {
                    "mobilised" => ForceModel::Mobilised,
                    "frictionless" => ForceModel::Frictionless,
                    other => {
                        return Err(c.fail(
                            "criteria.force_model",
                            format!("{other:?}"),
                            "must be \"mobilised\" or \"frictionless\" (MODEL.md D22)",
                        ))
                    }
                },
            },
        };
        // the hand grasps the object's side, as each robust object must (robust_load)
        if scene.object.grasp_height >= scene.object.length {
            return Err(c.fail(
                "object.grasp_height",
                format!("{}", scene.object.grasp_height),
                &format!("must be below the object's top (object.length {})", scene.object.length),
            ));
        }
        if scene.object.grasp_height < scene.hand.w {
            return Err(c.fail(
                "object.grasp_height",
                format!("{}", scene.object.grasp_height),
                &super::checker::below_finger_rule(scene.hand.w),
            ));
        }
        if scene.env.g_eq != 0.0 && scene.env.theta_g.cos().abs() > 1e-12 {
            return Err(c.fail(
                "environment.theta_g_deg",
                format!("{}", en.theta_g_deg),
                &format!(
                    "must be -90 or 90 where environment.g_eq ({}) is not 0: finger 2 is finger 1's mirror image (MODEL.md §2, §8), which a gravity component along the fingers' closing axis x would break (docs/model.md decision 23)",
                    scene.env.g_eq
                ),
            ));
        }
        if cr.r_sing.len() > MAX_R_SING {
            return Err(c.fail(
                "criteria.r_sing",
                format!("{} radii", cr.r_sing.len()),
                &format!("must list at most {MAX_R_SING} radii"),
            ));
        }
        if cr.r_sing.is_empty() {
            return Err(c.fail("criteria.r_sing", "[]".into(), "must list at least one radius"));
        }
        if scene.contact.v_d <= scene.contact.v_s {
            return Err(c.fail("contact.v_d", format!("{}", scene.contact.v_d), "must be > contact.v_s"));
        }
        if scene.criteria.offset_max / scene.criteria.offset_step > 1e5 {
            return Err(c.fail(
                "criteria.offset_step",
                format!("{}", scene.criteria.offset_step),
                "gives more than 1e5 offsets",
            ));
        }
        let s = &raw.solver;
        c.check("solver.rtol", s.rtol)?;
        c.check("solver.atol", s.atol)?;
        let method = match s.method.as_deref() {
            None => Method::PROBLEM_DEFAULT,
            Some(m) => Method::parse(m).ok_or_else(|| {
                c.fail(
                    "solver.method",
                    format!("{m:?}"),
                    &format!("must be {} (docs/problem-files.md)", Method::accepted()),
                )
            })?,
        };
        method.check_atol(s.atol).map_err(|rule| c.fail("solver.atol", super::limits::num(s.atol), &rule))?;
        let solver = SolverSettings {
            rtol: s.rtol,
            atol: s.atol,
            max_steps: c.whole("solver.max_steps", s.max_steps)? as u64,
            method,
            method_named: s.method.is_some(),
        };
        let n = &raw.nominal;
        let nominal = Design {
            l21: c.check("nominal.l21", n.l21)?,
            b: c.check("nominal.b", n.b)?,
            t22: c.check("nominal.t22", n.t22)?,
            r: c.check("nominal.r", n.r)?,
            p: c.check("nominal.p", n.p)?,
            psi: deg(c.check("nominal.psi_deg", n.psi_deg)?),
        };
        let b = &raw.bounds;
        let pairs = [&b.l21, &b.b, &b.t22, &b.r, &b.p, &b.psi_deg];
        let mut lo = [0.0; 6];
        let mut hi = [0.0; 6];
        for (i, pr) in pairs.iter().enumerate() {
            let name = format!("bounds.{}", DESIGN_NAMES[i]);
            if pr.len() != 2 {
                return Err(c.fail(&name, format!("{pr:?}"), "must be [lower, upper]: exactly two numbers"));
            }
            lo[i] = c.check(&name, pr[0])?;
            hi[i] = c.check(&name, pr[1])?;
            if lo[i] >= hi[i] {
                return Err(c.fail(&name, format!("[{}, {}]", pr[0], pr[1]), "lower bound must be < upper bound"));
            }
        }
        check_scene(&scene, path)?;
        let robust = match &raw.robust {
            Some(r) => Some(r.validate(&scene, &c)?),
            None => None,
        };
        Ok(Problem {
            name: raw.name,
            scene,
            solver,
            nominal,
            bounds: Bounds { lo, hi },
            robust,
            source_text: text.to_string(),
        })
    }

    /// This problem with stage 3 in `scene` (its kind, and its object offset where given;
    /// None keeps the problem's), checked as a problem file's `[scene]` is (`path`: where the request came
    /// from, for the error; e.g. the command line).
    pub fn in_scene(&self, scene: SceneChoice, path: &Path) -> Result<Problem> {
        let mut p = self.clone();
        p.scene.setup.kind = scene.kind;
        if let Some(x) = scene.x_off {
            p.scene.setup.x_off = Checker { file: path }.check("scene.x_off", x)?;
        }
        check_scene(&p.scene, path)?;
        Ok(p)
    }
}

/// The rules between sections: the free scene needs the hand horizontal (MODEL.md §14.1),
/// and a ground that bears the object (its static sink under its weight at most
/// [`MAX_GROUND_SINK`]).
fn check_scene(scene: &SceneParams, path: &Path) -> Result<()> {
    if scene.setup.kind.is_free() && scene.env.g_eq != 0.0 {
        return Err(Checker { file: path }.fail(
            "environment.g_eq",
            super::limits::num(scene.env.g_eq),
            "must be 0 for the free scene ([scene] kind = \"free\": the hand horizontal, MODEL.md §14.1)",
        ));
    }
    if scene.setup.kind.is_free() {
        // Hertz points K_g δ^1.5 share the weight: δ = (m g / (n K_g))^(2/3)
        let st = &scene.setup;
        let per_point = scene.object.mass() * scene.env.g / st.ground_points as f64;
        let sink = (per_point / st.ground_k).powf(2.0 / 3.0);
        if sink > MAX_GROUND_SINK {
            let least = per_point / MAX_GROUND_SINK.powf(1.5);
            return Err(Checker { file: path }.fail(
                "scene.ground_k",
                super::limits::num(st.ground_k),
                &format!(
                    "the object would sink {:.3} mm into the ground under its own weight ({} points of K_g δ^1.5 bearing {:.3} N each); the free scene models a rigid floor: at least {} N/m^1.5 keeps the sink within {} mm",
                    sink * 1e3,
                    st.ground_points,
                    per_point,
                    super::limits::num(round_up_3(least)),
                    MAX_GROUND_SINK * 1e3
                ),
            ));
        }
    }
    Ok(())
}

/// `v` > 0 rounded up to three significant digits (a bound that still holds, for a message).
fn round_up_3(v: f64) -> f64 {
    let unit = 10f64.powi(v.log10().floor() as i32 - 2);
    // through its three-digit text, so that it prints without binary noise
    format!("{:.2e}", (v / unit).ceil() * unit).parse().unwrap_or(v)
}

/// The largest static sink of the object into the ground the free scene accepts (m): the
/// ground is a stiff contact standing in for a rigid floor (MODEL.md §14).
pub const MAX_GROUND_SINK: f64 = 1e-3;
