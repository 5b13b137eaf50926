//! Statics, spring sizing, symmetry and form closure (MODEL.md §6, §11 items 5, 8, 9, §13.11).
use crate::common::*;
use gripopt::eval::{stage_kinematics, stage_statics};
use gripopt::model::mass_matrix;
use gripopt::model::{
    admissible, closure_matrix, form_closure_test, grasp_at, max_offset, ClosureMatrix, OffsetFailure,
};
use gripopt::model::{birglen_residual, closed_pose, finger_forces, spring_preload, tangent_angles, ClosedPoseError};
use gripopt::model::{Finger, Kin};
use gripopt::sim::{FingerOde, State};
use nalgebra::{SMatrix, SVector};
use rand::{Rng, SeedableRng};

/// Random designs of the default box that pass stage 1 and have a centred closed pose.
fn designs(n: usize, seed: u64) -> Vec<Finger> {
    let s = scene();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut out = vec![];
    while out.len() < n {
        let Ok(k) = stage_kinematics(&random_design(&mut rng), &s) else { continue };
        if closed_pose(&k.finger, s.object.radius, 0.0).is_ok() {
            out.push(k.finger);
        }
    }
    out
}

#[test]
fn birglen_form_equals_row_formulation() {
    let s = scene();
    for f in designs(200, 1) {
        let (_, ts0) = spring_preload(&f, &s).unwrap();
        let cp = closed_pose(&f, s.object.radius, 0.0).unwrap();
        let ff = finger_forces(&f, &s, &cp, ts0).unwrap();
        let r = birglen_residual(&f, &cp, &ff);
        let j21 = cp.kin.j21();
        let expect = [s.hand.tau, s.hand.tau / j21 - ts0];
        for i in 0..2 {
            assert!((r[i] - expect[i]).abs() < 1e-9 * expect[i].abs().max(s.hand.tau), "{r:?} vs {expect:?}");
        }
    }
}

#[test]
fn spring_rule_matches_eq_4_12_and_balances_the_distal() {
    let s = scene();
    for f in designs(200, 2) {
        let (tmin, ts0) = spring_preload(&f, &s).unwrap();
        let k = Kin::new(&f, &f.open).unwrap();
        let m = mass_matrix(&f, &f.open, &k);
        // eq. 4.12 (O11 = O21): τ (M22 + M12) / (J21 (M11 + 2 M12 + M22))
        let eq412 = s.hand.tau * (m[(1, 1)] + m[(0, 1)]) / (k.j21() * (m[(0, 0)] + 2.0 * m[(0, 1)] + m[(1, 1)]));
        assert!((tmin - eq412).abs() < 1e-10 * eq412.abs().max(1e-6), "{tmin} vs {eq412}");
        assert_eq!(ts0, tmin.max(0.0));
        if tmin > 0.0 {
            // full dynamics at the open pose at rest: θ̈2 = 0 with the minimal spring
            let ode = FingerOde::new(&f, &s, ts0, 0.0);
            let ev = ode.evaluate(&State::from([f.open.q11, f.open.q21, 0.0, 0.0, 0.0])).unwrap();
            let th2dd = k.j_row().dot(&ev.qdd);
            assert!(th2dd.abs() < 1e-9 * ev.qdd.amax(), "θ̈2 = {th2dd} (q̈ {:?})", ev.qdd);
            // a weaker spring lets the distal fold (θ̈2 > 0)
            let ode = FingerOde::new(&f, &s, 0.9 * ts0, 0.0);
            let ev = ode.evaluate(&State::from([f.open.q11, f.open.q21, 0.0, 0.0, 0.0])).unwrap();
            assert!(k.j_row().dot(&ev.qdd) > 0.0);
        }
    }
}

#[test]
fn nominal_hand_forces_of_d7() {
    let s = scene();
    let f = Finger::new(&nominal(), &s).unwrap();
    let st = stage_statics(&f, &s).unwrap();
    close_abs(st.grasp.hand0[1], 3.74, 0.005, "F0_hand,y");
    close_abs(st.grasp.hand_mu[1], -11.33, 0.005, "Fmu_hand,y");
    assert!(st.form_closed_0);
}

#[test]
fn centred_symmetric_grasp_has_no_lateral_force() {
    let s = scene();
    for f in designs(100, 3) {
        let (_, ts0) = spring_preload(&f, &s).unwrap();
        let Ok(g) = grasp_at(&f, &s, ts0, 0.0) else { continue };
        assert!(g.hand0.x.abs() <= 1e-12, "{}", g.hand0.x);
        assert!(g.hand_mu.x.abs() <= 1e-12, "{}", g.hand_mu.x);
    }
}

