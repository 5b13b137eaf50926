//! The generic step loop (MODEL.md §8.7): take a step, find the earliest event in it
//! (sampling inside the step where an event may open and close again), locate it on the
//! dense interpolant, let the scene handle it, restart the stepper, and sample the
//! trajectory at steps, events and on a uniform grid. Knows nothing of fingers or criteria.

use super::events::{hermite_may_cross, locate, EventKind, EventValues};
use super::integrate::{hermite, Dopri5, Radau5, Stats, StepError, Stepper, Tol, TrBdf2};
use super::result::{Method, SimOptions, MAX_EVENTS};
use super::scene::{Point, Scene};
use nalgebra::SVector;

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// The scene asked to stop at an event.
    Stopped,
    /// The end time was reached.
    TimeUp,
    /// The budget of accepted + rejected steps was spent.
    StepBudget,
    /// The step size underflowed.
    StepTooSmall,
    /// The model was undefined at a state the run reached.
    Undefined,
    /// More than [`MAX_EVENTS`] events.
    Aborted,
    /// The scene refused the initial state ([`Scene::begin`]).
    Declined,
}

/// The driver's account of a run.
#[derive(Debug, Clone, Copy)]
pub struct Run<Ev> {
    /// How it ended.
    pub end: End,
    /// The time reached.
    pub t: f64,
    /// The evaluation at the last state reached (None: ended before the first step).
    pub last: Option<Ev>,
    /// Events located (including one that aborted the run).
    pub events: u32,
    /// The stepper's counters.
    pub stats: Stats,
    /// Model evaluations made to locate events (count as right-hand-side evaluations).
    pub locate_evals: u64,
}

/// Run `scene` from t = 0 to `t_end` with the method, budget, recording and tracing of
/// `opts` and the tolerances `tol`, and return the scene's output.
pub fn simulate<const N: usize, const E: usize, Sc: Scene<N, E>>(
    mut scene: Sc,
    opts: &SimOptions,
    tol: Tol<N>,
    t_end: f64,
) -> Sc::Output {
    let run = match opts.method {
        Method::Radau5 => drive(&mut scene, &mut Radau5::<N>::new(tol, 1e-5), opts, t_end),
        Method::TrBdf2 => drive(&mut scene, &mut TrBdf2::new(tol, 1e-5), opts, t_end),
        Method::Dopri5 => drive(&mut scene, &mut Dopri5::new(tol, 1e-6), opts, t_end),
    };
    scene.finish(&run)
}

/// The step loop with a given stepper.
pub fn drive<const N: usize, const E: usize, Sc: Scene<N, E>, St: Stepper<N>>(
    scene: &mut Sc,
    stepper: &mut St,
    opts: &SimOptions,
    t_max: f64,
) -> Run<Sc::Eval> {
    let mut run = Run { end: End::Undefined, t: 0.0, last: None, events: 0, stats: Stats::default(), locate_evals: 0 };
    let mut t = 0.0;
    let mut y = scene.initial_state();
    let Some(mut ev) = scene.evaluate(&y) else {
        run.stats = stepper.stats();
        return run;
    };
    let mut g = scene.event_values(&y, &ev);
    if !scene.begin(&y, &ev, &g) {
        run.end = End::Declined;
        run.stats = stepper.stats();
        return run;
    }
    let mut fy = scene.derivative(&y, &ev);
    let kinds = scene.events();
    let record = opts.record;
    let mut grid_next = 0.0;
    if record {
        scene.sample(Point::Start, t, &y, &ev);
    }
    run.end = loop {
        let stats = stepper.stats();
        if stats.steps + stats.rejected >= opts.max_steps {
            break End::StepBudget;
        }
        if t >= t_max * (1.0 - 1e-15) {
            break End::TimeUp;
        }
        let acc = match stepper.advance(scene, t, &y, &fy, t_max - t) {
            Ok(a) => a,
            Err(StepError::StepTooSmall) => break End::StepTooSmall,
            Err(StepError::RhsFailed) => break End::Undefined,
        };
        let Some(ev1) = scene.take_accepted(&acc.y).or_else(|| scene.evaluate(&acc.y)) else {
            break End::Undefined;
        };
        let g1 = scene.event_values(&acc.y, &ev1);
        let (t0, y0, f0) = (t, y, fy);
        let interp = |tt: f64| hermite(t0, &y0, &f0, acc.t, &acc.y, &acc.f, tt);
        let best = earliest_event(scene, &kinds, &interp, (t0, &g), (acc.t, &g1), &mut run.locate_evals);
        // uniform grid samples inside the accepted part of the step
        let t_stop = best.map(|b| b.0).unwrap_or(acc.t);
        if record {
            if let Some(dt) = opts.grid_dt {
                while grid_next <= t_stop {
                    let yg = interp(grid_next);
                    if let Some(evg) = scene.evaluate(&yg) {
                        scene.sample(Point::Grid, grid_next, &yg, &evg);
                    }
                    grid_next += dt;
                }
            }
        }
        let Some((te, k)) = best else {
            t = acc.t;
            y = acc.y;
            fy = acc.f;
            ev = ev1;
            g = g1;
            scene.track(Point::Step, &ev, &g);
            if record {
                scene.sample(Point::Step, t, &y, &ev);
            }
            continue;
        };
        // ---- process the event at te ----------------------------------------------------
        if opts.trace {
            eprintln!("event {:?} at t {te:.9e} (step {t0:.9e}..{:.9e}) {}", kinds[k], acc.t, scene.trace_state());
        }
        run.events += 1;
        if run.events > MAX_EVENTS {
            break End::Aborted;
        }
        t = te;
        y = interp(te);
        let Some(eve) = scene.evaluate(&y) else { break End::Undefined };
        ev = eve;
        let response = scene.handle(k, t, &ev, &g1);
        if response.restart {
            stepper.restart(stepper.h());
        }
        let Some(ev2) = scene.evaluate(&y) else { break End::Undefined };
        ev = ev2;
        fy = scene.derivative(&y, &ev);
        g = scene.event_values(&y, &ev);
        scene.track(Point::Event, &ev, &g);
        if record {
            scene.sample(Point::Event, t, &y, &ev);
        }
        if response.stop {
            break End::Stopped;
        }
    };
    run.t = t;
    run.last = Some(ev);
    run.stats = stepper.stats();
    run
}

