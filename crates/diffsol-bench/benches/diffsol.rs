//! The fixed-object grasp through diffsol's solvers (TR-BDF2, ESDIRK34, BDF), against the
//! reference of `gripopt bench work-precision`: a comparison, not a second simulator.
//!
//! `cargo bench -p gripopt-diffsol-bench --bench diffsol [-- PROBLEM --rtols … --atol … --out …]`
//! writes `OUT/work_precision_diffsol.csv` and `.svg` (diffsol's rows only; with
//! `--with-gripopt` gripopt's own rows first, in all three) and prints the table. The
//! reference, the error measures and the writers are the library's (`gripopt::bench`).
//!
//! Same right-hand side ([`FingerOde`]), the simulator's own contact-memory rule
//! ([`Memory::update`], [`Memory::event_value`]) and the same first-contact, t_stab and
//! final-force outputs as the simulator; the force criterion and the singularity event are
//! left out (the benchmark designs meet neither). diffsol's explicit Tsit45 is not compared:
//! restarted at the first onset through `state_mut`, it ran on to t_max in a few steps.

use anyhow::Result;
use clap::Parser;
use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod, OdeSolverStopReason, Vector};
use gripopt::bench::{print_table, print_targets, time_it, Measured, Reference, Row, WorkPrecision};
use gripopt::eval::StaticsResult;
use gripopt::model::Finger;
use gripopt::params::{Design, Problem, SceneParams};
use gripopt::sim::compliant_equilibrium;
use gripopt::sim::Rhs;
use gripopt::sim::{impact, u_min};
use gripopt::sim::{FingerOde, State, NS};
use gripopt::sim::{Memory, MemoryChange, MAX_EVENTS};
use std::cell::{Cell, RefCell};
use std::path::PathBuf;

type M = NalgebraMat<f64>;
type LS = NalgebraLU<f64>;

/// The diffsol rows of the work-precision table (`cargo bench -p gripopt-diffsol-bench --bench diffsol -- …`).
#[derive(Parser)]
#[command(name = "diffsol-bench")]
struct Args {
    /// Problem file (a relative path is taken from the repository root: `cargo bench`
    /// runs a bench in its package's folder).
    #[arg(default_value = "problems/bottle-1l.toml")]
    problem: PathBuf,
    /// Design (default: the problem's nominal).
    #[arg(long)]
    design: Option<String>,
    /// Output folder (relative: from the repository root).
    #[arg(long, default_value = "results/bench")]
    out: PathBuf,
    /// Maximum repetitions per point (each point also stops after ~1 s).
    #[arg(long, default_value_t = 200)]
    reps: usize,
    /// Absolute tolerance on angles and rates, fixed for every rtol (default: 1e-3·rtol).
    #[arg(long)]
    atol: Option<f64>,
    /// Relative tolerances, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8])]
    rtols: Vec<f64>,
    /// Also gripopt's own integrators (Radau IIA, TR-BDF2, Dormand–Prince), first in the
    /// table, the CSV and the plot.
    #[arg(long)]
    with_gripopt: bool,
    /// Passed by `cargo bench`; ignored.
    #[arg(long, hide = true)]
    bench: bool,
}

fn main() -> Result<()> {
    let mut a = Args::parse();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for p in [&mut a.problem, &mut a.out] {
        if p.is_relative() {
            *p = root.join(&*p);
        }
    }
    gripopt::bench::check_atol(a.atol)?;
    let p = Problem::load(&a.problem)?;
    let design = match &a.design {
        None => p.nominal,
        Some(s) => Design::parse_assignments(s).map_err(anyhow::Error::msg)?,
    };
    let reference = Reference::new(&p, &design)?;
    reference.print(a.atol, &mut std::io::stdout())?;
    let wp = WorkPrecision { out_dir: a.out.clone(), reps: a.reps, atol: a.atol, rtols: a.rtols.clone() };
    let mut rows = if a.with_gripopt { reference.own_rows(&wp) } else { vec![] };
    rows.extend(diffsol_rows(&reference, &wp));
    let csv = a.out.join("work_precision_diffsol.csv");
    let svg = a.out.join("work_precision_diffsol.svg");
    gripopt::bench::write_csv(&rows, &csv)?;
    print_table(&rows, &mut std::io::stdout())?;
    print_targets(&rows, &mut std::io::stdout())?;
    gripopt::bench::plot(&rows, &svg)?;
    println!("wrote {} and {}", csv.display(), svg.display());
    Ok(())
}

