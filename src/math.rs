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
