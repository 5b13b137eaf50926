//! Uncertain inputs of a robust problem (`[robust.uncertainty]`): a distribution per input
//! and how a scenario's values are drawn from one uniform number per input (inverse CDF), so
//! that every input has its own fixed slot in a scenario's random stream (common random
//! numbers: adding or removing one uncertain input changes no other input's draws).

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

/// The uncertain inputs, in their slot order (the order of a scenario's uniform numbers).
pub const INPUTS: [&str; 7] = ["x_off", "height_offset", "mu_phalanx", "mu_ground", "restitution", "fill", "tau"];

/// What each input means (docs, errors).
pub const INPUT_MEANINGS: [&str; 7] = [
    "object offset along the palm (m; replaces [scene] x_off)",
    "object lowered (−) or raised (+) against the finger plane (m; added to the grasp height)",
    "factor on the object–phalanx friction mu_s and mu_d",
    "factor on the object–ground friction mu_g",
    "restitution e object–phalanx (the value itself)",
    "fill level: factor on the object's density (its mass)",
    "factor on the object's grip torque (motor torque tolerance)",
];

/// `[robust.uncertainty]`: a distribution per uncertain input; `None` = fixed at its nominal.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Uncertainty {
    /// One per input of [`INPUTS`], in that order.
    pub inputs: [Option<Dist>; 7],
}

impl Uncertainty {
    /// The inputs that are uncertain (slot indices).
    pub fn uncertain(&self) -> Vec<usize> {
        (0..INPUTS.len()).filter(|&i| self.inputs[i].is_some()).collect()
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
