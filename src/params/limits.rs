//! The admissible range of every numeric input: one table, used by the problem-file
//! validation, by the command-line flags that set the same quantities, and printed in
//! docs/problem-files.md. Ranges are physically meaningful for a hand-sized gripper and an
//! object it can hold; they exclude values that would make the model meaningless (a
//! negative mass) or a run endless (a sweep step of 1e-300°), not merely unusual ones.

/// The admissible range of one input field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// Dotted field name as in the problem file (`hand.tau`; arrays without the index).
    pub field: &'static str,
    /// Lower end.
    pub lo: f64,
    /// Whether the lower end itself is excluded.
    pub lo_open: bool,
    /// Upper end (always included).
    pub hi: f64,
    /// Unit as written in the file.
    pub unit: &'static str,
    /// Why the lower end is where it is, where that is not plain physics (said when a value
    /// below it is refused); empty otherwise.
    pub reason: &'static str,
}

const fn open(field: &'static str, lo: f64, hi: f64, unit: &'static str) -> Limit {
    Limit { field, lo, lo_open: true, hi, unit, reason: "" }
}
const fn closed(field: &'static str, lo: f64, hi: f64, unit: &'static str) -> Limit {
    Limit { field, lo, lo_open: false, hi, unit, reason: "" }
}
impl Limit {
    const fn because(mut self, reason: &'static str) -> Limit {
        self.reason = reason;
        self
    }
}

/// Every numeric field with its range, in problem-file order.
pub const LIMITS: &[Limit] = &[
    open("hand.tau", 0.0, 100.0, "N·m"),
    open("hand.w", 0.0, 0.05, "m"),
    open("hand.rho_f", 0.0, 25_000.0, "kg/m³"),
    open("hand.r_open", 0.0, 1.0, "m"),
    closed("hand.k_s", 0.0, 1e3, "N·m/rad"),
    open("hand.k_stop", 0.0, 1e6, "N·m/rad"),
    closed("hand.c_stop", 0.0, 1e3, "s/rad"),
    open("object.radius", 0.0, 0.5, "m"),
    open("object.length", 0.0, 2.0, "m"),
    open("object.density", 0.0, 25_000.0, "kg/m³"),
    open("object.grasp_height", 0.0, 2.0, "m"),
    open("contact.mu_s", 0.0, 5.0, "-"),
    open("contact.mu_d", 0.0, 5.0, "-"),
    open("contact.v_s", 0.0, 1.0, "m/s"),
    open("contact.v_d", 0.0, 1.0, "m/s"),
    closed("contact.restitution", 0.01, 0.99, "-"),
    open("contact.k_contact", 0.0, 1e12, "N/m^1.5"),
    open("contact.v_min", 0.0, 1.0, "m/s"),
    open("contact.eps_sep", 0.0, 1e-3, "m"),
    closed("environment.g", 0.0, 100.0, "m/s²"),
    closed("environment.g_eq", 0.0, 100.0, "m/s²"),
    closed("environment.theta_g_deg", -360.0, 360.0, "°"),
    open("environment.mu_g", 0.0, 5.0, "-"),
    closed("environment.mu_p", 0.0, 5.0, "-"),
    open("criteria.r_sing", 0.0, 0.5, "m"),
    open("criteria.margin_sing_deg", 0.0, 90.0, "°"),
    closed("criteria.sweep_step_deg", 0.01, 45.0, "°"),
    open("criteria.dx_max", 0.0, 1.0, "m"),
    open("criteria.theta_max_deg", 0.0, 90.0, "°"),
    open("criteria.fold_max_deg", 0.0, 180.0, "°"),
    closed("criteria.offset_step", 1e-6, 0.1, "m"),
    closed("criteria.offset_max", 0.0, 0.5, "m"),
    open("criteria.t_filter", 0.0, 10.0, "s"),
    // below ~1e-11 the threshold η·U_min sinks into the rounding noise of the excess energy
    // (a difference of energies many orders larger): the stability event then fires on noise,
    // and t_stab stops growing as η falls (bottle-1l's nominal: 0.0559 s at 1e-10, 0.0800 s
    // at 1e-11, 0.1510 s at 1e-13 but 0.1509 s at 1e-14; issue 44)
    closed("criteria.eta_stab", 1e-10, 1.0, "-").because("a smaller threshold sinks into the rounding noise of the excess energy: the stability test would fire on noise"),
    open("criteria.t_max", 0.0, 10.0, "s"),
    closed("scene.x_off", -0.1, 0.1, "m"),
    open("scene.t_obs", 0.0, 10.0, "s"),
    closed("scene.ground_points", 3.0, 16.0, "points"),
    open("scene.ground_k", 0.0, 1e12, "N/m^1.5"),
    open("scene.ground_v_s", 0.0, 1.0, "m/s"),
    open("scene.ground_v_d", 0.0, 1.0, "m/s"),
    closed("solver.rtol", 1e-12, 0.1, "-"),
    closed("solver.atol", 1e-15, 1.0, "rad, rad/s"),
    closed("solver.max_steps", 1.0, 1e8, "steps"),
    open("l21", 0.0, 0.5, "m"),
    open("b", 0.0, 0.5, "m"),
    open("t22", 0.0, 0.5, "m"),
    open("r", 0.0, 10.0, "-"),
    open("p", 0.0, 10.0, "-"),
    closed("psi_deg", 0.0, 360.0, "°"),
];

