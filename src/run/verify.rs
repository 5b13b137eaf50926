//! `verify`: does the thesis's prediction hold? Every design of a run's front (or every
//! feasible design, or a seeded sample of the problem's box) is simulated in the free scene
//! (MODEL.md §14) by the one simulation call: the centred scene's impact (§9.1) and force
//! (§9.3) criteria *predict* whether the object moves, the free scene *measures* it
//! (§14.4's verdict). The rows ([`VerifyRow`], serialised as verify.csv's columns);
//! [`Confusion`] counts prediction against measurement. The command itself (folder, lock,
//! files) is `verify_run`.

use super::checkpoint::Checkpoint;
use super::folder::read_table;
use super::gripper::GripperInfo;
use super::info::RunInfo;
use super::outputs::DesignRow;
use crate::cells::{line, Floats};
use crate::error::{Error, Result};
use crate::eval::{evaluate, EvalOptions, Study};
use crate::optim::Individual;
use crate::params::{Design, DesignParameters, Problem};
use crate::record::{keep_poses, ProblemUse, VerifyMeasure};
use crate::sim::{FreeEnd, PoseSample};
use rand::SeedableRng;
use rayon::prelude::*;
use serde::{Serialize, Serializer};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The verify results of a run's designs.
pub const VERIFY_FILE: &str = "verify.csv";
/// The verify results of a sample of the problem's box (`--sample`).
pub const VERIFY_SAMPLE_FILE: &str = "verify_sample.csv";

/// Which designs to verify.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VerifySource {
    /// The run's front: the checkpoint's feasible non-dominated designs (those of `pareto.csv`).
    Pareto,
    /// Every feasible design of the checkpoint's population and archive (those of
    /// `population.csv` and `archive.csv`; by id, once).
    All,
    /// `n` designs drawn from the problem's bounds with seed `seed` that pass stage 2.
    Sample {
        /// How many designs.
        n: usize,
        /// Seed of the draw (ChaCha8).
        seed: u64,
    },
}

/// One verified design: the centred scene's prediction and the free scene's measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct VerifyRow {
    /// Design id (the run's id, or the draw's index for a sample).
    pub id: u64,
    /// The design.
    pub design: Design,
    /// E_cyl / E_lim at the centred first contact (None: no contact).
    pub impact_ratio: Option<f64>,
    /// §9.1's E_trans and E_rot at the centred first contact (J).
    pub e_trans_rot: Option<(f64, f64)>,
    /// The smaller of the filtered (over the grasp) and static force margins (N).
    pub force_margin: f64,
    /// The centred grasp reached stability (t_stab found).
    pub stable: bool,
    /// The centred criteria predict motion: impact ratio > 1 or force margin < 0.
    pub predicted_moves: bool,
    /// Largest horizontal displacement of G in the free scene (m).
    pub max_displacement: f64,
    /// Largest tilt in the free scene (°).
    pub max_tilt_deg: f64,
    /// Peak translational and rotational kinetic energy of the object during the first contact (J).
    pub peak_e: (f64, f64),
    /// §14.4's verdict: the object moved more than Δx_max or θ_max (None: not observed,
    /// the free scene ended before t_obs).
    pub moved: Option<bool>,
    /// Tilt above 45° (None: not observed).
    pub toppled: Option<bool>,
    /// No phalanx in contact at t_end (None: not observed).
    pub escaped: Option<bool>,
    /// A phalanx met the rim or a face.
    pub rim_contact: bool,
    /// How the free scene ended (observed to t_obs, or why it stopped early).
    pub end: FreeEnd,
    /// Time the free scene reached (s; t_obs unless it ended early).
    pub t_end: f64,
}

