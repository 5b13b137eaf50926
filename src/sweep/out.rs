//! Where a sweep writes: `sweep --out DIR` takes a new or empty folder, or one holding only
//! an earlier sweep's files, which the new sweep replaces (none left beside the new ones).
//! An earlier sweep's files are known from its sweep.csv: its first line is gripopt's title
//! and its `# files:` line lists every file that sweep wrote (sweep.csv is written first,
//! listing the files planned, so a sweep stopped halfway leaves nothing unlisted; once
//! every file is written, its `# sha256:` line records their content). Never into a run
//! folder, never over a file a sweep did not write (a user's own sweep.csv); an earlier
//! sweep's file whose content is no longer what that sweep wrote is set aside, never
//! removed. The folder is locked while a sweep writes it.
//!
//! The units of sweep.csv's columns: the varied names' (their fields' units) and the
//! evaluation record's keys' ([`record_unit`]); the numeric keys a sweep's stage computes,
//! which `--y` and `--color` may plot ([`plot_keys`]).

use super::spec::{Stage, SweepSpec, ARRAY_KEYS};
use crate::cells::{cells, Floats};
use crate::error::{Error, Result};
use crate::eval::{Evaluation, Record};
use std::path::{Path, PathBuf};

/// The sweep's table.
pub const SWEEP_FILE: &str = "sweep.csv";
/// The bisected boundaries.
pub const BOUNDARIES_FILE: &str = "boundaries.csv";
/// The title of sweep.csv (its first line starts with it).
pub const SWEEP_TITLE: &str = "# gripopt sweep.csv";

/// A file an earlier sweep in the folder wrote (its sweep.csv's `# files:` line lists it).
#[derive(Debug, Clone, PartialEq)]
pub struct EarlierFile {
    /// The file.
    pub path: PathBuf,
    /// Its content is what the earlier sweep wrote (the SHA-256 its sweep.csv's `# sha256:`
    /// line records; sweep.csv itself, gripopt's by its title): the new sweep may replace or
    /// remove it. Otherwise (edited since, or the earlier sweep stopped before it recorded
    /// the hashes) it is set aside, never removed or overwritten.
    pub proven: bool,
}

/// Take the sweep output folder `dir`: create it, hold its lock (a held one is refused,
/// naming the holder), and check it ([`check_out_folder`]). The lock is released when the
/// returned guard drops.
pub fn open_out_folder(dir: &Path) -> Result<(crate::fsutil::lock::RunLock, Vec<EarlierFile>)> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::RunDir { path: dir.to_path_buf(), message: "--out: not a folder".into() });
    }
    let new = !dir.exists();
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, "cannot create the output folder", e))?;
    let checked = crate::fsutil::lock::RunLock::acquire(dir).and_then(|lock| Ok((lock, check_out_folder(dir)?)));
    if checked.is_err() && new {
        let _ = std::fs::remove_dir(dir); // made here, only if still empty
    }
    checked
}

