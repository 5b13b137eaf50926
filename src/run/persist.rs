//! Outputs, recording and checkpoints off the critical path: a background persister thread
//! fed by a bounded channel (one generation queued besides the one being written =
//! backpressure and bounded memory). For generation k it writes the outputs (archive, CSVs),
//! then shard k durably, and THEN checkpoint k, while
//! generation k+1 evaluates, so the crash guarantee is the one of synchronous observers:
//! every shard up to the checkpoint's generation is durable, and a resume drops and
//! rewrites later ones (nothing lost or duplicated after kill -9).
//!
//! Errors of the persister are kept and returned by the observer at the next generation, or
//! by [`Persister::finish`] at the end; a failed shard is never followed by its checkpoint.
//! The shard encoder runs in the persister's own rayon pool (a quarter of the run's threads),
//! never in the evaluation pool, so the two cannot block each other; it collects the
//! encoded designs in order, so the bytes do not depend on the thread count.

use super::checkpoint::Checkpoint;
use super::gripper::GripperInfo;
use super::observers::OutputsObserver;
use crate::optim::{Individual, Nsga2Settings, Nsga2State};
use crate::record::Recorder;
use crate::{Error, Result};
use argmin::core::observers::Observe;
use argmin::core::KV;
use std::path::PathBuf;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

/// What the persister did in this process (seconds are wall time on its thread).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PersistStats {
    /// Generations persisted.
    pub generations: u64,
    /// Seconds writing the outputs (archive, CSVs).
    pub outputs_s: f64,
    /// Seconds writing shards (encoding, compression, framing, fsync).
    pub record_s: f64,
    /// Seconds serialising and writing checkpoints.
    pub checkpoint_s: f64,
    /// Seconds the optimiser waited for the persister (backpressure and the final flush).
    pub wait_s: f64,
    /// Seconds the optimiser spent handing generations over (cloning the state).
    pub handover_s: f64,
}

/// Fixed parts of every checkpoint.
#[derive(Debug, Clone)]
pub struct CheckpointSpec {
    /// Checkpoint path.
    pub path: PathBuf,
    /// SHA-256 of the problem file.
    pub problem_hash: String,
    /// Algorithm settings.
    pub settings: Nsga2Settings,
    /// Run options that change results.
    pub options: serde_json::Value,
    /// Wall seconds before this process started.
    pub wall_before: f64,
    /// Start of this process's run.
    pub start: Instant,
}

struct Job {
    state: Nsga2State<GripperInfo>,
    wall_s: f64,
}

#[derive(Default)]
struct Shared {
    /// Last generation whose shard and checkpoint are durable.
    done: u64,
    /// First error (kept until handed to the optimiser).
    error: Option<Error>,
    /// The thread has stopped (error or channel closed).
    stopped: bool,
    stats: PersistStats,
}

/// The background persister and its argmin observer (clone the handle into the executor).
#[derive(Clone)]
pub struct Persister {
    tx: Arc<Mutex<Option<SyncSender<Job>>>>,
    thread: Arc<Mutex<Option<JoinHandle<()>>>>,
    shared: Arc<(Mutex<Shared>, Condvar)>,
    spec: Arc<CheckpointSpec>,
    crash_after: Option<u64>,
}

impl Persister {
    /// Start the thread. `outputs`: the outputs observer (archive, CSVs); `recorder`: the
    /// shard recorder (None when recording is off); `threads`: the run's thread count (the
    /// persister's pool gets a quarter of it, at least one); `crash_after`: test hook, fail once that
    /// generation is durable, as a crash would.
    pub fn start(outputs: Option<OutputsObserver>, recorder: Option<Arc<Mutex<Recorder>>>, spec: CheckpointSpec, threads: usize, crash_after: Option<u64>) -> Result<Self> {
        // a quarter of the run's threads: enough to encode and compress beside the evaluation
        // at many cores, without oversubscribing a few (measured: 2 threads better with 1)
        let pool = rayon::ThreadPoolBuilder::new().num_threads((threads / 4).max(1)).thread_name(|k| format!("gripopt-persist-{k}")).build()?;
        let (tx, rx) = sync_channel::<Job>(1);
        let shared = Arc::new((Mutex::new(Shared::default()), Condvar::new()));
        let sh = shared.clone();
        let sp = spec.clone();
        let thread = std::thread::Builder::new()
            .name("gripopt-persist".into())
            .spawn(move || persist_loop(rx, outputs, recorder, pool, sp, sh))
            .map_err(|e| Error::io(&spec.path, "cannot start the persister thread for", e))?;
        Ok(Persister { tx: Arc::new(Mutex::new(Some(tx))), thread: Arc::new(Mutex::new(Some(thread))), shared, spec: Arc::new(spec), crash_after })
    }

    fn take_error(&self) -> Option<Error> {
        self.shared.0.lock().expect("persister lock").error.take()
    }

