//! Simulating one design in a scene (diagnostic mode: to stability, or the free scene to its
//! end): `gripopt simulate`, `replay --scene`, Python's `Problem.simulate`. One way for every
//! object: a design on the problem's reference `[object]` is simulated on the 1 × 1 study of
//! its scene, on one of a robust problem's objects on the problem's study (the object's
//! cylinder and grip torque, the spring sized at `[hand] tau`, as the robust evaluation's
//! stage 2 has them).

use crate::error::{Error, Result};
use crate::eval::{EvalOptions, Record, SimulationRecord, Study};
use crate::params::{limit, Design, Problem, SceneChoice};
use crate::sim::{Controls, Integration, Method, PoseSample, SceneSpec, Sink, Trajectory};
use std::path::Path;

/// What to simulate a design in, and how.
#[derive(Debug, Clone)]
pub struct SimulateRequest {
    /// The scene (None: the problem's `[scene]`).
    pub scene: Option<SceneChoice>,
    /// One of a robust problem's objects by name (None: the reference `[object]`).
    pub object: Option<String>,
    /// Relative tolerance (None: the problem's `solver.rtol`).
    pub rtol: Option<f64>,
    /// Integration method (None: the problem's `solver.method`).
    pub method: Option<Method>,
    /// Contacts with the object (false: the linkage closes on nothing; the centred scene
    /// only).
    pub contacts: bool,
}

impl Default for SimulateRequest {
    fn default() -> Self {
        SimulateRequest { scene: None, object: None, rtol: None, method: None, contacts: true }
    }
}

/// A simulation's outcome (its samples went to the caller's sink).
#[derive(Debug, Clone)]
pub struct Simulated {
    /// The record (the JSON of `gripopt simulate --json`) with its method.
    pub record: SimulationRecord,
    /// The robust object simulated (None: the reference `[object]`).
    pub object: Option<String>,
    /// The relative tolerance it ran with.
    pub rtol: f64,
}

/// A design simulated in a scene: its record, and the samples of the simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulation {
    /// The record (the JSON of `gripopt simulate --json`).
    pub record: SimulationRecord,
    /// The robust object simulated (None: the reference `[object]`).
    pub object: Option<String>,
    /// The grasp's samples (the centred or offset scene; in the free scene, the centred
    /// scene's prediction).
    pub trajectory: Trajectory,
    /// The free scene's object poses (empty in the other scenes).
    pub poses: Vec<PoseSample>,
}

/// Why a robust object named `name` cannot be picked in problem `p`.
#[derive(Debug, Clone, PartialEq)]
pub enum NoSuchObject {
    /// The problem has no `[robust]`: its one object is its `[object]`.
    NotRobust,
    /// No object of that name; the problem's objects, by name.
    Unknown(Vec<String>),
}

/// The index of the robust object `name` among `[[robust.objects]]` of `p`.
pub fn object_index(p: &Problem, name: &str) -> std::result::Result<usize, NoSuchObject> {
    let robust = p.robust.as_ref().ok_or(NoSuchObject::NotRobust)?;
    robust
        .objects
        .iter()
        .position(|o| o.name == name)
        .ok_or_else(|| NoSuchObject::Unknown(robust.objects.iter().map(|o| o.name.clone()).collect()))
}

/// Whether `rtol` is an admissible relative tolerance (the range of `solver.rtol`): Err the
/// rule it breaks.
pub fn check_rtol(rtol: f64) -> std::result::Result<(), String> {
    limit("solver.rtol").check(rtol).map(|_| ())
}

/// `problem` in `req`'s scene (None: as it is), checked as a problem file's `[scene]` is.
fn in_scene(problem: &Problem, req: &SimulateRequest) -> Result<Problem> {
    match req.scene {
        Some(s) => problem.in_scene(s, Path::new("the simulation's scene")),
        None => Ok(problem.clone()),
    }
}

/// The numerics of `req` for problem `p`: an input error where its tolerance or method does
/// not fit (a front end words its own argument first: `--rtol`, `rtol =`).
fn integration(p: &Problem, req: &SimulateRequest) -> Result<Integration> {
    let s = &p.solver;
    let rtol = req.rtol.unwrap_or(s.rtol);
    check_rtol(rtol).map_err(|rule| Error::Input(format!("rtol {rtol}: {rule}")))?;
    let method = req.method.unwrap_or(s.method);
    method.check_atol(s.atol).map_err(|rule| {
        Error::Input(format!("method `{method}`: the problem's solver.atol {}: {rule}", crate::params::fmt_num(s.atol)))
    })?;
    // the problem's own settings (the default's scaling included) unless a method is given
    Ok(Integration::overridden(s, req.method, req.rtol))
}

