//! Human and JSON reports of `evaluate` and `simulate`.

use anyhow::{bail, Context, Result};
use gripopt::eval::DynamicsRecord;
use gripopt::eval::{evaluate as eval_design, EvalOptions, Record};
use gripopt::params::{Design, Problem};
use gripopt::sim::{simulate as sim_run, Controls, Integration, Method, SceneSpec, Trajectory};
use std::io::Write;
use std::path::Path;

fn opt(v: Option<f64>, scale: f64, prec: usize) -> String {
    match v {
        Some(x) => format!("{:.*}", prec, x * scale),
        None => "—".into(),
    }
}

fn yes_no(v: Option<bool>) -> &'static str {
    match v {
        Some(true) => "yes",
        Some(false) => "no",
        None => "—",
    }
}

/// `gripopt evaluate`.
pub fn evaluate(p: &Problem, x: &Design, json: bool, static_only: bool) -> Result<()> {
    let opts = if static_only { EvalOptions::statics_only() } else { EvalOptions::full(p) };
    let ev = eval_design(x, &p.scene, &opts);
    let r = Record::from_eval(&ev);
    if json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    let d = |v: Option<f64>| opt(v, 180.0 / std::f64::consts::PI, 4);
    let mm = |v: Option<f64>| opt(v, 1e3, 4);
    println!(
        "problem {}  design l21={} b={} t22={} r={} p={} psi={:.3} deg  (l_hand {:.4} m)",
        p.name,
        x.l21,
        x.b,
        x.t22,
        x.r,
        x.p,
        x.psi.to_degrees(),
        x.l_hand()
    );
    println!("stage 0/1  kinematics");
    println!("  l11 {} mm  l22 {} mm  l12 {} mm", mm(r.l11), mm(r.l22), mm(r.l12));
    println!(
        "  open pose q11 {} deg  q21 {} deg  q12 {} deg  q22 {} deg  q13 {} deg  Gamma {}  sigma {}",
        d(r.q11_0),
        d(r.q21_0),
        d(r.q12_0),
        d(r.q22_0),
        d(r.q13_0),
        opt(r.gamma, 1.0, 0),
        opt(r.sigma, 1.0, 0)
    );
    println!(
        "  singularity margin {} deg (limit {:.1})",
        opt(r.min_margin_deg, 1.0, 3),
        p.scene.criteria.margin_sing.to_degrees()
    );
    println!("stage 2    statics (centred object, R = {} mm)", p.scene.object.radius * 1e3);
    println!("  spring torque tau_s0 {} N·m (tau_s^min {})", opt(r.tau_s0, 1.0, 6), opt(r.tau_s_min, 1.0, 6));
    println!(
        "  closed pose theta1 {} deg  theta2 {} deg  k1 {} mm  k2 {} mm",
        d(r.theta1),
        d(r.theta2),
        mm(r.k1),
        mm(r.k2)
    );
    println!(
        "  f0  {} / {} N   f_mu {} / {} N",
        opt(r.f0_1, 1.0, 4),
        opt(r.f0_2, 1.0, 4),
        opt(r.fmu_1, 1.0, 4),
        opt(r.fmu_2, 1.0, 4)
    );
    println!(
        "  F_hand0 ({}, {}) N   F_hand_mu ({}, {}) N",
        opt(r.fhand0_x, 1.0, 4),
        opt(r.fhand0_y, 1.0, 4),
        opt(r.fhandmu_x, 1.0, 4),
        opt(r.fhandmu_y, 1.0, 4)
    );
    println!(
        "  alpha {}  mean force {} N  form closed at 0: {}  max_offset {} mm{}",
        opt(r.alpha, 1.0, 5),
        opt(r.mean_force, 1.0, 4),
        yes_no(r.form_closed_0),
        mm(r.max_offset.filter(|m| *m >= 0.0)),
        r.max_offset_ended_by.as_ref().map(|s| format!(" (scan ended by: {s})")).unwrap_or_default()
    );
    if !static_only {
        print_dyn(&r.dynamics);
        if let Some(f) = &r.free {
            print_free(f);
        }
    }
    match (&r.failed_stage, &r.reason) {
        (Some(s), Some(why)) => {
            println!("verdict    DISCARDED at stage {s}: {why} (violation {:.4})", r.violation.unwrap_or(0.0))
        }
        _ => {
            let o = ev.objectives();
            println!(
                "verdict    FEASIBLE  objectives: max_offset {:.3} mm, alpha {:.5}, mean force {:.4} N, t_stab {}",
                -o[0] * 1e3,
                o[1],
                -o[2],
                if o[3].is_nan() { "— (not computed)".to_string() } else { format!("{:.6} s", o[3]) }
            );
        }
    }
    Ok(())
}

