//! Adaptive one-step integrators on fixed-size states: TR-BDF2 (L-stable, stiff; Hosea &
//! Shampine 1996 with its third-order embedded estimate, filtered by (I − dhJ)⁻¹) and
//! Dormand–Prince 5(4) (explicit, for comparison and non-stiff references). Both expose
//! accepted steps with (y, f) at both ends so a driver can do cubic Hermite dense output
//! and event location. No heap allocation.

use nalgebra::{Complex, SMatrix, SVector};

/// A right-hand side y' = f(t, y). `None` marks a state where f is undefined (the driver
/// turns it into an abort or a smaller step).
pub trait Rhs<const N: usize> {
    /// Evaluate f(t, y).
    fn eval(&mut self, t: f64, y: &SVector<f64, N>) -> Option<SVector<f64, N>>;
    /// Identifier of the smooth piece of a piecewise-smooth f that `y` lies on (stop
    /// engaged, force clipped, …). Finite differences never straddle two pieces, so the
    /// Jacobian is that of one smooth branch. Default: f is smooth.
    fn piece(&self, _y: &SVector<f64, N>) -> u64 {
        0
    }
    /// f(t, y) together with `piece(y)`; override when the evaluation knows its piece
    /// for free.
    fn eval_piece(&mut self, t: f64, y: &SVector<f64, N>) -> Option<(SVector<f64, N>, u64)> {
        let f = self.eval(t, y)?;
        Some((f, self.piece(y)))
    }
    /// As [`Rhs::eval_piece`], at the end of an accepted step (a system may keep a fuller
    /// evaluation there for its driver).
    fn eval_accepted(&mut self, t: f64, y: &SVector<f64, N>) -> Option<(SVector<f64, N>, u64)> {
        self.eval_piece(t, y)
    }
}

/// Work counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps (error test or Newton failure).
    pub rejected: u64,
    /// Right-hand-side evaluations.
    pub rhs: u64,
    /// Jacobian evaluations.
    pub jac: u64,
    /// LU factorisations.
    pub lu: u64,
    /// Newton iterations (implicit methods).
    pub newton: u64,
    /// Step attempts rejected because Newton failed (part of `rejected`).
    pub newton_fail: u64,
}

/// Tolerances: relative and per-component absolute.
#[derive(Debug, Clone, Copy)]
pub struct Tol<const N: usize> {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance per component.
    pub atol: SVector<f64, N>,
}

impl<const N: usize> Tol<N> {
    /// Scaled RMS norm of `e` with weights from `y0`, `y1`.
    #[inline]
    pub fn norm(&self, e: &SVector<f64, N>, y0: &SVector<f64, N>, y1: &SVector<f64, N>) -> f64 {
        let mut s = 0.0;
        for i in 0..N {
            let sc = self.atol[i] + self.rtol * y0[i].abs().max(y1[i].abs());
            let r = e[i] / sc;
            s += r * r;
        }
        (s / N as f64).sqrt()
    }
}

/// Why a step could not be taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepError {
    /// The step size fell below the minimum.
    StepTooSmall,
    /// f was undefined at the current state itself.
    RhsFailed,
}

/// An accepted step.
#[derive(Debug, Clone, Copy)]
pub struct Accepted<const N: usize> {
    /// New time.
    pub t: f64,
    /// New state.
    pub y: SVector<f64, N>,
    /// f at the new state.
    pub f: SVector<f64, N>,
}

/// An adaptive one-step method.
pub trait Stepper<const N: usize> {
    /// Take one accepted step from (t, y, f) with h ≤ h_max, adapting the step size.
    fn advance<S: Rhs<N>>(
        &mut self,
        sys: &mut S,
        t: f64,
        y: &SVector<f64, N>,
        f: &SVector<f64, N>,
        h_max: f64,
    ) -> Result<Accepted<N>, StepError>;
    /// Forget step-size history and Jacobians (after a discontinuity of f).
    fn restart(&mut self, h: f64);
    /// Counters.
    fn stats(&self) -> Stats;
    /// Current step size proposal.
    fn h(&self) -> f64;
    /// Method name.
    fn name(&self) -> &'static str;
}

/// Cubic Hermite interpolation on an accepted step.
#[inline]
pub fn hermite<const N: usize>(
    t0: f64,
    y0: &SVector<f64, N>,
    f0: &SVector<f64, N>,
    t1: f64,
    y1: &SVector<f64, N>,
    f1: &SVector<f64, N>,
    t: f64,
) -> SVector<f64, N> {
    let h = t1 - t0;
    if h == 0.0 {
        return *y1;
    }
    let s = (t - t0) / h;
    let s2 = s * s;
    let s3 = s2 * s;
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    y0 * h00 + f0 * (h10 * h) + y1 * h01 + f1 * (h11 * h)
}

