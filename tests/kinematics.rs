//! Jacobians against central finite differences of the direct geometric model (MODEL.md
//! §5.3–5.5, §6.3) at random valid configurations of random designs.
use crate::common::*;
use gripopt::math::{perp, V2};
use gripopt::model::{kinetic_energy_bodies, mass_matrix, reduced};
use gripopt::model::{Finger, Kin, Pose};
use nalgebra::Vector2;
use rand::{Rng, SeedableRng};

/// Random (design, pose) pairs: designs in the default box that build, poses between the
/// open pose and ~80° of closure that the DGM can assemble away from singularities.
fn samples(n: usize, seed: u64) -> Vec<(Finger, Pose)> {
    let s = scene();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut out = vec![];
    while out.len() < n {
        let Ok(f) = Finger::new(&random_design(&mut rng), &s) else { continue };
        let q11 = f.open.q11 + rng.random_range(-0.3..1.4);
        let q21 = f.open.q21 + rng.random_range(-0.3..1.0);
        let Ok(pose) = f.dgm(q11, q21) else { continue };
        let sing = [pose.q12.sin().abs(), pose.q22.sin().abs(), pose.q13.sin().abs()];
        if sing.iter().any(|v| *v < 0.2) {
            continue;
        }
        out.push((f, pose));
    }
    out
}

/// Central difference of `g` with respect to the active angle `j` at `q` (step 1e-6).
fn d_dq(q: Vector2<f64>, j: usize, g: impl Fn(Vector2<f64>) -> Vector2<f64>) -> Vector2<f64> {
    let h = 1e-6;
    let mut e = Vector2::zeros();
    e[j] = h;
    (g(q + e) - g(q - e)) / (2.0 * h)
}

fn qd(f: &Finger, q: Vector2<f64>) -> Vector2<f64> {
    let p = f.dgm(q[0], q[1]).expect("pose near a valid pose assembles");
    Vector2::new(p.q12, p.q22)
}

#[test]
fn jd_and_jx_match_central_differences() {
    for (f, p) in samples(200, 1) {
        let k = Kin::new(&f, &p).unwrap();
        let h = 1e-6;
        let q0 = Vector2::new(p.q11, p.q21);
        for j in 0..2 {
            let dq = d_dq(q0, j, |q| qd(&f, q));
            let dx = d_dq(q0, j, |q| f.dgm(q[0], q[1]).unwrap().o13);
            for i in 0..2 {
                let scale = k.jd.column(j).amax().max(1.0);
                assert!((k.jd[(i, j)] - dq[i]).abs() < 1e-7 * scale, "J_d[{i}{j}] {} vs fd {}", k.jd[(i, j)], dq[i]);
                let sx = k.jx.column(j).amax().max(1e-3);
                assert!((k.jx[(i, j)] - dx[i]).abs() < 1e-7 * sx, "J_X[{i}{j}] {} vs fd {}", k.jx[(i, j)], dx[i]);
            }
        }
        // O11 = O21: q_d depends on q11 − q21 only (MODEL.md §5.3)
        assert!((k.jd[(0, 1)] + k.jd[(0, 0)]).abs() < 1e-9 * k.jd[(0, 0)].abs().max(1.0));
        assert!((k.jd[(1, 1)] + k.jd[(1, 0)]).abs() < 1e-9 * k.jd[(1, 0)].abs().max(1.0));
        // G: θ̇ = G q̇_a
        let g = k.g();
        let v = Vector2::new(0.3, -0.7);
        let th = |q: Vector2<f64>| {
            let pz = f.dgm(q[0], q[1]).unwrap();
            Vector2::new(pz.q21, pz.q22 + f.psi)
        };
        let q0 = Vector2::new(p.q11, p.q21);
        let dth = (th(q0 + v * h) - th(q0 - v * h)) / (2.0 * h);
        assert!((g * v - dth).amax() < 1e-7 * dth.amax().max(1.0));
    }
}

