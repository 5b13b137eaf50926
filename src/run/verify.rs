//! `verify`: does the thesis's prediction hold? Every design of a run's front (or every
//! feasible design, or a seeded sample of the problem's box) is simulated twice: in the
//! centred scene, whose impact (§9.1) and force (§9.3) criteria *predict* whether the object
//! moves, and in the free scene (MODEL.md §14), which *measures* it (§14.4's verdict). The
//! rows go to `RUN_DIR/verify.csv` (or `verify_sample.csv`), written atomically under the
//! run folder's lock; [`Confusion`] counts prediction against measurement.

use super::lock::RunLock;
use super::verify_rec::VerifyRecording;
use crate::eval::{evaluate, EvalOptions, FreeEnd, FreeMeasure};
use crate::fsutil::write_atomic;
use crate::params::{Design, Problem, SceneKind, DESIGN_NAMES};
use crate::record::keep_poses;
use crate::sim::{simulate, Controls, Integration, PoseSample, SceneSpec};
use crate::{Error, Result};
use rand::SeedableRng;
use rayon::prelude::*;
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
    /// The designs of `pareto.csv`.
    Pareto,
    /// Every feasible design of `population.csv` and `archive.csv` (by id, once).
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
    let s = &p.scene;
    let ev = evaluate(x, s, &EvalOptions::statics_only());
    let (k, st) = (ev.kin?, ev.statics?);
    let o = Integration::from_solver(&p.solver);
    let c = *simulate(&k.finger, s, &st, &SceneSpec::Centred, &o, &Controls::DIAGNOSTIC, &mut ()).grasp()?;
    let mut all_poses: Vec<PoseSample> = vec![];
    let spec = SceneSpec::free(s.setup.x_off);
    let f = if scene_dt.is_some() {
        *simulate(&k.finger, s, &st, &spec, &o, &Controls::DIAGNOSTIC, &mut all_poses).free()?
    } else {
        *simulate(&k.finger, s, &st, &spec, &o, &Controls::DIAGNOSTIC, &mut ()).free()?
    };
    let poses = scene_dt.map(|dt| keep_poses(&all_poses, dt)).unwrap_or_default();
    let impact_ratio = c.first.map(|fc| fc.impact.e_cyl / fc.impact.e_lim);
    let force_margin = c.min_force_margin.min(c.static_force_margin);
    let end = FreeMeasure::from_result(&f, s.setup.x_off).end;
    let seen = |v: bool| (end == FreeEnd::Observed).then_some(v);
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
        end,
        t_end: f.t_end,
    };
    Some((row, poses))
}

/// Split one CSV line into fields (double-quoted fields with `""` escapes).
fn split_csv(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(ch) = chars.next() {
        match (ch, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            _ => cur.push(ch),
        }
    }
    out.push(cur);
    out
}

/// The (id, design) rows of a design CSV (pareto.csv, population.csv, archive.csv; `#`
/// lines skipped), feasible ones only.
pub fn read_design_csv(path: &Path) -> Result<Vec<(u64, Design)>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, "cannot read the run's design table", e))?;
    let bad = |line: usize, m: String| Error::RunDir { path: path.to_path_buf(), message: format!("line {line}: {m}") };
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.starts_with('#') && !l.trim().is_empty());
    let Some((hl, header)) = lines.next() else { return Err(bad(1, "no header row".into())) };
    let cols = split_csv(header);
    let col =
        |name: &str| cols.iter().position(|c| c == name).ok_or_else(|| bad(hl + 1, format!("no column `{name}`")));
    let id_c = col("id")?;
    let feas_c = col("feasible")?;
    let xs: Vec<usize> = DESIGN_NAMES.iter().map(|n| col(n)).collect::<Result<_>>()?;
    let mut out = Vec::new();
    for (i, l) in lines {
        let f = split_csv(l);
        let get = |c: usize| f.get(c).map(String::as_str).ok_or_else(|| bad(i + 1, format!("only {} fields", f.len())));
        if get(feas_c)? != "true" {
            continue;
        }
        let id: u64 = get(id_c)?
            .parse()
            .map_err(|_| bad(i + 1, format!("id `{}` is not an integer", get(id_c).unwrap_or(""))))?;
        let mut a = [0.0; 6];
        for (k, &c) in xs.iter().enumerate() {
            let v = get(c)?;
            a[k] = v
                .parse()
                .ok()
                .filter(|x: &f64| x.is_finite())
                .ok_or_else(|| bad(i + 1, format!("{} = `{v}` is not a number", DESIGN_NAMES[k])))?;
        }
        out.push((id, Design::from_array(&a)));
    }
    Ok(out)
}

