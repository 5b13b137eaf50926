//! What a sweep is: the varied names and what each sets ([`Knob`], [`resolve`]), their
//! values ([`Vary`]), the whole grid with its stages ([`SweepSpec`]: checked, its points, the
//! problem and design at a point), and the record keys a sweep flattens ([`ARRAY_KEYS`]).

use crate::error::{Error, Result};
use crate::params::{limit, scene_kinds_using, Design, Problem, DESIGN_NAMES, LIMITS};

/// Problem-file fields that are whole numbers: swept over whole values only.
pub const INTEGER_FIELDS: [&str; 2] = ["scene.ground_points", "solver.max_steps"];

/// Largest number of values along one varied name.
pub const MAX_N: usize = 10_000;
/// Largest number of grid points of one sweep.
pub const MAX_POINTS: usize = 200_000;

/// Which stages a sweep runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Stages 0–1 (validity, open pose, singularity sweep).
    Kinematics,
    /// Stages 0–2.
    Static,
    /// Stages 0–3 (pipeline mode: stage 3 stops at the first violated criterion).
    Dynamic,
}

/// What a varied name sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Knob {
    /// Design variable by index into [`DESIGN_NAMES`].
    Design(usize),
    /// l11 (m): p = l11/l21 and ψ = 140 − 25.6 p (not with ψ varied).
    L11,
    /// l22 (m): r = l22/l11.
    L22,
    /// l_hand (m): t22 = (l_hand − b − 2 l21)/2.
    LHand,
    /// A numeric problem-file field, by its index into [`LIMITS`].
    Field(usize),
    /// `mu_scale`: a factor on the object–phalanx friction μ_s and μ_d of the simulated grasp
    /// (stage 3; stage 2's design statics keep the problem's μ_s, as a robust scenario does);
    /// 0 = frictionless phalanges (the friction mechanism of docs/scenes.md).
    MuScale,
}

/// One `--vary NAME=LO:HI:N`.
#[derive(Debug, Clone, PartialEq)]
pub struct Vary {
    /// The name as given (the CSV column).
    pub name: String,
    /// What it sets.
    pub knob: Knob,
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Number of values (1 = lo only).
    pub n: usize,
}

fn bad(flag: &str, what: &str, msg: impl std::fmt::Display) -> Error {
    Error::Input(format!("{flag} {what}: {msg}"))
}

/// Resolve a name to what it sets (`flag` is used in errors).
pub fn resolve(name: &str, flag: &str) -> Result<Knob> {
    if let Some(i) = DESIGN_NAMES.iter().position(|n| *n == name) {
        return Ok(Knob::Design(i));
    }
    match name {
        "l11" => return Ok(Knob::L11),
        "l22" => return Ok(Knob::L22),
        "l_hand" => return Ok(Knob::LHand),
        "mu_scale" => return Ok(Knob::MuScale),
        _ => {}
    }
    let is_field = |l: &&crate::params::Limit| !DESIGN_NAMES.contains(&l.field) && l.field != "criteria.r_sing";
    if let Some(i) = LIMITS.iter().position(|l| l.field == name && is_field(&l)) {
        return Ok(Knob::Field(i));
    }
    let short: Vec<usize> = (0..LIMITS.len())
        .filter(|&i| is_field(&&LIMITS[i]) && LIMITS[i].field.rsplit('.').next() == Some(name))
        .collect();
    match short.as_slice() {
        [i] => Ok(Knob::Field(*i)),
        [] => Err(bad(
            flag,
            name,
            format!(
                "unknown name (a design variable {}, a derived l11, l22, l_hand, mu_scale (phalanx friction factor), or a numeric problem-file field such as tau, density, grasp_height, radius, restitution, hand.w)",
                DESIGN_NAMES.join(", ")
            ),
        )),
        many => Err(bad(flag, name, format!("ambiguous; use one of {}", many.iter().map(|&i| LIMITS[i].field).collect::<Vec<_>>().join(", ")))),
    }
}

/// The admissible range of what a knob sets, for checking the varied values.
fn knob_limit(k: Knob) -> (f64, bool, f64, &'static str) {
    let l = match k {
        Knob::Design(i) => limit(DESIGN_NAMES[i]),
        Knob::Field(i) => &LIMITS[i],
        // derived lengths: the same range as the design lengths
        Knob::L11 | Knob::L22 => limit("l21"),
        Knob::LHand => return (0.0, true, 2.0, "m"),
        Knob::MuScale => return (0.0, false, 10.0, "-"),
    };
    (l.lo, l.lo_open, l.hi, l.unit)
}

