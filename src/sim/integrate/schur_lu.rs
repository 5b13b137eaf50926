//! The dense LU of the Schur complement of [`super::reduced`]: an m×m LU with partial
//! pivoting in N×N storage, real ([`RealLu`]) or complex with its real and imaginary parts
//! stored apart ([`ComplexLu`], so that the inner loops are plain real arithmetic).

use super::lu::{pivot_row, Scalar};
use nalgebra::Complex;

/// A scalar of the reduced factorisations (`f64` or `Complex<f64>`) with its dense
/// storage for the Schur complement's LU.
pub trait ReducedScalar: Scalar {
    /// Dense storage of an m×m LU (m ≤ N).
    type Mat<const N: usize>: SchurLu<Self, N>;
}

impl ReducedScalar for f64 {
    type Mat<const N: usize> = RealLu<N>;
}

impl ReducedScalar for Complex<f64> {
    type Mat<const N: usize> = ComplexLu<N>;
}

/// An m×m LU with partial pivoting in N×N storage (the Schur complement S).
pub trait SchurLu<T, const N: usize>: Clone + std::fmt::Debug {
    /// Zeroed storage.
    fn zeros() -> Self;
    /// S = c·I − A − B/c on the leading m×m block (A, B real; `inv_c` = 1/c).
    fn build(&mut self, c: T, inv_c: T, a: &[[f64; N]; N], b: &[[f64; N]; N], m: usize);
    /// S_rk = v (tests).
    #[cfg(test)]
    fn set(&mut self, r: usize, k: usize, v: T);
    /// S_rk −= x·a for a real a.
    fn sub_scaled(&mut self, r: usize, k: usize, x: T, a: f64);
    /// Factor the leading m×m block in place; false if singular.
    fn factor(&mut self, m: usize) -> bool;
    /// Solve S x = b in place (b in `x`).
    fn solve(&self, x: &mut [T; N], m: usize);
}

/// A real [`SchurLu`].
#[derive(Debug, Clone)]
pub struct RealLu<const N: usize> {
    a: [[f64; N]; N],
    inv_diag: [f64; N],
    piv: [usize; N],
}

impl<const N: usize> SchurLu<f64, N> for RealLu<N> {
    fn zeros() -> Self {
        RealLu { a: [[0.0; N]; N], inv_diag: [0.0; N], piv: [0; N] }
    }
    fn build(&mut self, c: f64, inv_c: f64, a: &[[f64; N]; N], b: &[[f64; N]; N], m: usize) {
        for r in 0..m {
            let (row, ar, br) = (&mut self.a[r][..m], &a[r][..m], &b[r][..m]);
            for k in 0..m {
                row[k] = -ar[k] - inv_c * br[k];
            }
            row[r] += c;
        }
    }
    #[cfg(test)]
    fn set(&mut self, r: usize, k: usize, v: f64) {
        self.a[r][k] = v;
    }
    #[inline(always)]
    fn sub_scaled(&mut self, r: usize, k: usize, x: f64, a: f64) {
        self.a[r][k] -= x * a;
    }
    #[inline(never)]
    fn factor(&mut self, m: usize) -> bool {
        let a = &mut self.a;
        for k in 0..m {
            let Some(p) = pivot_row(k, m, |i| a[i][k].abs()) else { return false };
            self.piv[k] = p;
            if p != k {
                a.swap(p, k);
            }
            let d = 1.0 / a[k][k];
            self.inv_diag[k] = d;
            let n = m - k - 1;
            let (top, rest) = a.split_at_mut(k + 1);
            let pivot = &top[k][k + 1..m];
            for row in rest[..n].iter_mut() {
                let l = row[k] * d;
                row[k] = l;
                if l != 0.0 {
                    let x = &mut row[k + 1..m];
                    for j in 0..n {
                        x[j] -= l * pivot[j];
                    }
                }
            }
        }
        true
    }
    fn solve(&self, x: &mut [f64; N], m: usize) {
        for k in 0..m {
            x.swap(k, self.piv[k]);
        }
        for i in 1..m {
            x[i] -= dot(&self.a[i][..i], &x[..i]);
        }
        for i in (0..m).rev() {
            x[i] = (x[i] - dot(&self.a[i][i + 1..m], &x[i + 1..m])) * self.inv_diag[i];
        }
    }
}

