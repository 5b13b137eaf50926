//! The design vector, its names and the design bounds (MODEL.md §1.2).

use crate::error::{Error, Result};
use crate::math::deg;
use serde::{Deserialize, Serialize};

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

/// A design as written in files and records: the optimiser's vector, ψ in degrees (the
/// parameters of `/designs`, the design columns of every CSV and JSON record).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DesignParameters {
    /// l21 (m).
    pub l21: f64,
    /// b (m).
    pub b: f64,
    /// t22 (m).
    pub t22: f64,
    /// r.
    pub r: f64,
    /// p.
    pub p: f64,
    /// ψ (deg).
    pub psi_deg: f64,
}

impl DesignParameters {
    /// From the optimiser's vector (l21, b, t22, r, p, ψ°).
    pub fn from_array(x: &[f64; 6]) -> Self {
        DesignParameters { l21: x[0], b: x[1], t22: x[2], r: x[3], p: x[4], psi_deg: x[5] }
    }
    /// The optimiser's vector.
    pub fn to_array(&self) -> [f64; 6] {
        [self.l21, self.b, self.t22, self.r, self.p, self.psi_deg]
    }
    /// The design (ψ converted to radians).
    pub fn design(&self) -> Design {
        Design::from_array(&self.to_array())
    }
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
    /// Why the design has no finger (stage 0's "a length is not positive", MODEL.md §3),
    /// naming the length and its value: a given length l21, b, t22 that is not positive or
    /// not finite, ψ not finite, or a derived length l11 = p·l21, l22 = r·l11 that is not
    /// positive, said as an underflow when both factors are positive (a subnormal input such
    /// as 5e-324 m: its product rounds to 0). None when every length is positive and finite.
    pub fn invalid_length(&self) -> Option<String> {
        let n = super::fmt_num;
        for (name, v) in [("l21", self.l21), ("b", self.b), ("t22", self.t22)] {
            if !(v.is_finite() && v > 0.0) {
                return Some(format!("{name} = {} m is not a positive length", n(v)));
            }
        }
        if !self.psi.is_finite() {
            return Some(format!("psi_deg = {} is not finite", n(self.psi.to_degrees())));
        }
        let l11 = self.p * self.l21;
        let derived = [
            ("l11 = p·l21", "p", self.p, "l21", self.l21, l11),
            ("l22 = r·l11", "r", self.r, "l11", l11, self.r * l11),
        ];
        for (what, fa, a, fb, b, v) in derived {
            if v.is_finite() && v > 0.0 {
                continue;
            }
            let product = format!("{what} = {} × {} m = {} m", n(a), n(b), n(v));
            if a > 0.0 && b > 0.0 && v == 0.0 {
                let tiny: Vec<String> = [(fa, a), (fb, b)]
                    .iter()
                    .filter(|(_, x)| !x.is_normal())
                    .map(|(f, x)| format!("{f} = {}", n(*x)))
                    .collect();
                let why = if tiny.is_empty() {
                    String::new()
                } else {
                    let s = if tiny.len() == 1 { "is a subnormal number" } else { "are subnormal numbers" };
                    format!(
                        " ({} {s}, below {:.1e}: far below any length the model can compute with)",
                        tiny.join(" and "),
                        f64::MIN_POSITIVE
                    )
                };
                return Some(format!("{product}: the product underflows to 0{why}"));
            }
            return Some(format!("{product} is not a positive length"));
        }
        None
    }

    /// Parse `l21=..,b=..,t22=..,r=..,p=..,psi_deg=..` (all six required, each once).
    pub fn parse_assignments(s: &str) -> Result<Self> {
        let mut vals: [Option<f64>; 6] = [None; 6];
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (k, v) = part
                .split_once('=')
                .ok_or_else(|| Error::Input(format!("--design: `{part}` is not of the form name=value")))?;
            let k = k.trim();
            let idx = DESIGN_NAMES.iter().position(|n| *n == k).ok_or_else(|| {
                Error::Input(format!("--design: unknown variable `{k}` (expected one of {})", DESIGN_NAMES.join(", ")))
            })?;
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| Error::Input(format!("--design: `{k}` = `{}` is not a number", v.trim())))?;
            if !x.is_finite() {
                return Err(Error::Input(format!("--design: `{k}` = {x} is not finite")));
            }
            if vals[idx].replace(x).is_some() {
                return Err(Error::Input(format!("--design: `{k}` given twice")));
            }
        }
        let mut arr = [0.0; 6];
        for (i, v) in vals.iter().enumerate() {
            arr[i] = v.ok_or_else(|| Error::Input(format!("--design: missing `{}`", DESIGN_NAMES[i])))?;
        }
        Ok(Design::from_array(&arr))
    }
}

/// Inclusive design bounds, in optimiser units (ψ in degrees).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Bounds {
    /// Lower bounds.
    pub lo: [f64; 6],
    /// Upper bounds.
    pub hi: [f64; 6],
}

impl Bounds {
    /// A design drawn uniformly in the box (each variable from `[lo, hi)`, in order).
    pub fn sample<R: rand::Rng + ?Sized>(&self, rng: &mut R) -> Design {
        let mut x = [0.0; 6];
        for i in 0..6 {
            x[i] = rng.random_range(self.lo[i]..self.hi[i]);
        }
        Design::from_array(&x)
    }
    /// Is the design (in optimiser units) inside the box?
    pub fn contains(&self, d: &Design) -> bool {
        let x = d.to_array();
        (0..6).all(|i| x[i] >= self.lo[i] && x[i] <= self.hi[i])
    }
}
