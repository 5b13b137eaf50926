//! The stiffness-switching method (`Method::Auto`: Dormand–Prince 5(4) where accuracy holds
//! its steps, RADAU5 where stability would): against RADAU5 at a tight tolerance, on the
//! nominal grasp, seeded designs of the box and the nominal free scene.

use crate::common::{bottle, nominal, random_design};
use gripopt::eval::{stage_kinematics, stage_statics};
use gripopt::params::{Design, Problem};
use gripopt::sim::{
    diagnostic_grasp, simulate, Controls, DynamicsResult, EventKind, EventNote, FreeResult, FreeSetup, Integration,
    Method, SceneSpec, Sink,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::Path;

fn grasp(x: &Design, rtol: f64, m: Method) -> Option<DynamicsResult> {
    let s = bottle().scene;
    let k = stage_kinematics(x, &s).ok()?;
    let st = stage_statics(&k.finger, &s).ok()?;
    Some(diagnostic_grasp(&k.finger, &s, &st, &Integration::new(rtol, rtol * 1e-3, 5_000_000).with_method(m)))
}

fn rel(a: Option<f64>, b: Option<f64>) -> f64 {
    match (a, b) {
        (Some(a), Some(b)) => (a / b - 1.0).abs(),
        (None, None) => 0.0,
        _ => f64::INFINITY,
    }
}

/// At rtol 1e-7 the switching method gives the reference's verdict, t_stab and impact energy
/// (RADAU5 at 1e-10) on the nominal design and on 12 seeded designs that pass stage 2, and
/// RADAU5 takes over in most of them (Jacobians were computed).
#[test]
fn auto_agrees_with_a_tight_radau_reference() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut designs = vec![nominal()];
    while designs.len() < 13 {
        let x = random_design(&mut rng);
        if grasp(&x, 1e-4, Method::Radau5).is_some() {
            designs.push(x);
        }
    }
    let (mut implicit_used, mut worst_t, mut worst_e) = (0, 0.0f64, 0.0f64);
    for x in &designs {
        let reference = grasp(x, 1e-10, Method::Radau5).unwrap();
        let auto = grasp(x, 1e-7, Method::Auto).unwrap();
        assert_eq!(auto.outcome, reference.outcome, "{x:?}");
        let et = rel(auto.t_stab, reference.t_stab);
        let ee = rel(auto.first.map(|f| f.impact.e_cyl), reference.first.map(|f| f.impact.e_cyl));
        (worst_t, worst_e) = (worst_t.max(et), worst_e.max(ee));
        if auto.stats.jac > 0 {
            implicit_used += 1;
        }
    }
    // t_stab is a threshold crossing of a decaying oscillation: where the decay is slow, an
    // error of the phase moves it by up to ~1e-4 (RADAU5 at the default 1e-6: 5.5e-5 here)
    assert!(worst_t < 3e-4 && worst_e < 1e-5, "t_stab {worst_t:e}, E_cyl {worst_e:e}");
    assert!(implicit_used >= 10, "RADAU5 took over in {implicit_used} of 13 grasps");
}

/// The nominal free scene with the switching method at rtol 1e-7 measures the object's
/// largest displacement and tilt as RADAU5 at 1e-10 does (within 1e-4 and 1e-3 relative).
#[test]
fn auto_free_scene_matches_the_reference() {
    let s = bottle().scene;
    let k = stage_kinematics(&nominal(), &s).unwrap();
    let st = stage_statics(&k.finger, &s).unwrap();
    let spec = SceneSpec::Free { x_off: 0.0, setup: FreeSetup::default(), t_end: None };
    let run = |rtol: f64, m: Method| {
        let o = Integration::new(rtol, rtol * 1e-3, 50_000_000).with_method(m);
        *simulate(&k.finger, &s, &st, &spec, &o, &Controls::DIAGNOSTIC, &mut ()).free().expect("free scene")
    };
    let (reference, auto) = (run(1e-10, Method::Radau5), run(1e-7, Method::Auto));
    assert_eq!((auto.moved, auto.toppled), (reference.moved, reference.toppled));
    let d = (auto.object_max_displacement / reference.object_max_displacement - 1.0).abs();
    let tilt = (auto.object_max_tilt_deg / reference.object_max_tilt_deg - 1.0).abs();
    assert!(d < 1e-4 && tilt < 1e-3, "displacement {d:e}, tilt {tilt:e}");
    assert!(auto.stats.jac > 0, "RADAU5 took over on the ground contacts");
}

