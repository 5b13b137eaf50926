//! Adaptive one-step integrators on fixed-size states, one method per file: Radau IIA
//! order 5 ([`Radau5`], stiff, the default), TR-BDF2 ([`TrBdf2`], stiff) and Dormand–Prince
//! 5(4) ([`Dopri5`], explicit, for comparison); the S-stage Radau IIA ([`RadauIIA`]) shares
//! RADAU5's step loop ([`RadauStepper`], `radau_stepper`) with its own coefficients. Each exposes accepted steps with (y, f) at
//! both ends so a driver can do cubic Hermite dense output ([`hermite`]) and event
//! location. The implicit methods share the Jacobian's refresh policy (`jacobian`; the
//! Jacobian itself is the system's [`Rhs::jacobian`], by default dense forward differences,
//! [`fd_jacobian`]) and the start of a step attempt (`jacobian`'s `prepare_attempt`), and the LU ([`Lu`]);
//! Radau IIA also solves its Newton systems by block elimination over a system's
//! [`Partition`] (`reduced`). No heap allocation.

mod dense;
mod dopri5;
mod jacobian;
mod lu;
mod radau;
mod radau5;
mod radau_coefficients;
mod radau_stepper;
mod reduced;
mod schur_lu;
mod switching;
mod trbdf2;

pub use dense::hermite;
pub use dopri5::Dopri5;
pub use jacobian::fd_jacobian;
pub use lu::{Lu, Scalar};
pub use radau::{RadauIIA, RadauIIAScheme};
pub use radau5::{Radau5, Radau5Scheme};
pub use radau_coefficients::RadauCoefficients;
pub use radau_stepper::{RadauScheme, RadauStepper};
pub use reduced::Partition;
pub use switching::Switching;
pub use trbdf2::TrBdf2;

use nalgebra::{SMatrix, SVector};

/// Identifier of the smooth piece of a piecewise-smooth right-hand side: a set of on/off
/// flags (stop engaged, a force clipped, …; the system names its flags, see
/// [`Piece::with`]). Two states on the same piece have equal values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Piece(u64);

impl Piece {
    /// The piece of a smooth f (no flag set).
    pub const SMOOTH: Piece = Piece(0);
    /// The "piece" of a state where f is undefined.
    pub const UNDEFINED: Piece = Piece(u64::MAX);

    /// This piece with flag `bit` (0..64) set.
    #[inline(always)]
    #[must_use]
    pub const fn with(self, bit: u32) -> Piece {
        Piece(self.0 | 1 << bit)
    }

    /// Is flag `bit` set?
    #[inline]
    pub const fn has(self, bit: u32) -> bool {
        self.0 & (1 << bit) != 0
    }
}

