//! The generic step loop (MODEL.md §8.7): take a step, find the earliest event in it
//! ([`EventSearch`]), let the scene handle it, restart the stepper, and report samples at
//! steps, events and on a uniform grid to the caller's [`Sink`]. Knows nothing of fingers
//! or criteria.

use super::events::{Crossing, EventKind, EventSearch, EventValues};
use super::integrate::{hermite, Dopri5, Radau5, Stats, StepError, StepPoint, Stepper, Switching, Tol, TrBdf2};
use super::result::MAX_EVENTS;
use super::scene::{End, Response, Run, Scene};
use super::settings::{Controls, Integration, Method};
use super::sink::{EventNote, Point, Sink};
use nalgebra::SVector;

/// Run `scene` from t = 0 to `t_end` with the method, first step and budget of `integ`,
/// the tolerances `tol` and the grid of `ctl`, reporting to `sink`, and return how the
/// run ended (the scene, which keeps its criteria, makes its own output from it).
pub fn simulate<const N: usize, const E: usize, Sc: Scene<N, E>, K: Sink + ?Sized>(
    scene: &mut Sc,
    integ: &Integration,
    ctl: &Controls,
    tol: Tol<N>,
    t_end: f64,
    sink: &mut K,
) -> Run<N, Sc::Eval> {
    match integ.method {
        Method::Radau5 => drive(scene, &mut Radau5::<N>::new(tol, integ.h0), integ, ctl, t_end, sink),
        Method::TrBdf2 => drive(scene, &mut TrBdf2::new(tol, integ.h0), integ, ctl, t_end, sink),
        Method::Dopri5 => drive(scene, &mut Dopri5::new(tol, integ.h0), integ, ctl, t_end, sink),
        Method::Auto => drive(scene, &mut Switching::new(tol, integ.h0), integ, ctl, t_end, sink),
    }
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
    let mut run = Run {
        end: End::Undefined,
        t: 0.0,
        y: scene.initial_state(),
        last: None,
        events: 0,
        stats: Stats::default(),
        locate_evals: 0,
    };
    let Some(Begun { mut y, mut ev, mut g, mut search }) = begin(scene, &mut run, sink) else {
        run.stats = stepper.stats();
        return run;
    };
    let mut fy = scene.derivative(&y, &ev);
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
                grid_samples(scene, &interp, &mut grid_next, dt, t_stop, sink);
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
        g = scene.event_values(&y, &ev);
        let mut stop = response.stop;
        if !stop && any_stranded(scene, &search, &g) {
            match stranded_onsets(scene, &search, t, &y, &mut ev, &mut g, &mut run.events, sink) {
                Ok(r) => {
                    if r.restart {
                        stepper.restart();
                    }
                    stop = r.stop;
                }
                Err(end) => break end,
            }
        }
        fy = scene.derivative(&y, &ev);
        scene.track(Point::Event, &ev, &g);
        if record {
            scene.sample(Point::Event, t, &y, &ev, sink);
        }
        if stop {
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

/// Where the step loop starts: the state as the scene begins, its evaluation and event
/// values, and the event search over the scene's events.
struct Begun<const N: usize, const E: usize, Ev> {
    y: SVector<f64, N>,
    ev: Ev,
    g: EventValues<E>,
    search: EventSearch<E>,
}

/// Begin the run at `run.y` (the initial state): the scene's `begin`, then the state as it
/// begins and, for a contact that starts past δ = 0 within `begin`'s allowance, its onset at
/// t = 0⁺ (MODEL.md §8.7, for the reason [`stranded_onsets`] gives). None: the run ended
/// before its first step (`run.end`, and `run.last` when the scene stopped it, set).
fn begin<const N: usize, const E: usize, Sc: Scene<N, E>, K: Sink + ?Sized>(
    scene: &mut Sc,
    run: &mut Run<N, Sc::Eval>,
    sink: &mut K,
) -> Option<Begun<N, E, Sc::Eval>> {
    let y = run.y;
    let ev = scene.evaluate(&y)?;
    let g = scene.event_values(&y, &ev);
    if !scene.begin(&y, &ev, &g) {
        run.end = End::Declined;
        return None;
    }
    // `begin` may set contact memories (the free scene's ground points, pre-sunk at rest, are
    // in contact from the start): the initial derivative, event values and sample are those
    // of the state as it begins, as after an event's response
    let mut ev = scene.evaluate(&y)?;
    let mut g = scene.event_values(&y, &ev);
    let search = EventSearch::new(scene.events());
    if any_stranded(scene, &search, &g) {
        match stranded_onsets(scene, &search, 0.0, &y, &mut ev, &mut g, &mut run.events, sink) {
            Ok(r) if !r.stop => {}
            Ok(_) => {
                run.end = End::Stopped;
                run.last = Some(ev);
                return None;
            }
            Err(end) => {
                run.end = end;
                return None;
            }
        }
    }
    Some(Begun { y, ev, g, search })
}

/// The uniform grid's samples from `*next` up to `t_stop` (inside the accepted part of a
/// step), the state at each from `interp`; `*next` moves past them by `dt`.
#[inline]
fn grid_samples<const N: usize, const E: usize, Sc: Scene<N, E>, K: Sink + ?Sized>(
    scene: &Sc,
    interp: &impl Fn(f64) -> SVector<f64, N>,
    next: &mut f64,
    dt: f64,
    t_stop: f64,
    sink: &mut K,
) {
    while *next <= t_stop {
        let yg = interp(*next);
        if let Some(evg) = scene.evaluate(&yg) {
            scene.sample(Point::Grid, *next, &yg, &evg, sink);
        }
        *next += dt;
    }
}

/// Onsets of contacts stranded past their threshold at an event's state (time `t`, state `y`,
/// its evaluation `ev` and event values `g`, both updated here).
///
/// An event located within rounding of another contact's δ = 0 can leave that contact at
/// δ > 0 with no memory: §8.7 gives the others an onset only when δ̇ > 0 as well, and a
/// grazing contact's δ̇ is rounding noise too (the free scene's palm, placed at δ = 0, sits at
/// |δ| ~ 1e-16 until a finger pushes the object onto it). Its event function, already > 0,
/// can then never be seen crossing up: the contact penetrates with no force until some later
/// event's sweep happens to give it an onset, at whatever δ̇ it has by then. Which side of
/// zero the rounding falls on depends on the interpolant the event state was taken from, so
/// the outcome did too (docs/benchmarks.md, "Stiffness switching"). Each such contact gets
/// its own onset here, as if located now (δ̇⁻ floored at v_min, docs/model.md item 8), noted
/// as an event of zero-length step. Err: the run ends (too many events, model undefined).
#[allow(clippy::too_many_arguments)]
// rare: kept out of the step loop's code ([`any_stranded`] decides whether to call it)
#[inline(never)]
fn stranded_onsets<const N: usize, const E: usize, Sc: Scene<N, E>, K: Sink + ?Sized>(
    scene: &mut Sc,
    search: &EventSearch<E>,
    t: f64,
    y: &SVector<f64, N>,
    ev: &mut Sc::Eval,
    g: &mut EventValues<E>,
    events: &mut u32,
    sink: &mut K,
) -> Result<Response, End> {
    let mut out = Response { restart: false, stop: false };
    for k in 0..E {
        if !stranded(scene, search, g, k) {
            continue;
        }
        sink.event(&EventNote { kind: search.kind(k), t, step: [t, t], memories: scene.memories() });
        *events += 1;
        if *events > MAX_EVENTS {
            return Err(End::Aborted);
        }
        let response = scene.handle(k, t, ev, g);
        out.restart |= response.restart;
        *ev = scene.evaluate(y).ok_or(End::Undefined)?;
        *g = scene.event_values(y, ev);
        if response.stop {
            out.stop = true;
            break;
        }
    }
    Ok(out)
}

/// Is contact event `k` stranded: an onset (up) crossing whose event value is already > 0?
#[inline]
fn stranded<const N: usize, const E: usize, Sc: Scene<N, E>>(
    scene: &Sc,
    search: &EventSearch<E>,
    g: &EventValues<E>,
    k: usize,
) -> bool {
    g.g[k] > 0.0 && matches!(search.kind(k), EventKind::Contact(_)) && scene.crossing(k) == Some(Crossing::Up)
}

/// Does any contact need [`stranded_onsets`]?
#[inline]
fn any_stranded<const N: usize, const E: usize, Sc: Scene<N, E>>(
    scene: &Sc,
    search: &EventSearch<E>,
    g: &EventValues<E>,
) -> bool {
    (0..E).any(|k| stranded(scene, search, g, k))
}