impl VerifyRow {
    /// The free scene ran to t_obs, so the motion was observed.
    pub fn observed(&self) -> bool {
        self.end == FreeEnd::Observed
    }
    /// Prediction and measurement agree (None: not observed).
    pub fn agrees(&self) -> Option<bool> {
        self.moved.map(|m| self.predicted_moves == m)
    }
    /// Object peak E_trans and E_rot over §9.1's (None: no centred contact, or not observed).
    pub fn energy_ratios(&self) -> (Option<f64>, Option<f64>) {
        let e = self.e_trans_rot.filter(|_| self.observed());
        (e.map(|e| self.peak_e.0 / e.0), e.map(|e| self.peak_e.1 / e.1))
    }
    /// `free_end` as verify.csv writes it: "t_obs", or why the free scene stopped early.
    pub fn free_end(&self) -> String {
        self.end.to_string()
    }
    /// The row's prediction and measurement, as verify.csv and `/verify` write them.
    pub fn measure(&self) -> VerifyMeasure {
        let (peak_e_trans_ratio, peak_e_rot_ratio) = self.energy_ratios();
        VerifyMeasure {
            impact_ratio: self.impact_ratio,
            e_trans: self.e_trans_rot.map(|e| e.0),
            e_rot: self.e_trans_rot.map(|e| e.1),
            force_margin: self.force_margin,
            stable: self.stable,
            predicted_moves: self.predicted_moves,
            object_max_displacement: self.max_displacement,
            object_max_tilt_deg: self.max_tilt_deg,
            object_peak_e_trans: self.peak_e.0,
            object_peak_e_rot: self.peak_e.1,
            free_end: self.end,
            moved: self.moved,
            toppled: self.toppled,
            escaped: self.escaped,
            rim_contact: self.rim_contact,
            agrees: self.agrees(),
            peak_e_trans_ratio,
            peak_e_rot_ratio,
        }
    }
}

/// The 2×2 table: predicted moves (rows) against measured moved (columns).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Confusion {
    /// Predicted to move, moved.
    pub pred_moved: usize,
    /// Predicted to move, stayed (the criteria too strict).
    pub pred_stayed: usize,
    /// Predicted to stay, moved (the criteria too lax).
    pub ok_moved: usize,
    /// Predicted to stay, stayed.
    pub ok_stayed: usize,
    /// Rows left out: the free scene ended before t_obs (nothing observed).
    pub not_observed: usize,
}

impl Confusion {
    /// Count `rows`.
    pub fn of(rows: &[VerifyRow]) -> Self {
        let mut c = Confusion::default();
        for r in rows {
            match (r.predicted_moves, r.moved) {
                (_, None) => c.not_observed += 1,
                (true, Some(true)) => c.pred_moved += 1,
                (true, Some(false)) => c.pred_stayed += 1,
                (false, Some(true)) => c.ok_moved += 1,
                (false, Some(false)) => c.ok_stayed += 1,
            }
        }
        c
    }
    /// Rows counted in the table (observed ones).
    pub fn total(&self) -> usize {
        self.pred_moved + self.pred_stayed + self.ok_moved + self.ok_stayed
    }
}

/// What `verify` did.
#[derive(Debug, Clone)]
pub struct VerifySummary {
    /// The file written.
    pub file: PathBuf,
    /// The rows, in id order.
    pub rows: Vec<VerifyRow>,
    /// Prediction against measurement.
    pub confusion: Confusion,
    /// Ids of designs that stages 0–2 discarded on re-evaluation (left out of the CSV).
    pub skipped: Vec<u64>,
    /// Median of peak object E_trans / §9.1's E_trans and of E_rot / E_rot (None: no rows with contact).
    pub median_energy_ratio: Option<(f64, f64)>,
    /// The MCAP recording written (verify.mcap or verify_sample.mcap), unless recording was off.
    pub recording: Option<PathBuf>,
    /// Designs verified (found in the file, or drawn and passing stages 0–2 for a sample).
    pub designs: usize,
}

/// Verify one design of problem `p` (whose scene must be set up as the free scene to
/// measure: kind, x_off). None when stages 0–2 discard it. The same options as
/// `gripopt simulate --scene free` (diagnostic mode, the problem's solver settings).
pub fn verify_design(p: &Problem, id: u64, x: &Design) -> Option<VerifyRow> {
    verify_design_poses(p, id, x, None).map(|(r, _)| r)
}

