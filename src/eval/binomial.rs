//! The confidence interval of a success probability from s successes in n trials:
//! Clopper–Pearson, the "exact" interval (it inverts the binomial tails themselves, so its
//! coverage is never below the level asked, whatever n and p; Wilson's score interval can
//! fall below it for small n and p near 0 or 1, which is exactly where a robust design's
//! P(stay) lives: K = 8–32 scenarios, most or all of them staying).

/// P(X ≤ s) for X ~ Binomial(n, p), summed in log space (no overflow for large n).
pub fn binomial_cdf(s: u64, n: u64, p: f64) -> f64 {
    if s >= n {
        return 1.0;
    }
    if p <= 0.0 {
        return 1.0;
    }
    if p >= 1.0 {
        return 0.0;
    }
    let (lp, lq) = (p.ln(), (-p).ln_1p());
    let mut lc = 0.0; // ln C(n, j), built up j by j
    let mut sum = 0.0;
    for j in 0..=s {
        if j > 0 {
            lc += ((n - j + 1) as f64).ln() - (j as f64).ln();
        }
        sum += (lc + j as f64 * lp + (n - j) as f64 * lq).exp();
    }
    sum.min(1.0)
}

/// Clopper–Pearson interval [lo, hi] at `level` (e.g. 0.95) for `s` successes in `n`
/// trials: lo solves P(X ≥ s | lo) = (1 − level)/2 (0 when s = 0), hi solves
/// P(X ≤ s | hi) = (1 − level)/2 (1 when s = n). Found by bisection to 1e-14.
pub fn clopper_pearson(s: u64, n: u64, level: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let a = 0.5 * (1.0 - level);
    // P(X ≥ s | p) increases with p; P(X ≤ s | p) decreases with p
    let lo = if s == 0 { 0.0 } else { bisect(|p| 1.0 - binomial_cdf(s - 1, n, p) - a) };
    let hi = if s == n { 1.0 } else { bisect(|p| a - binomial_cdf(s, n, p)) };
    (lo, hi)
}

/// The root in (0, 1) of an increasing function.
fn bisect(f: impl Fn(f64) -> f64) -> f64 {
    let (mut a, mut b) = (0.0_f64, 1.0_f64);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(m) < 0.0 {
            a = m;
        } else {
            b = m;
        }
        if b - a < 1e-14 {
            break;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms_at_the_ends() {
        // s = n: lo = (α/2)^(1/n); s = 0: hi = 1 − (α/2)^(1/n)
        for n in [1u64, 8, 32] {
            let (lo, hi) = clopper_pearson(n, n, 0.95);
            assert!((lo - 0.025f64.powf(1.0 / n as f64)).abs() < 1e-12 && hi == 1.0);
            let (lo, hi) = clopper_pearson(0, n, 0.95);
            assert!(lo == 0.0 && (hi - (1.0 - 0.025f64.powf(1.0 / n as f64))).abs() < 1e-12);
        }
    }
}
