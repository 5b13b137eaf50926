//! Radau IIA with S stages (order 2S − 1, S odd; [`RadauIIA<N, 5>`] is order 9) after Hairer &
//! Wanner's RADAU: the coefficients computed at construction ([`RadauCoefficients`]), the
//! stage system transformed with A⁻¹ = T Λ T⁻¹ into one real and (S − 1)/2 complex linear
//! systems per Newton iteration (each solved by the block elimination of a system's
//! [`Partition`] where J fits it, else by dense LUs), and RADAU5's Newton control, error
//! estimate (order S, filtered by (γ/h − J)⁻¹) and predictive step-size controller with the
//! exponent 1/(S + 1), all from the step loop shared with RADAU5 ([`RadauStepper`]). The
//! step-count experiment of issue 23 (item 2): the default stepper stays [`super::Radau5`].

use super::lu::Lu;
use super::radau_coefficients::RadauCoefficients;
use super::radau_stepper::{RadauScheme, RadauStepper, Stages};
use super::reduced::{Partition, ReducedLu};
use super::{Stats, Tol};
use nalgebra::{Complex, SMatrix, SVector};

/// Radau IIA with S stages (S odd): see the module documentation.
pub type RadauIIA<const N: usize, const S: usize> = RadauStepper<N, S, RadauIIAScheme<N, S>>;

/// Dense LUs of the Newton matrices: γ/h − J and one (α_p + iβ_p)/h − J per pair.
type DenseLus<const N: usize> = (Lu<f64, N>, Vec<Lu<Complex<f64>, N>>);

/// The S-stage Radau IIA coefficients and the storage of the Newton factorisations.
#[derive(Debug, Clone)]
pub struct RadauIIAScheme<const N: usize, const S: usize> {
    k: RadauCoefficients<S>,
    /// 1/Π_{m≠k}(n_k − n_m) over the nodes (0, c_1, …, c_S), for k = 1..S.
    lag_den: [f64; S],
    /// Dense LUs, where the system has no partition or J does not fit it.
    dense: Option<DenseLus<N>>,
    /// The block eliminations, one per pair (the first also holds the real shift), when the
    /// system has a partition.
    part: Option<Vec<ReducedLu<N>>>,
    prepared: Option<(u64, bool)>,
    reduced: bool,
    lu_h: f64,
}

/// out_i = Σ_j m_ij v_j.
#[inline(always)]
fn mix<const N: usize, const S: usize>(m: &[[f64; S]; S], v: &Stages<N, S>) -> Stages<N, S> {
    let mut out = [SVector::<f64, N>::zeros(); S];
    for (i, o) in out.iter_mut().enumerate() {
        for (j, vj) in v.iter().enumerate() {
            *o += vj * m[i][j];
        }
    }
    out
}

impl<const N: usize, const S: usize> RadauIIA<N, S> {
    /// New stepper.
    pub fn new(tol: Tol<N>, h0: f64) -> Self {
        let k = RadauCoefficients::<S>::new();
        let mut lag_den = [0.0; S];
        for (kk, den) in lag_den.iter_mut().enumerate() {
            let nk = k.c[kk];
            let mut p = nk; // the node 0
            for (m, &cm) in k.c.iter().enumerate() {
                if m != kk {
                    p *= nk - cm;
                }
            }
            *den = 1.0 / p;
        }
        let scheme = RadauIIAScheme { k, lag_den, dense: None, part: None, prepared: None, reduced: false, lu_h: 0.0 };
        RadauStepper::with_scheme(scheme, tol, h0)
    }
}

impl<const N: usize, const S: usize> RadauIIAScheme<N, S> {
    fn solve_c(&self, p: usize, re: &SVector<f64, N>, im: &SVector<f64, N>) -> (SVector<f64, N>, SVector<f64, N>) {
        match (&self.part, self.reduced) {
            (Some(reds), true) => reds[p].solve_complex(re, im),
            _ => {
                let b = SVector::<Complex<f64>, N>::from_fn(|k, _| Complex::new(re[k], im[k]));
                let x = self.dense.as_ref().expect("factored").1[p].solve(&b);
                (x.map(|c| c.re), x.map(|c| c.im))
            }
        }
    }

