//! `--scene centred|offset:X|free[:X]` for `simulate` and `replay` (MODEL.md §14): parsing,
//! the one dispatch of a diagnostic simulation to its scene's report (the centred scene's is
//! `report::simulate`), the offset and free scenes' reports, and `replay --scene` in a scene
//! other than the run's.

use anyhow::{bail, Context, Result};
use gripopt::eval::{evaluate as eval_design, EvalOptions, FreeMeasure, FreeRecord};
use gripopt::params::{limit, Design, Problem, SceneKind};
use gripopt::sim::{simulate as sim_run, Controls, Integration, SceneSpec};
use std::io::Write;
use std::path::Path;

/// Parse `centred`, `offset:X` or `free[:X]` (metres) into the problem's `[scene]`.
pub fn apply_scene(p: &mut Problem, arg: &str) -> Result<()> {
    let setup = &mut p.scene.setup;
    match arg.split_once(':') {
        None if arg == "centred" => setup.kind = SceneKind::Centred,
        None if arg == "free" => setup.kind = SceneKind::Free,
        Some(("offset", x)) => {
            let v: f64 = x.parse().with_context(|| format!("--scene offset:{x}: not a number"))?;
            limit("scene.x_off").check(v).map_err(|r| anyhow::anyhow!("--scene offset:{x}: {r}"))?;
            setup.kind = SceneKind::Offset;
            setup.x_off = v;
        }
        Some(("free", x)) => {
            let v: f64 = x.parse().with_context(|| format!("--scene free:{x}: not a number"))?;
            limit("scene.x_off").check(v).map_err(|r| anyhow::anyhow!("--scene free:{x}: {r}"))?;
            setup.kind = SceneKind::Free;
            setup.x_off = v;
        }
        _ => bail!("--scene {arg}: must be centred, offset:X or free[:X] (metres)"),
    }
    if setup.kind == SceneKind::Free && p.scene.env.g_eq != 0.0 {
        bail!("--scene free needs environment.g_eq = 0 (hand horizontal, MODEL.md §14.1)");
    }
    Ok(())
}

/// How `simulate` (and `replay --scene`) runs a design: the diagnostic simulation's options
/// and outputs.
pub struct SimulateOpts<'a> {
    /// Relative tolerance (default: the problem's).
    pub rtol: Option<f64>,
    /// Integration method (centred scene).
    pub method: gripopt::sim::Method,
    /// Contacts with the object (centred scene; false: the linkage alone).
    pub contacts: bool,
    /// Print every located event to stderr (centred scene).
    pub trace: bool,
    /// One JSON object instead of the text report.
    pub json: bool,
    /// Write the trajectory to this CSV file.
    pub csv: Option<&'a Path>,
    /// Plot the grasp to this SVG file (centred scene only).
    pub plot: Option<&'a Path>,
    /// Keys added to the JSON object.
    pub extra: serde_json::Map<String, serde_json::Value>,
}

/// `gripopt simulate`: the diagnostic simulation of design `x` in the problem's scene.
pub fn simulate_in_scene(p: &Problem, x: &Design, o: &SimulateOpts<'_>) -> Result<()> {
    if p.scene.setup.kind == SceneKind::Centred {
        return crate::cli::report::simulate(
            p, x, o.rtol, o.method, o.contacts, o.trace, o.json, o.csv, o.plot, &o.extra,
        );
    }
    let kind = p.scene.setup.kind;
    if o.plot.is_some() {
        bail!(
            "--plot: only the centred scene is plotted so far{}",
            if kind == SceneKind::Free { " (use --csv for the free scene)" } else { "" }
        );
    }
    if !o.contacts {
        bail!("--no-contact: only the centred scene runs without contacts (the {kind} scene needs the object)");
    }
    if kind == SceneKind::Offset && o.csv.is_some() {
        bail!("--csv: the offset scene writes no trajectory yet (the centred and free scenes do)");
    }
    simulate(p, x, o)
}

/// "yes", "no", or "—" (not known).
fn flag(v: Option<bool>) -> &'static str {
    match v {
        Some(true) => "yes",
        Some(false) => "no",
        None => "—",
    }
}