/// The files an earlier sweep in `dir` wrote (its sweep.csv's `# files:` line), which the
/// new one replaces; an error naming what is not a sweep's: a run folder, a file no
/// sweep.csv lists, a sweep.csv gripopt did not write. The folder's lock file and its
/// `set-aside/` folder are the sweep's own.
pub fn check_out_folder(dir: &Path) -> Result<Vec<EarlierFile>> {
    if !dir.exists() {
        return Ok(vec![]);
    }
    let bad = |message: String| Err(Error::RunDir { path: dir.to_path_buf(), message });
    if !dir.is_dir() {
        return bad("--out: not a folder".into());
    }
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, "cannot list the output folder", e))?;
    let own =
        |n: &str| n == crate::fsutil::lock::LOCK_FILE || (n == crate::fsutil::SET_ASIDE_DIR && dir.join(n).is_dir());
    let mut names: Vec<String> =
        rd.flatten().map(|e| e.file_name().to_string_lossy().to_string()).filter(|n| !own(n)).collect();
    names.sort();
    // a lock file alone marks no run: the sweep's own lock holds this folder
    let run_mark = ["run.json", "checkpoint.json", "recording"]
        .into_iter()
        .find(|f| std::fs::symlink_metadata(dir.join(f)).is_ok());
    if let Some(f) = run_mark {
        return bad(format!(
            "--out: a gripopt run folder (it holds {f}); a sweep writes into a folder of its own, never into a run's"
        ));
    }
    if names.is_empty() {
        return Ok(vec![]);
    }
    let listed = listed_files(&dir.join(SWEEP_FILE))?;
    let is_listed = |n: &String| listed.iter().any(|(f, _)| f == n);
    let foreign: Vec<&String> = names.iter().filter(|n| !is_listed(n) && !n.ends_with(".tmp")).collect();
    if let Some(first) = foreign.first() {
        let why = if listed.is_empty() {
            "it holds no sweep.csv written by gripopt"
        } else {
            "not listed in its sweep.csv's `# files:` line"
        };
        return Err(Error::RunDir {
            path: dir.join(first),
            message: format!("not written by a gripopt sweep ({why}): a sweep never overwrites or leaves beside its own what it did not write; give --out a new or empty folder, or one of an earlier sweep"),
        });
    }
    let mut earlier = vec![];
    for n in names.iter().filter(|n| is_listed(n)) {
        let path = dir.join(n);
        let sha = listed.iter().find(|(f, _)| f == n).and_then(|(_, h)| h.as_deref());
        let proven = std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file())
            && (n == SWEEP_FILE
                || sha.is_some_and(|h| {
                    crate::fsutil::read_regular(&path, crate::fsutil::caps::TABLE)
                        .is_ok_and(|b| crate::fsutil::sha256_hex(&b) == h)
                }));
        earlier.push(EarlierFile { path, proven });
    }
    // temporary files a killed sweep left: only a name attributes them
    earlier.extend(
        names
            .iter()
            .filter(|n| n.ends_with(".tmp") && !is_listed(n))
            .map(|n| EarlierFile { path: dir.join(n), proven: false }),
    );
    Ok(earlier)
}

/// The files listed by the sweep.csv at `path`, each with the SHA-256 its `# sha256:` line
/// records (none when the sweep stopped before it wrote them); none when the file is absent;
/// an error naming it when it is not a gripopt sweep's.
fn listed_files(path: &Path) -> Result<Vec<(String, Option<String>)>> {
    let text = match crate::fsutil::read_regular(path, crate::fsutil::caps::TABLE) {
        Ok(b) => String::from_utf8_lossy(&b).to_string(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(vec![]),
        Err(e) => return Err(Error::io(path, "cannot read", e)),
    };
    let header = || text.lines().take_while(|l| l.starts_with('#'));
    let files =
        header().find_map(|l| l.strip_prefix("# files: ")).map(|l| l.split(", ").map(String::from).collect::<Vec<_>>());
    let hashes: Vec<(String, String)> = header()
        .find_map(|l| l.strip_prefix(SHA256_LINE))
        .map(|l| l.split(", ").filter_map(|p| p.split_once('=')).map(|(f, h)| (f.to_string(), h.to_string())).collect())
        .unwrap_or_default();
    match files {
        Some(f) if text.starts_with(SWEEP_TITLE) => Ok(f
            .into_iter()
            .map(|n| {
                let h = hashes.iter().find(|(f, _)| *f == n).map(|(_, h)| h.clone());
                (n, h)
            })
            .collect()),
        _ => Err(Error::RunDir {
            path: path.to_path_buf(),
            message: "not written by a gripopt sweep (no `# gripopt sweep.csv` title and `# files:` line): a sweep never overwrites it; give --out a new or empty folder".into(),
        }),
    }
}

/// The start of sweep.csv's line of the SHA-256 of every file the sweep wrote
/// (`# sha256: NAME=HEX, …`), written once they are all written.
pub const SHA256_LINE: &str = "# sha256: ";

/// The unit of a key of the evaluation record as a sweep.csv column (`-`: none; `text`,
/// `bool`).
pub fn record_unit(key: &str) -> &'static str {
    let k = key.rsplit('.').next().unwrap_or(key);
    // an array's or a finger's element, `name_0`, `name_1`: the name's unit
    let k = match k.rsplit_once('_') {
        Some((a, d)) if !d.is_empty() && d.chars().all(|c| c.is_ascii_digit()) => a,
        _ => k,
    };
    match k {
        "l21" | "b" | "t22" | "l_hand" | "l11" | "l12" | "l22" | "k1" | "k2" | "max_offset" | "x_off" => "m",
        "object_max_displacement" | "object_max_dx" | "object_max_dy" | "object_final_displacement" => "m",
        "psi_deg" | "min_margin_deg" | "object_max_tilt_deg" | "object_final_tilt_deg" => "deg",
        "q11" | "q21" | "q12" | "q22" | "q13" | "theta1" | "theta2" | "theta2_first_contact" => "rad",
        "object_max_spin" => "rad",
        "masses" | "m_finger" => "kg",
        "tau_s_min" | "tau_s0" => "N·m",
        "f0" | "fmu" | "fhand0_x" | "fhand0_y" | "fhandmu_x" | "fhandmu_y" | "mean_force" | "mean_force_mu" => "N",
        "mean_force_0" | "min_force_margin" | "static_force_margin" | "f_stab" | "fstar" => "N",
        "hand_x_end" | "hand_y_end" | "hand0_x" | "hand0_y" => "N",
        "t_first_contact" | "t_stab" | "t_end" | "cpu_s" => "s",
        "v_impact" => "m/s",
        "e_cyl" | "e_trans" | "e_rot" | "e_lim" | "object_peak_e_trans" | "object_peak_e_rot" | "energy" => "J",
        "max_energy_rise" => "J",
        "max_qdd_end" => "rad/s^2",
        "violation" => "stage units",
        "form_closed" | "knuckle_contact" | "impact_ok" | "fold_ok" | "force_ok" | "moved" | "toppled" | "escaped"
        | "rim_contact" | "recentres" | "feasible" => "bool",
        "max_offset_ended_by"
        | "force_model"
        | "first_contact_phalanx"
        | "outcome"
        | "end"
        | "reason"
        | "cause"
        | "scene"
        | "verdict" => "text",
        _ => "-",
    }
}