    /// The Lagrange weight of Z_kk at s over the nodes (0, c_1, …, c_S).
    fn lagrange(&self, kk: usize, s: f64) -> f64 {
        let mut l = s * self.lag_den[kk];
        for (m, &cm) in self.k.c.iter().enumerate() {
            if m != kk {
                l *= s - cm;
            }
        }
        l
    }
}

impl<const N: usize, const S: usize> RadauScheme<N, S> for RadauIIAScheme<N, S> {
    fn nodes(&self) -> &[f64; S] {
        &self.k.c
    }

    fn set_partition(&mut self, part: Option<Partition<N>>) {
        self.part = part.map(|p| (0..self.k.pairs.len()).map(|_| ReducedLu::new(p)).collect());
    }

    fn factor(&mut self, j: &SMatrix<f64, N, N>, version: u64, h: f64, stats: &mut Stats) -> bool {
        if (self.reduced || self.dense.is_some()) && self.lu_h == h {
            return true;
        }
        self.reduced = false;
        stats.lu += 1;
        let shift = |p: usize| Complex::new(self.k.pairs[p].0 / h, self.k.pairs[p].1 / h);
        if let Some(reds) = self.part.as_mut() {
            let fits = match self.prepared {
                Some((v, fits)) if v == version => fits,
                _ => {
                    let fits = reds.iter_mut().all(|r| r.prepare(j));
                    self.prepared = Some((version, fits));
                    fits
                }
            };
            if fits {
                let mut ok = reds[0].factor(self.k.gamma / h, shift(0));
                for (p, r) in reds.iter_mut().enumerate().skip(1) {
                    ok = ok && r.factor_complex(shift(p));
                }
                self.reduced = ok;
                self.dense = None;
                self.lu_h = h;
                return ok;
            }
        }
        let e = SMatrix::<f64, N, N>::from_diagonal_element(self.k.gamma / h) - j;
        let mut cs = Vec::with_capacity(self.k.pairs.len());
        for p in 0..self.k.pairs.len() {
            let ac = shift(p);
            let ec = SMatrix::<Complex<f64>, N, N>::from_fn(|r, c| {
                let d = if r == c { ac } else { Complex::new(0.0, 0.0) };
                d - Complex::new(j[(r, c)], 0.0)
            });
            match Lu::factor(ec) {
                Some(l) => cs.push(l),
                None => {
                    self.dense = None;
                    return false;
                }
            }
        }
        self.dense = Lu::factor(e).map(|l| (l, cs));
        self.lu_h = h;
        self.dense.is_some()
    }

    fn drop_factor(&mut self) {
        self.dense = None;
        self.reduced = false;
    }

    fn to_transformed(&self, z: &Stages<N, S>) -> Stages<N, S> {
        mix(&self.k.ti, z)
    }

    fn to_stages(&self, w: &Stages<N, S>) -> Stages<N, S> {
        mix(&self.k.t, w)
    }

    fn newton_increments(&self, r: &Stages<N, S>, w: &Stages<N, S>, h: f64) -> Stages<N, S> {
        let mut d = [SVector::<f64, N>::zeros(); S];
        d[0] = self.solve_real(&(r[0] - w[0] * (self.k.gamma / h)));
        for p in 0..self.k.pairs.len() {
            let (a, b) = (1 + 2 * p, 2 + 2 * p);
            let (al, be) = (self.k.pairs[p].0 / h, self.k.pairs[p].1 / h);
            let ra = r[a] - (w[a] * al - w[b] * be);
            let rb = r[b] - (w[a] * be + w[b] * al);
            (d[a], d[b]) = self.solve_c(p, &ra, &rb);
        }
        d
    }

    fn solve_real(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        match (&self.part, self.reduced) {
            (Some(reds), true) => reds[0].solve_real(b),
            _ => self.dense.as_ref().expect("factored").0.solve(b),
        }
    }