/// Σ a_i b_i over two slices of one length.
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len();
    let b = &b[..n];
    let mut s = 0.0;
    for i in 0..n {
        s += a[i] * b[i];
    }
    s
}

/// Σ a_i b_i over complex slices given by their parts (ar + i·ai, br + i·bi): (Re, Im).
#[inline(always)]
fn cdot(ar: &[f64], ai: &[f64], br: &[f64], bi: &[f64]) -> (f64, f64) {
    let n = ar.len();
    let (ai, br, bi) = (&ai[..n], &br[..n], &bi[..n]);
    let (mut sr, mut si) = (0.0, 0.0);
    for i in 0..n {
        sr += ar[i] * br[i] - ai[i] * bi[i];
        si += ar[i] * bi[i] + ai[i] * br[i];
    }
    (sr, si)
}

/// A complex [`SchurLu`], real and imaginary parts stored apart (the inner loops are then
/// plain real arithmetic).
#[derive(Debug, Clone)]
pub struct ComplexLu<const N: usize> {
    re: [[f64; N]; N],
    im: [[f64; N]; N],
    inv_diag: [Complex<f64>; N],
    piv: [usize; N],
}

impl<const N: usize> SchurLu<Complex<f64>, N> for ComplexLu<N> {
    fn zeros() -> Self {
        ComplexLu { re: [[0.0; N]; N], im: [[0.0; N]; N], inv_diag: [Complex::new(0.0, 0.0); N], piv: [0; N] }
    }
    fn build(&mut self, c: Complex<f64>, inv_c: Complex<f64>, a: &[[f64; N]; N], b: &[[f64; N]; N], m: usize) {
        for r in 0..m {
            let (re, im, ar, br) = (&mut self.re[r][..m], &mut self.im[r][..m], &a[r][..m], &b[r][..m]);
            for k in 0..m {
                re[k] = -ar[k] - inv_c.re * br[k];
                im[k] = -inv_c.im * br[k];
            }
            re[r] += c.re;
            im[r] += c.im;
        }
    }
    #[cfg(test)]
    fn set(&mut self, r: usize, k: usize, v: Complex<f64>) {
        self.re[r][k] = v.re;
        self.im[r][k] = v.im;
    }
    #[inline(always)]
    fn sub_scaled(&mut self, r: usize, k: usize, x: Complex<f64>, a: f64) {
        self.re[r][k] -= x.re * a;
        self.im[r][k] -= x.im * a;
    }
    #[inline(never)]
    fn factor(&mut self, m: usize) -> bool {
        let (re, im) = (&mut self.re, &mut self.im);
        for k in 0..m {
            let Some(p) = pivot_row(k, m, |i| re[i][k].abs() + im[i][k].abs()) else { return false };
            self.piv[k] = p;
            if p != k {
                re.swap(p, k);
                im.swap(p, k);
            }
            let d = Complex::new(1.0, 0.0) / Complex::new(re[k][k], im[k][k]);
            self.inv_diag[k] = d;
            let n = m - k - 1;
            let (rtop, rrest) = re.split_at_mut(k + 1);
            let (itop, irest) = im.split_at_mut(k + 1);
            let (pr, pi) = (&rtop[k][k + 1..m], &itop[k][k + 1..m]);
            for (rrow, irow) in rrest[..n].iter_mut().zip(irest[..n].iter_mut()) {
                let (xr, xi) = (rrow[k], irow[k]);
                let (lr, li) = (xr * d.re - xi * d.im, xr * d.im + xi * d.re);
                rrow[k] = lr;
                irow[k] = li;
                if lr == 0.0 && li == 0.0 {
                    continue;
                }
                let (r, i) = (&mut rrow[k + 1..m], &mut irow[k + 1..m]);
                for j in 0..n {
                    r[j] -= lr * pr[j] - li * pi[j];
                    i[j] -= lr * pi[j] + li * pr[j];
                }
            }
        }
        true
    }
    fn solve(&self, x: &mut [Complex<f64>; N], m: usize) {
        for k in 0..m {
            x.swap(k, self.piv[k]);
        }
        let mut xr = [0.0; N];
        let mut xi = [0.0; N];
        for k in 0..m {
            xr[k] = x[k].re;
            xi[k] = x[k].im;
        }
        for i in 1..m {
            let (sr, si) = cdot(&self.re[i][..i], &self.im[i][..i], &xr[..i], &xi[..i]);
            xr[i] -= sr;
            xi[i] -= si;
        }
        for i in (0..m).rev() {
            let (sr, si) = cdot(&self.re[i][i + 1..m], &self.im[i][i + 1..m], &xr[i + 1..m], &xi[i + 1..m]);
            let v = Complex::new(xr[i] - sr, xi[i] - si) * self.inv_diag[i];
            xr[i] = v.re;
            xi[i] = v.im;
        }
        for k in 0..m {
            x[k] = Complex::new(xr[k], xi[k]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The hand-written LUs of the Schur complement (real, and complex with its parts
    /// stored apart) solve random m×m systems in N×N storage as nalgebra's LU does.
    #[test]
    fn schur_lus_match_nalgebra() {
        const N: usize = 8;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for m in 1..=N {
            for _ in 0..20 {
                let a = nalgebra::DMatrix::<f64>::from_fn(m, m, |_, _| rng.random_range(-1.0..1.0));
                let ai = nalgebra::DMatrix::<f64>::from_fn(m, m, |_, _| rng.random_range(-1.0..1.0));
                let b = nalgebra::DVector::<f64>::from_fn(m, |_, _| rng.random_range(-1.0..1.0));
                let bi = nalgebra::DVector::<f64>::from_fn(m, |_, _| rng.random_range(-1.0..1.0));
                let mut lu = RealLu::<N>::zeros();
                for r in 0..m {
                    for k in 0..m {
                        lu.set(r, k, a[(r, k)]);
                    }
                }
                assert!(lu.factor(m));
                let mut x = [0.0; N];
                x[..m].copy_from_slice(b.as_slice());
                lu.solve(&mut x, m);
                let dense = a.clone().lu().solve(&b).unwrap();
                let err = (0..m).map(|i| (x[i] - dense[i]).abs()).fold(0.0, f64::max);
                assert!(err <= 1e-10 * dense.amax().max(1.0), "real m {m}: {err:e}");
                let ac = a.zip_map(&ai, Complex::new);
                let bc = b.zip_map(&bi, Complex::new);
                let mut lu = ComplexLu::<N>::zeros();
                for r in 0..m {
                    for k in 0..m {
                        lu.set(r, k, ac[(r, k)]);
                    }
                }
                assert!(lu.factor(m));
                let mut x = [Complex::new(0.0, 0.0); N];
                x[..m].copy_from_slice(bc.as_slice());
                lu.solve(&mut x, m);
                let dense = ac.clone().lu().solve(&bc).unwrap();
                let err = (0..m).map(|i| (x[i] - dense[i]).norm()).fold(0.0, f64::max);
                let scale = dense.iter().map(|v| v.norm()).fold(1.0, f64::max);
                assert!(err <= 1e-10 * scale, "complex m {m}: {err:e}");
            }
        }
        // a singular matrix is refused
        let mut lu = RealLu::<N>::zeros();
        lu.set(0, 0, 1.0);
        lu.set(0, 1, 2.0);
        lu.set(1, 0, 2.0);
        lu.set(1, 1, 4.0);
        assert!(!lu.factor(2));
    }
}
