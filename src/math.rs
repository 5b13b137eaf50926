//! Small planar helpers shared by every model module (MODEL.md conventions).

use nalgebra::Vector2;

/// A planar vector.
pub type V2 = Vector2<f64>;

/// Unit vector at angle `a`: `e(a) = (cos a, sin a)`.
#[inline]
pub fn e(a: f64) -> V2 {
    let (s, c) = a.sin_cos();
    V2::new(c, s)
}

/// Points per turn of the table of [`sin_cos_fast`].
const SC_POINTS: usize = 128;

/// sin and cos of k·2π/128: libm's on the first octant (k ≤ 16, where the rounding of
/// k·π/64 moves sin and cos by under half an ulp), the rest by the exact symmetries
/// (sin, cos)(π/2 − a) = (cos, sin)(a) and (sin, cos)(a + π/2) = (cos, −sin)(a).
static SC_TABLE: std::sync::LazyLock<[[f64; 2]; SC_POINTS]> = std::sync::LazyLock::new(|| {
    let q = SC_POINTS / 4;
    let mut t = [[0.0; 2]; SC_POINTS];
    for k in 0..=q / 2 {
        let (s, c) = (k as f64 * (std::f64::consts::PI / (2 * q) as f64)).sin_cos();
        t[k] = [s, c];
        t[q - k] = [c, s];
    }
    for k in q..SC_POINTS {
        let [s, c] = t[k - q];
        t[k] = [c, -s];
    }
    t
});

/// `(sin x, cos x)` for the bounded angles of the simulator's right-hand side: x = a + r with
/// a a multiple of π/64 (Cody–Waite reduction) and |r| ≤ π/128; sin and cos of a from a
/// table, of r from their Taylor polynomials (truncation below 2e-18 relative), combined as
/// sin a + (sin a·(cos r − 1) + cos a·sin r) so that the correction carries the rounding
/// (error < 2 ulp, tested against libm). About a quarter of glibc's `sincos` cost, which
/// spends most of its time on range dispatch and rounding-mode guards, with no branch on
/// the quadrant; |x| ≥ 4e4 or non-finite x falls back to libm.
#[inline]
#[allow(clippy::excessive_precision)] // the published digits, kept for checking
pub fn sin_cos_fast(x: f64) -> (f64, f64) {
    const K: f64 = 64.0 / std::f64::consts::PI;
    // π/64 split: the first 33 bits (exact times n < 2²⁰) and the rest (fdlibm's π/2 split
    // over 32).
    const P1: f64 = 1.570_796_326_734_125_614_17 / 32.0;
    const P1T: f64 = 6.077_100_506_506_192_249_32e-11 / 32.0;
    if !(x.abs() < 40_000.0) {
        return x.sin_cos();
    }
    // round to nearest by the 1.5·2⁵² shift (f64::round is a libm call on the baseline
    // x86-64 target)
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    let n = (x * K + SHIFT) - SHIFT;
    let r = (x - n * P1) - n * P1T;
    let [sa, ca] = SC_TABLE[(n as i64 & (SC_POINTS as i64 - 1)) as usize];
    let z = r * r;
    let sr = r + r * z * (-1.0 / 6.0 + z * (1.0 / 120.0 - z * (1.0 / 5040.0)));
    let cm1 = -z * (0.5 - z * (1.0 / 24.0 - z * (1.0 / 720.0)));
    (sa + (sa * cm1 + ca * sr), ca + (ca * cm1 - sa * sr))
}

/// `e(a)` through [`sin_cos_fast`].
#[inline]
pub fn e_fast(a: f64) -> V2 {
    let (s, c) = sin_cos_fast(a);
    V2::new(c, s)
}

/// The inverse of a 2×2 matrix by its adjugate; `None` if the determinant is zero or NaN
/// (nalgebra's general `try_inverse` costs several times more in the simulator's
/// right-hand side).
#[inline(always)]
pub fn inv2(m: &nalgebra::Matrix2<f64>) -> Option<nalgebra::Matrix2<f64>> {
    let (a, b, c, d) = (m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]);
    let det = a * d - b * c;
    if !(det.abs() > 0.0) {
        return None;
    }
    let r = 1.0 / det;
    Some(nalgebra::Matrix2::new(d * r, -b * r, -c * r, a * r))
}