#[test]
fn mirror_symmetry_of_offset_grasps() {
    // Finger 2 is the x-mirror of finger 1: the grasp at −x_off is the mirror of that at +x_off.
    let s = scene();
    let f = Finger::new(&nominal(), &s).unwrap();
    let (_, ts0) = spring_preload(&f, &s).unwrap();
    for k in 1..12 {
        let x = k as f64 * 0.25e-3;
        let a = grasp_at(&f, &s, ts0, x).unwrap();
        let b = grasp_at(&f, &s, ts0, -x).unwrap();
        close_abs(a.hand0.x, -b.hand0.x, 1e-12, "Fx mirror");
        close_abs(a.hand0.y, b.hand0.y, 1e-12, "Fy mirror");
        close_abs(a.hand_mu.x, -b.hand_mu.x, 1e-12, "Fmu_x mirror");
        for i in 0..2 {
            close_abs(a.forces[0].f0[i], b.forces[1].f0[i], 1e-12, "f0 swap");
        }
        // the object moves toward finger 1's base: its proximal contact moves toward the base
        assert!(a.cp[0].k1 < a.cp[1].k1);
    }
}

// ---- form closure -------------------------------------------------------------------

/// Brute-force check: is {ω ≠ 0 : A_u ω ≥ 0, A_b ω = 0} empty? Parameterise the kernel of
/// the bilateral rows (4-D) and enumerate the candidate extreme rays of the cone, each the
/// 1-D kernel of 3 unilateral rows; the cone is non-trivial iff some ±ray satisfies all rows.
fn brute_force_closed(m: &ClosureMatrix) -> bool {
    let mut a = *m;
    for r in 0..7 {
        let n = a.row(r).norm();
        if n > 0.0 {
            let row = a.row(r) / n;
            a.set_row(r, &row);
        }
    }
    let ab = a.fixed_rows::<2>(5).into_owned();
    // kernel basis of the bilateral rows from the full SVD of its transpose padded to 6×6
    let mut pad = SMatrix::<f64, 6, 6>::zeros();
    pad.fixed_rows_mut::<2>(0).copy_from(&ab);
    let svd = pad.svd(false, true);
    let vt = svd.v_t.unwrap();
    let mut idx: Vec<usize> = (0..6).collect();
    idx.sort_by(|&i, &j| svd.singular_values[j].total_cmp(&svd.singular_values[i]));
    let basis: Vec<SVector<f64, 6>> = idx[2..].iter().map(|&i| vt.row(i).transpose()).collect();
    let nmat = SMatrix::<f64, 6, 4>::from_columns(&[basis[0], basis[1], basis[2], basis[3]]);
    let au = a.fixed_rows::<5>(0).into_owned() * nmat; // 5×4
                                                       // lineality: a common kernel of all 5 rows means not closed
    let s5 = au.svd(false, false).singular_values;
    if s5.iter().cloned().fold(f64::INFINITY, f64::min) < 1e-10 {
        return false;
    }
    for i in 0..5 {
        for j in i + 1..5 {
            for k in j + 1..5 {
                let r3 = SMatrix::<f64, 3, 4>::from_rows(&[au.row(i), au.row(j), au.row(k)]);
                let mut p4 = SMatrix::<f64, 4, 4>::zeros();
                p4.fixed_rows_mut::<3>(0).copy_from(&r3);
                let sv = p4.svd(false, true);
                let vt = sv.v_t.unwrap();
                let mut im = 0;
                for q in 1..4 {
                    if sv.singular_values[q] < sv.singular_values[im] {
                        im = q;
                    }
                }
                let d = vt.row(im).transpose();
                for sign in [1.0, -1.0] {
                    let v = au * (d * sign);
                    if v.iter().all(|x| *x >= -1e-9) {
                        return false;
                    }
                }
            }
        }
    }
    true
}

