//! Automatic stiffness switching: Dormand–Prince 5(4) where its steps are held by
//! accuracy, RADAU5 where they would be held by stability (LSODA's idea with Hairer's
//! stiffness test). The explicit method watches h·|λ| at its accepted steps (`h_lambda`);
//! after [`STIFF_STEPS`] steps with h·|λ| > [`STIFF_H_LAMBDA`] (just inside the edge of its
//! stability region) within a block of [`STIFF_WINDOW`] accepted steps it hands over to
//! RADAU5 at its step size. RADAU5 watches h·ρ(J) (ρ
//! bounded by Gelfand's formula on its Jacobian); after [`NONSTIFF_STEPS`] accepted steps
//! in a row well inside the explicit method's region it hands back.

use super::{Dopri5, Radau5, Rhs, Stats, StepError, StepPoint, Stepper, Tol};
use nalgebra::{SMatrix, SVector};

/// h·|λ| from which a Dormand–Prince step counts as held by stability (Hairer uses 3.25
/// for a real λ; an oscillatory λ meets the region's edge at ~3).
const STIFF_H_LAMBDA: f64 = 2.5;
/// Explicit steps near the stability edge, within one block of [`STIFF_WINDOW`], that switch
/// to RADAU5.
const STIFF_STEPS: u32 = 15;
/// The block of explicit steps the stiffness count looks at (counts restart after each).
const STIFF_WINDOW: u32 = 20;
/// h·ρ(J) below which a RADAU5 step could as well be explicit.
const NONSTIFF_H_RHO: f64 = 1.5;
/// RADAU5 steps in a row below [`NONSTIFF_H_RHO`] that switch back.
const NONSTIFF_STEPS: u32 = 5;

/// The stiffness-switching stepper: see the module documentation.
#[derive(Debug, Clone)]
pub struct Switching<const N: usize> {
    explicit: Dopri5<N>,
    implicit: Radau5<N>,
    stiff: bool,
    /// The last accepted step was the implicit method's.
    last_implicit: bool,
    /// Explicit steps at the stability edge within the current window, and the window's
    /// length so far.
    edge: (u32, u32),
    /// Implicit steps in a row that could be explicit.
    calm: u32,
    /// The Jacobian version whose spectral radius bounds these are: a lower bound (cheap,
    /// [`spectral_lower_bound`]) and Gelfand's upper bound, computed only where the lower one
    /// does not decide ([`spectral_bound`]).
    radius: (u64, f64, Option<f64>),
    /// Switches made (to RADAU5, back to Dormand–Prince).
    pub switches: (u32, u32),
}

impl<const N: usize> Switching<N> {
    /// New stepper, starting explicit with step `h0`.
    pub fn new(tol: Tol<N>, h0: f64) -> Self {
        Switching {
            explicit: Dopri5::new(tol, h0),
            implicit: Radau5::new(tol, h0),
            stiff: false,
            last_implicit: false,
            edge: (0, 0),
            calm: 0,
            radius: (0, 0.0, None),
            switches: (0, 0),
        }
    }

    /// After an explicit step: count it at the stability edge or not; switch when the
    /// window holds enough of them.
    fn watch_explicit(&mut self) {
        if self.explicit.h_lambda > STIFF_H_LAMBDA {
            self.edge.0 += 1;
        }
        self.edge.1 += 1;
        if self.edge.0 >= STIFF_STEPS {
            self.stiff = true;
            self.switches.0 += 1;
            self.implicit.restart();
            self.implicit.h = self.explicit.h;
            self.edge = (0, 0);
            self.calm = 0;
        } else if self.edge.1 >= STIFF_WINDOW {
            self.edge = (0, 0);
        }
    }

    /// After an implicit step of size `h`: count it as one that could be explicit or not;
    /// switch back after enough in a row.
    fn watch_implicit(&mut self, h: f64) {
        let jc = &self.implicit.jc;
        if !jc.valid {
            self.calm = 0;
            return;
        }
        if self.radius.0 != jc.version {
            self.radius = (jc.version, spectral_lower_bound(&jc.jac), None);
        }
        // h·ρ ≥ h·(lower bound) beyond the threshold (with room for the bounds' rounding):
        // not calm, whatever Gelfand's bound, which is then not computed (it costs four
        // products of N×N matrices); otherwise the decision is Gelfand's bound's, as always
        let calm = h * self.radius.1 <= NONSTIFF_H_RHO * (1.0 + 1e-6)
            && h * *self.radius.2.get_or_insert_with(|| spectral_bound(&jc.jac)) < NONSTIFF_H_RHO;
        if calm {
            self.calm += 1;
        } else {
            self.calm = 0;
        }
        if self.calm >= NONSTIFF_STEPS {
            self.stiff = false;
            self.switches.1 += 1;
            self.explicit.h = self.implicit.h;
            self.calm = 0;
            self.edge = (0, 0);
        }
    }
}