/// The grasp through each diffsol method at each rtol of `wp`, against `reference`; a
/// failed point is reported on stderr and left out.
fn diffsol_rows(reference: &Reference, wp: &WorkPrecision) -> Vec<Row> {
    let (f, s, st) = (&reference.finger, &reference.scene, &reference.statics);
    let mut rows = vec![];
    let pb = indicatif::ProgressBar::new((DsMethod::ALL.len() * wp.rtols.len()) as u64);
    pb.set_style(indicatif::ProgressStyle::with_template("diffsol [{bar:30}] {pos}/{len} {msg}").expect("template"));
    for m in DsMethod::ALL {
        for &rtol in &wp.rtols {
            pb.set_message(format!("{} rtol {rtol:e}", m.label()));
            pb.inc(1);
            let (r, tmin, tmed) = time_it(|| simulate(f, s, st, m, rtol, wp.atol_at(rtol)), 1.0, wp.reps);
            match r {
                Ok(r) => {
                    let measured = Measured {
                        t_first: r.t_first,
                        e_cyl: r.e_cyl,
                        t_stab: r.t_stab,
                        f_end: r.f_end,
                        steps: r.steps,
                        rhs: r.rhs,
                        same_verdict: r.t_stab.is_some() == reference.run.t_stab.is_some(),
                    };
                    rows.push(reference.row(m.label(), rtol, tmin, tmed, &measured));
                }
                Err(e) => pb.suspend(|| eprintln!("{} rtol {rtol:e}: failed ({e})", m.label())),
            }
        }
    }
    pb.finish_and_clear();
    rows
}

/// A diffsol method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DsMethod {
    /// diffsol's SDIRK with the TR-BDF2 tableau.
    TrBdf2,
    /// diffsol's ESDIRK 3(4).
    Esdirk34,
    /// diffsol's variable-order BDF (NDF).
    Bdf,
}

impl DsMethod {
    /// All methods compared.
    const ALL: [DsMethod; 3] = [DsMethod::TrBdf2, DsMethod::Esdirk34, DsMethod::Bdf];

    /// Label of the benchmark table.
    fn label(self) -> &'static str {
        match self {
            DsMethod::TrBdf2 => "ds-TrBdf2",
            DsMethod::Esdirk34 => "ds-Esdirk34",
            DsMethod::Bdf => "ds-Bdf",
        }
    }
}

/// What the comparison measures (the quantities of the work-precision table).
#[derive(Debug, Clone, Copy)]
struct DsResult {
    /// Time of the first contact onset.
    t_first: Option<f64>,
    /// E_cyl of the first impact.
    e_cyl: Option<f64>,
    /// Time to stability.
    t_stab: Option<f64>,
    /// Normal forces at t_stab.
    f_end: [f64; 2],
    /// Accepted steps.
    steps: u64,
    /// Right-hand-side evaluations, Jacobian products included.
    rhs: u64,
}

