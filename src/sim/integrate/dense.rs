//! Dense output on an accepted step: cubic Hermite interpolation through both ends' states
//! and derivatives.

use nalgebra::SVector;

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
