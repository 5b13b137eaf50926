//! The fixed-object grasp through diffsol's solvers (feature `diffsol`): a comparison for
//! `gripopt bench work-precision`, not a second simulator. Same right-hand side
//! ([`FingerOde`]), same contact memory rules and the same first-contact, t_stab and
//! final-force outputs as `sim::grasp`; the force criterion and the singularity event are
//! left out (the benchmark designs meet neither). diffsol's explicit Tsit45 is not compared:
//! restarted at the first onset through `state_mut`, it ran on to t_max in a few steps.

use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod, OdeSolverStopReason, Vector};
use gripopt::model::geometry::Finger;
use gripopt::eval::StaticsResult;
use gripopt::params::SceneParams;
use gripopt::sim::{impact, u_min};
use gripopt::sim::{FingerOde, Memory, State, NS};
use gripopt::sim::compliant_equilibrium;
use gripopt::sim::Rhs;
use std::cell::{Cell, RefCell};

type M = NalgebraMat<f64>;
type LS = NalgebraLU<f64>;

/// A diffsol method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DsMethod {
    /// diffsol's SDIRK with the TR-BDF2 tableau.
    TrBdf2,
    /// diffsol's ESDIRK 3(4).
    Esdirk34,
    /// diffsol's variable-order BDF (NDF).
    Bdf,
}

impl DsMethod {
    /// All methods compared.
    pub const ALL: [DsMethod; 3] = [DsMethod::TrBdf2, DsMethod::Esdirk34, DsMethod::Bdf];

    /// Label of the benchmark table.
    pub fn label(self) -> &'static str {
        match self {
            DsMethod::TrBdf2 => "ds-TrBdf2",
            DsMethod::Esdirk34 => "ds-Esdirk34",
            DsMethod::Bdf => "ds-Bdf",
        }
    }
}

/// What the comparison measures (the quantities of the work-precision table).
#[derive(Debug, Clone, Copy)]
pub struct DsResult {
    /// Time of the first contact onset.
    pub t_first: Option<f64>,
    /// E_cyl of the first impact.
    pub e_cyl: Option<f64>,
    /// Time to stability.
    pub t_stab: Option<f64>,
    /// Normal forces at t_stab.
    pub f_end: [f64; 2],
    /// Accepted steps.
    pub steps: u64,
    /// Right-hand-side evaluations, Jacobian products included.
    pub rhs: u64,
}

/// Simulate the nominal-scene grasp of finger `f` with a diffsol method at `rtol` (atol as
/// in `sim::grasp`: `atol` on angles and rates, 1e4·atol on the filtered force).
pub fn simulate(f: &Finger, s: &SceneParams, st: &StaticsResult, method: DsMethod, rtol: f64, atol: f64) -> anyhow::Result<DsResult> {
    let base = FingerOde::new(f, s, st.tau_s0, 0.0);
    let eq = compliant_equilibrium(&base, s, st.f0).ok_or_else(|| anyhow::anyhow!("no compliant equilibrium"))?;
    let threshold = s.eta_stab * u_min(s, st.f0);
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
        for i in 0..NS {
            out[i] = (f1[i] - f0[i]) / eps;
        }
    };
    let roots = |x: &[f64], _p: &[f64], _t: f64, out: &mut [f64]| {
        let mut o = ode.borrow_mut();
        o.mem = mem.get();
        match o.evaluate(&State::from_column_slice(x)) {
            Some(ev) => {
                for i in 0..2 {
                    let d = ev.contacts[i].geom.delta;
                    out[i] = if o.mem[i].active { d + s.eps_sep } else { d };
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
    solver.set_stop_time(s.t_max).map_err(|e| anyhow::anyhow!("{e}"))?;
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
                if events > 20_000 {
                    anyhow::bail!("more than 20000 events");
                }
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
                // otherwise the same memory rules as sim::grasp: the located contact changes, any
                // other one that is penetrating and approaching gets its onset too
                let mut m = mem.get();
                for i in (0..2).filter(|_| k < 2) {
                    let c = &ev.contacts[i];
                    let located = i == k;
                    if !m[i].active && c.geom.delta >= 0.0 && (located || c.delta_dot > 0.0) {
                        m[i] = Memory { active: true, vminus: c.delta_dot.max(s.v_min) };
                        if out.t_first.is_none() {
                            let minv = ev.m.try_inverse().unwrap_or_default();
                            out.t_first = Some(tr);
                            out.e_cyl = Some(impact(s, 1.0 / c.row.dot(&(minv * c.row)), c.delta_dot).e_cyl);
                            after_first.set(true);
                        }
                    } else if m[i].active && c.geom.delta <= -s.eps_sep && (located || c.delta_dot < 0.0) {
                        m[i] = Memory::default();
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