/// The earliest event in the step (t0, t1] with event values `g0`, `g1` at its ends, as
/// (time, index). Events that may open and close inside the step are sampled at four
/// points where the cubic through the end values and rates may cross.
fn earliest_event<const N: usize, const E: usize, Sc: Scene<N, E>>(
    scene: &Sc,
    kinds: &[EventKind; E],
    interp: &impl Fn(f64) -> SVector<f64, N>,
    (t0, g0): (f64, &EventValues<E>),
    (t1, g1): (f64, &EventValues<E>),
    evals: &mut u64,
) -> Option<(f64, usize)> {
    // g_k on the interpolant at t (each evaluation counted)
    let mut at = |k: usize, t: f64| {
        let y = interp(t);
        *evals += 1;
        let ev = scene.evaluate(&y)?;
        Some(scene.event_values(&y, &ev).g[k])
    };
    let mut best: Option<(f64, usize)> = None;
    let mut sampled = false;
    for k in 0..E {
        let Some(crossing) = scene.crossing(k) else { continue };
        let (ga, gb) = (g0.g[k], g1.g[k]);
        if crossing.crossed(ga, gb) {
            let te = locate(crossing, t0, ga, t1, gb, |t| at(k, t));
            if best.is_none_or(|(tb, _)| te < tb) {
                best = Some((te, k));
            }
        } else if kinds[k].sampled_inside() && !sampled && hermite_may_cross(ga, g0.rate[k], gb, g1.rate[k], t1 - t0) {
            sampled = true;
            let mut ta = t0;
            let mut gprev = *g0;
            for j in 1..=4 {
                let tj = t0 + (t1 - t0) * j as f64 / 4.0;
                let gj = if j == 4 {
                    *g1
                } else {
                    let yj = interp(tj);
                    let Some(evj) = scene.evaluate(&yj) else { break };
                    scene.event_values(&yj, &evj)
                };
                for kk in 0..E {
                    if !kinds[kk].sampled_inside() {
                        continue;
                    }
                    let Some(c) = scene.crossing(kk) else { continue };
                    let (a, b) = (gprev.g[kk], gj.g[kk]);
                    if c.crossed(a, b) && j < 4 {
                        let te = locate(c, ta, a, tj, b, |t| at(kk, t));
                        if best.is_none_or(|(tb, _)| te < tb) {
                            best = Some((te, kk));
                        }
                    }
                }
                if best.is_some_and(|(tb, _)| tb <= tj) {
                    break;
                }
                ta = tj;
                gprev = gj;
            }
        }
    }
    best
}
