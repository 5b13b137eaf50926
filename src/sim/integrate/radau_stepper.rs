//! The step loop shared by the Radau IIA methods ([`Radau5`](super::Radau5),
//! [`RadauIIA`](super::RadauIIA)) after Hairer & Wanner's RADAU5: the simplified Newton
//! iteration on the stages transformed with A⁻¹ = T Λ T⁻¹, its contraction control (carried
//! across steps; a predicted non-convergence shrinks h early), the error estimate filtered
//! by (γ/h − J)⁻¹, Gustafsson's predictive step-size controller and the Jacobian's refresh
//! policy. What differs between the methods (coefficients, the factorisations of the
//! transformed Newton systems, extrapolation to the next step's stages, dense output) is a
//! [`RadauScheme`].

use super::jacobian::JacobianCache;
use super::jacobian::{prepare_attempt, NewtonMatrix};
use super::reduced::Partition;
use super::{Rhs, Stats, StepError, StepPoint, Stepper, Tol};
use nalgebra::{SMatrix, SVector};

/// The stage values Z_1..Z_S (or their transforms) of an S-stage method.
pub type Stages<const N: usize, const S: usize> = [SVector<f64, N>; S];

/// The parts of an S-stage Radau IIA method that [`RadauStepper`] leaves to it.
pub trait RadauScheme<const N: usize, const S: usize> {
    /// The nodes c_1..c_S.
    fn nodes(&self) -> &[f64; S];
    /// Take the system's partition for the Newton solves (asked at the first step).
    fn set_partition(&mut self, part: Option<Partition<N>>);
    /// Factor the transformed Newton matrices (γ/h − J and the (α + iβ)/h − J) for step `h`
    /// from the Jacobian `jac` (`version`: its `JacobianCache` count), counting in
    /// `stats.lu`; true at once if already factored for `h`, false if singular.
    fn factor(&mut self, jac: &SMatrix<f64, N, N>, version: u64, h: f64, stats: &mut Stats) -> bool;
    /// Forget the factorisations (the Jacobian changed).
    fn drop_factor(&mut self);
    /// T⁻¹ applied to stage values: the transformed stages.
    fn to_transformed(&self, z: &Stages<N, S>) -> Stages<N, S>;
    /// T applied to transformed stages: the stage values.
    fn to_stages(&self, w: &Stages<N, S>) -> Stages<N, S>;
    /// One Newton increment of the transformed stages `w`, from the transformed values `r`
    /// of f at the stages: the solves of (Λ/h − J) d = r − (Λ/h) w, one real and one complex
    /// system per pair.
    fn newton_increments(&self, r: &Stages<N, S>, w: &Stages<N, S>, h: f64) -> Stages<N, S>;
    /// Solve (γ/h − J) x = b with the current factorisation.
    fn solve_real(&self, b: &SVector<f64, N>) -> SVector<f64, N>;
    /// Σ dd_i Z_i / h, the stages' part of the error estimate.
    fn error_stages(&self, z: &Stages<N, S>, h: f64) -> SVector<f64, N>;
    /// err^(1/(S + 1)), the step-size controller's root.
    fn root(&self, err: f64) -> f64;
    /// The last accepted step's collocation polynomial (step `hp`, stages `zp`) extrapolated
    /// to the stages of the next step `h`, relative to its start.
    fn extrapolate(&self, hp: f64, zp: &Stages<N, S>, h: f64) -> Stages<N, S>;
    /// The weights of Z_1..Z_S in the collocation polynomial at θ = (t − t0)/h.
    fn dense_weights(&self, th: f64) -> [f64; S];
}