/// [`verify_design`], with the free scene's poses to record every `scene_dt` of simulated
/// time (and the last; `record::keep_poses`) when `scene_dt` is given (recording does not
/// change the results).
pub fn verify_design_poses(
    p: &Problem,
    id: u64,
    x: &Design,
    scene_dt: Option<f64>,
) -> Option<(VerifyRow, Vec<PoseSample>)> {
    // the 1 × 1 study of the problem's object in the free scene, diagnosed to its end
    let mut scene = p.scene.clone();
    scene.setup = scene.setup.to_free();
    let study = Study::single(scene);
    let opts = EvalOptions::diagnostic(p);
    let start = study.start(x);
    if !start.passed() {
        return None;
    }
    let mut all_poses: Vec<PoseSample> = vec![];
    let (_, ev) = if scene_dt.is_some() {
        study.run_scenario(&start, 0, 0, &opts, &mut all_poses)
    } else {
        study.run_scenario(&start, 0, 0, &opts, &mut ())
    };
    let poses = scene_dt.map(|dt| keep_poses(&all_poses, dt)).unwrap_or_default();
    Some((row_of(id, x, &ev)?, poses))
}

/// The verify row of design `x`'s free-kind evaluation `ev` (None: the free scene did not
/// run); also a robust scenario's (`gripopt replay --scenario`).
pub(crate) fn row_of(id: u64, x: &Design, ev: &crate::eval::Evaluation) -> Option<VerifyRow> {
    let (c, f) = (ev.dynamics?, ev.free?);
    let impact_ratio = c.first.map(|fc| fc.impact.e_cyl / fc.impact.e_lim);
    let force_margin = c.min_force_margin.min(c.static_force_margin);
    let seen = |v: bool| f.end.observed().then_some(v);
    let row = VerifyRow {
        id,
        design: *x,
        impact_ratio,
        e_trans_rot: c.first.map(|fc| (fc.impact.e_trans, fc.impact.e_rot)),
        force_margin,
        stable: c.t_stab.is_some(),
        predicted_moves: impact_ratio.is_some_and(|r| r > 1.0) || force_margin < 0.0,
        max_displacement: f.object_max_displacement,
        max_tilt_deg: f.object_max_tilt_deg,
        peak_e: (f.object_peak_e_trans, f.object_peak_e_rot),
        moved: seen(f.moved),
        toppled: seen(f.toppled),
        escaped: seen(f.escaped),
        rim_contact: f.rim_contact,
        end: f.end,
        t_end: f.t_end,
    };
    Some(row)
}

/// The (id, design) rows of a design CSV (pareto.csv, population.csv, archive.csv; `#`
/// lines skipped), feasible ones only; read with the csv crate into [`DesignRow`]s.
pub fn read_design_csv(path: &Path) -> Result<Vec<(u64, Design)>> {
    Ok(read_design_rows(path)?
        .into_iter()
        .filter(|r| r.feasible)
        .map(|r| (r.id, Design::from_array(&r.parameters())))
        .collect())
}

/// Every row of a design CSV (errors name the file and line; see [`read_table`]).
pub fn read_design_rows(path: &Path) -> Result<Vec<DesignRow>> {
    let rows: Vec<DesignRow> = read_table(path)?;
    for row in &rows {
        if let Some(k) = row.parameters().iter().position(|v| !v.is_finite()) {
            let message = format!("design {}: {} is not a finite number", row.id, crate::params::DESIGN_NAMES[k]);
            return Err(Error::RunDir { path: path.to_path_buf(), message });
        }
    }
    Ok(rows)
}

/// The run's designs to verify, taken from its checkpoint (the run's state, not the CSV views
/// of it, which a user may have edited): with `all` every feasible design of the population
/// and the archive (population.csv's and archive.csv's feasible rows), otherwise the
/// reported front (pareto.csv's: [`super::reported_front`]); each with the generation that
/// created it, in id order. `path`: the checkpoint's file, named by the error for a design
/// that has not six values.
pub fn checkpoint_designs(cp: &Checkpoint<GripperInfo>, all: bool, path: &Path) -> Result<Vec<(u64, u64, Design)>> {
    let chosen: Vec<&Individual<GripperInfo>> = if all {
        let archive = cp.archive.iter().flat_map(|a| a.members.iter());
        cp.state.population.iter().chain(archive).filter(|i| i.eval.cv.is_feasible()).collect()
    } else {
        super::archive::reported_front(&cp.state, cp.archive.as_ref())
    };
    let mut m = BTreeMap::new();
    for ind in chosen {
        let x: &[f64; 6] = ind.x.as_slice().try_into().map_err(|_| Error::Checkpoint {
            file: path.to_path_buf(),
            message: format!("design {}: field `x` has {} values, expected 6", ind.id, ind.x.len()),
        })?;
        m.entry(ind.id).or_insert((ind.generation, Design::from_array(x)));
    }
    Ok(m.into_iter().map(|(id, (g, x))| (id, g, x)).collect())
}