const HMIN: f64 = 1e-14;

/// LU factorisation with partial pivoting of a fixed-size square matrix (no allocation),
/// real (`f64`) or complex (`Complex<f64>`, for the transformed Radau IIA system).
#[derive(Debug, Clone, Copy)]
pub struct Lu<T: Scalar, const N: usize> {
    lu: SMatrix<T, N, N>,
    piv: [usize; N],
}

/// The field of an [`Lu`]: `f64` or `Complex<f64>`.
pub trait Scalar: nalgebra::ComplexField<RealField = f64> + Copy {}
impl Scalar for f64 {}
impl Scalar for Complex<f64> {}

impl<T: Scalar, const N: usize> Lu<T, N> {
    /// Factor `a`; `None` if singular.
    #[inline]
    pub fn factor(mut a: SMatrix<T, N, N>) -> Option<Self> {
        let mut piv = [0usize; N];
        for k in 0..N {
            let mut p = k;
            let mut m = a[(k, k)].norm1();
            for i in k + 1..N {
                let v = a[(i, k)].norm1();
                if v > m {
                    m = v;
                    p = i;
                }
            }
            if !(m > 0.0) || !m.is_finite() {
                return None;
            }
            piv[k] = p;
            if p != k {
                a.swap_rows(p, k);
            }
            let d = T::one() / a[(k, k)];
            for i in k + 1..N {
                let l = a[(i, k)] * d;
                a[(i, k)] = l;
                for j in k + 1..N {
                    let akj = a[(k, j)];
                    a[(i, j)] -= l * akj;
                }
            }
        }
        Some(Lu { lu: a, piv })
    }

    /// Solve A x = b.
    #[inline]
    pub fn solve(&self, b: &SVector<T, N>) -> SVector<T, N> {
        let mut x = *b;
        for k in 0..N {
            x.swap_rows(k, self.piv[k]);
        }
        for i in 0..N {
            let mut s = x[i];
            for j in 0..i {
                s -= self.lu[(i, j)] * x[j];
            }
            x[i] = s;
        }
        for i in (0..N).rev() {
            let mut s = x[i];
            for j in i + 1..N {
                s -= self.lu[(i, j)] * x[j];
            }
            x[i] = s / self.lu[(i, i)];
        }
        x
    }
}

// ---------------------------------------------------------------------------------------
// Finite-difference Jacobian shared by the implicit methods
// ---------------------------------------------------------------------------------------

/// A finite-difference Jacobian that never straddles a kink of a piecewise-smooth f (see
/// [`Rhs::piece`]) and is reused across steps until the state leaves its smooth piece,
/// Newton converges slowly, or a step is rejected.
#[derive(Debug, Clone)]
struct JacobianCache<const N: usize> {
    jac: SMatrix<f64, N, N>,
    valid: bool,
    /// Computed at the current step's start (a failure cannot be blamed on staleness).
    fresh: bool,
    piece: u64,
    /// Newton contracted slowly in the last step.
    slow: bool,
    /// The piece of the last accepted state, known from its evaluation.
    known: Option<(SVector<f64, N>, u64)>,
}

impl<const N: usize> JacobianCache<N> {
    fn new() -> Self {
        JacobianCache { jac: SMatrix::zeros(), valid: false, fresh: false, piece: 0, slow: false, known: None }
    }

    /// The piece of `y` (from the last accepted evaluation when `y` is that state).
    fn piece_of<S: Rhs<N>>(&self, sys: &S, y: &SVector<f64, N>) -> u64 {
        match self.known {
            Some((yk, p)) if yk == *y => p,
            _ => sys.piece(y),
        }
    }

    /// At the start of a step: drop a stale Jacobian.
    fn start_step<S: Rhs<N>>(&mut self, sys: &S, y: &SVector<f64, N>) {
        if self.valid && !self.fresh && (self.slow || self.piece_of(sys, y) != self.piece) {
            self.valid = false;
        }
        self.slow = false;
    }

    /// Compute J at (t, y); false if f is undefined at a perturbed state.
    fn compute<S: Rhs<N>>(&mut self, sys: &mut S, t: f64, y: &SVector<f64, N>, f: &SVector<f64, N>, stats: &mut Stats) -> bool {
        let sq = f64::EPSILON.sqrt();
        let mut yp = *y;
        self.piece = self.piece_of(sys, y);
        for j in 0..N {
            let mut dy = sq * y[j].abs().max(1e-3);
            yp[j] = y[j] + dy;
            stats.rhs += 1;
            let Some((mut fp, p)) = sys.eval_piece(t, &yp) else { return false };
            if p != self.piece {
                // one-sided difference on the other side, inside the piece of y
                dy = -dy;
                yp[j] = y[j] + dy;
                stats.rhs += 1;
                let Some((fm, _)) = sys.eval_piece(t, &yp) else { return false };
                fp = fm;
            }
            self.jac.set_column(j, &((fp - f) / dy));
            yp[j] = y[j];
        }
        stats.jac += 1;
        self.valid = true;
        self.fresh = true;
        true
    }
}

