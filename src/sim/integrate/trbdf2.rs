//! TR-BDF2 (Hosea & Shampine 1996): L-stable, stiff, order 2, with its third-order embedded
//! estimate filtered by (I − dhJ)⁻¹.

use super::jacobian::JacobianCache;
use super::jacobian::{prepare_attempt, NewtonMatrix};
use super::lu::Lu;
use super::{Rhs, Stats, StepError, StepPoint, Stepper, Tol};
use nalgebra::{SMatrix, SVector};

/// TR-BDF2 (γ = 2 − √2) as an ESDIRK with a simplified Newton iteration, finite-difference
/// Jacobian reused across steps, and a filtered third-order error estimate.
#[derive(Debug, Clone)]
pub struct TrBdf2<const N: usize> {
    tol: Tol<N>,
    h: f64,
    jc: JacobianCache<N>,
    lu: Option<Lu<f64, N>>,
    lu_h: f64,
    stats: Stats,
    /// Newton convergence threshold relative to the tolerance.
    pub kappa: f64,
    /// Maximum Newton iterations per stage.
    pub max_newton: usize,
    /// Recompute the Jacobian after every accepted step (else: on a change of smooth piece,
    /// slow Newton convergence, or a rejected step).
    pub refresh_every_step: bool,
}

const SQRT2: f64 = std::f64::consts::SQRT_2;
const GAMMA: f64 = 2.0 - SQRT2;
const D: f64 = GAMMA / 2.0;
const W: f64 = SQRT2 / 4.0;
// Embedded third-order weights (Hosea & Shampine): ((1 − w)/3, (3w + 1)/3, d/3).
const E1: f64 = W - (1.0 - W) / 3.0;
const E2: f64 = W - (3.0 * W + 1.0) / 3.0;
const E3: f64 = D - D / 3.0;

impl<const N: usize> TrBdf2<N> {
    /// New stepper with tolerances and an initial step size.
    pub fn new(tol: Tol<N>, h0: f64) -> Self {
        TrBdf2 {
            tol,
            h: h0,
            jc: JacobianCache::new(),
            lu: None,
            lu_h: 0.0,
            stats: Stats::default(),
            kappa: 0.05,
            max_newton: 8,
            refresh_every_step: false,
        }
    }

    /// Solve Y − d h f(Y) = rhs by simplified Newton from `z`; returns (Y, k = f(Y)).
    fn newton<S: Rhs<N>>(
        &mut self,
        sys: &mut S,
        t: f64,
        h: f64,
        rhs: &SVector<f64, N>,
        mut z: SVector<f64, N>,
        yref: &SVector<f64, N>,
    ) -> Option<(SVector<f64, N>, SVector<f64, N>)> {
        let lu = self.lu.as_ref()?;
        let mut prev = f64::INFINITY;
        let mut theta = 0.5f64;
        for it in 0..self.max_newton {
            self.stats.rhs += 1;
            let fz = sys.eval(t, &z)?;
            let g = rhs + fz * (D * h) - z;
            let dz = lu.solve(&g);
            z += dz;
            let n = self.tol.norm(&dz, yref, &z);
            if !n.is_finite() {
                return None;
            }
            if it > 0 {
                theta = n / prev;
                if theta >= 0.99 {
                    return None;
                }
                if theta > 0.2 {
                    self.jc.slow = true;
                }
            }
            let eta = if it == 0 { 1.0 } else { theta / (1.0 - theta) };
            if eta * n <= self.kappa || n <= 1e-12 {
                self.stats.rhs += 1;
                let k = sys.eval(t, &z)?;
                return Some((z, k));
            }
            prev = n;
        }
        None
    }
}

impl<const N: usize> NewtonMatrix<N> for TrBdf2<N> {
    fn parts(&mut self) -> (&mut JacobianCache<N>, &mut Stats, &mut f64) {
        (&mut self.jc, &mut self.stats, &mut self.h)
    }
    fn drop_factor(&mut self) {
        self.lu = None;
    }
    fn factor(&mut self, h: f64) -> bool {
        if self.lu.is_some() && self.lu_h == h {
            return true;
        }
        let a = SMatrix::<f64, N, N>::identity() - self.jc.jac * (D * h);
        self.stats.lu += 1;
        let Some(lu) = Lu::factor(a) else {
            self.lu = None;
            return false;
        };
        self.lu = Some(lu);
        self.lu_h = h;
        true
    }
}

