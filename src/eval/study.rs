//! The study: what a problem asks of every design. Its objects, its scenarios (the unit of
//! evaluation: an object under one set of inputs, in one scene), and how a design's scenarios
//! are folded into its verdict — every scenario must pass (a single-object problem: one
//! object, one nominal scenario, the 1 × 1 study) or each object must stay with probability
//! ≥ p_min (a robust problem's chance constraint over drawn scenarios). Evaluating a design
//! is `start` (stages 0–2 once per design and object, `scenario.rs`) → `run_scenario` (stage
//! 3 in the scenario's scene) → `fold` (stopping rule, aggregation, verdict, `fold.rs`) → the
//! one [`Record`](super::Record), whose 1 × 1 form is the flat record.

use super::stages::EvalOptions;
use crate::params::{Problem, Robust, Scenario, SceneParams, STREAM_OPTIMISE};

/// One object of a study: the cylinder and grip torque every scenario of it starts from.
#[derive(Debug, Clone)]
pub struct StudyObject {
    /// Its name (`[[robust.objects]] name`); None for a single-object problem's `[object]`,
    /// whose discards name no object.
    pub name: Option<String>,
    /// Its nominal scene (its cylinder and grip torque; stage 2 runs in it).
    pub scene: SceneParams,
}

/// One scenario of a study: its inputs and the scene stage 3 runs in.
#[derive(Debug, Clone)]
pub struct StudyScenario {
    /// Which object and draw, and the value of every uncertain input.
    pub scenario: Scenario,
    /// The scene of its stage 3.
    pub scene: SceneParams,
    /// Its inputs differ from its object's nominal ones, so its static grasp is recomputed
    /// at its own torque and friction (the spring kept); false: stage 2's grasp is its own.
    pub drawn: bool,
}

/// How a design's scenarios decide its verdict.
#[derive(Debug, Clone)]
pub enum Constraint {
    /// Every scenario must pass: a single-object problem (one scenario), its verdict that
    /// scenario's.
    AllPass,
    /// Per object, P(stay) ≥ p_min over its scenarios, objectives aggregated as the section
    /// says (a robust problem's `[robust]`).
    Chance(Box<Robust>),
}

/// What a problem asks of every design (see the module's documentation).
#[derive(Debug, Clone)]
pub struct Study {
    /// The problem's own scene (the hand, the spring's sizing torque, the contact laws, the
    /// criteria; its objects' scenes are built from it).
    pub base: SceneParams,
    /// The objects (at least one).
    pub objects: Vec<StudyObject>,
    /// K: scenarios per object.
    pub k: usize,
    /// Every scenario, object-major (index o·K + k).
    pub scenarios: Vec<StudyScenario>,
    /// How the scenarios decide the verdict.
    pub constraint: Constraint,
    /// Stop a design's scenarios once its verdict is known (the constraint cannot be met).
    pub early_stop: bool,
}

impl Study {
    /// The study a run of problem `p` evaluates its designs on through `opts`' stages: a
    /// robust problem's optimisation scenarios when stage 3 runs, otherwise the 1 × 1 study of
    /// its scene and `[object]` (a robust problem's stages 0–2 alone concern its reference
    /// object, as `gripopt evaluate --static-only` reports them).
    pub fn of(p: &Problem, opts: &EvalOptions) -> Self {
        match &p.robust {
            Some(r) if opts.dynamics => Self::drawn(p, r, STREAM_OPTIMISE, r.count(STREAM_OPTIMISE), r.early_stop),
            _ => Self::single(p.scene.clone()),
        }
    }

    /// The 1 × 1 study of scene `scene`: its object, one scenario at its nominal inputs, in
    /// its own scene kind, all-pass.
    pub fn single(scene: SceneParams) -> Self {
        let scenario = Scenario { object: 0, k: 0, stream: STREAM_OPTIMISE, values: Robust::nominal_values(&scene) };
        Study {
            objects: vec![StudyObject { name: None, scene: scene.clone() }],
            k: 1,
            scenarios: vec![StudyScenario { scenario, scene: scene.clone(), drawn: false }],
            constraint: Constraint::AllPass,
            early_stop: false,
            base: scene,
        }
    }

    /// The study of robust problem `p` (section `r`) with `n` scenarios per object drawn from
    /// `stream` (the optimisation's, or `verify`'s out-of-sample stream with every scenario
    /// run): its objects at their nominal inputs, the chance constraint.
    pub fn drawn(p: &Problem, r: &Robust, stream: u64, n: usize, early_stop: bool) -> Self {
        let base = p.scene.clone();
        let objects = r
            .objects
            .iter()
            .map(|o| {
                let mut s = base.clone();
                s.object = o.object;
                s.hand.tau = o.tau;
                StudyObject { name: Some(o.name.clone()), scene: s }
            })
            .collect();
        let scenarios = (0..r.objects.len())
            .flat_map(|o| (0..n).map(move |k| (o, k)))
            .map(|(o, k)| {
                let scenario = r.scenario(&base, o, k, stream);
                let scene = scenario.scene(&base, &r.objects[o]);
                StudyScenario { scenario, scene, drawn: true }
            })
            .collect();
        Study { base, objects, k: n, scenarios, constraint: Constraint::Chance(Box::new(r.clone())), early_stop }
    }

    /// Number of objects.
    pub fn objects(&self) -> usize {
        self.objects.len()
    }

    /// Scenario k of object o.
    pub fn scenario(&self, o: usize, k: usize) -> &StudyScenario {
        &self.scenarios[o * self.k + k]
    }

    /// The order scenarios are run in: round k visits object 0's, 1's, … scenario k.
    pub fn sequence(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.k).flat_map(move |k| (0..self.objects()).map(move |o| (o, k)))
    }

    /// Scenarios in all.
    pub fn planned(&self) -> usize {
        self.k * self.objects()
    }

    /// The robust section of a chance-constrained study.
    pub fn chance(&self) -> Option<&Robust> {
        match &self.constraint {
            Constraint::Chance(r) => Some(r),
            Constraint::AllPass => None,
        }
    }

    /// True for the 1 × 1 study: its verdict and record are its one scenario's evaluation.
    pub fn is_single(&self) -> bool {
        self.chance().is_none() && self.planned() == 1
    }

    /// Failures an object may have while its constraint can still hold over K scenarios.
    pub fn failures_allowed(&self) -> usize {
        self.chance().map_or(0, |r| r.failures_allowed(self.k))
    }

    /// The name of object `o` as a discard names it (None: a single-object problem's).
    pub fn object_name(&self, o: usize) -> Option<&str> {
        self.objects.get(o).and_then(|ob| ob.name.as_deref())
    }
}
