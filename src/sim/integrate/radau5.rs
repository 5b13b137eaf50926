//! Radau IIA of order 5 (3 stages) after Hairer & Wanner's RADAU5: its fixed coefficients,
//! Newton factorisations and collocation polynomial ([`Radau5Scheme`]) for the shared step
//! loop ([`RadauStepper`]).

use super::lu::Lu;
use super::radau_stepper::{RadauScheme, RadauStepper, Stages};
use super::reduced::{Partition, ReducedLu};
use super::{Stats, Tol};
use nalgebra::{Complex, SMatrix, SVector};

/// Radau IIA of order 5 after Hairer & Wanner's RADAU5: stiffly accurate, L-stable. The
/// simplified Newton iteration uses their transformation A⁻¹ = T Λ T⁻¹, so each Jacobian
/// costs one real N×N LU of γ/h − J and one complex N×N LU of (α + iβ)/h − J instead of a
/// 3N×3N one (or, for a system with a [`Partition`] that J fits, LUs of its kept states'
/// Schur complements only). Newton's contraction is carried across steps and a predicted
/// non-convergence shrinks h early; the step size follows Gustafsson's predictive
/// controller; the error estimate is RADAU5's, filtered by (γ/h − J)⁻¹ (see
/// [`RadauStepper`]).
pub type Radau5<const N: usize> = RadauStepper<N, 3, Radau5Scheme<N>>;

/// RADAU5's coefficients (the constants of Hairer & Wanner's code) and the storage of its
/// Newton factorisations.
#[derive(Debug, Clone)]
pub struct Radau5Scheme<const N: usize> {
    /// γ/h − J.
    lu_r: Option<Lu<f64, N>>,
    /// (α + iβ)/h − J.
    lu_c: Option<Lu<Complex<f64>, N>>,
    /// The system's partition for the Newton solves, with the storage of both reduced
    /// factorisations.
    part: Option<ReducedLu<N>>,
    /// The Jacobian (its version) the reduced parts were prepared from, and whether it
    /// fitted the partition.
    prepared: Option<(u64, bool)>,
    /// The reduced factorisations are the current ones (else `lu_r`, `lu_c`).
    reduced: bool,
    lu_h: f64,
    eig: RadauEig,
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
    let mut out = [SVector::<f64, N>::zeros(); 3];
    for j in 0..N {
        let (a, b, c) = (v[0][j], v[1][j], v[2][j]);
        for (i, o) in out.iter_mut().enumerate() {
            o[j] = a * m[i][0] + b * m[i][1] + c * m[i][2];
        }
    }
    out
}

/// 1/Π_{m≠k} (n_k − n_m) for the nodes (0, c1, c2, 1) and k = 1, 2, 3.
const LAGRANGE_DEN: [f64; 3] = [
    1.0 / (RC[0] * (RC[0] - RC[1]) * (RC[0] - RC[2])),
    1.0 / (RC[1] * (RC[1] - RC[0]) * (RC[1] - RC[2])),
    1.0 / (RC[2] * (RC[2] - RC[0]) * (RC[2] - RC[1])),
];

impl<const N: usize> Radau5<N> {
    /// New stepper.
    pub fn new(tol: Tol<N>, h0: f64) -> Self {
        let scheme = Radau5Scheme {
            lu_r: None,
            lu_c: None,
            part: None,
            prepared: None,
            reduced: false,
            lu_h: 0.0,
            eig: RadauEig::new(),
        };
        RadauStepper::with_scheme(scheme, tol, h0)
    }
}

impl<const N: usize> RadauScheme<N, 3> for Radau5Scheme<N> {
    fn nodes(&self) -> &[f64; 3] {
        &RC
    }

    fn set_partition(&mut self, part: Option<Partition<N>>) {
        self.part = part.map(ReducedLu::new);
    }