/// Record keys that are text or yes/no, never a number to plot.
const TEXT_KEYS: [&str; 4] = ["feasible", "reason", "cause", "scene"];

/// The numeric record keys that `spec`'s stage computes, in record order (arrays as
/// `key_0`, `key_1`, … as sweep.csv names them): the design and the verdict's stage and
/// violation always, the kinematics keys from stage 1, the statics keys from stage 2, the
/// grasp and the problem's scene keys (and x_off) at stage 3.
pub fn plot_keys(spec: &SweepSpec) -> Vec<String> {
    let json = |c: Vec<(String, String)>| c.into_iter().map(|(k, _)| k).collect::<Vec<_>>();
    let mut r = Record::from_eval(&Evaluation::new(spec.design)).with_scene_parts(spec.problem.scene.setup.kind);
    if spec.problem.solver.method == crate::params::Method::Auto {
        // the switching method's counters (the default solver's since session 38)
        (r.grasp.work.switches, r.grasp.work.explicit_steps) = (Some(0), Some(0));
        if let Some(f) = r.free_scene.as_mut() {
            (f.work.switches, f.work.explicit_steps) = (Some(0), Some(0));
        }
    }
    let mut skip: Vec<String> = TEXT_KEYS.iter().map(|k| k.to_string()).collect();
    if spec.stage != Stage::Dynamic {
        skip.extend(json(cells(&r.grasp, Floats::Json)));
        (r.offset_scene, r.free_scene) = (None, None);
        skip.push("x_off".into());
    }
    if spec.stage == Stage::Kinematics {
        skip.extend(json(cells(&r.statics, Floats::Json)));
    }
    let mut keys = vec![];
    for k in json(cells(&r, Floats::Json)).into_iter().filter(|k| !skip.contains(k)) {
        match ARRAY_KEYS.iter().find(|a| a.0 == k) {
            Some(&(_, n)) => keys.extend((0..n).map(|i| format!("{k}_{i}"))),
            None => keys.push(k),
        }
    }
    keys
}

/// Check the keys of `--y` (`+` joins keys) and `--color` against [`plot_keys`]: an
/// unknown key, or one `spec`'s stage does not compute, is an error naming it and listing
/// the keys that stage gives.
pub fn check_plot_keys(spec: &SweepSpec, flag: &str, values: &[String]) -> Result<()> {
    let valid = plot_keys(spec);
    for v in values {
        for k in v.split('+') {
            if !valid.iter().any(|x| x == k) {
                let stage = match spec.stage {
                    Stage::Kinematics => "kinematics (stages 0-1)",
                    Stage::Static => "static (stages 0-2)",
                    Stage::Dynamic => "dynamic (stages 0-3)",
                };
                let why = if k.is_empty() { "an empty key".to_string() } else { format!("`{k}` is not a numeric key") };
                return Err(Error::Input(format!(
                    "{flag} {v}: {why} of the --stage {stage} record; one of: {}",
                    valid.join(", ")
                )));
            }
        }
    }
    Ok(())
}
