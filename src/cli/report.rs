//! Human and JSON reports of `evaluate`, and the text of the records' stage-3 parts
//! (shared with `simulate`).

use anyhow::Result;
use gripopt::app::{
    fmt_num, Design, FreeSceneRecord, GraspRecord, ImpactRecord, KinematicsRecord, Problem, Stages, StaticsRecord,
    WorkRecord,
};

/// A value scaled, to `prec` decimals, or "—".
pub fn opt(v: Option<f64>, scale: f64, prec: usize) -> String {
    match v {
        // an absurd value (a design far outside its bounds) in scientific notation, not
        // hundreds of digits
        Some(x) if (x * scale).abs() >= 1e9 => format!("{:.*e}", prec, x * scale),
        Some(x) => format!("{:.*}", prec, x * scale),
        None => "—".into(),
    }
}

/// A value in its unit (N, m/s, deg) to 4 decimals, or "—".
pub fn dec4(v: Option<f64>) -> String {
    opt(v, 1.0, 4)
}

/// A value in thousandths of its SI unit (mm, ms, g, mJ) to 4 decimals, or "—".
pub fn milli(v: Option<f64>) -> String {
    opt(v, 1e3, 4)
}

/// An angle in radians shown in degrees to 4 decimals, or "—".
pub fn degrees(v: Option<f64>) -> String {
    opt(v, 180.0 / std::f64::consts::PI, 4)
}

/// "yes", "no", or "—" (not known).
pub fn yes_no(v: Option<bool>) -> &'static str {
    match v {
        Some(true) => "yes",
        Some(false) => "no",
        None => "—",
    }
}