/// Which run state a `verify.csv` checked (its `# run:` line).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VerifiedGeneration {
    /// The completed generations of the run when it was verified.
    pub generation: u64,
    /// The checkpoint's content checksum then.
    pub checkpoint_sha256: String,
}

/// The `# run:` line of verify.csv and verify_robust.csv: the run state a verification
/// checked (the completed generations, the checkpoint's content checksum) and the problem
/// files used; [`RunFolder::verified_generation`] reads it back.
pub(super) fn run_line(run_id: &str, state: &VerifiedGeneration, used: &[&ProblemUse]) -> String {
    let problems: Vec<String> = used.iter().map(|p| format!("{} {}", p.file, p.sha256)).collect();
    format!(
        "# run: {}, generation {}, checkpoint sha256 {}; problem sha256: {}\n",
        if run_id.is_empty() { "run" } else { run_id },
        state.generation,
        state.checkpoint_sha256,
        problems.join(", ")
    )
}

/// The checkpoint file of a run folder (the state `verify` checks).
pub(crate) const CHECKPOINT_FILE: &str = "checkpoint.json";

/// The run state a verify checks: the folder's checkpoint, loaded and its checksum verified.
pub(crate) struct CheckedState {
    pub(crate) checkpoint: Checkpoint<GripperInfo>,
    path: PathBuf,
    sha256: String,
}

impl CheckedState {
    /// Load `dir`'s checkpoint (a missing one is an error naming it).
    pub(crate) fn load(dir: &Path, info: &RunInfo) -> Result<Self> {
        let path = dir.join(CHECKPOINT_FILE);
        // absent; anything else there (a pipe, a folder) is refused by the read, naming it
        if std::fs::symlink_metadata(&path).is_err() {
            let message = match info.completed_generations {
                0 => "missing: the run has not completed its first generation; nothing to verify yet".to_string(),
                g => format!("missing, but run.json records {g} completed generations: verify takes the run's designs from its checkpoint; restore checkpoint.json (e.g. from a backup)"),
            };
            return Err(Error::RunDir { path, message });
        }
        let (checkpoint, sha256) = Checkpoint::load_with_sha256(&path)?;
        // run.json names this checkpoint (not an older or newer one restored beside it)
        super::attribution::check_run_json(dir, info, checkpoint.state.generation, &sha256)?;
        Ok(CheckedState { checkpoint, path, sha256 })
    }

    /// Its designs to verify (see [`checkpoint_designs`]).
    pub(crate) fn designs(&self, all: bool) -> Result<Vec<(u64, u64, Design)>> {
        checkpoint_designs(&self.checkpoint, all, &self.path)
    }

    /// The front as pareto.csv's rows (built from the same individuals pareto.csv is written
    /// from), in id order.
    pub(crate) fn front_rows(&self) -> Vec<DesignRow> {
        let cp = &self.checkpoint;
        super::archive::reported_front(&cp.state, cp.archive.as_ref())
            .into_iter()
            .map(|i| DesignRow::of(i, Some(0)))
            .collect()
    }

    /// The state as verify.csv's `# run:` line names it.
    pub(crate) fn attribution(&self) -> VerifiedGeneration {
        VerifiedGeneration { generation: self.checkpoint.state.generation, checkpoint_sha256: self.sha256.clone() }
    }
}