    fn factor(&mut self, j: &SMatrix<f64, N, N>, version: u64, h: f64, stats: &mut Stats) -> bool {
        if (self.reduced || self.lu_r.is_some()) && self.lu_h == h {
            return true;
        }
        self.reduced = false;
        if let Some(red) = self.part.as_mut() {
            let fits = match self.prepared {
                Some((v, fits)) if v == version => fits,
                _ => {
                    let fits = red.prepare(j);
                    self.prepared = Some((version, fits));
                    fits
                }
            };
            if fits {
                stats.lu += 1;
                let ac = Complex::new(self.eig.alpha / h, self.eig.beta / h);
                if red.factor(self.eig.gamma / h, ac) {
                    self.reduced = true;
                    self.lu_h = h;
                    return true;
                }
                self.lu_r = None;
                self.lu_c = None;
                return false;
            }
        }
        let e = SMatrix::<f64, N, N>::from_diagonal_element(self.eig.gamma / h) - j;
        let ac = Complex::new(self.eig.alpha / h, self.eig.beta / h);
        let ec = SMatrix::<Complex<f64>, N, N>::from_fn(|r, c| {
            let d = if r == c { ac } else { Complex::new(0.0, 0.0) };
            d - Complex::new(j[(r, c)], 0.0)
        });
        stats.lu += 1;
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

    fn drop_factor(&mut self) {
        self.lu_r = None;
        self.reduced = false;
    }

    fn to_transformed(&self, z: &Stages<N, 3>) -> Stages<N, 3> {
        mix3(&RTI, z)
    }

    fn to_stages(&self, w: &Stages<N, 3>) -> Stages<N, 3> {
        mix3(&RT, w)
    }

    fn newton_increments(&self, r: &Stages<N, 3>, w: &Stages<N, 3>, h: f64) -> Stages<N, 3> {
        let (gh, ah, bh) = (self.eig.gamma / h, self.eig.alpha / h, self.eig.beta / h);
        let r1 = r[0] - w[0] * gh;
        let r2 = r[1] - (w[1] * ah - w[2] * bh);
        let r3 = r[2] - (w[1] * bh + w[2] * ah);
        let d1 = self.solve_real(&r1);
        let (d2, d3) = self.solve_c(&r2, &r3);
        [d1, d2, d3]
    }

    /// Solve (γ/h − J) x = b with the current factorisation.
    #[inline]
    fn solve_real(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        match (&self.part, self.reduced) {
            (Some(red), true) => red.solve_real(b),
            _ => self.lu_r.as_ref().expect("factored").solve(b),
        }
    }

    fn error_stages(&self, z: &Stages<N, 3>, h: f64) -> SVector<f64, N> {
        (z[0] * DD[0] + z[1] * DD[1] + z[2] * DD[2]) / h
    }

    fn root(&self, err: f64) -> f64 {
        err.sqrt().sqrt()
    }

    fn extrapolate(&self, hp: f64, zp: &Stages<N, 3>, h: f64) -> Stages<N, 3> {
        // The polynomial through (0, 0), (c_i, zp_i) in s = (t − t_{n−1}) / hp; the new
        // stages sit at s = 1 + c_i h / hp, and the origin moves to y_n = y_{n−1} + zp_3.
        // Its Lagrange weights at s, L_k(s) = Π_{m≠k} (s − n_m)/(n_k − n_m) over the nodes
        // (0, c1, c2, 1), minus 1 for the third (the origin's move).
        let mut z = [SVector::<f64, N>::zeros(); 3];
        let nodes = [0.0, RC[0], RC[1], RC[2]];
        for (i, zi) in z.iter_mut().enumerate() {
            let sv = 1.0 + RC[i] * h / hp;
            let d = [sv - nodes[0], sv - nodes[1], sv - nodes[2], sv - nodes[3]];
            let l1 = d[0] * d[2] * d[3] * LAGRANGE_DEN[0];
            let l2 = d[0] * d[1] * d[3] * LAGRANGE_DEN[1];
            let l3 = d[0] * d[1] * d[2] * LAGRANGE_DEN[2] - 1.0;
            for j in 0..N {
                zi[j] = zp[0][j] * l1 + zp[1][j] * l2 + zp[2][j] * l3;
            }
        }
        z
    }

    fn dense_weights(&self, th: f64) -> [f64; 3] {
        // the collocation polynomial through (0, 0), (c_k, Z_k)
        let d = [th - RC[0], th - RC[1], th - RC[2]];
        [th * d[1] * d[2] * LAGRANGE_DEN[0], th * d[0] * d[2] * LAGRANGE_DEN[1], th * d[0] * d[1] * LAGRANGE_DEN[2]]
    }
}

impl<const N: usize> Radau5Scheme<N> {
    /// Solve ((α + iβ)/h − J) x = re + i·im with the current factorisation: (Re x, Im x).
    #[inline]
    fn solve_c(&self, re: &SVector<f64, N>, im: &SVector<f64, N>) -> (SVector<f64, N>, SVector<f64, N>) {
        match (&self.part, self.reduced) {
            (Some(red), true) => red.solve_complex(re, im),
            _ => {
                let b = SVector::<Complex<f64>, N>::from_fn(|k, _| Complex::new(re[k], im[k]));
                let x = self.lu_c.as_ref().expect("factored").solve(&b);
                (x.map(|c| c.re), x.map(|c| c.im))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::integrate::testsys::Osc;
    use crate::sim::integrate::{Rhs, StepPoint, Stepper};
    use nalgebra::Vector2;

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

    #[test]
    fn radau5_accuracy_and_order() {
        let mut errs = vec![];
        for rtol in [1e-6, 1e-9] {
            let mut st: Radau5<2> = Radau5::new(Tol { rtol, atol: Vector2::new(rtol, rtol) }, 1e-3);
            let mut sys = Osc(1.0);
            let mut p = StepPoint::at(&mut sys, 0.0, Vector2::new(1.0, 0.0)).unwrap();
            while p.t < 3.0 {
                p = st.advance(&mut sys, &p, 3.0 - p.t).unwrap();
            }
            errs.push(((p.y[0] - 3f64.cos()).abs(), st.stats().steps));
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
        let mut p = StepPoint::at(&mut sys, 0.0, Vector2::new(0.0, 1.0)).unwrap();
        while p.t < 2.0 {
            p = st.advance(&mut sys, &p, 2.0 - p.t).unwrap();
        }
        assert!((p.y[0] - 2f64.sin()).abs() < 1e-8);
        assert!((p.y[1] - (-2f64).exp()).abs() < 1e-8);
        assert!(st.stats().steps < 500, "{:?}", st.stats());
    }
}
