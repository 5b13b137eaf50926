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

/// `(sin x, cos x)` for the bounded angles of the simulator's right-hand side: Cody–Waite
/// reduction by π/2 and fdlibm's minimax kernels on [−π/4, π/4] (error < 2 ulp, tested
/// against libm). About a third of glibc's `sincos` cost, which spends most of its time on
/// range dispatch and rounding-mode guards; |x| ≥ 2²⁰ or non-finite x falls back to libm.
#[inline]
#[allow(clippy::excessive_precision)] // the published digits, kept for checking
pub fn sin_cos_fast(x: f64) -> (f64, f64) {
    const FRAC_2_PI: f64 = std::f64::consts::FRAC_2_PI;
    // π/2 split: the first 33 bits (exact times n < 2²⁰) and the rest.
    const PIO2_1: f64 = 1.570_796_326_734_125_614_17;
    const PIO2_1T: f64 = 6.077_100_506_506_192_249_32e-11;
    if !(x.abs() < 1_048_576.0) {
        return x.sin_cos();
    }
    let n = (x * FRAC_2_PI).round();
    let r = (x - n * PIO2_1) - n * PIO2_1T;
    let z = r * r;
    // fdlibm __kernel_sin / __kernel_cos coefficients
    let s = r + r
        * z
        * (-1.666_666_666_666_663_243_48e-1
            + z * (8.333_333_333_322_489_461_24e-3
                + z * (-1.984_126_982_985_794_931_34e-4
                    + z * (2.755_731_370_707_006_767_89e-6
                        + z * (-2.505_076_025_340_686_341_95e-8 + z * 1.589_690_995_211_550_102_21e-10)))));
    let cr = z
        * z
        * (4.166_666_666_666_660_190_37e-2
            + z * (-1.388_888_888_887_410_957_49e-3
                + z * (2.480_158_728_947_672_941_78e-5
                    + z * (-2.755_731_435_139_066_330_35e-7
                        + z * (2.087_572_321_298_174_827_90e-9 + z * -1.135_964_755_778_819_482_65e-11)))));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let c = w + (((1.0 - w) - hz) + cr);
    match (n as i64) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `e(a)` through [`sin_cos_fast`].
#[inline]
pub fn e_fast(a: f64) -> V2 {
    let (s, c) = sin_cos_fast(a);
    V2::new(c, s)
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
        // exact quadrant signs and the fallback
        assert_eq!(sin_cos_fast(0.0), (0.0, 1.0));
        let (s, c) = sin_cos_fast(1e7);
        assert_eq!((s, c), 1e7f64.sin_cos());
        assert!(sin_cos_fast(f64::NAN).0.is_nan());
    }
    use std::f64::consts::PI;

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
