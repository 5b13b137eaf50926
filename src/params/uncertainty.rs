//! Uncertain inputs of a robust problem (`[robust.uncertainty]`): a distribution per input
//! and how a scenario's values are drawn from one uniform number per input (inverse CDF), so
//! that every input has its own fixed slot in a scenario's random stream (common random
//! numbers: adding or removing one uncertain input changes no other input's draws).

use super::scene::{ObjectCase, SceneParams};
use serde::{Deserialize, Serialize};

/// A distribution of one uncertain input.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dist {
    /// Uniform on [lo, hi].
    Uniform {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
    /// Normal with mean and standard deviation, truncated to [lo, hi].
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation (> 0).
        sd: f64,
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
    },
    /// One of a fixed list of values, each equally likely.
    List(Vec<f64>),
}

impl Dist {
    /// The value at the uniform number `u` ∈ [0, 1) (inverse CDF).
    pub fn at(&self, u: f64) -> f64 {
        match self {
            Dist::Uniform { lo, hi } => lo + u * (hi - lo),
            Dist::Normal { mean, sd, lo, hi } => {
                let (a, b) = (phi((lo - mean) / sd), phi((hi - mean) / sd));
                let p = (a + u * (b - a)).clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON);
                (mean + sd * phi_inv(p)).clamp(*lo, *hi)
            }
            Dist::List(v) => v[((u * v.len() as f64) as usize).min(v.len() - 1)],
        }
    }
    /// The smallest and largest value it can give.
    pub fn support(&self) -> (f64, f64) {
        match self {
            Dist::Uniform { lo, hi } | Dist::Normal { lo, hi, .. } => (*lo, *hi),
            Dist::List(v) => v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x))),
        }
    }
    /// The centre of a deterministic design: the uniform's midpoint, the normal's mean, the
    /// list's median (the lower middle of an even list).
    pub fn centre(&self) -> f64 {
        match self {
            Dist::Uniform { lo, hi } => 0.5 * (lo + hi),
            Dist::Normal { mean, .. } => *mean,
            Dist::List(v) => {
                let mut s = v.clone();
                s.sort_by(f64::total_cmp);
                s[(s.len() - 1) / 2]
            }
        }
    }
}

/// Standard normal CDF Φ(x) = erfc(−x/√2)/2.
pub fn phi(x: f64) -> f64 {
    0.5 * libm::erfc(-x / std::f64::consts::SQRT_2)
}

/// Inverse standard normal CDF: Acklam's rational approximation (relative error 1.2e-9)
/// refined by one Halley step on Φ (full double precision in the body of the distribution).
pub fn phi_inv(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383_577_518_672_69e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] =
        [-5.447609879822406e1, 1.615858368580409e2, -1.556989798598866e2, 6.680131188771972e1, -1.328068155288572e1];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [7.784695709041462e-3, 3.224671290700398e-1, 2.445134137142996, 3.754408661907416];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    let x = if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    };
    // one Halley step: e = Φ(x) − p, u = e √(2π) exp(x²/2)
    let e = phi(x) - p;
    let u = e * (2.0 * std::f64::consts::PI).sqrt() * (0.5 * x * x).exp();
    x - u / (1.0 + 0.5 * x * u)
}

/// One uncertain input of a grasp: a row of [`INPUTS`]. Everything about the input is here —
/// its key in `[robust.uncertainty]` and in a scenario's record, what it means, its nominal
/// value, how a drawn value enters a scenario's scene, which draws are admissible and how it
/// is shown — so adding an input is adding a row.
#[derive(Clone, Copy)]
pub struct InputRow {
    /// The key (`[robust.uncertainty] NAME`, the record's `inputs.NAME`).
    pub name: &'static str,
    /// What it means (docs, errors).
    pub meaning: &'static str,
    /// Its value when not uncertain, in the problem's scene.
    pub nominal: fn(&SceneParams) -> f64,
    /// A scenario's scene with value `v` of this input (the object's case `o`).
    pub apply: fn(&mut SceneParams, &ObjectCase, f64),
    /// Why draws in [lo, hi] are not admissible for object `o` of the problem's scene, if they
    /// are not (the rule, for the error naming the field).
    pub admissible: fn(f64, f64, &ObjectCase, &SceneParams) -> Result<(), String>,
    /// How a value is shown (`gripopt replay --scenario`'s inputs line).
    pub shown: fn(f64) -> String,
}

