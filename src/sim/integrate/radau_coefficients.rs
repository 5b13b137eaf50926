//! The coefficients of the S-stage Radau IIA method (order 2S − 1, S odd) computed at run
//! time, for [`super::RadauIIA`]: the nodes (roots of P_S(2x − 1) − P_{S−1}(2x − 1), the last
//! one 1), the collocation matrix A, the real transformation A⁻¹ = T Λ T⁻¹ with Λ =
//! diag(γ, [[α_k, −β_k], [β_k, α_k]]) (one real eigenvalue, (S − 1)/2 complex pairs), and the
//! error estimate of Hairer & Wanner (IV.8): ŷ − y = γ0 h f(y0) + Σ e_i Z_i with γ0 = 1/γ and
//! the embedded weights of order S, filtered by (γ/h − J)⁻¹, i.e. DD = γ e. For S = 3 they
//! are RADAU5's (tested).

use nalgebra::{Complex, DMatrix, DVector};

/// The coefficients of an S-stage Radau IIA method.
#[derive(Debug, Clone)]
pub struct RadauCoefficients<const S: usize> {
    /// Nodes c (the last is 1).
    pub c: [f64; S],
    /// A (row-major).
    pub a: [[f64; S]; S],
    /// T with A⁻¹ = T Λ T⁻¹.
    pub t: [[f64; S]; S],
    /// T⁻¹.
    pub ti: [[f64; S]; S],
    /// The real eigenvalue γ of A⁻¹.
    pub gamma: f64,
    /// The complex pairs (α_k, β_k), β_k > 0, in the order of T's columns (1, 2), (3, 4), ….
    pub pairs: Vec<(f64, f64)>,
    /// The error estimate's weights: err = (γ/h − J)⁻¹ (f0 + Σ dd_i Z_i / h).
    pub dd: [f64; S],
}

/// P_S(x) − P_{S−1}(x) of the Legendre polynomials, at x.
fn radau_poly(s: usize, x: f64) -> f64 {
    let (mut p0, mut p1) = (1.0, x);
    for n in 1..s {
        let p2 = ((2 * n + 1) as f64 * x * p1 - n as f64 * p0) / (n + 1) as f64;
        p0 = p1;
        p1 = p2;
    }
    p1 - p0
}

/// The S nodes on (0, 1]: sign changes of the Radau polynomial on a fine grid, bisected.
fn nodes<const S: usize>() -> [f64; S] {
    let mut c = [1.0; S];
    let f = |u: f64| radau_poly(S, 2.0 * u - 1.0);
    let n = 20_000;
    let mut k = 0;
    for i in 0..n - 1 {
        let (mut a, mut b) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
        if f(a) * f(b) < 0.0 && k < S - 1 {
            for _ in 0..200 {
                let m = 0.5 * (a + b);
                if f(a) * f(m) <= 0.0 {
                    b = m;
                } else {
                    a = m;
                }
            }
            c[k] = 0.5 * (a + b);
            k += 1;
        }
    }
    assert_eq!(k, S - 1, "Radau IIA nodes");
    c
}

/// The null vector of the complex matrix m (S×S, rank S − 1) by inverse iteration.
fn null_vector(m: &DMatrix<Complex<f64>>) -> DVector<Complex<f64>> {
    let s = m.nrows();
    let shift = Complex::new(1e-13 * m.norm(), 0.0);
    let lu = (m + DMatrix::<Complex<f64>>::identity(s, s) * shift).lu();
    let mut x = DVector::<Complex<f64>>::from_fn(s, |i, _| Complex::new(1.0 + 0.1 * i as f64, 0.3));
    for _ in 0..4 {
        x = lu.solve(&x).expect("shifted matrix regular");
        let n = x.norm();
        x /= Complex::new(n, 0.0);
    }
    x
}