/// Simulate the nominal-scene grasp of finger `f` with a diffsol method at `rtol` (atol as
/// in `sim::grasp`: `atol` on angles and rates, 1e4·atol on the filtered force).
fn simulate(
    f: &Finger,
    s: &SceneParams,
    st: &StaticsResult,
    method: DsMethod,
    rtol: f64,
    atol: f64,
) -> anyhow::Result<DsResult> {
    let base = FingerOde::new(f, s, st.tau_s0, 0.0);
    let eq = compliant_equilibrium(&base, s, st.grasp.f0).ok_or_else(|| anyhow::anyhow!("no compliant equilibrium"))?;
    let threshold = s.criteria.eta_stab * u_min(s, st.grasp.f0);
    let mem = Cell::new([Memory::default(); 2]);
    let after_first = Cell::new(false);
    let evals = Cell::new(0u64);
    let ode = RefCell::new(base);
    let rhs = |x: &[f64], _p: &[f64], t: f64, out: &mut [f64]| {
        let mut o = ode.borrow_mut();
        o.mem = mem.get();
        evals.set(evals.get() + 1);
        let d = o.eval(t, &State::from_column_slice(x)).unwrap_or(State::repeat(f64::NAN));
        out.copy_from_slice(d.as_slice());
    };
    // J·v by a forward difference of the same right-hand side.
    let jac = |x: &[f64], p: &[f64], t: f64, v: &[f64], out: &mut [f64]| {
        let xs = State::from_column_slice(x);
        let vs = State::from_column_slice(v);
        let vn = vs.amax();
        if vn == 0.0 {
            out.fill(0.0);
            return;
        }
        let eps = f64::EPSILON.sqrt() * xs.amax().max(1.0) / vn;
        let mut f0 = [0.0; NS];
        let mut f1 = [0.0; NS];
        rhs(x, p, t, &mut f0);
        rhs((xs + eps * vs).as_slice(), p, t, &mut f1);
        for (o, (a, b)) in out.iter_mut().zip(f1.iter().zip(&f0)) {
            *o = (a - b) / eps;
        }
    };
    let roots = |x: &[f64], _p: &[f64], _t: f64, out: &mut [f64]| {
        let mut o = ode.borrow_mut();
        o.mem = mem.get();
        match o.evaluate(&State::from_column_slice(x)) {
            Some(ev) => {
                for (i, g) in out.iter_mut().take(2).enumerate() {
                    *g = o.mem[i].event_value(ev.contacts[i].geom.delta, s.contact.eps_sep);
                }
                out[2] = if after_first.get() { ev.energy - eq.v_star - threshold } else { 1.0 };
                // the distal stop engaging or releasing: a kink of the right-hand side
                out[3] = ev.theta2;
            }
            None => out.fill(f64::NAN),
        }
    };
    let y0 = [f.open.q11, f.open.q21, 0.0, 0.0, 0.0];
    let mut problem = OdeBuilder::<M>::new()
        .rtol(rtol)
        .atol([atol, atol, atol, atol, atol * 1e4])
        .rhs_implicit(rhs, jac)
        .init(move |_p, _t, y: &mut [f64]| y.copy_from_slice(&y0), NS)
        .root(roots, 4)
        .build()
        .map_err(|e| anyhow::anyhow!("diffsol problem: {e}"))?;
    // diffsol counts Newton failures over the whole run (default limit 50); a grasp with
    // contact kinks has more than that, as gripopt's own Radau IIA has on the nominal.
    problem.ode_options.max_nonlinear_solver_failures = 1_000_000;
    match method {
        DsMethod::TrBdf2 => run(problem.tr_bdf2::<LS>()?, s, &ode, &mem, &after_first, &evals),
        DsMethod::Esdirk34 => run(problem.esdirk34::<LS>()?, s, &ode, &mem, &after_first, &evals),
        DsMethod::Bdf => run(problem.bdf::<LS>()?, s, &ode, &mem, &after_first, &evals),
    }
}