#[test]
fn kernel_test_agrees_with_brute_force_on_random_matrices() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut closed, mut open) = (0, 0);
    for case in 0..4000 {
        let mut m = ClosureMatrix::zeros();
        for r in 0..7 {
            for c in 0..6 {
                m[(r, c)] = rng.random_range(-1.0..1.0);
            }
        }
        if case % 2 == 0 {
            // make it closable: choose y with positive unilateral part and fix the last
            // unilateral row so that M_cᵀ y = 0
            let y: Vec<f64> =
                (0..7).map(|i| if i < 5 { rng.random_range(0.1..1.0) } else { rng.random_range(-1.0..1.0) }).collect();
            let mut acc = SVector::<f64, 6>::zeros();
            for r in 0..7 {
                if r != 4 {
                    acc += m.row(r).transpose() * y[r];
                }
            }
            let row = -acc / y[4];
            m.set_row(4, &row.transpose());
        }
        let fast = form_closure_test(&m).closed;
        let slow = brute_force_closed(&m);
        assert_eq!(fast, slow, "case {case}: kernel test {fast}, brute force {slow}\n{m}");
        if fast {
            closed += 1
        } else {
            open += 1
        }
    }
    assert!(closed > 500 && open > 500, "closed {closed} open {open}");
}

#[test]
fn kernel_test_agrees_with_brute_force_on_real_grasps() {
    let s = scene();
    let mut seen = [0, 0];
    for f in designs(150, 6) {
        let (_, ts0) = spring_preload(&f, &s).unwrap();
        for k in 0..40 {
            let Ok(g) = grasp_at(&f, &s, ts0, k as f64 * 0.5e-3) else { break };
            let m = closure_matrix(&f, &g.cp);
            let fast = form_closure_test(&m).closed;
            assert_eq!(fast, brute_force_closed(&m));
            seen[fast as usize] += 1;
        }
    }
    assert!(seen[0] > 0 && seen[1] > 0, "{seen:?}");
}

#[test]
fn hand_made_closure_cases() {
    let s = scene();
    let f = Finger::new(&nominal(), &s).unwrap();
    let (_, ts0) = spring_preload(&f, &s).unwrap();
    let g = grasp_at(&f, &s, ts0, 0.0).unwrap();
    let m = closure_matrix(&f, &g.cp);
    // enclosed: palm below, both fingers wrapped around
    assert!(form_closure_test(&m).closed);
    // without the palm the object can be pushed into the palm direction
    let mut no_palm = m;
    no_palm.set_row(4, &nalgebra::RowSVector::<f64, 6>::zeros());
    assert!(!form_closure_test(&no_palm).closed);
    assert!(!brute_force_closed(&no_palm));
    // finger 2 withdrawn (its contact normals point away from the object): free to slide out
    let mut one_finger = m;
    for r in [2, 3] {
        for c in 0..2 {
            one_finger[(r, c)] = -m[(r, c)];
        }
    }
    assert!(!form_closure_test(&one_finger).closed);
    // a pure translation escaping along −x is blocked only by finger 2: check it directly
    let esc = SVector::<f64, 6>::from([-1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let v = one_finger * esc;
    assert!(v.fixed_rows::<5>(0).iter().all(|x| *x >= -1e-12));
}

#[test]
fn offset_scan_endings() {
    // MODEL.md §13 item 11: scans ending by form-closure loss, by k2 > t22 and by force
    // positiveness; each ending is checked independently at the first failing offset.
    let s = scene();
    let mut kinds = [0usize; 3];
    for f in designs(400, 8) {
        let Ok(st) = stage_statics(&f, &s) else { continue };
        let scan = max_offset(&f, &s, st.tau_s0);
        assert_eq!(scan.max_offset, st.max_offset);
        let Some(end) = scan.ended_by else { continue };
        if scan.max_offset < 0.0 {
            assert_eq!(end, OffsetFailure::NotFormClosed);
            continue;
        }
        // the last offset is admissible, the next is not
        assert!(admissible(&f, &s, st.tau_s0, scan.max_offset).is_ok());
        let next = scan.max_offset + s.criteria.offset_step;
        match end {
            OffsetFailure::NotFormClosed => {
                let g = grasp_at(&f, &s, st.tau_s0, next).unwrap();
                assert!(!brute_force_closed(&closure_matrix(&f, &g.cp)));
                kinds[0] += 1;
            }
            OffsetFailure::NoClosedPose(j, ClosedPoseError::DistalBeyondTip) => {
                let xc = if j == 0 { next } else { -next };
                let (_, _, k2, _) = tangent_angles(&f, s.object.radius, xc).unwrap();
                assert!(k2 > f.t22);
                kinds[1] += 1;
            }
            OffsetFailure::ForceNotPositive(v) => {
                let g = grasp_at(&f, &s, st.tau_s0, next).unwrap();
                assert!(g.min_force() <= 0.0 && (g.min_force() - v).abs() < 1e-12);
                kinds[2] += 1;
            }
            _ => {}
        }
    }
    assert!(kinds.iter().all(|k| *k > 0), "endings seen (closure, tip, force): {kinds:?}");
}