/// MODEL.md §13's hard cases with the switching method: a 100× stiffer contact, an impact
/// at zero velocity at R = R_open, the finger closing on nothing
/// into the parallel singularity, and a tiny step budget each end as RADAU5 at a tight
/// tolerance says, with finite values and bounded work.
#[test]
fn hard_cases_end_as_the_reference_says() {
    use crate::common::scene;
    use gripopt::sim::DynOutcome;
    let run = |x: &Design, s: &gripopt::params::SceneParams, o: &Integration, ctl: &Controls| {
        let k = stage_kinematics(x, s).unwrap();
        let st = stage_statics(&k.finger, s).unwrap();
        *simulate(&k.finger, s, &st, &SceneSpec::Centred, o, ctl, &mut ()).grasp().expect("a grasp")
    };
    let auto = |rtol: f64| Integration::new(rtol, rtol * 1e-3, 2_000_000).with_method(Method::Auto);
    let reference = Integration::new(1e-10, 1e-13, 2_000_000);
    let d = Controls::DIAGNOSTIC;
    // stiff contact: the same verdict and t_stab in bounded work (the explicit method takes
    // the 10× faster contact oscillation in ~1 000 steps; RADAU5 at 1e-10 takes 14 566)
    let mut s = scene();
    s.contact.k_contact = 5.3e10;
    let (a, r) = (run(&nominal(), &s, &auto(1e-7), &d), run(&nominal(), &s, &reference, &d));
    assert_eq!(a.outcome, r.outcome);
    assert!(rel(a.t_stab, r.t_stab) < 3e-4 && a.stats.steps < 20_000, "{:?}", a.stats);
    // R = R_open: contact at 0⁺, a gentle impact
    let mut s = scene();
    s.object.radius = s.hand.r_open;
    let x = Design { t22: 0.05, ..nominal() };
    let (a, r) = (run(&x, &s, &auto(1e-7), &d), run(&x, &s, &reference, &d));
    assert_eq!((a.outcome, a.impact_ok), (r.outcome, r.impact_ok));
    assert!(a.first.expect("first contact").t < 1e-4);
    // closing on nothing into the singularity: the abort, at the reference's time
    let mut s = scene();
    s.criteria.t_max = 0.05;
    let x = crate::common::singular_closing_design();
    let free = Controls { contacts: false, ..Controls::DIAGNOSTIC };
    let (a, r) = (run(&x, &s, &auto(1e-7), &free), run(&x, &s, &reference, &free));
    assert_eq!((a.outcome, r.outcome), (DynOutcome::Singular, DynOutcome::Singular));
    assert!((a.t_end / r.t_end - 1.0).abs() < 1e-6, "{} against {}", a.t_end, r.t_end);
    // a budget of 50 steps ends in a clean discard
    let tiny = Integration::new(1e-8, 1e-11, 50).with_method(Method::Auto);
    let a = run(&nominal(), &scene(), &tiny, &d);
    assert_eq!(a.outcome, DynOutcome::StepBudget);
}

// ---- a free-scene case where auto flipped the verdict at a tighter tolerance (session 36) ----
// The object rests against the palm at δ = 0 (MODEL.md §14.1); the first finger onset was
// located on Dormand–Prince's continuous extension at a state with the palm's δ = +1.2e-16 and
// δ̇ = −2.6e-11 (both rounding noise), which §8.7's rule for the other contacts (onset needs
// δ̇ > 0) left without an onset while its event function was already past zero: the palm then
// took no force until a later event's sweep, and the object moved 0.99 mm instead of 1.11 mm
// (feasible instead of "moved"). The driver now gives such a stranded contact its onset at
// once. The reference here is RADAU5 at the same rtol and problem tolerances, which is
// converged: RADAU5 at 1e-7 and 1e-9 agree to 1.7e-7 relative on the displacement and
// 1.5e-11 s on the first ground release.

/// The reviewer's design (problems/can.toml).
const DESIGN: &str = "l21=0.04700809104375605,b=0.06675656712156379,t22=0.04427807742924113,\
                      r=0.3398467492859208,p=0.3804499789300759,psi_deg=124.38439802740419";

/// Keeps the time of the first ground point's release (a contact of index ≥ 5 with its
/// memory set before the event) and the palm's onsets.
#[derive(Default)]
struct Releases {
    first_ground_release: Option<f64>,
    palm_onsets: u32,
}