/// The run's designs to verify, in id order.
pub fn run_designs(dir: &Path, all: bool) -> Result<Vec<(u64, Design)>> {
    let files: &[&str] = if all { &["population.csv", "archive.csv"] } else { &["pareto.csv"] };
    let mut m = BTreeMap::new();
    for f in files {
        let path = dir.join(f);
        if !path.is_file() {
            return Err(Error::RunDir {
                path,
                message: "missing: the run has not written its first generation's results".into(),
            });
        }
        for (id, x) in read_design_csv(&path)? {
            m.entry(id).or_insert(x);
        }
    }
    Ok(m.into_iter().collect())
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

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// A CSV field: quoted when it holds a comma or a quote.
fn field(v: &str) -> String {
    if v.contains([',', '"']) {
        format!("\"{}\"", v.replace('"', "\"\""))
    } else {
        v.to_string()
    }
}

/// Columns of verify.csv.
pub const VERIFY_COLUMNS: [&str; 25] = [
    "id",
    "l21",
    "b",
    "t22",
    "r",
    "p",
    "psi_deg",
    "impact_ratio",
    "e_trans",
    "e_rot",
    "force_margin",
    "stable",
    "predicted_moves",
    "object_max_displacement",
    "object_max_tilt_deg",
    "object_peak_e_trans",
    "object_peak_e_rot",
    "free_end",
    "moved",
    "toppled",
    "escaped",
    "rim_contact",
    "agrees",
    "peak_e_trans_ratio",
    "peak_e_rot_ratio",
];

/// verify.csv's text (`#` header lines, then one row per design).
pub fn verify_csv(rows: &[VerifyRow], x_off: f64) -> String {
    let mut s = String::from("# gripopt verify.csv: the centred criteria's prediction (impact ratio E_cyl/E_lim > 1 or force margin < 0 → predicted_moves) against the free scene's measured motion (MODEL.md §14.4)\n");
    let _ = writeln!(s, "# scene free, x_off {x_off} m; units: lengths m, psi_deg and object_max_tilt_deg deg, energies J, force_margin N; *_ratio = object peak / §9.1 value");
    s.push_str("# free_end: t_obs, or why the free scene stopped early (then moved, toppled, escaped, agrees and the ratios are empty: nothing observed)\n");
    s.push_str(&VERIFY_COLUMNS.join(","));
    s.push('\n');
    for r in rows {
        let a = r.design.to_array();
        let (et, er) = r.energy_ratios();
        let (pt, pr) = (r.e_trans_rot.map(|e| e.0), r.e_trans_rot.map(|e| e.1));
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.id,
            a[0],
            a[1],
            a[2],
            a[3],
            a[4],
            a[5],
            opt(r.impact_ratio),
            opt(pt),
            opt(pr),
            r.force_margin,
            r.stable,
            r.predicted_moves,
            r.max_displacement,
            r.max_tilt_deg,
            r.peak_e.0,
            r.peak_e.1,
            field(&r.free_end()),
            opt(r.moved),
            opt(r.toppled),
            opt(r.escaped),
            r.rim_contact,
            opt(r.agrees()),
            opt(et),
            opt(er),
        );
    }
    s
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) })
}

