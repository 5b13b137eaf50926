//! `gripopt replay RUN --design ID --scenario OBJECT:K`: one scenario of a robust design
//! re-simulated, compared with its recording, recorded to MCAP (docs/robust.md).

use anyhow::Result;
use gripopt::app::NoSuchObject;
use std::path::Path;

/// Replay the scenario and report it (text or JSON; `--csv`: the free object's poses).
pub fn replay_scenario(dir: &Path, id: u64, arg: &str, json: bool, csv: Option<&Path>) -> Result<i32> {
    let (object, k) = gripopt::app::parse_scenario(arg)?;
    let r = gripopt::app::replay_scenario(dir, id, &object, k, true)?;
    if let Some(path) = csv {
        let mut s = String::from("t,x,y,z,qw,qx,qy,qz\n");
        for p in &r.poses {
            let (g, q) = (p.g, p.q);
            s.push_str(&format!(
                "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
                p.t, g[0], g[1], g[2], q[0], q[1], q[2], q[3]
            ));
        }
        crate::cli::out::write_file(path, s.as_bytes())?;
    }
    if json {
        outln!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        let s = &r.scenario;
        outln!("design {id}, object {object}, scenario {k} of {}", dir.display());
        outln!("  inputs: {}", s.inputs.shown());
        outln!("  outcome: {}", outcome(s));
        match r.verified {
            Some(true) => outln!("  verified: the re-simulation equals the recorded scenario, bit for bit"),
            Some(false) => match &r.recorded {
                Some(rec) if rec.inputs != s.inputs => {
                    outln!(
                        "  NOT verified: the recording drew other inputs for this scenario; it says {}",
                        outcome(rec)
                    )
                }
                Some(rec) => outln!("  NOT verified: the recording says {} (`--json`: every value)", outcome(rec)),
                None => outln!("  NOT verified: nothing recorded to compare"),
            },
            None => {
                outln!("  not in the recording (the design's scenarios stopped early before it): nothing compared")
            }
        }
        if let Some(why) = &r.not_recorded {
            outln!("  {why}");
        }
        if let Some(m) = &r.recording {
            outln!(
                "  recorded to {} (open in Foxglove with {})",
                m.display(),
                dir.join(gripopt::app::VERIFY_LAYOUT_FILE).display()
            );
        }
    }
    Ok(if r.verified == Some(false) { 3 } else { 0 })
}

/// A scenario's outcome in words: stays or why not, and what was measured.
fn outcome(s: &gripopt::app::ScenarioRecord) -> String {
    let mm = |v: Option<f64>| v.map_or("—".into(), |v| format!("{:.4} mm", v * 1e3));
    format!(
        "{} (max displacement {}, max tilt {}, t_stab {})",
        if s.stays { "stays".to_string() } else { format!("fails: {}", s.cause.map_or("?", |c| c.as_str())) },
        mm(s.max_displacement),
        s.max_tilt_deg.map_or("—".into(), |v| format!("{v:.4}°")),
        s.t_stab.map_or("—".into(), |v| format!("{:.3} ms", v * 1e3))
    )
}

/// The robust objects' names of `p`, comma-separated (empty for a problem without [robust]).
pub fn object_names(p: &gripopt::app::Problem) -> String {
    p.robust.iter().flat_map(|r| &r.objects).map(|o| o.name.as_str()).collect::<Vec<_>>().join(", ")
}

/// The index of `--object NAME` among the robust objects of `p` (read from `source`); an
/// input error naming the flag when `p` has no [robust] (`without`: what the command does
/// with the problem's one `[object]` instead) or no object of that name. `export --object`
/// and `simulate --object`.
pub fn object_index(p: &gripopt::app::Problem, name: &str, source: &str, without: &str) -> Result<usize> {
    // a name that reads as nothing (empty, blanks, control characters) quoted
    let shown = if name.trim().is_empty() || name.chars().any(|c| c.is_whitespace() || c.is_control()) {
        format!("\"{}\"", crate::cli::out::shown(name))
    } else {
        name.to_string()
    };
    gripopt::app::object_index(p, name).map_err(|why| {
        let message = match why {
            NoSuchObject::NotRobust => format!(
                "--object {shown}: {source}: the problem is not robust (no [robust] section): it has one object, its [object], which {without}; --object picks one of a robust problem's [[robust.objects]] (docs/robust.md)"
            ),
            NoSuchObject::Unknown(names) => format!(
                "--object {shown}: {source}: no such robust object; the problem's [[robust.objects]] are: {}",
                names.join(", ")
            ),
        };
        gripopt::Error::Input(message).into()
    })
}