fn print_dyn(r: &DynamicsRecord) {
    println!("stage 3    dynamics");
    if r.steps.is_none() {
        println!("  not run");
        return;
    }
    println!(
        "  first contact t {} ms on {}  v_impact {} m/s  m_finger {} g  theta2 {} deg",
        opt(r.t_first_contact, 1e3, 4),
        r.first_contact_phalanx.unwrap_or("—"),
        opt(r.v_impact, 1.0, 4),
        opt(r.m_finger, 1e3, 4),
        opt(r.theta2_first_contact, 180.0 / std::f64::consts::PI, 4)
    );
    println!(
        "  impact energy E_cyl {} mJ (limit {} mJ)  E_trans {} mJ  E_rot {} mJ",
        opt(r.e_cyl, 1e3, 5),
        opt(r.e_lim, 1e3, 5),
        opt(r.e_trans, 1e3, 5),
        opt(r.e_rot, 1e3, 5)
    );
    println!(
        "  force margin min {} N (static {} N)",
        opt(r.min_force_margin, 1.0, 4),
        opt(r.static_force_margin, 1.0, 4)
    );
    println!(
        "  t_stab {} ms  forces at t_stab {} / {} N  f* {} / {} N  max|qdd| {} rad/s^2",
        opt(r.t_stab, 1e3, 5),
        opt(r.f_stab_1, 1.0, 4),
        opt(r.f_stab_2, 1.0, 4),
        opt(r.fstar_1, 1.0, 4),
        opt(r.fstar_2, 1.0, 4),
        opt(r.max_qdd_end, 1.0, 3)
    );
    println!(
        "  steps {} rejected {} rhs {} events {} cpu {} ms",
        r.steps.unwrap_or(0),
        r.rejected_steps.unwrap_or(0),
        r.rhs_evals.unwrap_or(0),
        r.events.unwrap_or(0),
        opt(r.cpu_s, 1e3, 3)
    );
}

/// The free scene's measurement of a free-kind stage 3 (MODEL.md §14.4).
fn print_free(f: &gripopt::eval::FreeRecord) {
    println!("stage 3    free scene (x_off {} mm): the impact and force criteria above are the prediction; this measurement decides", opt(f.object_x_off, 1e3, 3));
    let Some(end) = f.free_end.as_deref() else {
        println!("  not run (the centred grasp was discarded first)");
        return;
    };
    if end != "t_obs" {
        println!("  ended early: {end}");
    }
    println!(
        "  object max displacement {} mm (dx {} mm, dy {} mm)  max tilt {} deg  final {} mm / {} deg",
        opt(f.object_max_displacement, 1e3, 4),
        opt(f.object_max_dx, 1e3, 4),
        opt(f.object_max_dy, 1e3, 4),
        opt(f.object_max_tilt_deg, 1.0, 4),
        opt(f.object_final_displacement, 1e3, 4),
        opt(f.object_final_tilt_deg, 1.0, 4)
    );
    println!(
        "  peak E_trans {} mJ  E_rot {} mJ during the first contact",
        opt(f.object_peak_e_trans, 1e3, 4),
        opt(f.object_peak_e_rot, 1e3, 4)
    );
    println!(
        "  moved {}  toppled {}  escaped {}  rim_contact {}",
        yes_no(f.moved),
        yes_no(f.toppled),
        yes_no(f.escaped),
        yes_no(f.rim_contact)
    );
}