impl Vary {
    /// Parse `NAME=LO:HI:N`, checking the name, N and the range against the field's limits.
    pub fn parse(s: &str) -> Result<Vary> {
        let flag = "--vary";
        let (name, spec) =
            s.split_once('=').ok_or_else(|| bad(flag, s, "expected NAME=LO:HI:N, e.g. tau=0.30:0.40:11"))?;
        let name = name.trim();
        let knob = resolve(name, flag)?;
        let parts: Vec<&str> = spec.split(':').map(str::trim).collect();
        if parts.len() != 3 {
            return Err(bad(flag, s, "expected NAME=LO:HI:N (three fields after `=`)"));
        }
        let num = |t: &str, what: &str| -> Result<f64> {
            let v: f64 = t.parse().map_err(|_| bad(flag, s, format!("{what} `{t}` is not a number")))?;
            if !v.is_finite() {
                return Err(bad(flag, s, format!("{what} `{t}` is not finite")));
            }
            Ok(v)
        };
        let lo = num(parts[0], "LO")?;
        let hi = num(parts[1], "HI")?;
        let n: usize =
            parts[2].parse().map_err(|_| bad(flag, s, format!("N `{}` is not a whole number >= 1", parts[2])))?;
        if n < 1 {
            return Err(bad(flag, s, "N must be at least 1"));
        }
        if n > MAX_N {
            return Err(bad(flag, s, format!("N = {n} is more than {MAX_N} values along one name")));
        }
        if lo > hi {
            return Err(bad(flag, s, format!("LO = {lo} is greater than HI = {hi}")));
        }
        if n > 1 && lo == hi {
            return Err(bad(flag, s, "LO = HI with N > 1 repeats one value; use N = 1"));
        }
        let (llo, lo_open, lhi, unit) = knob_limit(knob);
        for (what, v) in [("LO", lo), ("HI", hi)] {
            let below = if lo_open { v <= llo } else { v < llo };
            if below || v > lhi {
                return Err(bad(
                    flag,
                    s,
                    format!(
                        "{what} = {} is outside the admissible range {}{}, {}] {unit} of `{name}` (src/params/limits.rs)",
                        crate::params::fmt_num(v),
                        if lo_open { "(" } else { "[" },
                        crate::params::fmt_num(llo),
                        crate::params::fmt_num(lhi)
                    ),
                ));
            }
        }
        let v = Vary { name: name.to_string(), knob, lo, hi, n };
        if v.is_integer() {
            if let Some(x) = v.values().into_iter().find(|x| x.fract() != 0.0) {
                let field = match knob {
                    Knob::Field(i) => LIMITS[i].field,
                    _ => name,
                };
                return Err(bad(
                    flag,
                    s,
                    format!("{field} is a whole number, and this grid gives {x} (which would run as {}): choose LO, HI and N so that every value is whole, e.g. N = HI − LO + 1", x.round()),
                ));
            }
        }
        Ok(v)
    }

    /// It sets a whole-number field (swept over whole values, bisected over them).
    pub fn is_integer(&self) -> bool {
        matches!(self.knob, Knob::Field(i) if INTEGER_FIELDS.contains(&LIMITS[i].field))
    }

    /// The unit of its values.
    pub fn unit(&self) -> &'static str {
        knob_limit(self.knob).3
    }

    /// The n values, evenly spaced, lo and hi exact.
    pub fn values(&self) -> Vec<f64> {
        if self.n == 1 {
            return vec![self.lo];
        }
        (0..self.n)
            .map(
                |i| {
                    if i + 1 == self.n {
                        self.hi
                    } else {
                        self.lo + (self.hi - self.lo) * i as f64 / (self.n - 1) as f64
                    }
                },
            )
            .collect()
    }
}

/// A whole sweep.
#[derive(Debug, Clone)]
pub struct SweepSpec {
    /// The problem (its nominal design is the base design unless `design` is set).
    pub problem: Problem,
    /// Base design.
    pub design: Design,
    /// 1–3 varied names (the first varies fastest in the CSV).
    pub vary: Vec<Vary>,
    /// Stages to run.
    pub stage: Stage,
    /// Keep l_hand of the base design (t22 derived) when l21 or b vary (thesis §4.1.2 holds l_hand fixed).
    pub hold_l_hand: bool,
    /// Apply ψ = 140 − 25.6 p at every point (thesis eq. 4.15); not with ψ varied.
    pub psi_rule: bool,
}