/// An implicit stepper's Jacobian and factored Newton matrix, for the shared start of a
/// step attempt ([`prepare_attempt`]).
trait NewtonMatrix<const N: usize> {
    /// The Jacobian cache, the counters and the step-size proposal.
    fn parts(&mut self) -> (&mut JacobianCache<N>, &mut Stats, &mut f64);
    /// Forget the factorisation (the Jacobian changed).
    fn drop_factor(&mut self);
    /// Factor the Newton matrix for step `h` (no-op if already factored for `h`).
    fn factor(&mut self, h: f64) -> bool;
}

/// Start a step attempt: bound h, refresh the Jacobian if needed and factor. `Ok(None)`:
/// retry (a stale Jacobian was dropped, or h halved after a singular matrix).
fn prepare_attempt<M: NewtonMatrix<N>, S: Rhs<N>, const N: usize>(
    m: &mut M,
    sys: &mut S,
    t: f64,
    y: &SVector<f64, N>,
    f: &SVector<f64, N>,
    h_max: f64,
) -> Result<Option<f64>, StepError> {
    let (jc, stats, h_prop) = m.parts();
    let h = h_prop.min(h_max);
    if h < HMIN {
        return Err(StepError::StepTooSmall);
    }
    if !jc.valid {
        if !jc.compute(sys, t, y, f, stats) {
            return Err(StepError::RhsFailed);
        }
        m.drop_factor();
    }
    if m.factor(h) {
        return Ok(Some(h));
    }
    let (jc, stats, h_prop) = m.parts();
    if !jc.fresh {
        jc.valid = false;
    } else {
        *h_prop = h * 0.5;
        stats.rejected += 1;
    }
    Ok(None)
}

// ---------------------------------------------------------------------------------------
// TR-BDF2
// ---------------------------------------------------------------------------------------

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

    fn factor_matrix(&mut self, h: f64) -> bool {
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
        self.factor_matrix(h)
    }
}

impl<const N: usize> Stepper<N> for TrBdf2<N> {
    fn advance<S: Rhs<N>>(
        &mut self,
        sys: &mut S,
        t: f64,
        y: &SVector<f64, N>,
        f: &SVector<f64, N>,
        h_max: f64,
    ) -> Result<Accepted<N>, StepError> {
        self.jc.start_step(sys, y);
        loop {
            let Some(h) = prepare_attempt(self, sys, t, y, f, h_max)? else { continue };
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
                return Ok(Accepted { t: t + h, y: y3, f: k3 });
            }
            self.stats.rejected += 1;
            let fac = if err.is_finite() { (0.9 * err.powf(-1.0 / 3.0)).clamp(0.1, 0.9) } else { 0.25 };
            self.h = h * fac;
            if !self.jc.fresh {
                self.jc.valid = false;
            }
        }
    }

    fn restart(&mut self, h: f64) {
        self.h = h;
        self.jc.valid = false;
        self.lu = None;
    }

    fn stats(&self) -> Stats {
        self.stats
    }

    fn h(&self) -> f64 {
        self.h
    }

    fn name(&self) -> &'static str {
        "tr-bdf2"
    }
}

impl<const N: usize> TrBdf2<N> {
    fn newton_failed(&mut self, h: f64) {
        self.stats.rejected += 1;
        if self.jc.fresh {
            self.h = h * 0.25;
        } else {
            self.jc.valid = false;
        }
    }
}

