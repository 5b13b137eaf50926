//! The finite-difference Jacobian shared by the implicit methods, its refresh policy, and
//! the start of their step attempts (the Jacobian refreshed when needed, the Newton matrix
//! factored: [`prepare_attempt`]).

use super::{Piece, Rhs, Stats, StepError, StepPoint, HMIN};
use nalgebra::{SMatrix, SVector};

/// A finite-difference Jacobian that never straddles a kink of a piecewise-smooth f (see
/// [`Rhs::piece`]) and is reused across steps until the state leaves its smooth piece,
/// Newton converges slowly, or a step is rejected.
#[derive(Debug, Clone)]
pub(super) struct JacobianCache<const N: usize> {
    /// The Jacobian.
    pub(super) jac: SMatrix<f64, N, N>,
    /// Usable (else recomputed at the next attempt).
    pub(super) valid: bool,
    /// Computed at the current step's start (a failure cannot be blamed on staleness).
    pub(super) fresh: bool,
    /// The smooth piece it was computed on.
    pub(super) piece: Piece,
    /// Newton contracted slowly in the last step.
    pub(super) slow: bool,
    /// The piece of the last accepted state, known from its evaluation.
    pub(super) known: Option<(SVector<f64, N>, Piece)>,
    /// Counts the Jacobians computed (what a factorisation was prepared from).
    pub(super) version: u64,
}

impl<const N: usize> JacobianCache<N> {
    /// No Jacobian yet.
    pub(super) fn new() -> Self {
        JacobianCache {
            jac: SMatrix::zeros(),
            valid: false,
            fresh: false,
            piece: Piece::SMOOTH,
            slow: false,
            known: None,
            version: 0,
        }
    }

    /// The piece of `y` (from the last accepted evaluation when `y` is that state).
    fn piece_of<S: Rhs<N>>(&self, sys: &S, y: &SVector<f64, N>) -> Piece {
        match self.known {
            Some((yk, p)) if yk == *y => p,
            _ => sys.piece(y),
        }
    }

    /// After a Newton iteration failed with step `h`: with a fresh Jacobian the step is
    /// to blame, and the smaller step `h · shrink` is returned; with a stale one the
    /// Jacobian is dropped (recomputed at the next attempt) and the step kept (None).
    pub(super) fn newton_failed(&mut self, h: f64, shrink: f64) -> Option<f64> {
        if self.fresh {
            Some(h * shrink)
        } else {
            self.valid = false;
            None
        }
    }

    /// At the start of a step: drop a stale Jacobian.
    pub(super) fn start_step<S: Rhs<N>>(&mut self, sys: &S, y: &SVector<f64, N>) {
        if self.valid && !self.fresh && (self.slow || self.piece_of(sys, y) != self.piece) {
            self.valid = false;
        }
        self.slow = false;
    }

    /// Compute J at the point `at` with the system's [`Rhs::jacobian`]; false if f is undefined at
    /// a perturbed state.
    pub(super) fn compute<S: Rhs<N>>(&mut self, sys: &mut S, at: &StepPoint<N>, stats: &mut Stats) -> bool {
        self.piece = self.piece_of(sys, &at.y);
        if !sys.jacobian(at, self.piece, &mut self.jac, stats) {
            return false;
        }
        stats.jac += 1;
        self.version += 1;
        self.valid = true;
        self.fresh = true;
        true
    }
}

/// An implicit stepper's Jacobian and factored Newton matrix, for the shared start of a
/// step attempt ([`prepare_attempt`]).
pub(super) trait NewtonMatrix<const N: usize> {
    /// The Jacobian cache, the counters and the step-size proposal.
    fn parts(&mut self) -> (&mut JacobianCache<N>, &mut Stats, &mut f64);
    /// Forget the factorisation (the Jacobian changed).
    fn drop_factor(&mut self);
    /// Factor the Newton matrix for step `h` (no-op if already factored for `h`).
    fn factor(&mut self, h: f64) -> bool;
}