impl SweepSpec {
    /// Check the combination of names.
    pub fn validate(&self) -> Result<()> {
        if self.vary.is_empty() {
            return Err(Error::Input("--vary: give 1 to 3 names (none given)".into()));
        }
        if self.vary.len() > 3 {
            return Err(Error::Input(format!("--vary: at most 3 names, {} given", self.vary.len())));
        }
        for (i, a) in self.vary.iter().enumerate() {
            for b in &self.vary[..i] {
                if a.knob == b.knob {
                    return Err(Error::Input(format!("--vary {}: the same quantity as --vary {}", a.name, b.name)));
                }
            }
        }
        let has = |k: Knob| self.vary.iter().any(|v| v.knob == k);
        let design = |n: &str| Knob::Design(DESIGN_NAMES.iter().position(|d| *d == n).unwrap_or(0));
        if has(Knob::L11) && has(design("p")) {
            return Err(Error::Input("--vary l11 and --vary p set the same ratio p = l11/l21".into()));
        }
        if has(Knob::L22) && has(design("r")) {
            return Err(Error::Input("--vary l22 and --vary r set the same ratio r = l22/l11".into()));
        }
        if has(Knob::LHand) && has(design("t22")) {
            return Err(Error::Input("--vary l_hand and --vary t22: l_hand sets t22".into()));
        }
        if self.hold_l_hand && (has(Knob::LHand) || has(design("t22"))) {
            let v = if has(Knob::LHand) { "l_hand" } else { "t22" };
            return Err(Error::Input(format!("--hold-l-hand with --vary {v}: holding l_hand sets t22; give one")));
        }
        if has(design("psi_deg")) && (self.psi_rule || has(Knob::L11)) {
            let rule = if self.psi_rule { "--psi-rule" } else { "--vary l11 (which applies the rule)" };
            let why = "the rule psi = 140 - 25.6 p sets psi at every point; give one";
            return Err(Error::Input(format!("{rule} with --vary psi_deg: {why}")));
        }
        if self.hold_l_hand && !has(design("l21")) && !has(design("b")) {
            return Err(Error::Input("--hold-l-hand: keeps l_hand while l21 or b vary, and neither is varied".into()));
        }
        for v in &self.vary {
            let Knob::Field(i) = v.knob else { continue };
            let field = LIMITS[i].field;
            let kind = self.problem.scene.setup.kind;
            let Some(kinds) = scene_kinds_using(field) else { continue };
            if !kinds.contains(&kind) {
                let names: Vec<String> = kinds.iter().map(|k| format!("\"{k}\"")).collect();
                return Err(Error::Input(format!(
                    "--vary {}: the problem's scene kind \"{kind}\" ([scene] kind) does not use {field}, which only the {} scene{} simulate{}: every point would be the same; sweep a problem whose [scene] kind is {} (docs/scenes.md)",
                    v.name,
                    kinds.iter().map(|k| k.as_str()).collect::<Vec<_>>().join(" and "),
                    if kinds.len() > 1 { "s" } else { "" },
                    if kinds.len() > 1 { "" } else { "s" },
                    names.join(" or ")
                )));
            }
        }
        let total: usize =
            self.vary.iter().map(|v| v.n).try_fold(1usize, |a, n| a.checked_mul(n)).unwrap_or(usize::MAX);
        if total > MAX_POINTS {
            return Err(Error::Input(format!("--vary: {total} grid points is more than {MAX_POINTS}")));
        }
        Ok(())
    }

    /// Number of grid points.
    pub fn len(&self) -> usize {
        self.vary.iter().map(|v| v.n).product()
    }

    /// True for an empty grid (never, once validated).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The grid point `k` as values of the varied names (first name fastest).
    pub fn point(&self, mut k: usize) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.vary.len());
        for v in &self.vary {
            let vals = v.values();
            out.push(vals[k % v.n]);
            k /= v.n;
        }
        out
    }

    /// The problem and design at the given values of the varied names.
    pub fn apply(&self, values: &[f64]) -> Result<(Problem, Design)> {
        let mut p = self.problem.clone();
        let mut x = self.design.to_array();
        let base_l_hand = self.design.l_hand();
        let mut derived = Vec::new();
        for (v, &val) in self.vary.iter().zip(values) {
            match v.knob {
                Knob::Design(i) => x[i] = val,
                Knob::Field(i) => set_field(&mut p, LIMITS[i].field, val)?,
                k => derived.push((k, val)),
            }
        }
        let psi_varied = self.vary.iter().any(|v| v.knob == Knob::Design(5));
        let mut psi_rule = self.psi_rule && !psi_varied;
        // derived relations, in dependency order: l11 (needs l21), l22 (needs l11), l_hand (needs b, l21)
        for want in [Knob::L11, Knob::L22, Knob::LHand] {
            for &(k, val) in derived.iter().filter(|(k, _)| *k == want) {
                match k {
                    Knob::L11 => {
                        x[4] = val / x[0];
                        psi_rule |= !psi_varied;
                    }
                    Knob::L22 => x[3] = val / (x[4] * x[0]),
                    Knob::LHand => x[2] = (val - x[1] - 2.0 * x[0]) / 2.0,
                    _ => {}
                }
            }
        }
        if self.hold_l_hand && !derived.iter().any(|(k, _)| *k == Knob::LHand) {
            x[2] = (base_l_hand - x[1] - 2.0 * x[0]) / 2.0;
        }
        if psi_rule {
            x[5] = psi_thesis(x[4]);
        }
        Ok((p, Design::from_array(&x)))
    }
}

