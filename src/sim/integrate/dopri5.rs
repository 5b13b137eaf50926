//! Dormand–Prince 5(4): explicit, for comparison and non-stiff references.

use super::{Rhs, Stats, StepError, StepPoint, Stepper, Tol, HMIN};
use nalgebra::SVector;

/// The weights of k1, k3, k4, k5, k6, k7 in the dense output's fifth coefficient.
const D: [f64; 6] = [
    -12715105075.0 / 11282082432.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

/// Explicit Dormand–Prince 5(4) with FSAL, Hairer's PI step-size controller, a stiffness
/// estimate and the continuous extension of order 4.
#[derive(Debug, Clone)]
pub struct Dopri5<const N: usize> {
    tol: Tol<N>,
    /// The step-size proposal.
    pub(super) h: f64,
    stats: Stats,
    /// h·|λ| estimated at the last accepted step (Hairer's stiffness test:
    /// h ‖k7 − k6‖ / ‖y1 − Y6‖; above ~3.3 the step is held by stability, not accuracy).
    pub(super) h_lambda: f64,
    /// The last accepted step's continuous extension: (t0, h, its five coefficient vectors).
    cont: Option<(f64, f64, [SVector<f64, N>; 5])>,
    /// The error of the last accepted step (at least 1e-4), for the PI controller.
    err_old: f64,
    /// The last attempt was rejected (the next accepted step may not grow h).
    last_rejected: bool,
}

/// (Σ_j c_j k_j)·h, the sum taken left to right, component by component.
#[inline(always)]
fn scaled<const N: usize, const M: usize>(h: f64, k: [&SVector<f64, N>; M], c: [f64; M]) -> SVector<f64, N> {
    SVector::from_fn(|i, _| {
        let mut s = k[0][i] * c[0];
        for j in 1..M {
            s += k[j][i] * c[j];
        }
        s * h
    })
}

/// y + (Σ_j c_j k_j)·h, component by component.
#[inline(always)]
fn stage<const N: usize, const M: usize>(
    y: &SVector<f64, N>,
    h: f64,
    k: [&SVector<f64, N>; M],
    c: [f64; M],
) -> SVector<f64, N> {
    let d = scaled(h, k, c);
    SVector::from_fn(|i, _| y[i] + d[i])
}

/// The PI controller's β (Hairer's DOPRI5: 0.04) and the exponent of the error, 1/5 − 0.75 β.
const BETA: f64 = 0.04;
const EXPO: f64 = 0.2 - 0.75 * BETA;

impl<const N: usize> Dopri5<N> {
    /// New stepper.
    pub fn new(tol: Tol<N>, h0: f64) -> Self {
        Dopri5 { tol, h: h0, stats: Stats::default(), h_lambda: 0.0, cont: None, err_old: 1e-4, last_rejected: false }
    }
}

impl<const N: usize> Stepper<N> for Dopri5<N> {
    fn advance<S: Rhs<N>>(&mut self, sys: &mut S, from: &StepPoint<N>, h_max: f64) -> Result<StepPoint<N>, StepError> {
        let (t, y, f) = (from.t, &from.y, &from.f);
        loop {
            let h = self.h.min(h_max);
            if h < HMIN {
                return Err(StepError::StepTooSmall);
            }
            let k1 = *f;
            // each stage's state in one pass over the components (the same operations in the
            // same order as the vector expressions y + (Σ c_j k_j)·h: bit for bit their values)
            let r = (|| {
                let k2 = sys.eval(t + h / 5.0, &SVector::from_fn(|i, _| y[i] + k1[i] * (h / 5.0)))?;
                let k3 = sys.eval(t + 0.3 * h, &stage(y, h, [&k1, &k2], [3.0 / 40.0, 9.0 / 40.0]))?;
                let k4 =
                    sys.eval(t + 0.8 * h, &stage(y, h, [&k1, &k2, &k3], [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0]))?;
                let a5 = [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0];
                let k5 = sys.eval(t + 8.0 / 9.0 * h, &stage(y, h, [&k1, &k2, &k3, &k4], a5))?;
                let a6 = [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0];
                let y6 = stage(y, h, [&k1, &k2, &k3, &k4, &k5], a6);
                let k6 = sys.eval(t + h, &y6)?;
                let b = [35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0];
                let y1 = stage(y, h, [&k1, &k3, &k4, &k5, &k6], b);
                let (k7, _) = sys.eval_accepted(t + h, &y1)?;
                let ce =
                    [71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];
                let e = scaled(h, [&k1, &k3, &k4, &k5, &k6, &k7], ce);
                let dense = scaled(h, [&k1, &k3, &k4, &k5, &k6, &k7], D);
                let den = (y1 - y6).norm_squared();
                let h_lambda = if den > 0.0 { h * ((k7 - k6).norm_squared() / den).sqrt() } else { 0.0 };
                Some((y1, k7, e, h_lambda, dense))
            })();
            self.stats.rhs += 6;
            let Some((y1, k7, e, h_lambda, dense)) = r else {
                self.stats.rejected += 1;
                self.h = h * 0.25;
                continue;
            };
            let err = self.tol.norm(&e, y, &y1);
            if err <= 1.0 {
                self.stats.steps += 1;
                self.h_lambda = h_lambda;
                let dy = y1 - y;
                let c3 = k1 * h - dy;
                self.cont = Some((t, h, [*y, dy, c3, dy - k7 * h - c3, dense]));
                // Hairer's PI step-size control: h · 0.9 err^−(1/5 − 0.75β) err_old^β,
                // no growth right after a rejection
                let fac = (0.9 * err.max(1e-10).powf(-EXPO) * self.err_old.powf(BETA)).clamp(0.2, 10.0);
                self.err_old = err.max(1e-4);
                self.h = if self.last_rejected { h * fac.min(1.0) } else { h * fac };
                self.last_rejected = false;
                return Ok(StepPoint { t: t + h, y: y1, f: k7 });
            }
            self.stats.rejected += 1;
            self.last_rejected = true;
            self.h = h * (0.9 * err.powf(-EXPO)).clamp(0.2, 0.9);
        }
    }

    /// Forget the controller's memory (the step size stays).
    fn restart(&mut self) {
        self.err_old = 1e-4;
        self.last_rejected = false;
    }

    /// Dormand and Prince's continuous extension of order 4 (Hairer, Nørsett & Wanner,
    /// §II.6), from the stages of the last accepted step.
    fn dense(&self, tt: f64) -> Option<SVector<f64, N>> {
        let (t0, h, [c1, c2, c3, c4, c5]) = self.cont.as_ref()?;
        let th = (tt - t0) / h;
        let th1 = 1.0 - th;
        Some(c1 + (c2 + (c3 + (c4 + c5 * th1) * th) * th1) * th)
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::integrate::testsys::run_osc;
    use nalgebra::Vector2;

    #[test]
    fn dopri5_accuracy() {
        let tol = Tol { rtol: 1e-11, atol: Vector2::new(1e-13, 1e-13) };
        let (y, _) = run_osc(Dopri5::new(tol, 1e-3), 2.0, 3.0);
        assert!((y[0] - 6.0f64.cos()).abs() < 1e-9);
    }

    /// y' = 1 + y², y(0) = 0: y = tan t (nonlinear, so no order is gained by linearity).
    struct Tan;
    impl Rhs<1> for Tan {
        fn eval(&mut self, _t: f64, y: &SVector<f64, 1>) -> Option<SVector<f64, 1>> {
            Some(SVector::<f64, 1>::new(1.0 + y[0] * y[0]))
        }
    }

    /// The continuous extension meets the step's ends and is of order ≥ 4 inside the step:
    /// its error at θ = 0.37 falls at least ~2⁵ = 32× when h halves.
    #[test]
    fn dopri5_dense_output_order() {
        let tol = Tol { rtol: 1.0, atol: SVector::<f64, 1>::new(1.0) };
        let err = |h: f64| {
            let mut st = Dopri5::new(tol, h);
            let p = StepPoint::at(&mut Tan, 0.0, SVector::<f64, 1>::new(0.0)).unwrap();
            let q = st.advance(&mut Tan, &p, h).unwrap();
            assert_eq!(q.t, h);
            assert!((st.dense(h).unwrap() - q.y).norm() < 1e-15);
            assert!((st.dense(0.0).unwrap() - p.y).norm() < 1e-15);
            let tm = 0.37 * h;
            let cubic = crate::sim::integrate::hermite(p.t, &p.y, &p.f, q.t, &q.y, &q.f, tm);
            ((st.dense(tm).unwrap()[0] - tm.tan()).abs(), (cubic[0] - tm.tan()).abs())
        };
        let ((e1, c1), (e2, c2)) = (err(0.2), err(0.1));
        let ratio = e1 / e2;
        assert!(ratio > 28.0, "{e1:e} {e2:e} ratio {ratio}");
        // an order of magnitude below the cubic Hermite through the step's ends
        assert!(e1 * 10.0 < c1 && e2 * 10.0 < c2, "{e1:e} {e2:e} against {c1:e} {c2:e}");
    }
}
