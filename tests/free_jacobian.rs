//! The free scene's block Jacobian (issue 13, item 6) against the dense forward-difference
//! Jacobian of the whole right-hand side, at states mid-grasp with contacts loaded; its
//! kinematic rows against their analytic values.

use crate::common::{bottle, nominal};
use gripopt::eval::{stage_kinematics, stage_statics};
use gripopt::sim::{
    drive, fd_jacobian, free_tolerances, Controls, FreeJacobian, FreeScene, FreeSetup, Integration, Radau5, Rhs, Stats,
    StepPoint,
};

/// State layout of the free scene (docs/scenes.md): fingers 0..8, G 8..11, q 11..15,
/// v_G 15..18, ω 18..21.
const G0: usize = 8;
const Q0: usize = 11;
const V0: usize = 15;
const W0: usize = 18;

/// Block and dense Jacobians at the state the nominal grasp reaches at `t_mid`, and the
/// piece flags there.
fn jacobians_at(t_mid: f64) -> (FreeJacobian, FreeJacobian, Stats, Stats, gripopt::sim::Piece, [f64; 21], [f64; 21]) {
    let s = bottle().scene;
    let k = stage_kinematics(&nominal(), &s).unwrap();
    let st = stage_statics(&k.finger, &s).unwrap();
    let opts = Integration::new(1e-7, 1e-10, 400_000);
    let mut scene = FreeScene::new(&k.finger, &s, st.tau_s0, 0.0, FreeSetup::default());
    let mut stepper = Radau5::new(free_tolerances(&opts), opts.h0);
    // the state reached at t_mid, with the contact memories of that moment
    let run = drive(&mut scene, &mut stepper, &opts, &Controls::DIAGNOSTIC, t_mid, &mut ());
    let (t, y) = (run.t, run.y);
    assert!((t - t_mid).abs() < 1e-12, "reached {t}");
    let at = StepPoint::at(&mut scene, t, y).expect("defined");
    let (f, piece) = (at.f, scene.piece(&y));
    let (mut jd, mut jb) = (FreeJacobian::zeros(), FreeJacobian::zeros());
    let (mut sd, mut sb) = (Stats::default(), Stats::default());
    assert!(fd_jacobian(&mut scene, &at, piece, &mut jd, &mut sd));
    assert!(scene.jacobian(&at, piece, &mut jb, &mut sb));
    let (mut ya, mut fa) = ([0.0; 21], [0.0; 21]);
    ya.copy_from_slice(y.as_slice());
    fa.copy_from_slice(f.as_slice());
    (jb, jd, sb, sd, piece, ya, fa)
}

