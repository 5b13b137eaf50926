//! Session 37 hostile pass fixes: the offset scene says why it could not start, the bench
//! names the scene it times and the stream it failed to write, `--reps`, the median and
//! `--scene`'s parsing say what they do, and `bench free --out` keeps earlier files.

use crate::common::bottle;
use gripopt::eval::{stage_kinematics, stage_statics, Cause};
use gripopt::model::{grasp_at, OffsetFailure};
use gripopt::params::SceneKind;
use gripopt::sim::{Controls, Integration};

/// The nominal design's verdict in the offset scene at `x_off`.
fn offset_verdict(x_off: f64) -> gripopt::eval::Verdict {
    let p = bottle();
    let integ = Integration::from_solver(&p.solver);
    let sim = gripopt::simulate(&p, &p.nominal, Some((SceneKind::Offset, Some(x_off))), &integ, &Controls::PIPELINE)
        .expect("stages 0–2 pass");
    sim.record.record.verdict
}

/// (1) Past the nominal's largest offset the static grasp at the offset does not exist (the
/// model's own `grasp_at` says which finger and why): the verdict names that failure with
/// its own cause, not "compliant static equilibrium not found". Where the grasp exists the
/// verdict is not this cause.
#[test]
fn an_offset_past_the_grasp_says_which_finger_has_no_closed_pose() {
    let p = bottle();
    let kin = stage_kinematics(&p.nominal, &p.scene).unwrap();
    let st = stage_statics(&kin.finger, &p.scene).unwrap();
    for x_off in [0.005, -0.006, 0.01] {
        let why = grasp_at(&kin.finger, &p.scene, st.tau_s0, x_off).expect_err("no grasp this far off");
        let OffsetFailure::NoClosedPose(j, e) = why else { panic!("{why:?}") };
        let v = offset_verdict(x_off);
        assert_eq!(v.failed_stage, Some(3));
        assert_eq!(v.cause, Some(Cause::NoOffsetGrasp), "{v:?}");
        assert_eq!(Cause::NoOffsetGrasp.as_str(), "no_offset_grasp");
        let reason = v.reason.unwrap();
        assert!(!reason.contains("equilibrium"), "{reason}");
        assert!(reason.contains(&format!("finger {}: {}", j + 1, e.reason())), "{reason}");
        assert!(reason.contains(&format!("x_off = {:.3} mm", x_off * 1e3)), "{reason}");
    }
    for x_off in [0.0, 0.002, 0.004] {
        assert!(grasp_at(&kin.finger, &p.scene, st.tau_s0, x_off).is_ok());
        assert_ne!(offset_verdict(x_off).cause, Some(Cause::NoOffsetGrasp));
    }
}