/// Most entries of `criteria.r_sing`.
pub const MAX_R_SING: usize = 100;
/// Largest problem file read (bytes).
pub const MAX_FILE_BYTES: u64 = 1 << 20;

/// The range of a field (`nominal.l21` and `bounds.l21` share `l21`).
///
/// # Panics
/// Never for the names used in this crate; an unknown name is a programming error and
/// is caught by the unit test that walks every caller's name.
pub fn limit(field: &str) -> &'static Limit {
    let base = field.strip_prefix("nominal.").or_else(|| field.strip_prefix("bounds.")).unwrap_or(field);
    let base = base.split('[').next().unwrap_or(base);
    LIMITS.iter().find(|l| l.field == base).unwrap_or_else(|| panic!("no limit for `{field}`"))
}

impl Limit {
    /// `Ok` if `v` lies in the range, else the rule it breaks ("must be a finite number",
    /// "must be > 0", "must be <= 100 N·m").
    pub fn check(&self, v: f64) -> Result<f64, String> {
        if !v.is_finite() {
            return Err("must be a finite number".into());
        }
        let below = if self.lo_open { v <= self.lo } else { v < self.lo };
        let unit = self.unit_suffix();
        if below {
            let op = if self.lo_open { ">" } else { ">=" };
            let why = if self.reason.is_empty() { String::new() } else { format!("; {}", self.reason) };
            return Err(format!(
                "must be {op} {}{unit} (the admissible range is {}{unit}{why})",
                num(self.lo),
                self.range()
            ));
        }
        if v > self.hi {
            return Err(format!("must be <= {}{unit} (the admissible range is {}{unit})", num(self.hi), self.range()));
        }
        Ok(v)
    }
    /// The range as text: `(0, 100]`, `[1e-12, 0.1]` (docs/problem-files.md's column).
    pub fn range(&self) -> String {
        format!("{}{}, {}]", if self.lo_open { "(" } else { "[" }, num(self.lo), num(self.hi))
    }
    /// ` unit` for a message, or nothing for a dimensionless quantity (unit `-`).
    fn unit_suffix(&self) -> String {
        if self.unit == "-" {
            String::new()
        } else {
            format!(" {}", self.unit)
        }
    }
}

/// A limit as people write it: `1e-12`, `0.05`, `25000`, `1e8`.
pub fn num(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e6) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_limit_is_a_proper_range_and_names_resolve() {
        for l in LIMITS {
            assert!(l.lo < l.hi, "{}", l.field);
            assert!(l.check(l.hi).is_ok() && l.check(l.hi * 1.000001 + 1e-300).is_err(), "{}", l.field);
            assert_eq!(l.check(l.lo).is_err(), l.lo_open, "{}", l.field);
        }
        assert_eq!(limit("bounds.psi_deg").field, "psi_deg");
        assert_eq!(limit("criteria.r_sing[2]").field, "criteria.r_sing");
        assert!(limit("hand.tau").check(f64::NAN).unwrap_err().contains("finite"));
    }
}