/// Every entry of the block Jacobian equals the dense one to 1e-5 of its column's norm (plus
/// the dense quotient's rounding), without a full right-hand-side evaluation; the blocks that do not couple are exactly
/// zero in both; the kinematic rows are exact.
#[test]
fn free_block_jacobian_equals_dense() {
    // 5.3 ms: just after the first impact, the object rocking on part of its rim;
    // 20 ms: the grasp settling, every phalanx loaded, two ground points lifted
    for t_mid in [5.3e-3, 20e-3] {
        let (jb, jd, sb, sd, piece, y, f) = jacobians_at(t_mid);
        assert_eq!(sb.rhs, 0, "the block Jacobian makes no full evaluation");
        assert!(sd.rhs >= 21);
        assert!((12..20).step_by(2).any(|b| piece.has(b)), "a phalanx contact is loaded at {t_mid}");
        let ground = (22..54).step_by(2).filter(|&b| piece.has(b)).count();
        eprintln!("t {t_mid}: {ground} ground points loaded");
        assert!((3..16).contains(&ground), "ground contacts loaded at {t_mid}: {ground}");
        // Both take the same steps, so they differ by rounding only: the dense difference
        // quotient of row r carries ε|f_r|/|dy| (the block one subtracts the changed
        // contributions alone). Each entry must agree to 1e-5 of its column's norm plus
        // 4ε|f_r|/|dy|; at most a quarter of the columns may need the rounding term.
        let (mut worst, mut noisy) = (0.0f64, 0);
        for c in 0..21 {
            let dy = f64::EPSILON.sqrt() * y[c].abs().max(1e-3);
            let norm = jd.column(c).norm();
            let mut needs_noise = false;
            for r in 0..21 {
                let d = (jb[(r, c)] - jd[(r, c)]).abs();
                let noise = 4.0 * f64::EPSILON * f[r].abs() / dy;
                assert!(
                    d <= 1e-5 * norm + noise,
                    "t {t_mid}: J({r}, {c}) block {} dense {} (column norm {norm:.3e}, rounding {noise:.2e})",
                    jb[(r, c)],
                    jd[(r, c)]
                );
                needs_noise |= d > 1e-5 * norm;
            }
            noisy += needs_noise as usize;
            worst = worst.max((jb.column(c) - jd.column(c)).norm() / norm.max(1e-300));
        }
        assert!(noisy <= 5, "{noisy} columns differ by more than 1e-5");
        // the fingers couple to each other only through the object: exactly zero
        for (r0, c0) in [(0, 4), (4, 0)] {
            for r in r0..r0 + 4 {
                for c in c0..c0 + 4 {
                    assert_eq!(jd[(r, c)], 0.0, "dense ({r}, {c})");
                    assert_eq!(jb[(r, c)], 0.0, "block ({r}, {c})");
                }
            }
        }
        // the contacts do couple fingers and object, both ways
        assert!(jb.view((2, G0), (2, 13)).norm() > 0.0 && jb.view((V0, 0), (6, 8)).norm() > 0.0);
        // kinematic rows: q̇ of the fingers, dG/dt = v exactly
        for r in 0..21 {
            for (row, one) in [(0, 2), (1, 3), (4, 6), (5, 7), (G0, V0), (G0 + 1, V0 + 1), (G0 + 2, V0 + 2)] {
                assert_eq!(jb[(row, r)], if r == one { 1.0 } else { 0.0 }, "row {row} column {r}");
            }
        }
        // dq/dt = ½ ω ⊗ q/|q|: against the quaternion product written out, at |q| = 1
        let q = [y[Q0], y[Q0 + 1], y[Q0 + 2], y[Q0 + 3]];
        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((n - 1.0).abs() < 1e-6);
        let qh = q.map(|v| v / n);
        // ∂/∂ω_x of ½ (0, ω) ⊗ q̂ = ½ (−q_x, q_w, −q_z, q_y)
        let dwx = [-qh[1], qh[0], -qh[3], qh[2]];
        for r in 0..4 {
            assert!((jb[(Q0 + r, W0)] - 0.5 * dwx[r]).abs() < 1e-15, "dq/dω_x row {r}");
            assert_eq!(jb[(Q0 + r, G0)], 0.0);
            assert_eq!(jb[(Q0 + r, V0)], 0.0);
        }
        // d/dt |q|² = 0 along q̇: q̂ᵀ ∂q̇/∂ω = 0 for every ω
        for c in W0..W0 + 3 {
            let s: f64 = (0..4).map(|r| qh[r] * jb[(Q0 + r, c)]).sum();
            assert!(s.abs() < 1e-15, "q̂ · ∂q̇/∂ω_{c} = {s}");
        }
        eprintln!("t {t_mid}: block vs dense: largest column difference {worst:.2e}, {noisy} columns beyond 1e-5 (dense rounding)");
    }
}

/// `gripopt bench free --json`: at rtol 1e-5 the block and the dense Jacobian and the
/// switching method all land within 1e-3 of the rtol-1e-10 reference on every output, with
/// the reference's verdict; the block rows make fewer full evaluations than the dense, the
/// switching method fewer Jacobians; bad rtols are refused.
#[test]
fn bench_free_rows() {
    let bin = env!("CARGO_BIN_EXE_gripopt");
    let problem = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml");
    let dir = std::env::temp_dir().join(format!("gripopt-bench-free-{}", std::process::id()));
    let out = std::process::Command::new(bin)
        .args(["bench", "free", problem, "--rtols", "1e-5", "--reps", "1", "--json", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
    let rows = v["rows"].as_array().unwrap();
    let labels: Vec<(&str, &str)> =
        rows.iter().map(|r| (r["method"].as_str().unwrap(), r["jacobian"].as_str().unwrap())).collect();
    assert_eq!(labels, [("radau5", "blocks"), ("auto", "blocks"), ("radau5", "dense")], "{v}");
    for r in rows {
        assert!(r["err_max"].as_f64().unwrap() < 1e-3, "{r}");
        assert_eq!(r["verdict_same"], true, "{r}");
    }
    let (blocks, auto, dense) = (&rows[0], &rows[1], &rows[2]);
    assert!(blocks["rhs"].as_u64().unwrap() < dense["rhs"].as_u64().unwrap(), "{v}");
    assert_eq!(dense["jac_block_evals"], 0);
    // the switching method leaves the fingers' approach to the explicit method
    assert!(auto["jac"].as_u64().unwrap() < blocks["jac"].as_u64().unwrap(), "{v}");
    assert!(dir.join("free_work_precision.csv").exists() && dir.join("free_work_precision.svg").exists());
    let _ = std::fs::remove_dir_all(&dir);
    let bad = std::process::Command::new(bin).args(["bench", "free", problem, "--rtols", "2"]).output().unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--rtols"), "{}", String::from_utf8_lossy(&bad.stderr));
}
