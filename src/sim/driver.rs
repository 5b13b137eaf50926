//! The generic step loop (MODEL.md §8.7): take a step, find the earliest event in it
//! ([`EventSearch`]), let the scene handle it, restart the stepper, and report samples at
//! steps, events and on a uniform grid to the caller's [`Sink`]. Knows nothing of fingers
//! or criteria.

use super::events::EventSearch;
use super::integrate::{hermite, Dopri5, Radau5, Stats, StepError, StepPoint, Stepper, Switching, Tol, TrBdf2};
use super::result::MAX_EVENTS;
use super::scene::{End, Run, Scene};
use super::settings::{Controls, Integration, Method};
use super::sink::{EventNote, Point, Sink};

/// Run `scene` from t = 0 to `t_end` with the method, first step and budget of `integ`,
/// the tolerances `tol` and the grid of `ctl`, reporting to `sink`, and return the
/// scene's output.
pub fn simulate<const N: usize, const E: usize, Sc: Scene<N, E>, K: Sink + ?Sized>(
    mut scene: Sc,
    integ: &Integration,
    ctl: &Controls,
    tol: Tol<N>,
    t_end: f64,
    sink: &mut K,
) -> Sc::Output {
    let run = match integ.method {
        Method::Radau5 => drive(&mut scene, &mut Radau5::<N>::new(tol, integ.h0), integ, ctl, t_end, sink),
        Method::TrBdf2 => drive(&mut scene, &mut TrBdf2::new(tol, integ.h0), integ, ctl, t_end, sink),
        Method::Dopri5 => drive(&mut scene, &mut Dopri5::new(tol, integ.h0), integ, ctl, t_end, sink),
        Method::Auto => drive(&mut scene, &mut Switching::new(tol, integ.h0), integ, ctl, t_end, sink),
    };
    scene.finish(&run)
}

/// The step loop with a given stepper.
pub fn drive<const N: usize, const E: usize, Sc: Scene<N, E>, St: Stepper<N>, K: Sink + ?Sized>(
    scene: &mut Sc,
    stepper: &mut St,
    integ: &Integration,
    ctl: &Controls,
    t_max: f64,
    sink: &mut K,
) -> Run<N, Sc::Eval> {
    let mut t = 0.0;
    let mut y = scene.initial_state();
    let mut run =
        Run { end: End::Undefined, t: 0.0, y, last: None, events: 0, stats: Stats::default(), locate_evals: 0 };
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
    // `begin` may set contact memories (the free scene's ground points, pre-sunk at rest, are
    // in contact from the start): the initial derivative, event values and sample are those
    // of the state as it begins, as after an event's response
    let Some(ev0) = scene.evaluate(&y) else {
        run.stats = stepper.stats();
        return run;
    };
    ev = ev0;
    g = scene.event_values(&y, &ev);
    let mut fy = scene.derivative(&y, &ev);
    let mut search = EventSearch::new(scene.events());
    let record = sink.wants_samples();
    let mut grid_next = 0.0;
    if record {
        scene.sample(Point::Start, t, &y, &ev, sink);
    }
    run.end = loop {
        let stats = stepper.stats();
        if stats.steps + stats.rejected >= integ.max_steps {
            break End::StepBudget;
        }
        if t >= t_max * (1.0 - 1e-15) {
            break End::TimeUp;
        }
        let from = StepPoint { t, y, f: fy };
        let acc = match stepper.advance(scene, &from, t_max - t) {
            Ok(a) => a,
            Err(StepError::StepTooSmall) => break End::StepTooSmall,
            Err(StepError::RhsFailed) => break End::Undefined,
        };
        let Some(ev1) = scene.take_accepted(&acc.y).or_else(|| scene.evaluate(&acc.y)) else {
            break End::Undefined;
        };
        let g1 = scene.event_values(&acc.y, &ev1);
        let own = stepper.dense_for_events();
        let st: &St = stepper;
        let interp = |tt: f64| {
            own.then(|| st.dense(tt))
                .flatten()
                .unwrap_or_else(|| hermite(from.t, &from.y, &from.f, acc.t, &acc.y, &acc.f, tt))
        };
        let sc: &Sc = scene;
        let best = search.earliest(
            |k| sc.crossing(k),
            |tt| {
                let yt = interp(tt);
                sc.evaluate(&yt).map(|e| sc.event_values(&yt, &e))
            },
            |k, tt| sc.event_value(k, &interp(tt)),
            (from.t, &g),
            (acc.t, &g1),
        );
        // uniform grid samples inside the accepted part of the step
        let t_stop = best.map(|b| b.0).unwrap_or(acc.t);
        if record {
            if let Some(dt) = ctl.grid_dt {
                while grid_next <= t_stop {
                    let yg = interp(grid_next);
                    if let Some(evg) = scene.evaluate(&yg) {
                        scene.sample(Point::Grid, grid_next, &yg, &evg, sink);
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
                scene.sample(Point::Step, t, &y, &ev, sink);
            }
            continue;
        };
        // ---- process the event at te ----------------------------------------------------
        sink.event(&EventNote { kind: search.kind(k), t: te, step: [from.t, acc.t], memories: scene.memories() });
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
            stepper.restart();
        }
        let Some(ev2) = scene.evaluate(&y) else { break End::Undefined };
        ev = ev2;
        fy = scene.derivative(&y, &ev);
        g = scene.event_values(&y, &ev);
        scene.track(Point::Event, &ev, &g);
        if record {
            scene.sample(Point::Event, t, &y, &ev, sink);
        }
        if response.stop {
            break End::Stopped;
        }
    };
    run.t = t;
    run.y = y;
    run.last = Some(ev);
    run.stats = stepper.stats();
    run.locate_evals = search.evals;
    run
}