    fn error_stages(&self, z: &Stages<N, S>, h: f64) -> SVector<f64, N> {
        let mut f2 = SVector::<f64, N>::zeros();
        for i in 0..S {
            f2 += z[i] * (self.k.dd[i] / h);
        }
        f2
    }

    fn root(&self, err: f64) -> f64 {
        err.powf(1.0 / (S + 1) as f64)
    }

    fn extrapolate(&self, hp: f64, zp: &Stages<N, S>, h: f64) -> Stages<N, S> {
        let mut z = [SVector::<f64, N>::zeros(); S];
        for (i, zi) in z.iter_mut().enumerate() {
            let sv = 1.0 + self.k.c[i] * h / hp;
            for kk in 0..S {
                let mut l = self.lagrange(kk, sv);
                if kk == S - 1 {
                    l -= 1.0;
                }
                *zi += zp[kk] * l;
            }
        }
        z
    }

    fn dense_weights(&self, th: f64) -> [f64; S] {
        std::array::from_fn(|kk| self.lagrange(kk, th))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::integrate::testsys::Osc;
    use crate::sim::integrate::{StepPoint, Stepper};
    use nalgebra::Vector2;

    /// Order of convergence on a smooth problem (the harmonic oscillator over a fixed step
    /// sequence): halving h divides the error by ~2^(2S−1); S = 5 reaches order ≥ 8.5, S = 3
    /// order ≥ 4.5. The adaptive order-9 method meets a tight tolerance in fewer steps than
    /// RADAU5.
    #[test]
    fn order_of_convergence_and_steps() {
        fn fixed<const S: usize>(h: f64) -> f64 {
            // every step accepted (loose error test), Newton converged to rounding
            let mut st: RadauIIA<2, S> = RadauIIA::new(Tol { rtol: 1.0, atol: Vector2::new(1.0, 1.0) }, h);
            st.kappa = 1e-14;
            st.max_newton = 60;
            let mut sys = Osc(1.0);
            let mut p = StepPoint::at(&mut sys, 0.0, Vector2::new(1.0, 0.0)).unwrap();
            let n = (4.0 / h).round() as usize;
            for _ in 0..n {
                st.h = h;
                p = st.advance(&mut sys, &p, h).unwrap();
            }
            (p.y[0] - p.t.cos()).abs().max((p.y[1] + p.t.sin()).abs())
        }
        let (e1, e2) = (fixed::<5>(1.0), fixed::<5>(0.5));
        assert!((e1 / e2).log2() > 8.5, "order-9 ratio {e1:e} / {e2:e}");
        let (e1, e2) = (fixed::<3>(0.4), fixed::<3>(0.2));
        assert!((e1 / e2).log2() > 4.5, "order-5 ratio {e1:e} / {e2:e}");
        let run = |order9: bool| {
            let tol = Tol { rtol: 1e-10, atol: Vector2::new(1e-12, 1e-12) };
            let mut sys = Osc(1.0);
            let mut p = StepPoint::at(&mut sys, 0.0, Vector2::new(1.0, 0.0)).unwrap();
            let mut a9: RadauIIA<2, 5> = RadauIIA::new(tol, 1e-3);
            let mut a5 = crate::sim::integrate::Radau5::new(tol, 1e-3);
            while p.t < 10.0 {
                let a =
                    if order9 { a9.advance(&mut sys, &p, 10.0 - p.t) } else { a5.advance(&mut sys, &p, 10.0 - p.t) };
                p = a.unwrap();
            }
            let steps = if order9 { a9.stats().steps } else { a5.stats().steps };
            ((p.y[0] - 10f64.cos()).abs(), steps)
        };
        let ((err9, n9), (err5, n5)) = (run(true), run(false));
        assert!(err9 < 1e-7 && err5 < 1e-7, "{err9:e} {err5:e}");
        assert!(n9 * 2 < n5, "order 9: {n9} steps, order 5: {n5}");
    }
}