// ---------------------------------------------------------------------------------------
// Dormand–Prince 5(4)
// ---------------------------------------------------------------------------------------

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
    fn advance<S: Rhs<N>>(
        &mut self,
        sys: &mut S,
        t: f64,
        y: &SVector<f64, N>,
        f: &SVector<f64, N>,
        h_max: f64,
    ) -> Result<Accepted<N>, StepError> {
        loop {
            let h = self.h.min(h_max);
            if h < HMIN {
                return Err(StepError::StepTooSmall);
            }
            let k1 = *f;
            let r = (|| {
                let k2 = sys.eval(t + h / 5.0, &(y + k1 * (h / 5.0)))?;
                let k3 = sys.eval(t + 0.3 * h, &(y + (k1 * (3.0 / 40.0) + k2 * (9.0 / 40.0)) * h))?;
                let k4 = sys.eval(t + 0.8 * h, &(y + (k1 * (44.0 / 45.0) - k2 * (56.0 / 15.0) + k3 * (32.0 / 9.0)) * h))?;
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
                let y1 = y + (k1 * (35.0 / 384.0) + k3 * (500.0 / 1113.0) + k4 * (125.0 / 192.0)
                    - k5 * (2187.0 / 6784.0)
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
                return Ok(Accepted { t: t + h, y: y1, f: k7 });
            }
            self.stats.rejected += 1;
            self.h = h * (0.9 * err.powf(-0.2)).clamp(0.1, 0.9);
        }
    }

    fn restart(&mut self, h: f64) {
        self.h = h;
    }

    fn stats(&self) -> Stats {
        self.stats
    }

    fn h(&self) -> f64 {
        self.h
    }

    fn name(&self) -> &'static str {
        "dopri5"
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    struct Osc(f64);
    impl Rhs<2> for Osc {
        fn eval(&mut self, _t: f64, y: &SVector<f64, 2>) -> Option<SVector<f64, 2>> {
            Some(Vector2::new(y[1], -self.0 * self.0 * y[0]))
        }
    }

    fn run<St: Stepper<2>>(mut st: St, omega: f64, t_end: f64) -> (SVector<f64, 2>, Stats) {
        let mut sys = Osc(omega);
        let mut t = 0.0;
        let mut y = Vector2::new(1.0, 0.0);
        let mut f = sys.eval(0.0, &y).unwrap();
        while t < t_end {
            let a = st.advance(&mut sys, t, &y, &f, t_end - t).unwrap();
            t = a.t;
            y = a.y;
            f = a.f;
        }
        (y, st.stats())
    }

    #[test]
    fn trbdf2_converges_second_order() {
        let tol = |r: f64| Tol { rtol: r, atol: Vector2::new(r, r) };
        let exact = 1.0f64.cos();
        let (y1, _) = run(TrBdf2::new(tol(1e-6), 1e-3), 1.0, 1.0);
        let (y2, _) = run(TrBdf2::new(tol(1e-9), 1e-3), 1.0, 1.0);
        let (e1, e2) = ((y1[0] - exact).abs(), (y2[0] - exact).abs());
        assert!(e1 < 1e-4, "{e1}");
        assert!(e2 < 1e-6, "{e2}");
        // order 2 (global error ∝ rtol^(2/3)): tightening rtol 1000× shrinks it ~100×
        assert!(e2 < e1 / 30.0, "{e1} {e2}");
    }

    #[test]
    fn dopri5_accuracy() {
        let tol = Tol { rtol: 1e-11, atol: Vector2::new(1e-13, 1e-13) };
        let (y, _) = run(Dopri5::new(tol, 1e-3), 2.0, 3.0);
        assert!((y[0] - 6.0f64.cos()).abs() < 1e-9);
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
        let (mut t, mut y) = (0.0, Vector2::new(0.0, 1.0));
        let mut f = sys.eval(0.0, &y).unwrap();
        while t < 1.0 {
            let a = st.advance(&mut sys, t, &y, &f, 1.0 - t).unwrap();
            (t, y, f) = (a.t, a.y, a.f);
        }
        assert!((y[0] - 1.0f64.cos()).abs() < 1e-5);
        assert!(st.stats().steps < 2000, "{:?}", st.stats());
    }
}

// ---------------------------------------------------------------------------------------
// Radau IIA (3 stages, order 5)
// ---------------------------------------------------------------------------------------

/// Radau IIA of order 5 after Hairer & Wanner's RADAU5: stiffly accurate, L-stable. The
/// simplified Newton iteration uses their transformation A⁻¹ = T Λ T⁻¹, so each Jacobian
/// costs one real N×N LU of γ/h − J and one complex N×N LU of (α + iβ)/h − J instead of a
/// 3N×3N one. Newton's contraction is carried across steps and a predicted non-convergence
/// shrinks h early; the step size follows Gustafsson's predictive controller; the error
/// estimate is RADAU5's, filtered by (γ/h − J)⁻¹.
#[derive(Debug, Clone)]
pub struct Radau5<const N: usize> {
    tol: Tol<N>,
    h: f64,
    jc: JacobianCache<N>,
    /// γ/h − J.
    lu_r: Option<Lu<f64, N>>,
    /// (α + iβ)/h − J.
    lu_c: Option<Lu<Complex<f64>, N>>,
    lu_h: f64,
    stats: Stats,
    first: bool,
    last_rejected: bool,
    prev_z: Option<(f64, [SVector<f64, N>; 3])>,
    /// Newton's η = θ/(1 − θ) of the last step (the first iteration's estimate).
    eta: f64,
    /// (h, err) of the last accepted step, for the predictive controller.
    acc: Option<(f64, f64)>,
    eig: RadauEig,
    /// Newton convergence threshold in tolerance units.
    pub kappa: f64,
    /// Maximum Newton iterations.
    pub max_newton: usize,
    /// Recompute the Jacobian after an accepted step whose Newton contraction θ exceeded
    /// this (RADAU5's `THET`).
    pub theta_jac: f64,
}

const SQ6: f64 = 2.449_489_742_783_178;
const RC: [f64; 3] = [(4.0 - SQ6) / 10.0, (4.0 + SQ6) / 10.0, 1.0];
/// Radau IIA coefficient matrix A (used by the tests of the transformation).
#[cfg(test)]
const RA: [[f64; 3]; 3] = [
    [(88.0 - 7.0 * SQ6) / 360.0, (296.0 - 169.0 * SQ6) / 1800.0, (-2.0 + 3.0 * SQ6) / 225.0],
    [(296.0 + 169.0 * SQ6) / 1800.0, (88.0 + 7.0 * SQ6) / 360.0, (-2.0 - 3.0 * SQ6) / 225.0],
    [(16.0 - SQ6) / 36.0, (16.0 + SQ6) / 36.0, 1.0 / 9.0],
];
const DD: [f64; 3] = [-(13.0 + 7.0 * SQ6) / 3.0, (-13.0 + 7.0 * SQ6) / 3.0, -1.0 / 3.0];
/// Hairer & Wanner's T with A⁻¹ = T Λ T⁻¹, Λ = [[γ, 0, 0], [0, α, −β], [0, β, α]].
#[allow(clippy::excessive_precision)]
const RT: [[f64; 3]; 3] = [
    [9.123_239_487_089_294_279_2e-2, -0.141_255_295_020_954_208_43, -3.002_919_410_514_742_449_2e-2],
    [0.241_717_932_707_107_018_96, 0.204_129_352_293_799_931_99, 0.382_942_112_757_261_937_79],
    [0.966_048_182_615_092_936_19, 1.0, 0.0],
];
/// T⁻¹.
#[allow(clippy::excessive_precision)]
const RTI: [[f64; 3]; 3] = [
    [4.325_579_890_063_155_351_0, 0.339_199_251_815_809_869_54, 0.541_770_539_935_874_871_19],
    [-4.178_718_591_551_904_727_3, -0.327_682_820_761_062_387_08, 0.476_623_554_500_550_451_96],
    [-0.502_872_634_945_786_875_95, 2.571_926_949_855_605_429_2, -0.596_039_204_828_224_924_97],
];

/// The eigenvalues of A⁻¹: γ (real) and α ± iβ.
#[derive(Debug, Clone, Copy)]
struct RadauEig {
    gamma: f64,
    alpha: f64,
    beta: f64,
}

impl RadauEig {
    fn new() -> Self {
        let c9 = 9f64.cbrt();
        let c81 = c9 * c9;
        let (a, b) = ((12.0 - c81 + c9) / 60.0, (c81 + c9) * 3f64.sqrt() / 60.0);
        let cno = a * a + b * b;
        RadauEig { gamma: 30.0 / (6.0 + c81 - c9), alpha: a / cno, beta: b / cno }
    }
}

#[inline(always)]
fn mix3<const N: usize>(m: &[[f64; 3]; 3], v: &[SVector<f64, N>; 3]) -> [SVector<f64, N>; 3] {
    let row = |i: usize| v[0] * m[i][0] + v[1] * m[i][1] + v[2] * m[i][2];
    [row(0), row(1), row(2)]
}

impl<const N: usize> Radau5<N> {
    /// New stepper.
    pub fn new(tol: Tol<N>, h0: f64) -> Self {
        Radau5 {
            tol,
            h: h0,
            jc: JacobianCache::new(),
            lu_r: None,
            lu_c: None,
            lu_h: 0.0,
            stats: Stats::default(),
            first: true,
            last_rejected: false,
            prev_z: None,
            eta: 1.0,
            acc: None,
            eig: RadauEig::new(),
            kappa: 0.1,
            max_newton: 7,
            theta_jac: 0.01,
        }
    }

    fn factor_matrix(&mut self, h: f64) -> bool {
        if self.lu_r.is_some() && self.lu_h == h {
            return true;
        }
        let j = &self.jc.jac;
        let e = SMatrix::<f64, N, N>::from_diagonal_element(self.eig.gamma / h) - j;
        let ac = Complex::new(self.eig.alpha / h, self.eig.beta / h);
        let ec = SMatrix::<Complex<f64>, N, N>::from_fn(|r, c| {
            let d = if r == c { ac } else { Complex::new(0.0, 0.0) };
            d - Complex::new(j[(r, c)], 0.0)
        });
        self.stats.lu += 1;
        match (Lu::factor(e), Lu::factor(ec)) {
            (Some(l), Some(lc)) => {
                self.lu_r = Some(l);
                self.lu_c = Some(lc);
                self.lu_h = h;
                true
            }
            _ => {
                self.lu_r = None;
                self.lu_c = None;
                false
            }
        }
    }

    /// Start of Newton: the previous step's collocation polynomial extrapolated to the new
    /// stages (zero after a restart or a rejection).
    fn predict(&self, h: f64) -> [SVector<f64, N>; 3] {
        let mut z = [SVector::<f64, N>::zeros(); 3];
        if let Some((hp, zp)) = self.prev_z.filter(|_| !self.first && !self.last_rejected) {
            // The polynomial through (0, 0), (c_i, zp_i) in s = (t − t_{n−1}) / hp; the new
            // stages sit at s = 1 + c_i h / hp, and the origin moves to y_n = y_{n−1} + zp_3.
            let nodes = [0.0, RC[0], RC[1], RC[2]];
            for i in 0..3 {
                let sv = 1.0 + RC[i] * h / hp;
                let mut val = SVector::<f64, N>::zeros();
                for k in 1..4 {
                    let mut l = 1.0;
                    for m in 0..4 {
                        if m != k {
                            l *= (sv - nodes[m]) / (nodes[k] - nodes[m]);
                        }
                    }
                    val += zp[k - 1] * l;
                }
                z[i] = val - zp[2];
            }
        }
        z
    }
}

/// Why a Newton iteration stopped without converging.
enum NewtonFail {
    /// f undefined, divergence or too many iterations: halve h (or refresh J).
    Diverged,
    /// Predicted not to converge in time: retry with h scaled by this factor.
    Slow(f64),
}

impl<const N: usize> Radau5<N> {
    /// Simplified Newton on the transformed stages; returns Z and the last contraction θ.
    fn newton<S: Rhs<N>>(
        &mut self,
        sys: &mut S,
        t: f64,
        y: &SVector<f64, N>,
        h: f64,
    ) -> Result<([SVector<f64, N>; 3], f64, usize), NewtonFail> {
        let (gh, ah, bh) = (self.eig.gamma / h, self.eig.alpha / h, self.eig.beta / h);
        let mut z = self.predict(h);
        let mut w = mix3(&RTI, &z);
        let mut eta = self.eta.max(f64::EPSILON).powf(0.8);
        let mut theta = self.theta_jac;
        let (mut prev, mut thq_old) = (0.0, 0.0);
        let lu_r = self.lu_r.as_ref().expect("factored");
        let lu_c = self.lu_c.as_ref().expect("factored");
        for it in 0..self.max_newton {
            self.stats.newton += 1;
            let mut fz = [SVector::<f64, N>::zeros(); 3];
            for i in 0..3 {
                self.stats.rhs += 1;
                fz[i] = sys.eval(t + RC[i] * h, &(y + z[i])).ok_or(NewtonFail::Diverged)?;
            }
            let r = mix3(&RTI, &fz);
            let r1 = r[0] - w[0] * gh;
            let r2 = r[1] - (w[1] * ah - w[2] * bh);
            let r3 = r[2] - (w[1] * bh + w[2] * ah);
            let d1 = lu_r.solve(&r1);
            let dc = lu_c.solve(&SVector::<Complex<f64>, N>::from_fn(|k, _| Complex::new(r2[k], r3[k])));
            let d2 = dc.map(|c| c.re);
            let d3 = dc.map(|c| c.im);
            let n1 = self.tol.norm(&d1, y, y);
            let n2 = self.tol.norm(&d2, y, y);
            let n3 = self.tol.norm(&d3, y, y);
            let n = ((n1 * n1 + n2 * n2 + n3 * n3) / 3.0).sqrt();
            if !n.is_finite() {
                return Err(NewtonFail::Diverged);
            }
            if it > 0 {
                let thq = n / prev;
                theta = if it == 1 { thq } else { (thq * thq_old).sqrt() };
                thq_old = thq;
                if theta >= 0.99 {
                    return Err(NewtonFail::Diverged);
                }
                eta = theta / (1.0 - theta);
                let left = self.max_newton as i32 - 2 - it as i32;
                if left >= 0 {
                    let dyth = eta * n * theta.powi(left) / self.kappa;
                    if dyth >= 1.0 {
                        let q = dyth.clamp(1e-4, 20.0);
                        return Err(NewtonFail::Slow(0.8 * q.powf(-1.0 / (4.0 + left as f64))));
                    }
                }
            }
            prev = n.max(f64::EPSILON);
            w[0] += d1;
            w[1] += d2;
            w[2] += d3;
            z = mix3(&RT, &w);
            if eta * n <= self.kappa || n <= 1e-12 {
                self.eta = eta;
                return Ok((z, theta, it + 1));
            }
        }
        Err(NewtonFail::Diverged)
    }
}

impl<const N: usize> NewtonMatrix<N> for Radau5<N> {
    fn parts(&mut self) -> (&mut JacobianCache<N>, &mut Stats, &mut f64) {
        (&mut self.jc, &mut self.stats, &mut self.h)
    }
    fn drop_factor(&mut self) {
        self.lu_r = None;
    }
    fn factor(&mut self, h: f64) -> bool {
        self.factor_matrix(h)
    }
}

impl<const N: usize> Stepper<N> for Radau5<N> {
    fn advance<S: Rhs<N>>(
        &mut self,
        sys: &mut S,
        t: f64,
        y: &SVector<f64, N>,
        f: &SVector<f64, N>,
        h_max: f64,
    ) -> Result<Accepted<N>, StepError> {
        self.jc.start_step(sys, y);
        loop {
            let Some(h) = prepare_attempt(self, sys, t, y, f, h_max)? else { continue };
            let (z, theta, iters) = match self.newton(sys, t, y, h) {
                Ok(v) => v,
                Err(NewtonFail::Diverged) => {
                    self.reject_newton(h);
                    continue;
                }
                Err(NewtonFail::Slow(fac)) => {
                    // RADAU5: shrink h and refactor; the Jacobian stays.
                    self.stats.rejected += 1;
                    self.stats.newton_fail += 1;
                    self.last_rejected = true;
                    self.h = h * fac;
                    continue;
                }
            };
            let y1 = y + z[2];
            // error estimate (RADAU5): (γ/h − J)⁻¹ (f0 + Σ dd_i Z_i / h)
            let f2 = (z[0] * DD[0] + z[1] * DD[1] + z[2] * DD[2]) / h;
            let le = self.lu_r.as_ref().expect("factored");
            let mut err_v = le.solve(&(f + f2));
            let mut err = self.tol.norm(&err_v, y, &y1);
            if err >= 1.0 && (self.first || self.last_rejected) {
                self.stats.rhs += 1;
                if let Some(f1) = sys.eval(t, &(y + err_v)) {
                    err_v = le.solve(&(f1 + f2));
                    err = self.tol.norm(&err_v, y, &y1);
                }
            }
            // RADAU5's step-size rule: safety factor lowered by Newton iterations.
            let safe = (0.9 * (1 + 2 * self.max_newton) as f64 / (iters + 2 * self.max_newton) as f64).min(0.9);
            let err_q = if err.is_finite() { err.max(1e-10) } else { 1e10 };
            let mut quot = (err_q.sqrt().sqrt() / safe).clamp(1.0 / 8.0, 5.0);
            if err.is_finite() && err <= 1.0 {
                self.stats.rhs += 1;
                let Some((fy1, piece)) = sys.eval_accepted(t + h, &y1) else {
                    self.reject_newton(h);
                    continue;
                };
                self.stats.steps += 1;
                // Gustafsson's predictive controller.
                if let Some((h_acc, err_acc)) = self.acc {
                    let fg = ((h_acc / h) * (err_q * err_q / err_acc).sqrt().sqrt() / 0.9).clamp(1.0 / 8.0, 5.0);
                    quot = quot.max(fg);
                }
                self.acc = Some((h, err_q.max(1e-2)));
                let mut h_new = h / quot;
                if self.last_rejected {
                    h_new = h_new.min(h);
                }
                self.first = false;
                self.last_rejected = false;
                self.prev_z = Some((h, z));
                self.jc.fresh = false;
                self.jc.known = Some((y1, piece));
                if theta > self.theta_jac {
                    self.jc.slow = true;
                }
                let q = h_new / h;
                self.h = if !self.jc.slow && (1.0..=1.2).contains(&q) { h } else { h_new };
                return Ok(Accepted { t: t + h, y: y1, f: fy1 });
            }
            self.stats.rejected += 1;
            self.h = if self.stats.steps == 0 { h * 0.1 } else { h / quot };
            self.last_rejected = true;
            if !self.jc.fresh {
                self.jc.valid = false;
            }
        }
    }

    fn restart(&mut self, h: f64) {
        self.h = h;
        self.jc.valid = false;
        self.lu_r = None;
        self.first = true;
        self.prev_z = None;
        self.acc = None;
        self.eta = 1.0;
    }

    fn stats(&self) -> Stats {
        self.stats
    }

    fn h(&self) -> f64 {
        self.h
    }

    fn name(&self) -> &'static str {
        "radau5"
    }
}