/// A right-hand side y' = f(t, y). `None` marks a state where f is undefined (the driver
/// turns it into an abort or a smaller step).
pub trait Rhs<const N: usize> {
    /// Evaluate f(t, y).
    fn eval(&mut self, t: f64, y: &SVector<f64, N>) -> Option<SVector<f64, N>>;
    /// Identifier of the smooth piece of a piecewise-smooth f that `y` lies on (stop
    /// engaged, force clipped, …). Finite differences never straddle two pieces, so the
    /// Jacobian is that of one smooth branch. Default: f is smooth.
    fn piece(&self, _y: &SVector<f64, N>) -> Piece {
        Piece::SMOOTH
    }
    /// f(t, y) together with `piece(y)`; override when the evaluation knows its piece
    /// for free.
    fn eval_piece(&mut self, t: f64, y: &SVector<f64, N>) -> Option<(SVector<f64, N>, Piece)> {
        let f = self.eval(t, y)?;
        Some((f, self.piece(y)))
    }
    /// As [`Rhs::eval_piece`], at the end of an accepted step (a system may keep a fuller
    /// evaluation there for its driver).
    fn eval_accepted(&mut self, t: f64, y: &SVector<f64, N>) -> Option<(SVector<f64, N>, Piece)> {
        self.eval_piece(t, y)
    }
    /// The Jacobian ∂f/∂y at the point `at` (t, y and f(t, y)) into `jac`, with `piece` = the
    /// piece of y; work goes to `stats` (`rhs`: full evaluations). False where f is undefined
    /// at a state it needs. Default: [`fd_jacobian`], dense forward differences, N
    /// evaluations; a system whose parts couple sparsely may exploit that.
    fn jacobian(&mut self, at: &StepPoint<N>, piece: Piece, jac: &mut SMatrix<f64, N, N>, stats: &mut Stats) -> bool {
        fd_jacobian(self, at, piece, jac, stats)
    }
    /// States the Newton solves may eliminate by blocks (see [`Partition`]): a second-order
    /// system's positions, whose rates are velocities. Used by [`Radau5`] wherever the
    /// Jacobian fits the partition. Default: none (dense LU).
    fn newton_partition(&self) -> Option<Partition<N>> {
        None
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
    /// Switches between the explicit and the implicit method, both ways (`Switching`
    /// only; None for a single method).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub switches: Option<u64>,
    /// Accepted steps taken by the explicit method (part of `steps`; `Switching` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub explicit_steps: Option<u64>,
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
    /// The weights 1/(atol_i + rtol·max(|y0_i|, |y1_i|)) of the scaled norm (see
    /// [`Tol::sum_sq`]).
    #[inline]
    pub fn weights(&self, y0: &SVector<f64, N>, y1: &SVector<f64, N>) -> SVector<f64, N> {
        SVector::<f64, N>::from_fn(|i, _| 1.0 / (self.atol[i] + self.rtol * y0[i].abs().max(y1[i].abs())))
    }

    /// Σ (e_i w_i)² with weights `w` from [`Tol::weights`] (the scaled RMS norm is
    /// √(sum / N)).
    #[inline]
    pub fn sum_sq(e: &SVector<f64, N>, w: &SVector<f64, N>) -> f64 {
        let mut s = 0.0;
        for i in 0..N {
            let r = e[i] * w[i];
            s += r * r;
        }
        s
    }

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

/// A point of the solution where a step starts or ends: time, state and f there.
#[derive(Debug, Clone, Copy)]
pub struct StepPoint<const N: usize> {
    /// Time.
    pub t: f64,
    /// State.
    pub y: SVector<f64, N>,
    /// f(t, y).
    pub f: SVector<f64, N>,
}

impl<const N: usize> StepPoint<N> {
    /// The point (t, y) of `sys`, with f evaluated there; `None` where f is undefined.
    pub fn at<S: Rhs<N>>(sys: &mut S, t: f64, y: SVector<f64, N>) -> Option<Self> {
        Some(StepPoint { t, y, f: sys.eval(t, &y)? })
    }
}

/// An adaptive one-step method.
pub trait Stepper<const N: usize> {
    /// Take one accepted step from `from` with h ≤ h_max, adapting the step size.
    fn advance<S: Rhs<N>>(&mut self, sys: &mut S, from: &StepPoint<N>, h_max: f64) -> Result<StepPoint<N>, StepError>;
    /// Forget step-size history and Jacobians (after a discontinuity of f); the step-size
    /// proposal stays.
    fn restart(&mut self);
    /// The method's own continuous output on the last accepted step at `t` (inside it), where
    /// it has one (a collocation method's polynomial); `None`: use [`hermite`].
    fn dense(&self, _t: f64) -> Option<SVector<f64, N>> {
        None
    }
    /// Should a driver locate events (and take states inside a step) on [`Stepper::dense`]
    /// rather than on the cubic Hermite? Default: no (RADAU5 keeps the Hermite, which its
    /// tolerances were tuned with; docs/benchmarks.md).
    fn dense_for_events(&self) -> bool {
        false
    }
    /// Counters.
    fn stats(&self) -> Stats;
}

/// The smallest step size.
const HMIN: f64 = 1e-14;

#[cfg(test)]
pub(crate) mod testsys {
    //! Test systems shared by the methods' tests.
    use super::{Rhs, Stats, StepPoint, Stepper};
    use nalgebra::{SVector, Vector2};

    /// The harmonic oscillator y'' = −ω² y.
    pub struct Osc(pub f64);
    impl Rhs<2> for Osc {
        fn eval(&mut self, _t: f64, y: &SVector<f64, 2>) -> Option<SVector<f64, 2>> {
            Some(Vector2::new(y[1], -self.0 * self.0 * y[0]))
        }
    }

    /// Integrate the oscillator from (1, 0) to `t_end`.
    pub fn run_osc<St: Stepper<2>>(mut st: St, omega: f64, t_end: f64) -> (SVector<f64, 2>, Stats) {
        let mut sys = Osc(omega);
        let mut p = StepPoint::at(&mut sys, 0.0, Vector2::new(1.0, 0.0)).unwrap();
        while p.t < t_end {
            p = st.advance(&mut sys, &p, t_end - p.t).unwrap();
        }
        (p.y, st.stats())
    }
}
