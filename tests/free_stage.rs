//! Stage 3 of a free-kind problem (docs/scenes.md): the free object's measured motion, not
//! the impact and force criteria, decides. Each verdict is checked against independent
//! simulations through the library (the centred scene in diagnostic mode, the free scene
//! itself) and against the physics (§14.4's limits; an offset object is pushed back toward
//! the centre), and an optimisation of a free-kind problem runs end to end.

use crate::common::{bottle, nominal};
use gripopt::eval::{evaluate_full, stage_kinematics, stage_statics, Reason, Record};
use gripopt::params::{Problem, SceneKind};
use gripopt::sim::{
    diagnostic_grasp as simulate_grasp, simulate, Controls, DynOutcome, FreeResult, Integration, SceneSpec,
};
use std::path::PathBuf;

/// bottle-1l.toml with `[scene] kind = "free"` and the given x_off (written under target/).
fn free_problem(x_off: f64, name: &str) -> (Problem, PathBuf) {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap();
    let text = text.replacen("kind = \"centred\"", "kind = \"free\"", 1).replacen(
        "x_off = 0.0 ",
        &format!("x_off = {x_off:e} "),
        1,
    );
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/free-stage-tests"));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    let p = Problem::load(&path).unwrap();
    assert_eq!(p.scene.setup.kind, SceneKind::Free);
    assert_eq!(p.scene.setup.x_off, x_off);
    (p, path)
}

/// The nominal design fails the impact criterion in the centred scene (E_cyl 5.83 mJ >
/// 3.94 mJ, MODEL.md's nominal numbers), so a centred-kind problem discards it at stage 3;
/// in the free kind the object is measured to barely move, so it is feasible, with the
/// centred grasp's t_stab as its objective and the measurement of the free scene itself.
#[test]
fn nominal_feasible_in_free_kind_discarded_in_centred_kind() {
    let centred = evaluate_full(&bottle(), &nominal());
    let d = centred.discard.expect("centred kind: the nominal is discarded");
    assert_eq!((d.stage, d.reason), (3, Reason::Dynamics(DynOutcome::ImpactEnergy)));

    let (p, _) = free_problem(0.0, "nominal");
    let ev = evaluate_full(&p, &nominal());
    assert!(ev.feasible(), "free kind: {:?}", ev.discard);
    let s = &p.scene;
    let k = stage_kinematics(&nominal(), s).unwrap();
    let st = stage_statics(&k.finger, s).unwrap();
    let o = Integration::from_solver(&p.solver);
    // the prediction: the centred grasp in diagnostic mode (impact criterion fails, stable)
    let c = simulate_grasp(&k.finger, s, &st, &o);
    let fc = c.first.unwrap();
    assert!(
        fc.impact.e_cyl > fc.impact.e_lim && (fc.impact.e_cyl - 5.83e-3).abs() < 0.01e-3,
        "E_cyl {}",
        fc.impact.e_cyl
    );
    assert_eq!(ev.objectives()[3], c.t_stab.unwrap(), "t_stab is the centred grasp's");
    // the measurement: the free scene, and §14.4's limits
    let f = free_scene(&k.finger, s, &st, 0.0, &o, &mut ());
    let m = ev.free.expect("the free scene ran");
    assert_eq!(m.object_max_displacement, f.object_max_displacement);
    assert_eq!(m.object_max_tilt_deg, f.object_max_tilt_deg);
    assert!(m.object_max_displacement < s.criteria.dx_max && m.object_max_tilt_deg < s.criteria.theta_max.to_degrees());
    assert!(!m.moved && !m.toppled && !m.escaped);

    // the record: the §14.4 keys beside the (informative) impact values, only in the free kind
    let r = serde_json::to_value(Record::from_eval(&ev)).unwrap();
    assert_eq!(r["free_scene"]["object_max_displacement"].as_f64(), Some(f.object_max_displacement));
    assert_eq!(r["free_scene"]["moved"], serde_json::json!(false));
    assert_eq!(r["e_cyl"].as_f64(), Some(fc.impact.e_cyl));
    assert_eq!(r["feasible"], serde_json::json!(true));
    let rc = serde_json::to_value(Record::from_eval(&centred)).unwrap();
    assert!(rc.get("free_scene").is_none() && rc.get("moved").is_none(), "no free keys in the centred kind");
}