fn run<'a, Eqn, S>(
    mut solver: S,
    s: &SceneParams,
    ode: &RefCell<FingerOde>,
    mem: &Cell<[Memory; 2]>,
    after_first: &Cell<bool>,
    evals: &Cell<u64>,
) -> anyhow::Result<DsResult>
where
    Eqn: diffsol::OdeEquations<T = f64, V = <M as diffsol::MatrixCommon>::V> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
{
    let mut out = DsResult { t_first: None, e_cyl: None, t_stab: None, f_end: [f64::NAN; 2], steps: 0, rhs: 0 };
    solver.set_stop_time(s.criteria.t_max).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut events = 0u32;
    loop {
        match solver.step().map_err(|e| anyhow::anyhow!("diffsol step: {e}"))? {
            OdeSolverStopReason::InternalTimestep => {
                if solver.get_statistics().number_of_steps > 5_000_000 {
                    anyhow::bail!("more than 5e6 steps");
                }
            }
            OdeSolverStopReason::TstopReached => break,
            OdeSolverStopReason::RootFound(tr, k) => {
                events += 1;
                if events > MAX_EVENTS {
                    anyhow::bail!("more than {MAX_EVENTS} events");
                }
                let tr = if k < 2 { past_crossing(&solver, s, ode, mem.get(), tr, k)? } else { tr };
                let yv = solver.interpolate(tr).map_err(|e| anyhow::anyhow!("{e}"))?;
                let y = State::from_fn(|i, _| yv.get_index(i));
                let mut o = ode.borrow_mut();
                o.mem = mem.get();
                let ev = o.evaluate(&y).ok_or_else(|| anyhow::anyhow!("DGM failed at an event"))?;
                if k == 2 {
                    out.t_stab = Some(tr);
                    out.f_end = [ev.contacts[0].normal_force, ev.contacts[1].normal_force];
                    break;
                }
                // k == 3: the stop kink, restarted below with the same right-hand side;
                // otherwise the simulator's memory rule: the located contact changes, any
                // other one that is penetrating and approaching gets its onset too
                let mut m = mem.get();
                for i in (0..2).filter(|_| k < 2) {
                    let c = &ev.contacts[i];
                    let change = m[i].update(c.geom.delta, c.delta_dot, i == k, s.contact.eps_sep, s.contact.v_min);
                    if change == MemoryChange::Onset && out.t_first.is_none() {
                        let minv = ev.m.try_inverse().unwrap_or_default();
                        out.t_first = Some(tr);
                        out.e_cyl = Some(impact(s, 1.0 / c.row.dot(&(minv * c.row)), c.delta_dot).e_cyl);
                        after_first.set(true);
                    }
                }
                mem.set(m);
                o.mem = m;
                drop(o);
                // restart at the event (with the new right-hand side after a contact change)
                let d = ode.borrow_mut().eval(tr, &y).ok_or_else(|| anyhow::anyhow!("RHS failed at an event"))?;
                let st = solver.state_mut();
                for i in 0..NS {
                    st.y.set_index(i, y[i]);
                    st.dy.set_index(i, d[i]);
                }
                *st.t = tr;
            }
        }
    }
    let stats = solver.get_statistics();
    out.steps = stats.number_of_steps as u64;
    out.rhs = evals.get();
    Ok(out)
}

/// The first time at or after `tr` (within the last step) where contact `k`'s event
/// function has crossed: positive for an inactive contact (onset), negative for an active one
/// (separation). diffsol's root finder may return a time where the event function is exactly
/// zero; the simulator's locator returns a time past the crossing, and that is what the
/// memory rule's "located" contact means. Steps of 1, 2, 4, … ulps; `tr` if none crosses.
fn past_crossing<'a, Eqn, S>(
    solver: &S,
    s: &SceneParams,
    ode: &RefCell<FingerOde>,
    mem: [Memory; 2],
    tr: f64,
    k: usize,
) -> anyhow::Result<f64>
where
    Eqn: diffsol::OdeEquations<T = f64, V = <M as diffsol::MatrixCommon>::V> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
{
    let crossed = |t: f64| -> anyhow::Result<bool> {
        let yv = solver.interpolate(t).map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut o = ode.borrow_mut();
        o.mem = mem;
        let ev = o
            .evaluate(&State::from_fn(|i, _| yv.get_index(i)))
            .ok_or_else(|| anyhow::anyhow!("DGM failed at an event"))?;
        let g = mem[k].event_value(ev.contacts[k].geom.delta, s.contact.eps_sep);
        Ok(if mem[k].active { g < 0.0 } else { g > 0.0 })
    };
    if crossed(tr)? {
        return Ok(tr);
    }
    let t_end = solver.state().t;
    let mut dt = tr.abs().max(f64::MIN_POSITIVE) * f64::EPSILON;
    for _ in 0..64 {
        let t = (tr + dt).min(t_end);
        if crossed(t)? {
            return Ok(t);
        }
        if t >= t_end {
            break;
        }
        dt *= 2.0;
    }
    Ok(tr)
}