/// Simulate `design` of `problem` as `req` asks, diagnostic mode, every sample and event to
/// `sink`: its record. Stages 0–2 must pass (on the object simulated); a scene the problem
/// cannot have (the free scene needs g_eq = 0), a robust object it does not have, or
/// `contacts` off outside the centred scene are input errors.
pub fn simulate_into<K: Sink + ?Sized>(
    problem: &Problem,
    design: &Design,
    req: &SimulateRequest,
    sink: &mut K,
) -> Result<Simulated> {
    let p = in_scene(problem, req)?;
    let kind = p.scene.setup.kind;
    if !req.contacts && !kind.runs_without_contacts() {
        return Err(Error::Input(format!(
            "--no-contact: only the centred scene runs without contacts (the {kind} scene needs the object)"
        )));
    }
    let integ = integration(&p, req)?;
    let ctl = Controls { contacts: req.contacts, ..Controls::DIAGNOSTIC };
    let spec = SceneSpec::of(&p.scene.setup);
    // the reference object on its 1 × 1 study; a robust object on the problem's study
    let (study, o) = match &req.object {
        None => (Study::single(p.scene.clone()), 0),
        Some(name) => {
            let o = object_index(&p, name).map_err(|why| {
                Error::Input(match why {
                    NoSuchObject::NotRobust => format!("object {name:?}: the problem is not robust (no [robust])"),
                    NoSuchObject::Unknown(names) => {
                        format!("object {name:?}: no such robust object (the problem's: {})", names.join(", "))
                    }
                })
            })?;
            (Study::of(&p, &EvalOptions::full(&p)), o)
        }
    };
    let ev = study.simulate_object(design, o, &spec, &integ, &ctl, sink);
    if ev.scene.is_none() {
        let d = ev.discard.expect("a design that did not reach its scene was discarded");
        let on = req.object.as_ref().map(|n| format!(" on object {n}")).unwrap_or_default();
        return Err(Error::Input(format!(
            "the design is discarded{on} at stage {} ({}); the grasp needs stages 0–2",
            d.stage, d.reason
        )));
    }
    let record = SimulationRecord { record: Record::from_eval(&ev), method: integ.method };
    Ok(Simulated { record, object: req.object.clone(), rtol: integ.rtol })
}

/// [`simulate_into`] keeping every sample: the record, the grasp's samples and the free
/// scene's poses.
pub fn simulate(problem: &Problem, design: &Design, req: &SimulateRequest) -> Result<Simulation> {
    let (mut trajectory, mut poses) = (Trajectory::default(), Vec::new());
    let s = simulate_into(problem, design, req, &mut (&mut trajectory, &mut poses))?;
    Ok(Simulation { record: s.record, object: s.object, trajectory, poses })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{pose_values, sample_values, POSE_COLUMNS, SAMPLE_COLUMNS};

    fn bottle() -> Problem {
        Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap()
    }

    /// A simulation's samples follow their columns, in the grasp and in the free scene.
    #[test]
    fn trajectory_values_follow_their_columns() {
        let p = bottle();
        let s = simulate(&p, &p.nominal, &SimulateRequest::default()).unwrap();
        let x = s.trajectory.samples[s.trajectory.samples.len() / 2];
        let v = sample_values(&x);
        let at = |name: &str| v[SAMPLE_COLUMNS.iter().position(|c| c.0 == name).unwrap()];
        assert_eq!([at("t"), at("q21"), at("fn_2"), at("energy_excess")], [x.t, x.q[1], x.normal[1], x.energy_excess]);
        let free = SimulateRequest { scene: Some(SceneChoice::free(None)), ..Default::default() };
        let f = simulate(&p, &p.nominal, &free).unwrap();
        let q = f.poses[f.poses.len() / 2];
        let v = pose_values(&q);
        let at = |name: &str| v[POSE_COLUMNS.iter().position(|c| c.0 == name).unwrap()];
        assert_eq!(
            [at("gz"), at("qw"), at("tilt_deg"), at("q21_2")],
            [q.g[2], q.q[0], q.tilt.to_degrees(), q.fingers[3]]
        );
    }

    /// `v` without its wall-clock seconds.
    fn untimed(v: serde_json::Value) -> serde_json::Value {
        match v {
            serde_json::Value::Object(m) => {
                m.into_iter().filter(|(k, _)| k != "cpu_s").map(|(k, v)| (k, untimed(v))).collect()
            }
            v => v,
        }
    }

    /// The reference object's simulation is `eval::simulate`'s (stages 0–2, then stage 3 in
    /// the scene), bit for bit.
    #[test]
    fn the_reference_object_is_simulated_as_eval_simulates() {
        let p = bottle();
        for scene in [None, Some(SceneChoice::parse("offset:0.002").unwrap())] {
            let req = SimulateRequest { scene, ..Default::default() };
            let s = simulate(&p, &p.nominal, &req).unwrap();
            let ps = in_scene(&p, &req).unwrap();
            let integ = Integration::from_solver(&ps.solver);
            let mut t = Trajectory::default();
            let spec = SceneSpec::of(&ps.scene.setup);
            let ev = crate::eval::simulate(&p.nominal, &ps.scene, &spec, &integ, &Controls::DIAGNOSTIC, &mut t);
            assert_eq!(
                untimed(serde_json::to_value(Record::from_eval(&ev)).unwrap()),
                untimed(serde_json::to_value(&s.record.record).unwrap())
            );
            assert_eq!(t, s.trajectory);
        }
    }
}