/// `n` designs drawn from `p`'s bounds (ChaCha8 with `seed`, in draw order) that pass stages
/// 0–2; ids are the draw's index. Deterministic, independent of the thread count.
pub fn sample_designs(p: &Problem, n: usize, seed: u64) -> Vec<(u64, Design)> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    let mut drawn = 0u64;
    while out.len() < n {
        let batch: Vec<(u64, Design)> =
            (0..(2 * n).max(16)).map(|k| (drawn + k as u64, p.bounds.sample(&mut rng))).collect();
        drawn += batch.len() as u64;
        let pass: Vec<bool> = batch
            .par_iter()
            .map(|(_, x)| evaluate(x, &p.scene, &EvalOptions::statics_only()).statics.is_some())
            .collect();
        out.extend(batch.into_iter().zip(pass).filter(|(_, ok)| *ok).map(|(d, _)| d).take(n - out.len()));
        if drawn > 1000 * n as u64 + 10_000 {
            break; // a box where almost nothing passes stage 2: return what was found
        }
    }
    out
}

/// Verify `designs` in parallel (in the current rayon pool), calling `tick` after each;
/// rows in the order given, designs discarded at stages 0–2 left out.
pub fn verify_designs(p: &Problem, designs: &[(u64, Design)], tick: &(dyn Fn() + Sync)) -> Vec<VerifyRow> {
    verify_designs_poses(p, designs, None, tick).into_iter().map(|(r, _)| r).collect()
}

/// [`verify_designs`] with each row's poses to record (see [`verify_design_poses`]).
pub fn verify_designs_poses(
    p: &Problem,
    designs: &[(u64, Design)],
    scene_dt: Option<f64>,
    tick: &(dyn Fn() + Sync),
) -> Vec<(VerifyRow, Vec<PoseSample>)> {
    designs
        .par_iter()
        .map(|(id, x)| {
            let r = verify_design_poses(p, *id, x, scene_dt);
            tick();
            r
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// A verified design as verify.csv writes it: its columns, in order (the id, the design's,
/// then [`VerifyMeasure`]'s: the centred prediction, the free scene's measurement, and their
/// comparison).
#[derive(Serialize)]
struct VerifyCells {
    id: u64,
    #[serde(flatten)]
    design: DesignParameters,
    #[serde(flatten)]
    measure: VerifyMeasure,
}

impl Serialize for VerifyRow {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let design = DesignParameters::from_array(&self.design.to_array());
        VerifyCells { id: self.id, design, measure: self.measure() }.serialize(s)
    }
}

/// verify.csv's columns, in order, with their units (`-`: none; the `# units:` line).
pub const VERIFY_COLUMNS: [(&str, &str); 25] = [
    ("id", "-"),
    ("l21", "m"),
    ("b", "m"),
    ("t22", "m"),
    ("r", "-"),
    ("p", "-"),
    ("psi_deg", "deg"),
    ("impact_ratio", "-"),
    ("e_trans", "J"),
    ("e_rot", "J"),
    ("force_margin", "N"),
    ("stable", "bool"),
    ("predicted_moves", "bool"),
    ("object_max_displacement", "m"),
    ("object_max_tilt_deg", "deg"),
    ("object_peak_e_trans", "J"),
    ("object_peak_e_rot", "J"),
    ("free_end", "text"),
    ("moved", "bool"),
    ("toppled", "bool"),
    ("escaped", "bool"),
    ("rim_contact", "bool"),
    ("agrees", "bool"),
    ("peak_e_trans_ratio", "-"),
    ("peak_e_rot_ratio", "-"),
];

/// verify.csv's text (`#` header lines, then one row per design).
pub fn verify_csv(rows: &[VerifyRow], x_off: f64) -> String {
    let mut s = String::from("# gripopt verify.csv: the centred criteria's prediction (impact ratio E_cyl/E_lim > 1 or force margin < 0 → predicted_moves) against the free scene's measured motion (MODEL.md §14.4)\n");
    let _ = writeln!(s, "# scene free, x_off {x_off} m; units: lengths m, psi_deg and object_max_tilt_deg deg, energies J, force_margin N; *_ratio = object peak / §9.1 value");
    s.push_str("# free_end: t_obs, or why the free scene stopped early (then moved, toppled, escaped, agrees and the ratios are empty: nothing observed)\n");
    if let Some(first) = rows.first() {
        s.push_str(&crate::cells::header(first).join(","));
        s.push('\n');
    }
    for r in rows {
        s.push_str(&line(r, Floats::Display));
    }
    s
}