impl<const S: usize> RadauCoefficients<S> {
    /// The coefficients of the S-stage method (S odd, 3 ≤ S ≤ 7).
    pub fn new() -> Self {
        assert!(S % 2 == 1 && (3..=7).contains(&S), "Radau IIA with an odd number of stages");
        let c = nodes::<S>();
        // A: Σ_j a_ij c_j^(k−1) = c_i^k / k, k = 1..S
        let v = DMatrix::<f64>::from_fn(S, S, |k, j| c[j].powi(k as i32));
        let vlu = v.clone().lu();
        let mut a = [[0.0; S]; S];
        for i in 0..S {
            let r = DVector::<f64>::from_fn(S, |k, _| c[i].powi(k as i32 + 1) / (k + 1) as f64);
            let row = vlu.solve(&r).expect("Vandermonde regular");
            for j in 0..S {
                a[i][j] = row[j];
            }
        }
        let am = DMatrix::<f64>::from_fn(S, S, |i, j| a[i][j]);
        let ainv = am.clone().try_inverse().expect("A regular");
        // eigen-decomposition of A⁻¹: one real eigenvalue, (S − 1)/2 pairs (β > 0)
        let eig = ainv.clone().complex_eigenvalues();
        let mut real: Vec<f64> = eig.iter().filter(|z| z.im.abs() < 1e-9 * z.norm()).map(|z| z.re).collect();
        let mut pairs: Vec<(f64, f64)> = eig.iter().filter(|z| z.im > 1e-9 * z.norm()).map(|z| (z.re, z.im)).collect();
        assert!(real.len() == 1 && pairs.len() == (S - 1) / 2, "eigenvalues of A⁻¹: {eig}");
        pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
        let gamma = real.pop().expect("one real eigenvalue");
        let ac = ainv.map(|x| Complex::new(x, 0.0));
        let mut tm = DMatrix::<f64>::zeros(S, S);
        {
            let mut m = ac.clone();
            for i in 0..S {
                m[(i, i)] -= Complex::new(gamma, 0.0);
            }
            let x = null_vector(&m);
            // a real eigenvector up to a phase
            let k = (0..S).max_by(|&i, &j| x[i].norm().total_cmp(&x[j].norm())).expect("S > 0");
            let phase = x[k].conj() / x[k].norm();
            for i in 0..S {
                tm[(i, 0)] = (x[i] * phase).re;
            }
        }
        for (p, &(al, be)) in pairs.iter().enumerate() {
            let mut m = ac.clone();
            for i in 0..S {
                m[(i, i)] -= Complex::new(al, be);
            }
            // A⁻¹(u + iv) = (α + iβ)(u + iv): columns u and −v give the block [[α, −β], [β, α]]
            let x = null_vector(&m);
            for i in 0..S {
                tm[(i, 1 + 2 * p)] = x[i].re;
                tm[(i, 2 + 2 * p)] = -x[i].im;
            }
        }
        let tim = tm.clone().try_inverse().expect("T regular");
        // the embedded weights: Σ_j b̂_j c_j^(k−1) = 1/k − γ0 [k = 1], γ0 = 1/γ
        let g0 = 1.0 / gamma;
        let r = DVector::<f64>::from_fn(S, |k, _| 1.0 / (k + 1) as f64 - if k == 0 { g0 } else { 0.0 });
        let bhat = vlu.solve(&r).expect("Vandermonde regular");
        let bdiff = DVector::<f64>::from_fn(S, |j, _| bhat[j] - a[S - 1][j]);
        let e = ainv.transpose() * bdiff;
        let mut out = RadauCoefficients { c, a, t: [[0.0; S]; S], ti: [[0.0; S]; S], gamma, pairs, dd: [0.0; S] };
        for i in 0..S {
            out.dd[i] = gamma * e[i];
            for j in 0..S {
                out.t[i][j] = tm[(i, j)];
                out.ti[i][j] = tim[(i, j)];
            }
        }
        out
    }
}

impl<const S: usize> Default for RadauCoefficients<S> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// S = 3 gives RADAU5's nodes, eigenvalues and error weights; for S = 3 and 5, A is the
    /// collocation matrix (row sums c, last row the weights of order 2S − 1) and T Λ T⁻¹ = A⁻¹.
    #[test]
    fn coefficients_of_radau5_and_radau9() {
        let c3 = RadauCoefficients::<3>::new();
        let sq6 = 6f64.sqrt();
        let c = [(4.0 - sq6) / 10.0, (4.0 + sq6) / 10.0, 1.0];
        let dd = [-(13.0 + 7.0 * sq6) / 3.0, (-13.0 + 7.0 * sq6) / 3.0, -1.0 / 3.0];
        for i in 0..3 {
            assert!((c3.c[i] - c[i]).abs() < 1e-14, "{:?}", c3.c);
            assert!((c3.dd[i] - dd[i]).abs() < 1e-11 * dd[i].abs(), "{:?} vs {dd:?}", c3.dd);
        }
        let c9 = 9f64.cbrt();
        assert!((c3.gamma - 30.0 / (6.0 + c9 * c9 - c9)).abs() < 1e-12);
        check_structure(&c3);
        let c5 = RadauCoefficients::<5>::new();
        check_structure(&c5);
        assert!((c5.c[0] - 0.057_104_196_114_517_68).abs() < 1e-14, "{:?}", c5.c);
    }

    fn check_structure<const S: usize>(k: &RadauCoefficients<S>) {
        let a = DMatrix::<f64>::from_fn(S, S, |i, j| k.a[i][j]);
        for i in 0..S {
            assert!((a.row(i).sum() - k.c[i]).abs() < 1e-13);
        }
        // the last row integrates polynomials of degree 2S − 2 exactly on [0, 1]
        for d in 0..2 * S - 1 {
            let q: f64 = (0..S).map(|j| k.a[S - 1][j] * k.c[j].powi(d as i32)).sum();
            assert!((q - 1.0 / (d + 1) as f64).abs() < 1e-12, "degree {d}: {q}");
        }
        let mut lam = DMatrix::<f64>::zeros(S, S);
        lam[(0, 0)] = k.gamma;
        for (p, &(al, be)) in k.pairs.iter().enumerate() {
            let (i, j) = (1 + 2 * p, 2 + 2 * p);
            lam[(i, i)] = al;
            lam[(j, j)] = al;
            lam[(i, j)] = -be;
            lam[(j, i)] = be;
        }
        let t = DMatrix::<f64>::from_fn(S, S, |i, j| k.t[i][j]);
        let ti = DMatrix::<f64>::from_fn(S, S, |i, j| k.ti[i][j]);
        let ainv = a.try_inverse().unwrap();
        assert!((&t * &ti - DMatrix::<f64>::identity(S, S)).amax() < 1e-12);
        assert!((t * lam * ti - &ainv).amax() < 1e-10 * ainv.amax());
    }
}