    /// Wait until generation `g` is durable (or the persister stopped); its first error.
    fn wait_for(&self, g: u64) -> Result<()> {
        let t0 = Instant::now();
        let (m, cv) = &*self.shared;
        let mut s = m.lock().expect("persister lock");
        while s.done < g && !s.stopped && s.error.is_none() {
            s = cv.wait(s).expect("persister lock");
        }
        s.stats.wait_s += t0.elapsed().as_secs_f64();
        match s.error.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Hand generation `st.generation` over (blocks while one generation is already queued).
    fn submit(&self, st: &Nsga2State<GripperInfo>) -> Result<()> {
        if let Some(e) = self.take_error() {
            return Err(e);
        }
        let t0 = Instant::now();
        let sp = &self.spec;
        let job = Job { state: st.clone(), wall_s: sp.wall_before + sp.start.elapsed().as_secs_f64() };
        let t1 = Instant::now();
        let sent = match self.tx.lock().expect("persister lock").as_ref() {
            Some(tx) => tx.send(job).is_ok(),
            None => false,
        };
        let mut s = self.shared.0.lock().expect("persister lock");
        s.stats.handover_s += (t1 - t0).as_secs_f64();
        s.stats.wait_s += t1.elapsed().as_secs_f64();
        if !sent {
            return Err(s.error.take().unwrap_or_else(|| Error::Optimiser("the persister thread stopped".into())));
        }
        Ok(())
    }

    /// Close the channel, wait for every queued generation to be durable, and return what
    /// the persister did, or its first error not yet reported.
    pub fn finish(&self) -> Result<PersistStats> {
        let t0 = Instant::now();
        self.tx.lock().expect("persister lock").take();
        if let Some(h) = self.thread.lock().expect("persister lock").take() {
            if h.join().is_err() {
                return Err(Error::Optimiser("the persister thread panicked".into()));
            }
        }
        let mut s = self.shared.0.lock().expect("persister lock");
        s.stats.wait_s += t0.elapsed().as_secs_f64();
        match s.error.take() {
            Some(e) => Err(e),
            None => Ok(s.stats),
        }
    }

    fn observe_state(&self, st: &Nsga2State<GripperInfo>) -> std::result::Result<(), argmin::core::Error> {
        self.submit(st)?;
        if let Some(k) = self.crash_after {
            if st.generation >= k {
                self.wait_for(st.generation)?;
                return Err(argmin::core::Error::msg(format!("simulated crash after generation {}", st.generation)));
            }
        }
        Ok(())
    }
}

impl Observe<Nsga2State<GripperInfo>> for Persister {
    fn observe_init(&mut self, _name: &str, st: &Nsga2State<GripperInfo>, _kv: &KV) -> std::result::Result<(), argmin::core::Error> {
        self.observe_state(st)
    }
    fn observe_iter(&mut self, st: &Nsga2State<GripperInfo>, _kv: &KV) -> std::result::Result<(), argmin::core::Error> {
        self.observe_state(st)
    }
}

fn persist_loop(rx: Receiver<Job>, mut outputs: Option<OutputsObserver>, recorder: Option<Arc<Mutex<Recorder>>>, pool: rayon::ThreadPool, sp: CheckpointSpec, shared: Arc<(Mutex<Shared>, Condvar)>) {
    let (m, cv) = &*shared;
    for job in rx.iter() {
        let g = job.state.generation;
        // outputs and archive beside the shard (independent files; re-doing a generation after
        // a crash is idempotent for both), then the checkpoint
        let timed = |f: &mut dyn FnMut() -> Result<()>| {
            let t = Instant::now();
            (f(), t.elapsed().as_secs_f64())
        };
        let ((out, out_s), (rec, rec_s)) = pool.install(|| {
            rayon::join(
                || {
                    timed(&mut || match outputs.as_mut() {
                        Some(o) => o.observe_iter(&job.state, &KV::new()).map_err(|e| e.downcast::<Error>().unwrap_or_else(|e| Error::Optimiser(e.to_string()))),
                        None => Ok(()),
                    })
                },
                || {
                    timed(&mut || match &recorder {
                        Some(r) => {
                            let refs: Vec<&Individual<GripperInfo>> = job.state.last_evaluated.iter().collect();
                            r.lock().expect("recorder lock").record_generation(g, &refs)
                        }
                        None => Ok(()),
                    })
                },
            )
        });
        let rec = out.and(rec);
        let t2 = Instant::now();
        let res = rec.and_then(|()| {
            let mut state = job.state;
            state.last_evaluated = vec![];
            Checkpoint::new(sp.problem_hash.clone(), sp.settings.clone(), sp.options.clone(), state, job.wall_s).save(&sp.path)
        });
        let mut s = m.lock().expect("persister lock");
        s.stats.outputs_s += out_s;
        s.stats.record_s += rec_s;
        s.stats.checkpoint_s += t2.elapsed().as_secs_f64();
        match res {
            Ok(()) => {
                s.done = g;
                s.stats.generations += 1;
                cv.notify_all();
            }
            Err(e) => {
                s.error = Some(e);
                s.stopped = true;
                cv.notify_all();
                return; // later generations are dropped: nothing after a failed shard
            }
        }
    }
    let mut s = m.lock().expect("persister lock");
    s.stopped = true;
    cv.notify_all();
}
