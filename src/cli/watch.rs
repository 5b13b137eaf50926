//! The sink of the CLI's single simulations (`evaluate`, `simulate`, `replay --scene`):
//! keeps the samples only when a CSV or plot asks for them (a stiff design can take
//! millions of steps), prints the trace of events when asked, and reports a simulation
//! still running after [`FIRST`] on stderr, then every [`EVERY`] (simulated time reached,
//! steps, seconds; on a terminal one line rewritten), so a long one (e.g. a tiny
//! `contact.v_s` with a large `solver.max_steps`) is never silent: ctrl-c stops it.

use crate::cli::csv_stream::CsvStream;
use gripopt::app::{EventNote, Point, PoseSample, Sample, Sink, Trajectory};
use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// When the first progress line is printed.
pub const FIRST: Duration = Duration::from_secs(2);
/// How often after that.
pub const EVERY: Duration = Duration::from_secs(5);

/// A CSV fed by the simulation: the grasp samples or the free scene's poses (steps and
/// events, not the grid).
pub enum Streamed {
    /// `simulate --csv` in the centred and offset scenes (true: with finger 2's columns,
    /// the offset scene).
    Samples(CsvStream, bool),
    /// `simulate --scene free --csv`.
    Poses(CsvStream),
}

impl Streamed {
    /// The stream, whichever it is.
    pub fn into_stream(self) -> CsvStream {
        match self {
            Streamed::Samples(s, _) | Streamed::Poses(s) => s,
        }
    }
}

/// Samples, trace and progress of one simulation.
pub struct Watch {
    /// Keep the samples (for `--csv`, `--plot`).
    keep: bool,
    /// Print every located event (`--trace`).
    trace: bool,
    /// The grasp samples kept.
    pub traj: Trajectory,
    /// The free scene's poses kept.
    pub poses: Vec<PoseSample>,
    /// The CSV the samples (or the free scene's poses) stream to, as they come.
    pub csv: Option<Streamed>,
    start: Instant,
    next: Duration,
    samples: u64,
    terminal: bool,
    shown: bool,
}

impl Watch {
    /// A sink keeping samples when `keep`, tracing events when `trace`.
    pub fn new(keep: bool, trace: bool) -> Self {
        Watch {
            keep,
            trace,
            traj: Trajectory::default(),
            poses: vec![],
            csv: None,
            start: Instant::now(),
            next: FIRST,
            samples: 0,
            terminal: std::io::stderr().is_terminal(),
            shown: false,
        }
    }

    fn tick(&mut self, t: f64) {
        self.samples += 1;
        if !self.samples.is_multiple_of(512) {
            return;
        }
        let e = self.start.elapsed();
        if e < self.next {
            return;
        }
        self.next = e + EVERY;
        let line = format!(
            "simulating: t = {:.4} ms of simulated time, {} steps, {:.0} s (ctrl-c stops it)",
            t * 1e3,
            self.samples,
            e.as_secs_f64()
        );
        let mut err = std::io::stderr().lock();
        let _ = if self.terminal { write!(err, "\r{line}") } else { writeln!(err, "{line}") };
        let _ = err.flush();
        self.shown = true;
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        if self.shown && self.terminal {
            let _ = writeln!(std::io::stderr());
        }
    }
}

impl Sink for Watch {
    fn wants_samples(&self) -> bool {
        true
    }
    fn finger(&mut self, at: Point, s: &Sample) {
        if self.keep {
            self.traj.finger(at, s);
        }
        if at != Point::Grid {
            if let Some(Streamed::Samples(c, finger2)) = self.csv.as_mut() {
                c.row(&gripopt::app::trajectory_row(s, *finger2));
            }
            self.tick(s.t);
        }
    }
    fn pose(&mut self, at: Point, s: &PoseSample) {
        if self.keep {
            self.poses.pose(at, s);
        }
        if at != Point::Grid {
            if let Some(Streamed::Poses(c)) = self.csv.as_mut() {
                c.row(&gripopt::app::pose_values(s));
            }
            self.tick(s.t);
        }
    }
    fn event(&mut self, e: &EventNote<'_>) {
        if self.trace {
            eprintln!(
                "event {:?} at t {:.9e} (step {:.9e}..{:.9e}) mem {:?}",
                e.kind, e.t, e.step[0], e.step[1], e.memories
            );
        }
    }
}