/// `gripopt evaluate`.
pub fn evaluate(p: &Problem, x: &Design, json: bool, static_only: bool) -> Result<()> {
    let stages = Stages::of(static_only);
    // the problem's study (a robust problem's objects and scenarios, or its one object in
    // its scene), with progress on stderr when a simulation takes long
    let rec = gripopt::app::evaluate_into(p, x, stages, &mut crate::cli::watch::Watch::new(false, false));
    if json {
        let v = gripopt::app::evaluation_record(p, &rec, stages);
        outln!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    print_head(p, x, static_only);
    print_kinematics(p, &rec.kinematics);
    print_statics(p, &rec.statics);
    if !static_only {
        print_dyn(&rec.grasp);
        if let Some(f) = &rec.free_scene {
            print_free(f, rec.x_off);
        }
    }
    if let Some(rb) = &rec.robust {
        out!("{}", gripopt::app::robust_summary(rb));
    }
    let v = &rec.verdict;
    match (&v.failed_stage, &v.reason) {
        (Some(s), Some(why)) => {
            let why = with_hint(why, p);
            let violation = gripopt::app::short_num(v.violation.unwrap_or(0.0), 4);
            outln!("verdict    DISCARDED at stage {s}: {why} (violation {violation})")
        }
        _ => {
            // the record's objectives: null (—) where not computed, e.g. max_offset of a
            // design not form closed at the centred object
            let [m, a, f, t] = rec.objectives();
            outln!(
                "verdict    FEASIBLE  objectives: max_offset {} mm, alpha {}, mean force {} N, t_stab {}",
                opt(m, 1e3, 3),
                opt(a, 1.0, 5),
                dec4(f),
                t.map_or("— (not computed)".to_string(), |t| format!("{t:.6} s"))
            );
        }
    }
    Ok(())
}

/// The report's first line: the problem, the design, the method where not the default.
fn print_head(p: &Problem, x: &Design, static_only: bool) {
    outln!(
        "problem {}  design l21={} b={} t22={} r={} p={} psi={:.3} deg  (l_hand {} m){}",
        crate::cli::out::shown(&p.name),
        fmt_num(x.l21),
        fmt_num(x.b),
        fmt_num(x.t22),
        fmt_num(x.r),
        fmt_num(x.p),
        x.psi.to_degrees(),
        dec4(Some(x.l_hand())),
        // the method of the grasp simulation, where it is not the default (RADAU5)
        if static_only || p.solver.method.is_default() {
            String::new()
        } else {
            format!("  method {}", p.solver.method)
        }
    );
}

/// Stages 0–1 of a record.
fn print_kinematics(p: &Problem, k: &KinematicsRecord) {
    outln!("stage 0/1  kinematics");
    outln!("  l11 {} mm  l22 {} mm  l12 {} mm", milli(k.l11), milli(k.l22), milli(k.l12));
    outln!(
        "  open pose q11 {} deg  q21 {} deg  q12 {} deg  q22 {} deg  q13 {} deg  Gamma {}  sigma {}",
        degrees(k.q11_0),
        degrees(k.q21_0),
        degrees(k.q12_0),
        degrees(k.q22_0),
        degrees(k.q13_0),
        opt(k.gamma, 1.0, 0),
        opt(k.sigma, 1.0, 0)
    );
    outln!(
        "  singularity margin {} deg (limit {:.1})",
        opt(k.min_margin_deg, 1.0, 3),
        p.scene.criteria.margin_sing.to_degrees()
    );
}

/// Stage 2 of a record.
fn print_statics(p: &Problem, r: &StaticsRecord) {
    outln!("stage 2    statics (centred object, R = {} mm)", p.scene.object.radius * 1e3);
    outln!("  spring torque tau_s0 {} N·m (tau_s^min {})", opt(r.tau_s0, 1.0, 6), opt(r.tau_s_min, 1.0, 6));
    outln!(
        "  closed pose theta1 {} deg  theta2 {} deg  k1 {} mm  k2 {} mm",
        degrees(r.theta1),
        degrees(r.theta2),
        milli(r.k1),
        milli(r.k2)
    );
    outln!("  f0  {} / {} N   f_mu {} / {} N", dec4(r.f0_1), dec4(r.f0_2), dec4(r.fmu_1), dec4(r.fmu_2));
    outln!(
        "  F_hand0 ({}, {}) N   F_hand_mu ({}, {}) N",
        dec4(r.fhand0_x),
        dec4(r.fhand0_y),
        dec4(r.fhandmu_x),
        dec4(r.fhandmu_y)
    );
    outln!(
        "  alpha {}  mean force {} N  form closed at 0: {}  max_offset {} mm{}",
        opt(r.alpha, 1.0, 5),
        dec4(r.mean_force),
        yes_no(r.form_closed_0),
        milli(r.max_offset),
        r.max_offset_ended_by.as_ref().map(|s| format!(" (scan ended by: {s})")).unwrap_or_default()
    );
}

/// A discard's reason for the text report, with the setting behind it where that is one
/// of the problem's: a step budget names `solver.max_steps` and its value (the record's
/// reason, which replay compares, stays as it is).
pub fn with_hint(why: &str, p: &Problem) -> String {
    with_steps_hint(why, Some(p.solver.max_steps))
}

/// [`with_hint`] with the step budget `max_steps` (None: unknown, the text as it is): the
/// discard summaries of optimise, resume and show, where the run's problem is read back.
pub fn with_steps_hint(why: &str, max_steps: Option<u64>) -> String {
    let budget = "step budget exhausted";
    match max_steps {
        Some(m) => why.replacen(
            budget,
            &format!("{budget} (solver.max_steps = {m}; the problem file's [solver] raises it)"),
            1,
        ),
        None => why.to_string(),
    }
}

/// The grasp's lines.
pub fn print_dyn(r: &GraspRecord) {
    outln!("stage 3    dynamics");
    if r.work.steps.is_none() {
        outln!("  not run");
        return;
    }
    print_impact(&r.impact, r.theta2_first_contact);
    outln!("  force margin min {} N (static {} N)", dec4(r.min_force_margin), dec4(r.static_force_margin));
    outln!(
        "  t_stab {} ms  forces at t_stab {} / {} N  f* {} / {} N  max|qdd| {} rad/s^2",
        opt(r.t_stab, 1e3, 5),
        dec4(r.f_stab_1),
        dec4(r.f_stab_2),
        dec4(r.fstar_1),
        dec4(r.fstar_2),
        opt(r.max_qdd_end, 1.0, 3)
    );
    print_work(&r.work);
}

/// The first contact's lines (θ2 at the contact, when known).
fn print_impact(i: &ImpactRecord, theta2: Option<f64>) {
    outln!(
        "  first contact t {} ms on {}  v_impact {} m/s  m_finger {} g  theta2 {} deg",
        milli(i.t_first_contact),
        i.first_contact_phalanx.map_or("—".into(), |p| format!("{p:?}").to_lowercase()),
        dec4(i.v_impact),
        milli(i.m_finger),
        degrees(theta2)
    );
    outln!(
        "  impact energy E_cyl {} mJ (limit {} mJ)  E_trans {} mJ  E_rot {} mJ",
        opt(i.e_cyl, 1e3, 5),
        opt(i.e_lim, 1e3, 5),
        opt(i.e_trans, 1e3, 5),
        opt(i.e_rot, 1e3, 5)
    );
}

/// A simulation's work on one line (the switching method's: how many steps were explicit
/// and how often it switched).
fn print_work(w: &WorkRecord) {
    let switching = match (w.explicit_steps, w.switches) {
        (Some(e), Some(k)) => {
            format!(" (Dormand-Prince {e}, RADAU5 the rest; {k} switch{})", if k == 1 { "" } else { "es" })
        }
        _ => String::new(),
    };
    outln!(
        "  steps {}{switching} rejected {} rhs {} events {} cpu {} ms",
        w.steps.unwrap_or(0),
        w.rejected_steps.unwrap_or(0),
        w.rhs_evals.unwrap_or(0),
        w.events.unwrap_or(0),
        opt(w.cpu_s, 1e3, 3)
    );
}

/// The free scene's measurement (MODEL.md §14.4), in a free-kind evaluation or simulation.
pub fn print_free(f: &FreeSceneRecord, x_off: Option<f64>) {
    outln!(
        "free scene (x_off {} mm): the impact and force criteria above are the prediction; this measurement decides",
        opt(x_off, 1e3, 3)
    );
    let Some(end) = f.end else {
        outln!("  not run (the centred grasp was discarded first)");
        return;
    };
    if !end.observed() {
        outln!("  ended early at t {} ms: {end} (nothing observed: no verdict)", milli(f.t_end));
    }
    outln!(
        "  object max displacement {} mm (dx {} mm, dy {} mm)  max tilt {} deg  final {} mm / {} deg",
        milli(f.object_max_displacement),
        milli(f.object_max_dx),
        milli(f.object_max_dy),
        dec4(f.object_max_tilt_deg),
        milli(f.object_final_displacement),
        dec4(f.object_final_tilt_deg)
    );
    outln!(
        "  peak E_trans {} mJ  E_rot {} mJ during the first contact",
        milli(f.object_peak_e_trans),
        milli(f.object_peak_e_rot)
    );
    outln!(
        "  moved {}  toppled {}  escaped {}  rim_contact {}",
        yes_no(f.moved),
        yes_no(f.toppled),
        yes_no(f.escaped),
        yes_no(f.rim_contact)
    );
    print_impact(&f.impact, None);
    print_work(&f.work);
}