/// With the object 4 mm off centre the hand pushes it back toward the centre (the static
/// recentring force exceeds the ground friction, docs/scenes.md): it slides about 2 mm,
/// more than Δx_max, so the free kind discards the design with the free scene's reason
/// and the violation max(d/Δx_max, tilt/θ_max) − 1 of the free scene's own result.
#[test]
fn offset_object_moves_and_is_discarded() {
    let x_off = 4e-3;
    let (p, _) = free_problem(x_off, "offset4");
    let ev = evaluate_full(&p, &nominal());
    let d = ev.discard.expect("discarded");
    assert_eq!(d.stage, 3);
    assert!(matches!(d.reason, Reason::ObjectMoved(_)), "{}", d.reason);
    assert!(d.reason.to_string().starts_with("free scene: the object does not barely move"), "{}", d.reason);

    let s = &p.scene;
    let k = stage_kinematics(&nominal(), s).unwrap();
    let st = stage_statics(&k.finger, s).unwrap();
    let o = Integration::from_solver(&p.solver);
    let mut poses = vec![];
    let f = free_scene(&k.finger, s, &st, x_off, &o, &mut poses);
    assert!(f.moved && f.object_max_displacement > 1.5 * s.criteria.dx_max, "{}", f.object_max_displacement);
    let v = (f.object_max_displacement / s.criteria.dx_max)
        .max(f.object_max_tilt_deg / s.criteria.theta_max.to_degrees())
        - 1.0;
    assert!((d.violation - v).abs() <= 1e-12 * v, "violation {} vs {v}", d.violation);
    // pushed back toward the centre: G's x moves from x_off toward 0
    let (g0, g1) = (poses.first().unwrap().g[0], poses.last().unwrap().g[0]);
    assert_eq!(g0, x_off);
    assert!(g1 < x_off - s.criteria.dx_max && g1 > -x_off, "G_x {g0} → {g1}");
    // the prediction (the centred scene) does not depend on x_off
    assert_eq!(
        ev.dynamics.unwrap().first,
        evaluate_full(&free_problem(0.0, "offset4-ref").0, &nominal()).dynamics.unwrap().first
    );
}

/// `optimise` of a free-kind problem with a tiny population runs end to end (recording
/// included, under target/mcap-check/ for the independent MCAP check), and every feasible
/// design of its front was measured to barely move.
#[test]
fn optimise_free_kind_end_to_end() {
    let (_, path) = free_problem(0.0, "optimise");
    let base = std::env::var_os("GRIPOPT_MCAP_CHECK_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/mcap-check")));
    let out = base.join("free-kind-optimise");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&base).unwrap();
    let spec = gripopt::run::RunSpec {
        problem_path: path,
        out: out.clone(),
        pop: 8,
        generations: 2,
        seed: 16,
        threads: Some(2),
        record: gripopt::record::RecordOptions::default(),
    };
    let s = gripopt::run::optimise(&spec).unwrap();
    assert_eq!((s.generations, s.evaluations), (2, 16));
    let p = Problem::load(out.join("problem.toml")).unwrap();
    assert_eq!(p.scene.setup.kind, SceneKind::Free);
    let front = gripopt::run::read_design_csv(&out.join("pareto.csv")).unwrap();
    assert!(!front.is_empty(), "seed 16 has feasible designs on its front");
    for (id, x) in front {
        let ev = evaluate_full(&p, &x);
        assert!(ev.feasible(), "design {id}");
        let m = ev.free.unwrap_or_else(|| panic!("design {id}: no free measurement"));
        assert!(m.object_max_displacement <= p.scene.criteria.dx_max && !m.moved, "design {id}");
        // the recording's /designs record carries the same measured motion
        let rec = gripopt::record::read_design(&out, id).unwrap();
        let f = rec.record.free_scene.as_ref().expect("a free-kind design's record has the free scene");
        assert_eq!(f.object_max_displacement, Some(m.object_max_displacement), "design {id}: {f:?}");
        assert_eq!(f.moved, Some(false), "design {id}: {f:?}");
    }
}

/// The free scene of finger `f` at `x_off` through the one simulation call, its poses to `sink`.
fn free_scene(
    f: &gripopt::model::Finger,
    s: &gripopt::params::SceneParams,
    st: &gripopt::eval::StaticsResult,
    x_off: f64,
    o: &Integration,
    sink: &mut dyn gripopt::sim::Sink,
) -> FreeResult {
    *simulate(f, s, st, &SceneSpec::free(x_off), o, &Controls::DIAGNOSTIC, sink).free().expect("the free scene")
}