/// `perp(v) = z × v = (−v_y, v_x)` (rotation by +90°).
#[inline]
pub fn perp(v: V2) -> V2 {
    V2::new(-v.y, v.x)
}

/// Planar cross product `a_x b_y − a_y b_x`.
#[inline]
pub fn cross(a: V2, b: V2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Angle of a vector, `atan2(v_y, v_x)`.
#[inline]
pub fn angle(v: V2) -> f64 {
    v.y.atan2(v.x)
}

/// Wrap an angle to (−π, π].
#[inline]
pub fn wrap(a: f64) -> f64 {
    use std::f64::consts::PI;
    let mut r = (a + PI).rem_euclid(2.0 * PI) - PI;
    if r <= -PI {
        r += 2.0 * PI;
    }
    r
}

/// Distance of an angle to the nearest multiple of π (singularity distance, MODEL.md §7).
#[inline]
pub fn dist_to_singular(a: f64) -> f64 {
    use std::f64::consts::PI;
    let m = a.abs() % PI;
    m.min(PI - m)
}

/// Degrees to radians.
#[inline]
pub fn deg(a: f64) -> f64 {
    a.to_radians()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast sincos agrees with libm to 2 ulp of 1 over the simulator's range and beyond.
    #[test]
    fn sin_cos_fast_matches_libm() {
        let mut worst: f64 = 0.0;
        let n = 200_000;
        for k in 0..=n {
            let x = -40.0 + 80.0 * k as f64 / n as f64;
            for x in [x, x * 1e-3, x * 1e-7] {
                let (s, c) = sin_cos_fast(x);
                let (s0, c0) = x.sin_cos();
                worst = worst.max((s - s0).abs()).max((c - c0).abs());
            }
        }
        assert!(worst <= 2.0 * f64::EPSILON, "worst {worst:e}");
        // exact at 0, and the fallback
        assert_eq!(sin_cos_fast(0.0), (0.0, 1.0));
        let (s, c) = sin_cos_fast(1e7);
        assert_eq!((s, c), 1e7f64.sin_cos());
        // the largest reduced arguments, up to the fallback
        for x in [39_999.9, -39_999.9, 12_345.678] {
            let (s, c) = sin_cos_fast(x);
            let (s0, c0) = x.sin_cos();
            assert!((s - s0).abs().max((c - c0).abs()) <= 2.0 * f64::EPSILON, "{x}");
        }
        assert!(sin_cos_fast(f64::NAN).0.is_nan());
    }
    use std::f64::consts::PI;

    /// The adjugate inverse agrees with nalgebra's; singular matrices have none.
    #[test]
    fn inverse_of_2x2() {
        let m = nalgebra::Matrix2::new(3.0, -1.5, 0.25, 2.0);
        assert!((inv2(&m).unwrap() - m.try_inverse().unwrap()).abs().max() < 1e-15);
        assert!(inv2(&nalgebra::Matrix2::new(1.0, 2.0, 2.0, 4.0)).is_none());
        assert!(inv2(&nalgebra::Matrix2::new(f64::NAN, 0.0, 0.0, 1.0)).is_none());
    }

    #[test]
    fn wrap_range() {
        assert!((wrap(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap(-PI) - PI).abs() < 1e-12);
        assert!((wrap(0.5) - 0.5).abs() < 1e-15);
        assert!((wrap(-0.5 - 2.0 * PI) + 0.5).abs() < 1e-12);
    }

    #[test]
    fn singular_distance() {
        assert!((dist_to_singular(deg(170.0)) - deg(10.0)).abs() < 1e-12);
        assert!((dist_to_singular(deg(-146.0)) - deg(34.0)).abs() < 1e-12);
        assert!((dist_to_singular(deg(20.0)) - deg(20.0)).abs() < 1e-12);
    }
}
