//! Dormand–Prince 5(4): explicit, for comparison and non-stiff references.

use super::{Rhs, Stats, StepError, StepPoint, Stepper, Tol, HMIN};

/// Explicit Dormand–Prince 5(4) with FSAL and a standard step-size controller.
#[derive(Debug, Clone)]
pub struct Dopri5<const N: usize> {
    tol: Tol<N>,
    h: f64,
    stats: Stats,
}

impl<const N: usize> Dopri5<N> {
    /// New stepper.
    pub fn new(tol: Tol<N>, h0: f64) -> Self {
        Dopri5 { tol, h: h0, stats: Stats::default() }
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
            let r = (|| {
                let k2 = sys.eval(t + h / 5.0, &(y + k1 * (h / 5.0)))?;
                let k3 = sys.eval(t + 0.3 * h, &(y + (k1 * (3.0 / 40.0) + k2 * (9.0 / 40.0)) * h))?;
                let k4 =
                    sys.eval(t + 0.8 * h, &(y + (k1 * (44.0 / 45.0) - k2 * (56.0 / 15.0) + k3 * (32.0 / 9.0)) * h))?;
                let k5 = sys.eval(
                    t + 8.0 / 9.0 * h,
                    &(y + (k1 * (19372.0 / 6561.0) - k2 * (25360.0 / 2187.0) + k3 * (64448.0 / 6561.0)
                        - k4 * (212.0 / 729.0))
                        * h),
                )?;
                let k6 = sys.eval(
                    t + h,
                    &(y + (k1 * (9017.0 / 3168.0) - k2 * (355.0 / 33.0)
                        + k3 * (46732.0 / 5247.0)
                        + k4 * (49.0 / 176.0)
                        - k5 * (5103.0 / 18656.0))
                        * h),
                )?;
                let y1 = y
                    + (k1 * (35.0 / 384.0) + k3 * (500.0 / 1113.0) + k4 * (125.0 / 192.0) - k5 * (2187.0 / 6784.0)
                        + k6 * (11.0 / 84.0))
                        * h;
                let k7 = sys.eval(t + h, &y1)?;
                let e = (k1 * (71.0 / 57600.0) - k3 * (71.0 / 16695.0) + k4 * (71.0 / 1920.0)
                    - k5 * (17253.0 / 339200.0)
                    + k6 * (22.0 / 525.0)
                    - k7 * (1.0 / 40.0))
                    * h;
                Some((y1, k7, e))
            })();
            self.stats.rhs += 6;
            let Some((y1, k7, e)) = r else {
                self.stats.rejected += 1;
                self.h = h * 0.25;
                continue;
            };
            let err = self.tol.norm(&e, y, &y1);
            if err <= 1.0 {
                self.stats.steps += 1;
                let fac = if err == 0.0 { 5.0 } else { (0.9 * err.powf(-0.2)).clamp(0.2, 5.0) };
                self.h = h * fac;
                return Ok(StepPoint { t: t + h, y: y1, f: k7 });
            }
            self.stats.rejected += 1;
            self.h = h * (0.9 * err.powf(-0.2)).clamp(0.1, 0.9);
        }
    }

    /// Nothing to forget: an explicit method keeps no history but its step size.
    fn restart(&mut self) {}

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
}