impl std::fmt::Debug for InputRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// The uncertain inputs, in their slot order (the order of a scenario's uniform numbers: a new
/// input goes at the end, so that no other input's draws change).
pub const INPUTS: [InputRow; 7] = [
    InputRow {
        name: "x_off",
        meaning: "object offset along the palm (m; replaces [scene] x_off)",
        nominal: |s| s.setup.x_off,
        apply: |s, _, v| s.setup.x_off = v,
        admissible: |lo, hi, _, _| within(lo, hi, -0.1, 0.1, "must keep the offset in [-0.1, 0.1] m"),
        shown: |v| format!("x_off {:.3} mm", v * 1e3),
    },
    InputRow {
        name: "height_offset",
        meaning: "object lowered (−) or raised (+) against the finger plane (m; added to the grasp height)",
        nominal: |_| 0.0,
        apply: |s, _, v| s.object.grasp_height += v,
        admissible: |lo, hi, o, scene| {
            let h = (o.object.grasp_height + lo, o.object.grasp_height + hi);
            if !(h.0 >= scene.hand.w) || h.1 >= o.object.length {
                return Err(format!(
                    "keeps object {}'s grasp height {} + offset on its side, in [hand.w {}, {}) (the fingers clear the floor and stay below the top)",
                    o.name, o.object.grasp_height, scene.hand.w, o.object.length
                ));
            }
            Ok(())
        },
        shown: |v| format!("height offset {:.3} mm", v * 1e3),
    },
    InputRow {
        name: "mu_phalanx",
        meaning: "factor on the object–phalanx friction mu_s and mu_d",
        nominal: |_| 1.0,
        apply: |s, _, v| {
            s.contact.mu_s *= v;
            s.contact.mu_d *= v;
        },
        admissible: |lo, hi, o, scene| {
            positive(lo, "a friction factor must be > 0 (no negative or zero friction draws)")?;
            scaled("contact.mu_s", scene.contact.mu_s.max(scene.contact.mu_d) * hi, o)
        },
        shown: |v| format!("phalanx friction x{v:.3}"),
    },
    InputRow {
        name: "mu_ground",
        meaning: "factor on the object–ground friction mu_g",
        nominal: |_| 1.0,
        apply: |s, _, v| s.env.mu_g *= v,
        admissible: |lo, hi, o, scene| {
            positive(lo, "a friction factor must be > 0 (no negative or zero friction draws)")?;
            scaled("environment.mu_g", scene.env.mu_g * hi, o)
        },
        shown: |v| format!("ground friction x{v:.3}"),
    },
    InputRow {
        name: "restitution",
        meaning: "restitution e object–phalanx (the value itself)",
        nominal: |s| s.contact.restitution,
        apply: |s, _, v| s.contact.restitution = v,
        admissible: |lo, hi, _, _| within(lo, hi, 0.01, 0.99, "must keep the restitution in [0.01, 0.99]"),
        shown: |v| format!("restitution {v:.3}"),
    },
    InputRow {
        name: "fill",
        meaning: "fill level: factor on the object's density (its mass)",
        nominal: |_| 1.0,
        apply: |s, _, v| s.object.density *= v,
        admissible: |lo, hi, o, _| {
            positive(lo, "a fill factor must be > 0 (an object has mass)")?;
            scaled("object.density", o.object.density * hi, o)
        },
        shown: |v| format!("fill x{v:.3}"),
    },
    InputRow {
        name: "tau",
        meaning: "factor on the object's grip torque (motor torque tolerance)",
        nominal: |_| 1.0,
        apply: |s, o, v| s.hand.tau = o.tau * v,
        admissible: |lo, hi, o, _| {
            positive(lo, "a torque factor must be > 0")?;
            scaled("hand.tau", o.tau * hi, o)
        },
        shown: |v| format!("torque x{v:.4}"),
    },
];

/// Number of uncertain inputs (the rows of [`INPUTS`]).
pub const N_INPUTS: usize = INPUTS.len();

/// The slot of input `name` in [`INPUTS`].
pub fn input_slot(name: &str) -> Option<usize> {
    INPUTS.iter().position(|r| r.name == name)
}

fn within(lo: f64, hi: f64, a: f64, b: f64, rule: &str) -> Result<(), String> {
    if lo < a || hi > b {
        return Err(rule.into());
    }
    Ok(())
}

fn positive(lo: f64, rule: &str) -> Result<(), String> {
    if !(lo > 0.0) {
        return Err(rule.into());
    }
    Ok(())
}

/// A scaled value of object `o` within `limit`'s admissible range.
fn scaled(limit: &str, v: f64, o: &ObjectCase) -> Result<(), String> {
    super::limits::limit(limit)
        .check(v)
        .map(|_| ())
        .map_err(|rule| format!("gives {limit} = {v} for object {}: {rule}", o.name))
}

/// `[robust.uncertainty]`: a distribution per uncertain input; `None` = fixed at its nominal.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Uncertainty {
    /// One per input of [`INPUTS`], in that order.
    pub inputs: [Option<Dist>; N_INPUTS],
}

impl Uncertainty {
    /// The inputs that are uncertain (slot indices).
    pub fn uncertain(&self) -> Vec<usize> {
        (0..N_INPUTS).filter(|&i| self.inputs[i].is_some()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cdf_and_its_inverse() {
        // Φ at tabulated points (Abramowitz & Stegun 26.2)
        for (x, p) in [(0.0, 0.5), (1.0, 0.841_344_746_068_542_9), (-1.96, 0.024_997_895_148_220_43)] {
            assert!((phi(x) - p).abs() < 1e-15, "{x}");
        }
        for p in [1e-10, 1e-4, 0.02, 0.3, 0.5, 0.77, 0.99, 1.0 - 1e-9] {
            let x = phi_inv(p);
            assert!((phi(x) - p).abs() < 1e-13 * p.max(1e-3), "{p}: {x}");
        }
    }

    #[test]
    fn draws_stay_in_their_support() {
        let n = Dist::Normal { mean: 1.0, sd: 0.3, lo: 0.7, hi: 1.1 };
        for k in 0..=100 {
            let v = n.at(k as f64 / 100.0 * 0.999_999);
            assert!((0.7..=1.1).contains(&v), "{v}");
        }
        assert_eq!(Dist::List(vec![3.0, 1.0, 2.0]).at(0.999), 2.0);
        assert_eq!(Dist::List(vec![3.0, 1.0, 2.0]).centre(), 2.0);
        assert_eq!(Dist::Uniform { lo: 1.0, hi: 3.0 }.at(0.25), 1.5);
    }
}