impl<const N: usize> Radau5<N> {
    fn reject_newton(&mut self, h: f64) {
        self.stats.rejected += 1;
        self.stats.newton_fail += 1;
        self.last_rejected = true;
        if self.jc.fresh {
            self.h = h * 0.5;
        } else {
            self.jc.valid = false;
        }
    }
}

#[cfg(test)]
mod radau_tests {
    use super::*;
    use nalgebra::Vector2;

    struct Osc;
    impl Rhs<2> for Osc {
        fn eval(&mut self, _t: f64, y: &SVector<f64, 2>) -> Option<SVector<f64, 2>> {
            Some(Vector2::new(y[1], -y[0]))
        }
    }

    /// Hairer's transformation: T T⁻¹ = I and T Λ T⁻¹ = A⁻¹ (independent of the stepper).
    #[test]
    fn radau_transformation_diagonalises_a_inverse() {
        let m = |a: &[[f64; 3]; 3]| nalgebra::Matrix3::from_fn(|i, j| a[i][j]);
        let (t, ti, a) = (m(&RT), m(&RTI), m(&RA));
        let e = RadauEig::new();
        let lam = nalgebra::Matrix3::new(e.gamma, 0.0, 0.0, 0.0, e.alpha, -e.beta, 0.0, e.beta, e.alpha);
        assert!((t * ti - nalgebra::Matrix3::identity()).abs().max() < 1e-15 * 10.0);
        let ainv = a.try_inverse().unwrap();
        assert!((t * lam * ti - ainv).abs().max() < 1e-12 * ainv.abs().max(), "{}", t * lam * ti - ainv);
    }

