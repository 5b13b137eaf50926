//! Variation operators: simulated binary crossover and bounded polynomial mutation
//! (Deb & Agrawal 1995; Deb & Goyal 1996), as in the reference NSGA-II.

use rand::Rng;

/// Operator parameters (defaults as pymoo's NSGA-II: SBX p 0.9, η 15, per-variable 0.5;
/// PM applied to an offspring with p 0.9, η 20, per-variable min(0.5, 1/n)).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Operators {
    /// Crossover probability per mating.
    pub p_cross: f64,
    /// SBX distribution index.
    pub eta_cross: f64,
    /// Per-variable probability of crossing.
    pub p_cross_var: f64,
    /// Probability that an offspring is mutated at all.
    pub p_mut: f64,
    /// PM distribution index.
    pub eta_mut: f64,
    /// Per-variable mutation probability (None = min(0.5, 1/n)).
    pub p_mut_var: Option<f64>,
}

impl Default for Operators {
    fn default() -> Self {
        Operators { p_cross: 0.9, eta_cross: 15.0, p_cross_var: 0.5, p_mut: 0.9, eta_mut: 20.0, p_mut_var: None }
    }
}

/// x^e with fast paths: integer e (repeated multiplication) and e = ±1/2^k (square roots).
#[inline]
fn pow_fast(x: f64, e: f64) -> f64 {
    if e == e.trunc() && e.abs() <= 64.0 {
        return x.powi(e as i32);
    }
    let inv = 1.0 / e;
    if inv == inv.trunc() && inv > 0.0 && (inv as u64).is_power_of_two() && inv <= 64.0 {
        let mut y = x;
        let mut k = inv as u64;
        while k > 1 {
            y = y.sqrt();
            k /= 2;
        }
        return y;
    }
    x.powf(e)
}

/// SBX on two parents within [lo, hi]; returns two children.
pub fn sbx<R: Rng>(rng: &mut R, a: &[f64], b: &[f64], lo: &[f64], hi: &[f64], op: &Operators) -> (Vec<f64>, Vec<f64>) {
    let mut c1 = a.to_vec();
    let mut c2 = b.to_vec();
    if rng.random::<f64>() > op.p_cross {
        return (c1, c2);
    }
    let eta = op.eta_cross;
    for i in 0..a.len() {
        if rng.random::<f64>() > op.p_cross_var || (a[i] - b[i]).abs() <= 1e-14 {
            continue;
        }
        let (y1, y2) = if a[i] < b[i] { (a[i], b[i]) } else { (b[i], a[i]) };
        let (yl, yu) = (lo[i], hi[i]);
        let u: f64 = rng.random();
        let betaq = |beta: f64| {
            let alpha = 2.0 - pow_fast(beta, -(eta + 1.0));
            if u <= 1.0 / alpha {
                pow_fast(u * alpha, 1.0 / (eta + 1.0))
            } else {
                pow_fast(1.0 / (2.0 - u * alpha), 1.0 / (eta + 1.0))
            }
        };
        let d = y2 - y1;
        let v1 = (0.5 * ((y1 + y2) - betaq(1.0 + 2.0 * (y1 - yl) / d) * d)).clamp(yl, yu);
        let v2 = (0.5 * ((y1 + y2) + betaq(1.0 + 2.0 * (yu - y2) / d) * d)).clamp(yl, yu);
        if rng.random::<f64>() < 0.5 {
            c1[i] = v2;
            c2[i] = v1;
        } else {
            c1[i] = v1;
            c2[i] = v2;
        }
    }
    (c1, c2)
}

/// Bounded polynomial mutation in place.
pub fn polynomial_mutation<R: Rng>(rng: &mut R, x: &mut [f64], lo: &[f64], hi: &[f64], op: &Operators) {
    let n = x.len();
    if rng.random::<f64>() > op.p_mut {
        return;
    }
    let pm = op.p_mut_var.unwrap_or((1.0 / n as f64).min(0.5));
    let eta = op.eta_mut;
    for i in 0..n {
        if rng.random::<f64>() > pm {
            continue;
        }
        let (yl, yu) = (lo[i], hi[i]);
        if yu <= yl {
            continue;
        }
        let y = x[i];
        let d1 = (y - yl) / (yu - yl);
        let d2 = (yu - y) / (yu - yl);
        let u: f64 = rng.random();
        let mp = 1.0 / (eta + 1.0);
        let dq = if u < 0.5 {
            let v = 2.0 * u + (1.0 - 2.0 * u) * pow_fast(1.0 - d1, eta + 1.0);
            pow_fast(v, mp) - 1.0
        } else {
            let v = 2.0 * (1.0 - u) + 2.0 * (u - 0.5) * pow_fast(1.0 - d2, eta + 1.0);
            1.0 - pow_fast(v, mp)
        };
        x[i] = (y + dq * (yu - yl)).clamp(yl, yu);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn fast_powers_match_powf() {
        for &x in &[1e-3, 0.37, 1.0, 2.5, 17.0] {
            for &e in &[-16.0, 16.0, 21.0, 1.0 / 16.0, 1.0 / 2.0, 1.0 / 21.0, 0.3] {
                let (a, b) = (pow_fast(x, e), f64::powf(x, e));
                assert!((a - b).abs() <= 1e-13 * b.abs(), "{x}^{e}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn operators_stay_in_bounds_and_sbx_preserves_the_mean() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let lo = [0.0, -1.0, 10.0];
        let hi = [1.0, 1.0, 20.0];
        let op = Operators { p_cross: 1.0, p_cross_var: 1.0, p_mut: 1.0, p_mut_var: Some(1.0), ..Default::default() };
        for _ in 0..2000 {
            let a = [rng.random_range(0.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(10.0..20.0)];
            let b = [rng.random_range(0.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(10.0..20.0)];
            let (mut c1, c2) = sbx(&mut rng, &a, &b, &lo, &hi, &op);
            for i in 0..3 {
                assert!(c1[i] >= lo[i] && c1[i] <= hi[i] && c2[i] >= lo[i] && c2[i] <= hi[i]);
                // unclamped SBX keeps the parents' mean; clamping only moves toward the box
                let mid = 0.5 * (a[i] + b[i]);
                let cm = 0.5 * (c1[i] + c2[i]);
                assert!((cm - mid).abs() <= (hi[i] - lo[i]) * 0.5 + 1e-12);
            }
            polynomial_mutation(&mut rng, &mut c1, &lo, &hi, &op);
            for i in 0..3 {
                assert!(c1[i] >= lo[i] && c1[i] <= hi[i]);
            }
        }
    }
}