/// `gripopt simulate` in the centred scene (`extra`: keys added to the JSON object).
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    p: &Problem,
    x: &Design,
    rtol: Option<f64>,
    method: Method,
    contacts: bool,
    trace: bool,
    json: bool,
    csv: Option<&Path>,
    plot: Option<&Path>,
    extra: &serde_json::Map<String, serde_json::Value>,
) -> Result<()> {
    let ev = eval_design(x, &p.scene, &EvalOptions::statics_only());
    let (Some(k), Some(st)) = (ev.kin, ev.statics) else {
        let d = ev.discard.expect("a design without statics was discarded");
        bail!("the design is discarded at stage {} ({}); the grasp needs stages 0–2", d.stage, d.reason);
    };
    let o = Integration::new(rtol.unwrap_or(p.solver.rtol), p.solver.atol, p.solver.max_steps).with_method(method);
    let ctl = Controls { contacts, ..Controls::DIAGNOSTIC };
    let _ = trace;
    let mut traj = Trajectory::default();
    let res = *sim_run(&k.finger, &p.scene, &st, &SceneSpec::Centred, &o, &ctl, &mut traj).grasp().unwrap();
    let rec = DynamicsRecord::from_result(Some(&res));
    let fstar = res.fstar;
    if let Some(path) = csv {
        let mut w = std::io::BufWriter::new(
            std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?,
        );
        writeln!(w, "t,q11,q21,q11_dot,q21_dot,theta2,delta_1,delta_2,fn_1,fn_2,ft_1,ft_2,hand_fy,filtered_fy,energy,energy_excess")?;
        for s in &traj.samples {
            writeln!(
                w,
                "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
                s.t,
                s.q[0],
                s.q[1],
                s.qd[0],
                s.qd[1],
                s.theta2,
                s.delta[0],
                s.delta[1],
                s.normal[0],
                s.normal[1],
                s.friction[0],
                s.friction[1],
                s.hand_fy,
                s.filtered_fy,
                s.energy,
                s.energy_excess
            )?;
        }
        w.flush()?;
    }
    if let Some(path) = plot {
        gripopt::run::grasp_plot(path, &format!("{}: grasp", p.name), &traj.samples)?;
    }
    let verdict = match res.discard_violation() {
        None => (true, None, None),
        Some(_) => (false, Some(3u8), Some(res.outcome.to_string())),
    };
    if json {
        let mut v = serde_json::to_value(&rec)?;
        let m = v.as_object_mut().expect("object");
        m.insert("fstar_1".into(), serde_json::json!(fstar[0]));
        m.insert("fstar_2".into(), serde_json::json!(fstar[1]));
        m.insert("f0_1".into(), serde_json::json!(st.f0[0]));
        m.insert("f0_2".into(), serde_json::json!(st.f0[1]));
        m.insert("impact_ok".into(), serde_json::json!(res.impact_ok));
        m.insert("fold_ok".into(), serde_json::json!(res.fold_ok));
        m.insert(
            "force_ok".into(),
            serde_json::json!(res.t_force_violation.is_none() && res.static_force_margin >= 0.0),
        );
        m.insert("t_end".into(), serde_json::json!(res.t_end));
        m.insert("method".into(), serde_json::json!(method_name(method)));
        m.insert("feasible".into(), serde_json::json!(verdict.0));
        m.insert("failed_stage".into(), serde_json::json!(verdict.1));
        m.insert("reason".into(), serde_json::json!(verdict.2));
        m.extend(extra.clone());
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!("problem {}  method {}  rtol {:e}", p.name, method_name(method), o.rtol);
    print_dyn(&rec);
    println!("  f0 (rigid statics) {:.4} / {:.4} N", st.f0[0], st.f0[1]);
    println!(
        "  criteria: impact {}  fold {}  force {}",
        ok(res.impact_ok),
        ok(res.fold_ok),
        if res.t_force_violation.is_none() && res.static_force_margin >= 0.0 { "ok" } else { "VIOLATED" }
    );
    match verdict.2 {
        None => println!("verdict    stable"),
        Some(why) => println!("verdict    DISCARDED at stage 3: {why}"),
    }
    if let Some(path) = csv {
        println!("trajectory: {} samples written to {}", traj.samples.len(), path.display());
    }
    Ok(())
}

fn ok(v: Option<bool>) -> &'static str {
    match v {
        Some(true) => "ok",
        Some(false) => "VIOLATED",
        None => "not reached",
    }
}

fn method_name(m: Method) -> &'static str {
    match m {
        Method::Radau5 => "radau5",
        Method::TrBdf2 => "trbdf2",
        Method::Dopri5 => "dopri5",
    }
}