/// The offset or free scene.
fn simulate(p: &Problem, x: &Design, so: &SimulateOpts<'_>) -> Result<()> {
    let (rtol, json, csv, extra) = (so.rtol, so.json, so.csv, &so.extra);
    let ev = eval_design(x, &p.scene, &EvalOptions::statics_only());
    let (Some(k), Some(st)) = (ev.kin, ev.statics) else {
        let d = ev.discard.expect("a design without statics was discarded");
        bail!("the design is discarded at stage {} ({}); the grasp needs stages 0–2", d.stage, d.reason);
    };
    let s = &p.scene;
    let o = Integration::new(rtol.unwrap_or(p.solver.rtol), p.solver.atol, p.solver.max_steps).with_method(so.method);
    let ctl = Controls::DIAGNOSTIC;
    let x_off = s.setup.x_off;
    if s.setup.kind == SceneKind::Offset {
        let r = match sim_run(&k.finger, s, &st, &SceneSpec::Offset { x_off }, &o, &ctl, &mut ()) {
            gripopt::sim::SceneResult::Offset(r) => r,
            _ => unreachable!(),
        };
        let d = &r.dynamics;
        let v = serde_json::json!({
            "scene": "offset", "x_off": x_off, "outcome": d.outcome.to_string(),
            "t_first_contact": d.first.map(|f| f.t), "first_phalanx": d.first.map(|f| f.phalanx),
            "e_cyl": d.first.map(|f| f.impact.e_cyl), "e_lim": d.first.map(|f| f.impact.e_lim),
            "t_stab": d.t_stab, "min_force_margin": d.min_force_margin, "static_force_margin": d.static_force_margin,
            "hand_x_end": r.hand_end[0], "hand_y_end": r.hand_end[1], "hand0_x": r.hand0[0], "hand0_y": r.hand0[1],
            "recentres": r.hand_end[0] * x_off < 0.0, "t_end": d.t_end, "steps": d.stats.steps, "cpu_s": d.cpu_s,
        });
        let mut v = v;
        v.as_object_mut().expect("object").extend(extra.clone());
        if json {
            println!("{}", serde_json::to_string_pretty(&v)?);
        } else {
            let ms = |t: Option<f64>| t.map_or("—".to_string(), |t| format!("{:.4} ms", t * 1e3));
            println!("problem {}  scene offset  x_off {x_off} m", p.name);
            println!("  outcome {}", d.outcome);
            println!(
                "  first contact {} on phalanx {}  E_cyl {} mJ (limit {} mJ)",
                ms(d.first.map(|f| f.t)),
                d.first.map_or("—".into(), |f| f.phalanx.to_string()),
                d.first.map_or("—".into(), |f| format!("{:.4}", f.impact.e_cyl * 1e3)),
                d.first.map_or("—".into(), |f| format!("{:.4}", f.impact.e_lim * 1e3))
            );
            println!(
                "  t_stab {}  force margin min {:.4} N (static {:.4} N)",
                ms(d.t_stab),
                d.min_force_margin,
                d.static_force_margin
            );
            println!(
                "  hand force at the end ({:.4}, {:.4}) N (static ({:.4}, {:.4}) N); recentres {}",
                r.hand_end[0],
                r.hand_end[1],
                r.hand0[0],
                r.hand0[1],
                if r.hand_end[0] * x_off < 0.0 { "yes" } else { "no" }
            );
            println!("  t_end {:.4} ms  steps {} cpu {:.2} ms", d.t_end * 1e3, d.stats.steps, d.cpu_s * 1e3);
        }
        return Ok(());
    }
    let centred = *sim_run(&k.finger, s, &st, &SceneSpec::Centred, &o, &ctl, &mut ()).grasp().unwrap();
    let mut poses: Vec<gripopt::sim::PoseSample> = vec![];
    let r = *sim_run(&k.finger, s, &st, &SceneSpec::free(x_off), &o, &ctl, &mut poses).free().unwrap();
    if let Some(path) = csv {
        let mut w = std::io::BufWriter::new(
            std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?,
        );
        writeln!(w, "t,gx,gy,gz,qw,qx,qy,qz,tilt_deg,q11_1,q21_1,q11_2,q21_2,energy")?;
        for p in &poses {
            writeln!(
                w,
                "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
                p.t,
                p.g[0],
                p.g[1],
                p.g[2],
                p.q[0],
                p.q[1],
                p.q[2],
                p.q[3],
                p.tilt.to_degrees(),
                p.fingers[0],
                p.fingers[1],
                p.fingers[2],
                p.fingers[3],
                p.energy
            )?;
        }
        w.flush()?;
    }
    let fr = FreeRecord::from_measure(Some(&FreeMeasure::from_result(&r, x_off)));
    let mut v = serde_json::json!({});
    let m = v.as_object_mut().expect("object");
    // the verdict only when the free scene ran to t_obs (as `evaluate` records it)
    m.insert("moved".into(), serde_json::json!(fr.moved));
    m.insert("toppled".into(), serde_json::json!(fr.toppled));
    m.insert("escaped".into(), serde_json::json!(fr.escaped));
    m.insert("free_end".into(), serde_json::json!(fr.free_end));
    let fc = centred.first;
    m.insert("scene".into(), serde_json::json!("free"));
    m.insert("x_off".into(), serde_json::json!(x_off));
    m.insert("outcome".into(), serde_json::json!(centred.outcome.to_string()));
    m.insert("impact_ok".into(), serde_json::json!(centred.impact_ok));
    m.insert("e_cyl".into(), serde_json::json!(fc.map(|f| f.impact.e_cyl)));
    m.insert("e_trans".into(), serde_json::json!(fc.map(|f| f.impact.e_trans)));
    m.insert("e_rot".into(), serde_json::json!(fc.map(|f| f.impact.e_rot)));
    m.insert("e_lim".into(), serde_json::json!(fc.map(|f| f.impact.e_lim)));
    m.insert("t_first_contact".into(), serde_json::json!(fc.map(|f| f.t)));
    m.insert("min_force_margin".into(), serde_json::json!(centred.min_force_margin));
    m.insert("static_force_margin".into(), serde_json::json!(centred.static_force_margin));
    m.insert(
        "force_ok".into(),
        serde_json::json!(centred.t_force_violation.is_none() && centred.static_force_margin >= 0.0),
    );
    m.insert("t_stab".into(), serde_json::json!(centred.t_stab));
    m.extend(extra.clone());
    if json {
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("problem {}  scene free  x_off {x_off} m", p.name);
        println!(
            "  object: max displacement {:.3e} m (dx {:.3e}, dy {:.3e})  max tilt {:.4}°  final {:.3e} m / {:.4}°",
            r.object_max_displacement,
            r.object_max_dx,
            r.object_max_dy,
            r.object_max_tilt_deg,
            r.object_final_displacement,
            r.object_final_tilt_deg
        );
        println!(
            "  peak E_trans {:.4e} J  E_rot {:.4e} J during the first contact",
            r.object_peak_e_trans, r.object_peak_e_rot
        );
        if let Some(why) = fr.free_end.filter(|e| *e != "t_obs") {
            println!("  ended early at t {:.4} ms: {why} (nothing observed: no verdict)", r.t_end * 1e3);
        }
        println!(
            "  moved {}  toppled {}  escaped {}  rim_contact {}",
            flag(fr.moved),
            flag(fr.toppled),
            flag(fr.escaped),
            flag(Some(r.rim_contact))
        );
        let impact = match centred.impact_ok {
            Some(true) => "holds",
            Some(false) => "fails",
            None => "— (no contact)",
        };
        println!("  centred criteria: impact criterion {impact}  outcome {}", centred.outcome);
        println!("  steps {} rhs {} events {} cpu {:.2} ms", r.stats.steps, r.rhs_evals, r.events, r.cpu_s * 1e3);
    }
    Ok(())
}