/// A lower bound of the spectral radius ρ of `a`: the traces of a and a² are the sums of the
/// eigenvalues and of their squares, so ρ ≥ |tr a| / N and ρ² ≥ |tr a²| / N; each trace is
/// taken less the bound of its rounding (N² + 2 ulps of its terms' magnitudes), so that the
/// bound holds in floating point. O(N²), against the N³ products of [`spectral_bound`].
fn spectral_lower_bound<const N: usize>(a: &SMatrix<f64, N, N>) -> f64 {
    let (mut t1, mut m1, mut t2, mut m2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for i in 0..N {
        t1 += a[(i, i)];
        m1 += a[(i, i)].abs();
        for j in 0..N {
            let p = a[(i, j)] * a[(j, i)];
            t2 += p;
            m2 += p.abs();
        }
    }
    let n = N as f64;
    let slack = (n * n + 2.0) * f64::EPSILON;
    let l1 = (t1.abs() - slack * m1).max(0.0) / n;
    let l2 = ((t2.abs() - slack * m2).max(0.0) / n).sqrt();
    l1.max(l2)
}

/// An upper bound of the spectral radius of `a`: ‖a^16‖_F^(1/16) (Gelfand's formula, four
/// squarings, rescaled at each to stay in range).
fn spectral_bound<const N: usize>(a: &SMatrix<f64, N, N>) -> f64 {
    let mut m = *a;
    let mut log_scale = 0.0;
    for k in 0..4 {
        let n = m.norm();
        if n == 0.0 || !n.is_finite() {
            return if n == 0.0 { 0.0 } else { f64::INFINITY };
        }
        m /= n;
        // m = a^(2^k) / s with log s = log_scale + log n, in units of a's power 2^k
        log_scale += n.ln() / f64::from(1u32 << k);
        m = m * m;
    }
    (log_scale + m.norm().ln() / 16.0).exp()
}

impl<const N: usize> Stepper<N> for Switching<N> {
    fn advance<S: Rhs<N>>(&mut self, sys: &mut S, from: &StepPoint<N>, h_max: f64) -> Result<StepPoint<N>, StepError> {
        if self.stiff {
            let p = self.implicit.advance(sys, from, h_max)?;
            self.last_implicit = true;
            self.watch_implicit(p.t - from.t);
            Ok(p)
        } else {
            let p = self.explicit.advance(sys, from, h_max)?;
            self.last_implicit = false;
            self.watch_explicit();
            Ok(p)
        }
    }

    fn restart(&mut self) {
        self.implicit.restart();
        self.explicit.restart();
    }

    /// The last accepted step's continuous output: Dormand and Prince's extension of order
    /// 4 after an explicit step; none after a RADAU5 step, whose events the driver locates
    /// on the cubic Hermite as for RADAU5 alone (its collocation polynomial measured no
    /// better there: docs/benchmarks.md).
    fn dense(&self, t: f64) -> Option<SVector<f64, N>> {
        if self.last_implicit {
            None
        } else {
            self.explicit.dense(t)
        }
    }

    fn dense_for_events(&self) -> bool {
        true
    }

    fn stats(&self) -> Stats {
        let (a, b) = (self.explicit.stats(), self.implicit.stats());
        Stats {
            steps: a.steps + b.steps,
            rejected: a.rejected + b.rejected,
            rhs: a.rhs + b.rhs,
            jac: a.jac + b.jac,
            lu: a.lu + b.lu,
            newton: a.newton + b.newton,
            newton_fail: a.newton_fail + b.newton_fail,
            switches: Some(u64::from(self.switches.0) + u64::from(self.switches.1)),
            explicit_steps: Some(a.steps),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Matrix3, Vector3};

    /// An oscillator (y1, y2) and a state y3 relaxed toward cos t at a rate λ(t) that is 1
    /// before t = 1, 1e5 from t = 1.2 to 2 and 1 again from t = 2.2 (smooth ramps between):
    /// y3 = cos t exactly whatever λ, so errors are measurable; stiff only in the middle.
    struct Relax;
    fn rate(t: f64) -> f64 {
        let ramp = |a: f64| {
            let x = ((t - a) / 0.2).clamp(0.0, 1.0);
            x * x * (3.0 - 2.0 * x)
        };
        1.0 + 1e5 * (ramp(1.0) - ramp(2.0))
    }
    impl Rhs<3> for Relax {
        fn eval(&mut self, t: f64, y: &SVector<f64, 3>) -> Option<SVector<f64, 3>> {
            Some(Vector3::new(y[1], -y[0], -rate(t) * (y[2] - t.cos()) - t.sin()))
        }
    }

    fn run<St: Stepper<3>>(st: &mut St) -> (SVector<f64, 3>, f64) {
        let mut sys = Relax;
        let mut p = StepPoint::at(&mut sys, 0.0, Vector3::new(1.0, 0.0, 1.0)).unwrap();
        let mut worst: f64 = 0.0;
        while p.t < 3.0 {
            p = st.advance(&mut sys, &p, 3.0 - p.t).unwrap();
            worst = worst.max((p.y[2] - p.t.cos()).abs()).max((p.y[0] - p.t.cos()).abs());
        }
        (p.y, worst)
    }

    #[test]
    fn switches_to_radau_where_stiff_and_back_where_not() {
        let tol = Tol { rtol: 1e-8, atol: Vector3::new(1e-10, 1e-10, 1e-10) };
        let mut auto = Switching::new(tol, 1e-4);
        let (_, err) = run(&mut auto);
        assert_eq!(auto.switches, (1, 1), "one switch each way");
        assert!(!auto.stiff, "explicit again at the end");
        assert!(err < 1e-6, "worst error {err:e}");
        // Dormand–Prince alone is held by stability in the stiff stretch: λ h ≤ ~3.3 for
        // 0.8 time units at λ = 1e5 is ≥ 24 000 steps; the switching run takes far fewer.
        let mut dp = Dopri5::new(tol, 1e-4);
        let (_, err_dp) = run(&mut dp);
        assert!(err_dp < 1e-6);
        let (a, d) = (auto.stats(), dp.stats());
        assert!(d.steps > 24_000, "{d:?}");
        assert!(a.steps * 10 < d.steps, "{a:?} against {d:?}");
        assert!(a.jac > 0 && a.lu > 0, "the implicit method ran: {a:?}");
        assert_eq!(a.switches, Some(2), "{a:?}");
        let explicit = a.explicit_steps.expect("the switching method counts its explicit steps");
        assert!(explicit > 0 && explicit < a.steps, "{a:?}");
        assert_eq!((d.switches, d.explicit_steps), (None, None), "a single method counts no switches");
    }

    #[test]
    fn spectral_bound_is_close_to_the_spectral_radius() {
        // eigenvalues −1000 and −1: radius 1000
        let a = Matrix2::new(-1000.0, 5.0, 0.0, -1.0);
        let r = spectral_bound(&a);
        assert!((1000.0..1100.0).contains(&r), "{r}");
        // a rotation-like oscillator ±7000 i
        let b = Matrix2::new(0.0, 1.0, -49e6, 0.0);
        let r = spectral_bound(&b);
        assert!((6993.0..10500.0).contains(&r), "{r}");
        assert_eq!(spectral_bound(&Matrix3::<f64>::zeros()), 0.0);
    }

    /// The cheap lower bound lies below the spectral radius (and so below Gelfand's upper
    /// bound, which then alone decides a switch back) for random matrices, oscillators and
    /// nilpotent ones, and is within a factor √N of it for a single dominant oscillation.
    #[test]
    fn spectral_lower_bound_is_below_the_radius() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..500 {
            let a =
                SMatrix::<f64, 6, 6>::from_fn(|_, _| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-3..4)));
            let rho = a.complex_eigenvalues().iter().map(|l| l.norm()).fold(0.0, f64::max);
            let low = spectral_lower_bound(&a);
            assert!(low <= rho * (1.0 + 1e-9), "{low} > {rho} for {a}");
            assert!(low <= spectral_bound(&a) * (1.0 + 1e-9));
        }
        // nilpotent: ρ = 0, and the bound is 0 despite the large entry
        let n = Matrix2::new(0.0, 1e10, 0.0, 0.0);
        assert_eq!(spectral_lower_bound(&n), 0.0);
        // ±7000 i: tr a² = −2·49e6, so the bound is 7000
        let b = Matrix2::new(0.0, 1.0, -49e6, 0.0);
        let low = spectral_lower_bound(&b);
        assert!((6999.0..=7000.0).contains(&low), "{low}");
    }
}
