//! `gripopt show RUN`: a run's front sorted by an objective, with units, each design with
//! its replay command (text or JSON). Reads the run's CSV files (rewritten every
//! generation, so a running run can be shown too).

use anyhow::{bail, Context, Result};
use gripopt::run::DESIGN_COLUMNS;
use std::path::{Path, PathBuf};

/// Arguments of `gripopt show`.
#[derive(clap::Args)]
pub struct ShowArgs {
    /// Run folder.
    run_dir: PathBuf,
    /// Sort the front by this objective, best first: max_offset, alpha, mean_force, t_stab.
    #[arg(long, default_value = "max_offset")]
    best: String,
    /// Show one design (of the front, the archive or the final population) in full.
    #[arg(long)]
    design: Option<u64>,
    /// Show the archive (every feasible non-dominated design of the run) instead of the
    /// population's front.
    #[arg(long)]
    archive: bool,
    /// At most this many designs (0 = all).
    #[arg(long, default_value_t = 0)]
    limit: usize,
    /// One JSON object: the run's status and the designs, with units.
    #[arg(long)]
    json: bool,
}

/// Rows of a design CSV as (header, rows), skipping `#` lines. A missing or unreadable
/// file, an empty one, or a row cut short (the files are written whole, ending in a line
/// break, with every row as long as the header) is an error naming the file (and line):
/// exit 2, the run folder is bad input.
fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<String>>)> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| gripopt::Error::io(path, "cannot read (is this a run folder with a completed generation?)", e))?;
    let bad = |line: usize, what: String| gripopt::Error::RunDir {
        path: path.to_path_buf(),
        message: format!(
            "line {line}: {what}; the file is damaged or truncated (gripopt rewrites it whole every generation)"
        ),
    };
    let mut lines =
        text.lines().enumerate().map(|(i, l)| (i + 1, l)).filter(|(_, l)| !l.starts_with('#') && !l.trim().is_empty());
    let Some((_, head)) = lines.next() else {
        return Err(gripopt::Error::RunDir { path: path.to_path_buf(), message: "empty: no header line".into() }.into());
    };
    let head: Vec<String> = head.split(',').map(String::from).collect();
    if head.first().map(String::as_str) != Some("id") {
        return Err(gripopt::Error::RunDir {
            path: path.to_path_buf(),
            message: format!("header `{}` does not start with `id`: not a gripopt design CSV", head.join(",")),
        }
        .into());
    }
    let mut rows = vec![];
    for (n, l) in lines {
        let r = split_row(l);
        if r.len() != head.len() {
            return Err(bad(n, format!("{} fields, the header has {}", r.len(), head.len())).into());
        }
        rows.push(r);
    }
    if !text.ends_with('\n') {
        return Err(bad(text.lines().count(), "the last line ends without a line break".into()).into());
    }
    Ok((head, rows))
}

/// `run.json` of the run folder: its status and completed generations. Missing, not JSON,
/// or without those fields is an error naming the file (exit 2).
fn read_run_json(dir: &Path) -> Result<serde_json::Value> {
    let p = dir.join("run.json");
    let text =
        std::fs::read_to_string(&p).map_err(|e| gripopt::Error::io(&p, "cannot read (is this a run folder?)", e))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|source| gripopt::Error::Json {
        path: p.clone(),
        what: "invalid run.json",
        source,
    })?;
    if !v["status"].is_string() || !v["completed_generations"].is_u64() {
        return Err(gripopt::Error::RunDir {
            path: p,
            message: "no `status` text or `completed_generations` count: the file is damaged".into(),
        }
        .into());
    }
    Ok(v)
}

/// Split a CSV line (only `reason` is quoted, without inner quotes).
fn split_row(l: &str) -> Vec<String> {
    let mut out = vec![];
    let (mut cur, mut quoted) = (String::new(), false);
    for c in l.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

fn unit(name: &str) -> &'static str {
    DESIGN_COLUMNS.iter().find(|c| c.0 == name).map_or("", |c| c.1)
}