    /// The complex LU solves a complex system (checked by multiplying back).
    #[test]
    fn complex_lu_solves() {
        let a = SMatrix::<Complex<f64>, 3, 3>::from_fn(|i, j| Complex::new((i * 3 + j) as f64 + if i == j { 5.0 } else { 0.0 }, (i as f64) - (j as f64) * 0.5));
        let b = SVector::<Complex<f64>, 3>::from_fn(|i, _| Complex::new(1.0 + i as f64, -(i as f64)));
        let x = Lu::factor(a).unwrap().solve(&b);
        assert!((a * x - b).norm() < 1e-13);
    }

    #[test]
    fn radau5_accuracy_and_order() {
        let mut errs = vec![];
        for rtol in [1e-6, 1e-9] {
            let mut st: Radau5<2> = Radau5::new(Tol { rtol, atol: Vector2::new(rtol, rtol) }, 1e-3);
            let mut sys = Osc;
            let (mut t, mut y) = (0.0, Vector2::new(1.0, 0.0));
            let mut f = sys.eval(0.0, &y).unwrap();
            while t < 3.0 {
                let a = st.advance(&mut sys, t, &y, &f, 3.0 - t).unwrap();
                (t, y, f) = (a.t, a.y, a.f);
            }
            errs.push(((y[0] - 3f64.cos()).abs(), st.stats().steps));
        }
        assert!(errs[0].0 < 1e-5, "{errs:?}");
        assert!(errs[1].0 < 1e-8, "{errs:?}");
        assert!(errs[1].1 < 400, "{errs:?}");
    }

    #[test]
    fn radau5_stiff_van_der_pol_like() {
        struct Stiff;
        impl Rhs<2> for Stiff {
            fn eval(&mut self, t: f64, y: &SVector<f64, 2>) -> Option<SVector<f64, 2>> {
                Some(Vector2::new(-1e7 * (y[0] - t.sin()) + t.cos(), -y[1]))
            }
        }
        let mut st: Radau5<2> = Radau5::new(Tol { rtol: 1e-8, atol: Vector2::new(1e-10, 1e-10) }, 1e-6);
        let mut sys = Stiff;
        let (mut t, mut y) = (0.0, Vector2::new(0.0, 1.0));
        let mut f = sys.eval(0.0, &y).unwrap();
        while t < 2.0 {
            let a = st.advance(&mut sys, t, &y, &f, 2.0 - t).unwrap();
            (t, y, f) = (a.t, a.y, a.f);
        }
        assert!((y[0] - 2f64.sin()).abs() < 1e-8);
        assert!((y[1] - (-2f64).exp()).abs() < 1e-8);
        assert!(st.stats().steps < 500, "{:?}", st.stats());
    }
}