/// Varied names whose values only stage 3 uses (the `[scene]` setup, the solver, `mu_scale`):
/// with `--stage kinematics` or `static` every point is the same in them. Their names, for
/// a warning.
pub fn stage3_only_names(spec: &SweepSpec) -> Vec<&str> {
    spec.vary
        .iter()
        .filter(|v| match v.knob {
            Knob::MuScale => true,
            Knob::Field(i) => LIMITS[i].field.starts_with("scene.") || LIMITS[i].field.starts_with("solver."),
            _ => false,
        })
        .map(|v| v.name.as_str())
        .collect()
}

/// Thesis eq. 4.15: ψ = 140 − 25.6 p (degrees).
pub fn psi_thesis(p: f64) -> f64 {
    140.0 - 25.6 * p
}

/// Set a numeric problem-file field by its dotted name (`*_deg` fields in degrees).
pub fn set_field(p: &mut Problem, field: &str, v: f64) -> Result<()> {
    let s = &mut p.scene;
    let d = v.to_radians();
    match field {
        "hand.tau" => s.hand.tau = v,
        "hand.w" => s.hand.w = v,
        "hand.rho_f" => s.hand.rho_f = v,
        "hand.r_open" => s.hand.r_open = v,
        "hand.k_s" => s.hand.k_s = v,
        "hand.k_stop" => s.hand.k_stop = v,
        "hand.c_stop" => s.hand.c_stop = v,
        "object.radius" => s.object.radius = v,
        "object.length" => s.object.length = v,
        "object.density" => s.object.density = v,
        "object.grasp_height" => s.object.grasp_height = v,
        "contact.mu_s" => s.contact.mu_s = v,
        "contact.mu_d" => s.contact.mu_d = v,
        "contact.v_s" => s.contact.v_s = v,
        "contact.v_d" => s.contact.v_d = v,
        "contact.restitution" => s.contact.restitution = v,
        "contact.k_contact" => s.contact.k_contact = v,
        "contact.v_min" => s.contact.v_min = v,
        "contact.eps_sep" => s.contact.eps_sep = v,
        "environment.g" => s.env.g = v,
        "environment.g_eq" => s.env.g_eq = v,
        "environment.theta_g_deg" => s.env.theta_g = d,
        "environment.mu_g" => s.env.mu_g = v,
        "environment.mu_p" => s.env.mu_p = v,
        "criteria.margin_sing_deg" => s.criteria.margin_sing = d,
        "criteria.sweep_step_deg" => s.criteria.sweep_step = d,
        "criteria.dx_max" => s.criteria.dx_max = v,
        "criteria.theta_max_deg" => s.criteria.theta_max = d,
        "criteria.fold_max_deg" => s.criteria.fold_max = d,
        "criteria.offset_step" => s.criteria.offset_step = v,
        "criteria.offset_max" => s.criteria.offset_max = v,
        "criteria.t_filter" => s.criteria.t_filter = v,
        "criteria.eta_stab" => s.criteria.eta_stab = v,
        "criteria.t_max" => s.criteria.t_max = v,
        "solver.rtol" => p.solver.rtol = v,
        "solver.atol" => p.solver.atol = v,
        "solver.max_steps" => p.solver.max_steps = v.round() as u64,
        "scene.x_off" => s.setup.x_off = v,
        "scene.t_obs" => s.setup.t_obs = v,
        "scene.ground_points" => s.setup.ground_points = v.round() as usize,
        "scene.ground_k" => s.setup.ground_k = v,
        "scene.ground_v_s" => s.setup.ground_v_s = v,
        "scene.ground_v_d" => s.setup.ground_v_d = v,
        other => return Err(Error::Input(format!("--vary {other}: not a numeric field a sweep can set"))),
    }
    if p.scene.contact.v_d <= p.scene.contact.v_s {
        return Err(Error::Input(format!("--vary {field} = {v}: contact.v_d must stay > contact.v_s")));
    }
    if p.scene.setup.ground_v_d <= p.scene.setup.ground_v_s {
        return Err(Error::Input(format!("--vary {field} = {v}: scene.ground_v_d must stay > scene.ground_v_s")));
    }
    Ok(())
}

/// Keys of the record that hold fixed-length arrays, with their lengths.
pub(crate) const ARRAY_KEYS: &[(&str, usize)] = &[("masses", 4), ("free_scene.energy", 2)];