#[test]
fn bd_matches_second_difference() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for (f, p) in samples(200, 2) {
        let k = Kin::new(&f, &p).unwrap();
        let v = Vector2::new(rng.random_range(-40.0..40.0), rng.random_range(-40.0..40.0));
        let bd = k.bd(&f, v);
        // q_a(t) = q0 + v t has q̈_a = 0, so q̈_d = b_d.
        let q0 = Vector2::new(p.q11, p.q21);
        let d2 = |h: f64| (qd(&f, q0 + v * h) - 2.0 * qd(&f, q0) + qd(&f, q0 - v * h)) / (h * h);
        // Richardson: (4 D(h/2) − D(h)) / 3 is O(h⁴)
        let h = 1e-3 / v.norm();
        let second = (d2(h / 2.0) * 4.0 - d2(h)) / 3.0;
        // roundoff of the second difference is ~ 8 ε |v|² / (|v| h)² ≈ 2e-8 |v|²
        let scale = bd.amax().max(v.norm_squared() * 0.05);
        assert!((bd - second).amax() < 5e-6 * scale, "b_d {bd:?} vs fd {second:?}");
    }
}

#[test]
fn point_jacobians_match_differences() {
    for (f, p) in samples(100, 3) {
        let k = Kin::new(&f, &p).unwrap();
        // material points fixed in body 21 and body 22 (local body coordinates a, b)
        for distal in [false, true] {
            let (a, b) = (0.013, 0.004);
            let point = |pz: &Pose| -> V2 {
                if distal {
                    pz.o22 + a * pz.x22 + b * perp(pz.x22)
                } else {
                    f.o21 + a * pz.x21 + b * perp(pz.x21)
                }
            };
            let jp = k.point_jacobian(&f, &p, point(&p), distal);
            for j in 0..2 {
                let d = d_dq(Vector2::new(p.q11, p.q21), j, |q| point(&f.dgm(q[0], q[1]).unwrap()));
                let sc = jp.column(j).amax().max(1e-3);
                assert!(
                    (jp.column(j) - d).amax() < 1e-7 * sc,
                    "J_P col {j} distal {distal}: {:?} vs {d:?}",
                    jp.column(j)
                );
            }
        }
    }
}

#[test]
fn mass_matrix_spd_and_kinetic_energy_identity() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for (f, p) in samples(200, 4) {
        let k = Kin::new(&f, &p).unwrap();
        let m = mass_matrix(&f, &p, &k);
        assert!((m[(0, 1)] - m[(1, 0)]).abs() < 1e-15 * m.amax());
        assert!(m[(0, 0)] > 0.0 && m.determinant() > 0.0, "M not PD: {m}");
        let v = Vector2::new(rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0));
        let t_red = 0.5 * v.dot(&(m * v));
        let t_body = kinetic_energy_bodies(&f, &p, &k, v);
        assert!((t_red - t_body).abs() < 1e-12 * t_body.abs().max(1e-12), "{t_red} vs {t_body}");
    }
}

#[test]
fn bias_is_the_lagrangian_coriolis_term() {
    // c(q, q̇) = Ṁ q̇ − ½ ∂/∂q (q̇ᵀ M q̇), with Ṁ and ∂M/∂q from differences of M(q).
    for (f, p) in samples(100, 5) {
        let k = Kin::new(&f, &p).unwrap();
        let v = Vector2::new(13.0, -21.0);
        let c = reduced(&f, &p, &k, v).c;
        let mq = |q: Vector2<f64>| {
            let pz = f.dgm(q[0], q[1]).unwrap();
            mass_matrix(&f, &pz, &Kin::new(&f, &pz).unwrap())
        };
        let q0 = Vector2::new(p.q11, p.q21);
        let h = 1e-6;
        let mut dm = [nalgebra::Matrix2::zeros(); 2];
        for j in 0..2 {
            let mut e = Vector2::zeros();
            e[j] = h;
            dm[j] = (mq(q0 + e) - mq(q0 - e)) / (2.0 * h);
        }
        let mdot = dm[0] * v[0] + dm[1] * v[1];
        let grad = Vector2::new(0.5 * v.dot(&(dm[0] * v)), 0.5 * v.dot(&(dm[1] * v)));
        let expect = mdot * v - grad;
        assert!((c - expect).amax() < 1e-6 * expect.amax().max(1e-6), "c {c:?} vs {expect:?}");
    }
}