/// An S-stage Radau IIA stepper with the scheme `M`: see the module documentation.
#[derive(Debug, Clone)]
pub struct RadauStepper<const N: usize, const S: usize, M> {
    scheme: M,
    tol: Tol<N>,
    /// The step-size proposal.
    pub(super) h: f64,
    pub(super) jc: JacobianCache<N>,
    /// The system's partition was asked for (at the first step).
    partitioned: bool,
    stats: Stats,
    first: bool,
    last_rejected: bool,
    /// (h, Z) of the last accepted step.
    prev_z: Option<(f64, Stages<N, S>)>,
    /// (t, y) at the start of the last accepted step (for [`Stepper::dense`]).
    prev_start: Option<(f64, SVector<f64, N>)>,
    /// Newton's η = θ/(1 − θ) of the last step (the first iteration's estimate).
    eta: f64,
    /// (h, err) of the last accepted step, for the predictive controller.
    acc: Option<(f64, f64)>,
    /// Newton convergence threshold in tolerance units.
    pub kappa: f64,
    /// Maximum Newton iterations.
    pub max_newton: usize,
    /// Recompute the Jacobian after an accepted step whose Newton contraction θ exceeded
    /// this (RADAU5's `THET`).
    pub theta_jac: f64,
}

/// Why a Newton iteration stopped without converging.
enum NewtonFail {
    /// f undefined, divergence or too many iterations: halve h (or refresh J).
    Diverged,
    /// Predicted not to converge in time: retry with h scaled by this factor.
    Slow(f64),
}

impl<const N: usize, const S: usize, M: RadauScheme<N, S>> RadauStepper<N, S, M> {
    /// New stepper with the scheme's coefficients and storage.
    pub fn with_scheme(scheme: M, tol: Tol<N>, h0: f64) -> Self {
        RadauStepper {
            scheme,
            tol,
            h: h0,
            jc: JacobianCache::new(),
            partitioned: false,
            stats: Stats::default(),
            first: true,
            last_rejected: false,
            prev_z: None,
            prev_start: None,
            eta: 1.0,
            acc: None,
            kappa: 0.1,
            max_newton: 7 + 2 * (S - 3),
            theta_jac: 0.01,
        }
    }

    /// Start of Newton: the previous step's collocation polynomial extrapolated to the new
    /// stages (zero after a restart or a rejection).
    fn predict(&self, h: f64) -> Stages<N, S> {
        match self.prev_z.as_ref().filter(|_| !self.first && !self.last_rejected) {
            Some((hp, zp)) => self.scheme.extrapolate(*hp, zp, h),
            None => [SVector::zeros(); S],
        }
    }

    /// Simplified Newton on the transformed stages; returns Z, the last contraction θ and
    /// the iterations.
    fn newton<Sy: Rhs<N>>(
        &mut self,
        sys: &mut Sy,
        t: f64,
        y: &SVector<f64, N>,
        h: f64,
    ) -> Result<(Stages<N, S>, f64, usize), NewtonFail> {
        let wts = self.tol.weights(y, y);
        let mut z = self.predict(h);
        let mut w = self.scheme.to_transformed(&z);
        let mut eta = self.eta.max(f64::EPSILON).powf(0.8);
        let mut theta = self.theta_jac;
        let (mut prev, mut thq_old) = (0.0, 0.0);
        for it in 0..self.max_newton {
            self.stats.newton += 1;
            let mut fz = [SVector::<f64, N>::zeros(); S];
            for (i, fzi) in fz.iter_mut().enumerate() {
                self.stats.rhs += 1;
                *fzi = sys.eval(t + self.scheme.nodes()[i] * h, &(y + z[i])).ok_or(NewtonFail::Diverged)?;
            }
            let r = self.scheme.to_transformed(&fz);
            let d = self.scheme.newton_increments(&r, &w, h);
            let n = (d.iter().map(|di| Tol::sum_sq(di, &wts)).sum::<f64>() / (S * N) as f64).sqrt();
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
            for (wi, di) in w.iter_mut().zip(&d) {
                *wi += di;
            }
            z = self.scheme.to_stages(&w);
            if eta * n <= self.kappa || n <= 1e-12 {
                self.eta = eta;
                return Ok((z, theta, it + 1));
            }
        }
        Err(NewtonFail::Diverged)
    }

    /// A step attempt rejected because Newton failed.
    fn reject_newton(&mut self, h: f64) {
        self.stats.rejected += 1;
        self.stats.newton_fail += 1;
        self.last_rejected = true;
        if let Some(h) = self.jc.newton_failed(h, 0.5) {
            self.h = h;
        }
    }
}