/// The free scene at x_off = 2 mm with `method` at `rtol` (the file's atol and step budget,
/// as `gripopt simulate` runs it), to `t_end` (None: t_obs).
fn free(method: Method, rtol: f64, t_end: Option<f64>) -> (FreeResult, Releases) {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/can.toml");
    let p = Problem::load(file).expect("can.toml loads");
    let p = p.in_scene(gripopt::SceneChoice::free(Some(0.002)), Path::new(file)).expect("free:0.002");
    let x = Design::parse_assignments(DESIGN).expect("design");
    let s = &p.scene;
    let k = stage_kinematics(&x, s).expect("kinematics");
    let st = stage_statics(&k.finger, s).expect("statics");
    let integ = Integration::new(rtol, p.solver.atol, p.solver.max_steps).with_method(method);
    let spec = match SceneSpec::of(&s.setup) {
        SceneSpec::Free { x_off, setup, .. } => SceneSpec::Free { x_off, setup, t_end },
        other => panic!("not the free scene: {other:?}"),
    };
    let mut sink = Releases::default();
    let r = *simulate(&k.finger, s, &st, &spec, &integ, &Controls::DIAGNOSTIC, &mut sink).free().expect("free scene");
    (r, sink)
}

/// The first ground release (Contact(14) at 7.6304935e-3 s, located within ~1e-11 s of each
/// other by RADAU5 at 1e-7 and 1e-9, Dormand–Prince and auto at 1e-7) comes 30 µs after the
/// first finger onset pushed the object onto the palm, so it measures whether the palm took
/// its load: auto at 1e-9 located it at 7.630482e-3 (1.1e-8 s early) without its palm onset.
/// 1e-10 s is ten times the spread of the converged runs.
/// Origin: session 36, auto's stranded palm onset in the free scene (see the section comment above).
#[test]
fn auto_locates_the_first_ground_release_as_radau5() {
    let t_end = Some(8e-3);
    let (_, reference) = free(Method::Radau5, 1e-9, t_end);
    let (_, auto) = free(Method::Auto, 1e-9, t_end);
    let (tr, ta) = (reference.first_ground_release.unwrap(), auto.first_ground_release.unwrap());
    assert!((7.6304e-3..7.6306e-3).contains(&tr), "RADAU5's first ground release at {tr:e}");
    assert!((ta - tr).abs() < 1e-10, "auto {ta:.12e} against RADAU5 {tr:.12e}: {:.2e} s", ta - tr);
    assert!(auto.palm_onsets >= 1, "the palm had its onset before the release");
}

/// The verdict and the largest displacement over the whole observation: auto at 1e-9 as
/// RADAU5 at 1e-9 ("moved", 1.1079 mm; the defect gave 0.9911 mm and "feasible"). 1e-5 relative:
/// RADAU5 at 1e-7 and 1e-9 differ by 1.7e-7, auto and RADAU5 at 1e-9 by 6.4e-8, and over a grid
/// of 143 free runs around this design auto and RADAU5 at 1e-9 by at most 1.9e-5 (docs/benchmarks.md,
/// "Stiffness switching"); the defect is a 1e-1 effect.
/// Origin: session 36, auto's stranded palm onset in the free scene (see the section comment above).
#[test]
fn auto_gives_radau5_verdict_on_the_free_scene() {
    let (reference, _) = free(Method::Radau5, 1e-9, None);
    let (auto, _) = free(Method::Auto, 1e-9, None);
    assert!(reference.moved, "RADAU5: the object moves {:e} m", reference.object_max_displacement);
    assert_eq!((auto.moved, auto.toppled), (reference.moved, reference.toppled));
    let d = (auto.object_max_displacement / reference.object_max_displacement - 1.0).abs();
    assert!(
        d < 1e-5,
        "displacement {:e} against {:e} m ({d:e})",
        auto.object_max_displacement,
        reference.object_max_displacement
    );
}

impl Sink for Releases {
    fn event(&mut self, e: &EventNote<'_>) {
        let EventKind::Contact(k) = e.kind else { return };
        let k = usize::from(k);
        if k >= 5 && e.memories[k].active && self.first_ground_release.is_none() {
            self.first_ground_release = Some(e.t);
        }
        if k == 4 && !e.memories[k].active {
            self.palm_onsets += 1;
        }
    }
}