impl<const N: usize> Stepper<N> for TrBdf2<N> {
    fn advance<S: Rhs<N>>(&mut self, sys: &mut S, from: &StepPoint<N>, h_max: f64) -> Result<StepPoint<N>, StepError> {
        let (t, y, f) = (from.t, &from.y, &from.f);
        self.jc.start_step(sys, y);
        loop {
            let Some(h) = prepare_attempt(self, sys, from, h_max)? else { continue };
            // Stage 2 (trapezoidal rule to t + γh).
            let rhs2 = y + f * (D * h);
            let z0 = y + f * (GAMMA * h);
            let Some((y2, k2)) = self.newton(sys, t + GAMMA * h, h, &rhs2, z0, y) else {
                self.newton_failed(h);
                continue;
            };
            // Stage 3 (BDF2 to t + h).
            let rhs3 = y + (f + k2) * (W * h);
            let z0 = y + (y2 - y) / GAMMA;
            let Some((y3, k3)) = self.newton(sys, t + h, h, &rhs3, z0, y) else {
                self.newton_failed(h);
                continue;
            };
            let est = (f * E1 + k2 * E2 + k3 * E3) * h;
            let est = self.lu.as_ref().map(|lu| lu.solve(&est)).unwrap_or(est);
            let err = self.tol.norm(&est, y, &y3);
            if err.is_finite() && err <= 1.0 {
                self.stats.steps += 1;
                let fac = if err == 0.0 { 4.0 } else { (0.9 * err.powf(-1.0 / 3.0)).clamp(0.2, 4.0) };
                // keep h (and the LU) when the change would be small
                if !(0.95..=1.2).contains(&fac) {
                    self.h = h * fac;
                } else {
                    self.h = h;
                }
                self.jc.fresh = false;
                if self.refresh_every_step {
                    self.jc.valid = false;
                }
                return Ok(StepPoint { t: t + h, y: y3, f: k3 });
            }
            self.stats.rejected += 1;
            let fac = if err.is_finite() { (0.9 * err.powf(-1.0 / 3.0)).clamp(0.1, 0.9) } else { 0.25 };
            self.h = h * fac;
            if !self.jc.fresh {
                self.jc.valid = false;
            }
        }
    }

    fn restart(&mut self) {
        self.jc.valid = false;
        self.lu = None;
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}

impl<const N: usize> TrBdf2<N> {
    fn newton_failed(&mut self, h: f64) {
        self.stats.rejected += 1;
        if let Some(h) = self.jc.newton_failed(h, 0.25) {
            self.h = h;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::integrate::testsys::run_osc;
    use nalgebra::Vector2;

    #[test]
    fn trbdf2_converges_second_order() {
        let tol = |r: f64| Tol { rtol: r, atol: Vector2::new(r, r) };
        let exact = 1.0f64.cos();
        let (y1, _) = run_osc(TrBdf2::new(tol(1e-6), 1e-3), 1.0, 1.0);
        let (y2, _) = run_osc(TrBdf2::new(tol(1e-9), 1e-3), 1.0, 1.0);
        let (e1, e2) = ((y1[0] - exact).abs(), (y2[0] - exact).abs());
        assert!(e1 < 1e-4, "{e1}");
        assert!(e2 < 1e-6, "{e2}");
        // order 2 (global error ∝ rtol^(2/3)): tightening rtol 1000× shrinks it ~100×
        assert!(e2 < e1 / 30.0, "{e1} {e2}");
    }

    #[test]
    fn trbdf2_l_stable_on_stiff_decay() {
        struct Stiff;
        impl Rhs<2> for Stiff {
            fn eval(&mut self, t: f64, y: &SVector<f64, 2>) -> Option<SVector<f64, 2>> {
                Some(Vector2::new(-1e6 * (y[0] - t.cos()), -y[1]))
            }
        }
        let mut st = TrBdf2::new(Tol { rtol: 1e-6, atol: Vector2::new(1e-9, 1e-9) }, 1e-6);
        let mut sys = Stiff;
        let mut p = StepPoint::at(&mut sys, 0.0, Vector2::new(0.0, 1.0)).unwrap();
        while p.t < 1.0 {
            p = st.advance(&mut sys, &p, 1.0 - p.t).unwrap();
        }
        assert!((p.y[0] - 1.0f64.cos()).abs() < 1e-5);
        assert!(st.stats().steps < 2000, "{:?}", st.stats());
    }
}