/// Verify run folder `dir`: checks it is a run (run.json, problem.toml), takes its lock,
/// loads the run's problem, switches it to the free scene (at `x_off`, default the
/// problem's), simulates the designs of `source` and writes the CSV atomically; with
/// `record`, also the MCAP recording of the free scene (verify.mcap or verify_sample.mcap,
/// with the Foxglove layout `foxglove-verify-layout.json`).
pub fn verify(
    dir: &Path,
    source: VerifySource,
    x_off: Option<f64>,
    record: bool,
    tick_len: &dyn Fn(usize),
    tick: &(dyn Fn() + Sync),
) -> Result<VerifySummary> {
    if !dir.is_dir() {
        return Err(Error::RunDir { path: dir.to_path_buf(), message: "not a folder".into() });
    }
    for f in ["run.json", "problem.toml"] {
        if !dir.join(f).is_file() {
            return Err(Error::RunDir {
                path: dir.to_path_buf(),
                message: format!("not a run folder (no {f}); give a folder written by `gripopt optimise`"),
            });
        }
    }
    let _lock = RunLock::acquire(dir)?;
    let mut p = Problem::load(dir.join("problem.toml"))?;
    if p.scene.env.g_eq != 0.0 {
        return Err(Error::RunDir {
            path: dir.join("problem.toml"),
            message: "environment.g_eq must be 0 for the free scene (hand horizontal, MODEL.md §14.1)".into(),
        });
    }
    p.scene.setup.kind = SceneKind::Free;
    if let Some(x) = x_off {
        p.scene.setup.x_off = x;
    }
    let (designs, file) = match source {
        VerifySource::Pareto => (run_designs(dir, false)?, VERIFY_FILE),
        VerifySource::All => (run_designs(dir, true)?, VERIFY_FILE),
        VerifySource::Sample { n, seed } => (sample_designs(&p, n, seed), VERIFY_SAMPLE_FILE),
    };
    if designs.is_empty() {
        let message = match source {
            VerifySource::Sample { n, seed } => format!("--sample {n} --seed {seed}: no drawn design passes stages 0–2 of problem.toml; nothing to verify, nothing written"),
            _ => "no feasible design to verify; nothing written".into(),
        };
        let path = match source {
            VerifySource::Pareto => dir.join("pareto.csv"),
            VerifySource::All => dir.join("population.csv"),
            VerifySource::Sample { .. } => dir.join("problem.toml"),
        };
        return Err(Error::RunDir { path, message });
    }
    tick_len(designs.len());
    let rec = if record { Some(VerifyRecording::new(dir, &source)?) } else { None };
    let with_poses = verify_designs_poses(&p, &designs, rec.as_ref().map(|r| r.opts.scene_dt), tick);
    let rows: Vec<VerifyRow> = with_poses.iter().map(|(r, _)| r.clone()).collect();
    let skipped: Vec<u64> = designs.iter().map(|d| d.0).filter(|id| !rows.iter().any(|r| r.id == *id)).collect();
    if rows.is_empty() {
        return Err(Error::RunDir {
            path: dir.to_path_buf(),
            message: format!(
                "all {} designs are discarded at stages 0–2 on re-evaluation; nothing to verify, nothing written",
                designs.len()
            ),
        });
    }
    let file = dir.join(file);
    write_atomic(&file, verify_csv(&rows, p.scene.setup.x_off).as_bytes())?;
    let recording = match rec {
        Some(r) => Some(r.write(&p, with_poses)?),
        None => None,
    };
    let et: Vec<f64> = rows.iter().filter_map(|r| r.energy_ratios().0).collect();
    let er: Vec<f64> = rows.iter().filter_map(|r| r.energy_ratios().1).collect();
    let median_energy_ratio = median(et).zip(median(er));
    Ok(VerifySummary {
        file,
        skipped,
        confusion: Confusion::of(&rows),
        rows,
        median_energy_ratio,
        recording,
        designs: designs.len(),
    })
}