/// A scene as `--scene` spells it (`centred`, `offset:X`, `free:X`).
fn scene_name(p: &Problem) -> String {
    match p.scene.setup.kind {
        SceneKind::Centred => "centred".into(),
        k => format!("{k}:{}", p.scene.setup.x_off),
    }
}

/// `gripopt replay RUN_DIR --design ID --scene S`. When S is the run's own scene (its
/// `problem.toml`: kind, and x_off for offset/free) this returns `None` and the caller
/// replays and verifies as usual. Otherwise it re-simulates the recorded design in S with
/// the run's problem and reports it like `simulate --scene S` (text, `--json`, `--csv`),
/// saying that a different scene cannot be verified against the recording; `Some(0)`.
pub fn replay_in_scene(
    dir: &Path,
    id: u64,
    scene: &str,
    json: bool,
    csv: Option<&Path>,
    plot: Option<&Path>,
) -> Result<Option<i32>> {
    let run_problem = Problem::load(dir.join("problem.toml"))?;
    let mut p = run_problem.clone();
    apply_scene(&mut p, scene)?;
    let (ran, recorded) = (scene_name(&p), scene_name(&run_problem));
    let (a, b) = (&p.scene.setup, &run_problem.scene.setup);
    // numerically: free:-0 is the run's free:0
    if a.kind == b.kind && (a.kind == SceneKind::Centred || a.x_off == b.x_off) {
        return Ok(None);
    }
    let rec = gripopt::record::read_design(dir, id)?;
    let x = rec.design()?;
    let note = format!(
        "design {id} of {} re-simulated in the {ran} scene; the run recorded the {recorded} scene, so a different scene cannot be verified against the recording (nothing compared)",
        dir.display()
    );
    let mut extra = serde_json::Map::new();
    extra.insert("replay".into(), serde_json::json!({"run_dir": dir.display().to_string(), "design": id, "file": rec.file.display().to_string(), "recorded_scene": recorded, "scene": ran}));
    extra.insert("verified".into(), serde_json::Value::Null);
    extra.insert("note".into(), serde_json::json!(note));
    if !json {
        println!("{note}");
    }
    let o = SimulateOpts {
        rtol: None,
        method: gripopt::sim::Method::Radau5,
        contacts: true,
        trace: false,
        json,
        csv,
        plot,
        extra,
    };
    simulate_in_scene(&p, &x, &o)
        .with_context(|| format!("replaying design {id} of {} in the {ran} scene", dir.display()))?;
    Ok(Some(0))
}