impl<const N: usize, const S: usize, M: RadauScheme<N, S>> NewtonMatrix<N> for RadauStepper<N, S, M> {
    fn parts(&mut self) -> (&mut JacobianCache<N>, &mut Stats, &mut f64) {
        (&mut self.jc, &mut self.stats, &mut self.h)
    }
    fn drop_factor(&mut self) {
        self.scheme.drop_factor();
    }
    fn factor(&mut self, h: f64) -> bool {
        self.scheme.factor(&self.jc.jac, self.jc.version, h, &mut self.stats)
    }
}

impl<const N: usize, const S: usize, M: RadauScheme<N, S>> Stepper<N> for RadauStepper<N, S, M> {
    fn advance<Sy: Rhs<N>>(
        &mut self,
        sys: &mut Sy,
        from: &StepPoint<N>,
        h_max: f64,
    ) -> Result<StepPoint<N>, StepError> {
        let (t, y, f) = (from.t, &from.y, &from.f);
        if !self.partitioned {
            self.scheme.set_partition(sys.newton_partition());
            self.partitioned = true;
        }
        self.jc.start_step(sys, y);
        loop {
            let Some(h) = prepare_attempt(self, sys, from, h_max)? else { continue };
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
            let y1 = y + z[S - 1];
            // error estimate (RADAU5): (γ/h − J)⁻¹ (f0 + Σ dd_i Z_i / h)
            let f2 = self.scheme.error_stages(&z, h);
            let mut err_v = self.scheme.solve_real(&(f + f2));
            let mut err = self.tol.norm(&err_v, y, &y1);
            if err >= 1.0 && (self.first || self.last_rejected) {
                self.stats.rhs += 1;
                if let Some(f1) = sys.eval(t, &(y + err_v)) {
                    err_v = self.scheme.solve_real(&(f1 + f2));
                    err = self.tol.norm(&err_v, y, &y1);
                }
            }
            // RADAU5's step-size rule: safety factor lowered by Newton iterations.
            let safe = (0.9 * (1 + 2 * self.max_newton) as f64 / (iters + 2 * self.max_newton) as f64).min(0.9);
            let err_q = if err.is_finite() { err.max(1e-10) } else { 1e10 };
            let mut quot = (self.scheme.root(err_q) / safe).clamp(1.0 / 8.0, 5.0);
            if err.is_finite() && err <= 1.0 {
                self.stats.rhs += 1;
                let Some((fy1, piece)) = sys.eval_accepted(t + h, &y1) else {
                    self.reject_newton(h);
                    continue;
                };
                self.stats.steps += 1;
                // Gustafsson's predictive controller.
                if let Some((h_acc, err_acc)) = self.acc {
                    let fg = ((h_acc / h) * self.scheme.root(err_q * err_q / err_acc) / 0.9).clamp(1.0 / 8.0, 5.0);
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
                self.prev_start = Some((t, *y));
                self.jc.fresh = false;
                self.jc.known = Some((y1, piece));
                if theta > self.theta_jac {
                    self.jc.slow = true;
                }
                let q = h_new / h;
                self.h = if !self.jc.slow && (1.0..=1.2).contains(&q) { h } else { h_new };
                return Ok(StepPoint { t: t + h, y: y1, f: fy1 });
            }
            self.stats.rejected += 1;
            self.h = if self.stats.steps == 0 { h * 0.1 } else { h / quot };
            self.last_rejected = true;
            if !self.jc.fresh {
                self.jc.valid = false;
            }
        }
    }

    fn dense(&self, tt: f64) -> Option<SVector<f64, N>> {
        let ((h, z), (t0, y0)) = (self.prev_z.as_ref()?, self.prev_start.as_ref()?);
        let l = self.scheme.dense_weights((tt - t0) / h);
        let mut y = *y0;
        for (zk, lk) in z.iter().zip(l) {
            y += zk * lk;
        }
        Some(y)
    }

    fn restart(&mut self) {
        self.jc.valid = false;
        self.scheme.drop_factor();
        self.first = true;
        self.prev_z = None;
        self.acc = None;
        self.eta = 1.0;
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}