/// `gripopt show`.
pub fn run(a: ShowArgs) -> Result<()> {
    let dir = &a.run_dir;
    let objectives = [("max_offset", true), ("alpha", false), ("mean_force", true), ("t_stab", false)];
    let Some(&(obj, maximise)) = objectives.iter().find(|o| o.0 == a.best) else {
        bail!("--best {}: expected one of max_offset, alpha, mean_force, t_stab", a.best);
    };
    let file = if a.archive { "archive.csv" } else { "pareto.csv" };
    let run = read_run_json(dir)?;
    let (head, mut rows) = read_csv(&dir.join(file))?;
    let col = |n: &str| head.iter().position(|h| h == n);
    let replay = |id: &str| format!("gripopt replay {} --design {id}", dir.display());
    if let Some(id) = a.design {
        let mut found = None;
        for f in ["pareto.csv", "archive.csv", "population.csv"] {
            // a file not written (yet) is skipped; a damaged one is an error
            if !dir.join(f).exists() {
                continue;
            }
            let (h, r) = read_csv(&dir.join(f))?;
            if let Some(row) = r.into_iter().find(|r| r.first().map(String::as_str) == Some(&id.to_string())) {
                found = Some((h, row, f));
                break;
            }
        }
        let Some((h, row, f)) = found else {
            bail!(
                "--design {id}: not in pareto.csv, archive.csv or population.csv of {} (older designs: `{}`)",
                dir.display(),
                replay(&id.to_string())
            )
        };
        if a.json {
            let mut m = serde_json::Map::new();
            for (k, v) in h.iter().zip(&row) {
                m.insert(k.clone(), serde_json::json!({ "value": json_value(v), "unit": unit(k) }));
            }
            m.insert("file".into(), serde_json::json!(f));
            m.insert("replay".into(), serde_json::json!(replay(&id.to_string())));
            println!("{}", serde_json::to_string_pretty(&serde_json::Value::Object(m))?);
        } else {
            println!("design {id} (from {f})");
            for (k, v) in h.iter().zip(&row) {
                let u = unit(k);
                let u = if matches!(u, "-" | "text" | "bool") { String::new() } else { format!(" {u}") };
                println!("  {k:<14} {}{u}", if v.is_empty() { "—" } else { v });
            }
            println!("  replay: {}", replay(&id.to_string()));
        }
        return Ok(());
    }
    let k = col(obj).with_context(|| format!("{file}: no column {obj}"))?;
    let val = |r: &Vec<String>| r.get(k).and_then(|v| v.parse::<f64>().ok());
    rows.sort_by(|x, y| {
        // designs without the value go last, whichever way the objective is better
        let (a, b) = (val(x).filter(|v| !v.is_nan()), val(y).filter(|v| !v.is_nan()));
        let o = match (a, b) {
            (Some(a), Some(b)) if maximise => b.total_cmp(&a),
            (Some(a), Some(b)) => a.total_cmp(&b),
            (Some(_), None) => std::cmp::Ordering::Less,
            (None, Some(_)) => std::cmp::Ordering::Greater,
            (None, None) => std::cmp::Ordering::Equal,
        };
        o.then_with(|| x[0].parse::<u64>().ok().cmp(&y[0].parse::<u64>().ok()))
    });
    if a.limit > 0 {
        rows.truncate(a.limit);
    }
    let shown = ["id", "max_offset", "alpha", "mean_force", "t_stab", "l21", "b", "t22", "r", "p", "psi_deg"];
    if a.json {
        let designs: Vec<serde_json::Value> = rows
            .iter()
            .map(|r| {
                let mut m = serde_json::Map::new();
                for (h, v) in head.iter().zip(r) {
                    m.insert(h.clone(), json_value(v));
                }
                m.insert("replay".into(), serde_json::json!(replay(&r[0])));
                serde_json::Value::Object(m)
            })
            .collect();
        let units: serde_json::Map<String, serde_json::Value> =
            DESIGN_COLUMNS.iter().map(|c| (c.0.to_string(), serde_json::json!(c.1))).collect();
        let v = serde_json::json!({
            "run_dir": dir.display().to_string(), "status": run["status"], "completed_generations": run["completed_generations"],
            "file": file, "sorted_by": obj, "direction": if maximise { "maximise" } else { "minimise" }, "units": units, "designs": designs,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!(
        "{} ({}, {} generations): {} designs of {file}, sorted by {obj} ({}), best first",
        dir.display(),
        run["status"].as_str().unwrap_or("?"),
        run["completed_generations"],
        rows.len(),
        if maximise { "higher is better" } else { "lower is better" }
    );
    let label = |n: &str| match n {
        "max_offset" => "max_offset mm".to_string(),
        "t_stab" => "t_stab ms".to_string(),
        "mean_force" => "mean_force N".to_string(),
        "psi_deg" => "psi deg".to_string(),
        "l21" | "b" | "t22" => format!("{n} mm"),
        _ => n.to_string(),
    };
    let line: Vec<String> = shown.iter().map(|n| format!(" {:>13}", label(n))).collect();
    println!("{}  replay", line.join(""));
    for r in &rows {
        let cells: Vec<String> = shown
            .iter()
            .map(|n| {
                let v = col(n).and_then(|k| r.get(k)).map(String::as_str).unwrap_or("");
                let scale = match *n {
                    "max_offset" | "t_stab" | "l21" | "b" | "t22" => 1e3,
                    _ => 1.0,
                };
                match (v.parse::<f64>(), *n) {
                    (_, "id") => format!(" {v:>13}"),
                    // small values (alpha near isotropy) keep their significant digits
                    (Ok(x), _) if x != 0.0 && (x * scale).abs() < 1e-3 => format!(" {:>13.4e}", x * scale),
                    (Ok(x), _) => format!(" {:>13.5}", x * scale),
                    _ => format!(" {:>13}", if v.is_empty() { "—" } else { v }),
                }
            })
            .collect();
        println!("{}  {}", cells.join(""), replay(&r[0]));
    }
    Ok(())
}

fn json_value(v: &str) -> serde_json::Value {
    if v.is_empty() {
        return serde_json::Value::Null;
    }
    if let Ok(x) = v.parse::<u64>() {
        return serde_json::json!(x);
    }
    if let Ok(x) = v.parse::<f64>() {
        return serde_json::json!(x);
    }
    match v {
        "true" => serde_json::json!(true),
        "false" => serde_json::json!(false),
        _ => serde_json::json!(v),
    }
}
