//! LU factorisation with partial pivoting of fixed-size square matrices (real or complex;
//! no allocation), used by the implicit methods' simplified Newton iterations.

use nalgebra::{Complex, SMatrix, SVector};

/// LU factorisation with partial pivoting of a fixed-size square matrix (no allocation),
/// real (`f64`) or complex (`Complex<f64>`, for the transformed Radau IIA system).
#[derive(Debug, Clone, Copy)]
pub struct Lu<T: Scalar, const N: usize> {
    lu: SMatrix<T, N, N>,
    piv: [usize; N],
}

/// The field of an [`Lu`]: `f64` or `Complex<f64>`.
pub trait Scalar: nalgebra::ComplexField<RealField = f64> + Copy {
    /// `self · r` for a real `r` (two multiplications for a complex `self`, not four).
    fn mul_real(self, r: f64) -> Self;
}
impl Scalar for f64 {
    #[inline(always)]
    fn mul_real(self, r: f64) -> Self {
        self * r
    }
}
impl Scalar for Complex<f64> {
    #[inline(always)]
    fn mul_real(self, r: f64) -> Self {
        Complex::new(self.re * r, self.im * r)
    }
}

/// Partial pivoting in column k of an m-row matrix: the row p in k..m of the largest
/// magnitude `mag(p)` (the first of equals); `None` where that is zero or not finite (the
/// matrix is singular).
#[inline(always)]
pub(super) fn pivot_row(k: usize, m: usize, mag: impl Fn(usize) -> f64) -> Option<usize> {
    let mut p = k;
    let mut mx = mag(k);
    for i in k + 1..m {
        let v = mag(i);
        if v > mx {
            mx = v;
            p = i;
        }
    }
    (mx > 0.0 && mx.is_finite()).then_some(p)
}

impl<T: Scalar, const N: usize> Lu<T, N> {
    /// Factor `a`; `None` if singular.
    #[inline]
    pub fn factor(mut a: SMatrix<T, N, N>) -> Option<Self> {
        let mut piv = [0usize; N];
        for k in 0..N {
            let p = pivot_row(k, N, |i| a[(i, k)].norm1())?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The complex LU solves a complex system (checked by multiplying back).
    #[test]
    fn complex_lu_solves() {
        let a = SMatrix::<Complex<f64>, 3, 3>::from_fn(|i, j| {
            Complex::new((i * 3 + j) as f64 + if i == j { 5.0 } else { 0.0 }, (i as f64) - (j as f64) * 0.5)
        });
        let b = SVector::<Complex<f64>, 3>::from_fn(|i, _| Complex::new(1.0 + i as f64, -(i as f64)));
        let x = Lu::factor(a).unwrap().solve(&b);
        assert!((a * x - b).norm() < 1e-13);
    }
}