/// Start a step attempt: bound h, refresh the Jacobian if needed and factor. `Ok(None)`:
/// retry (a stale Jacobian was dropped, or h halved after a singular matrix).
pub(super) fn prepare_attempt<M: NewtonMatrix<N>, S: Rhs<N>, const N: usize>(
    m: &mut M,
    sys: &mut S,
    from: &StepPoint<N>,
    h_max: f64,
) -> Result<Option<f64>, StepError> {
    let (jc, stats, h_prop) = m.parts();
    let h = h_prop.min(h_max);
    if h < HMIN {
        return Err(StepError::StepTooSmall);
    }
    if !jc.valid {
        if !jc.compute(sys, from, stats) {
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

/// The dense forward-difference Jacobian of `sys` at (t, y), f = f(t, y), into `jac`: one
/// evaluation per column (counted in `stats.rhs`), step √ε·max(|y_j|, 1e-3); where the
/// perturbed state leaves `piece` (the piece of y), the difference is taken on the other
/// side. Columns the system's [`Partition`](super::Partition) knows (a linear trailing
/// state) are set without evaluating. False if f is undefined at a perturbed state.
/// [`Rhs::jacobian`]'s default.
pub fn fd_jacobian<S: Rhs<N> + ?Sized, const N: usize>(
    sys: &mut S,
    at: &StepPoint<N>,
    piece: Piece,
    jac: &mut SMatrix<f64, N, N>,
    stats: &mut Stats,
) -> bool {
    let (t, y, f) = (at.t, &at.y, &at.f);
    let sq = f64::EPSILON.sqrt();
    let part = sys.newton_partition();
    let mut yp = *y;
    for j in 0..N {
        if let Some(d) = part.as_ref().and_then(|p| p.known_column(j)) {
            jac.set_column(j, &SVector::<f64, N>::zeros());
            jac[(j, j)] = d;
            continue;
        }
        let mut dy = sq * y[j].abs().max(1e-3);
        yp[j] = y[j] + dy;
        stats.rhs += 1;
        let Some((mut fp, p)) = sys.eval_piece(t, &yp) else { return false };
        if p != piece {
            // one-sided difference on the other side, inside the piece of y
            dy = -dy;
            yp[j] = y[j] + dy;
            stats.rhs += 1;
            let Some((fm, _)) = sys.eval_piece(t, &yp) else { return false };
            fp = fm;
        }
        jac.set_column(j, &((fp - f) / dy));
        yp[j] = y[j];
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::integrate::Partition;

    /// An oscillator with a low-pass filter of its position: y2' = (y0 − y2)/T.
    struct Filtered(f64);
    impl Rhs<3> for Filtered {
        fn eval(&mut self, _t: f64, y: &SVector<f64, 3>) -> Option<SVector<f64, 3>> {
            Some(SVector::<f64, 3>::new(y[1], -y[0], (y[0] - y[2]) / self.0))
        }
        fn newton_partition(&self) -> Option<Partition<3>> {
            Partition::new(&[&[0]])?.with_trailing_linear(&[(2, -1.0 / self.0)])
        }
    }

    /// The known column of a linear trailing state is set without an evaluation; the others
    /// are the forward differences.
    #[test]
    fn known_columns_need_no_evaluation() {
        let mut sys = Filtered(0.25);
        let y = SVector::<f64, 3>::new(0.3, -0.7, 0.1);
        let at = StepPoint::at(&mut sys, 0.0, y).unwrap();
        let mut jac = SMatrix::<f64, 3, 3>::zeros();
        let mut stats = Stats::default();
        assert!(fd_jacobian(&mut sys, &at, Piece::SMOOTH, &mut jac, &mut stats));
        assert_eq!(stats.rhs, 2);
        assert_eq!(jac.column(2), SVector::<f64, 3>::new(0.0, 0.0, -4.0));
        let exact = SMatrix::<f64, 3, 3>::new(0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 4.0, 0.0, -4.0);
        assert!((jac - exact).amax() < 1e-7, "{jac}");
    }
}
