//! Outputs, recording and checkpoints off the critical path: a background persister thread
//! and its own small rayon pool. For generation k the thread updates the archive and
//! rewrites the CSV views, and hands shard k to the pool, where it is encoded and compressed
//! while the next generations evaluate, and checkpoint k, which is serialised there too;
//! several generations can be in the pool at once. Generations are committed strictly in
//! order: once shard k is durable and checkpoint k serialised, its index
//! line and then checkpoint k (which holds the archive of generation k) are written, and the
//! caller is told ([`PersistHooks::on_commit`]: run.json follows the checkpoints). So the
//! crash guarantee is the one of synchronous observers: every shard up to the checkpoint's
//! generation is durable, and a resume drops and rewrites later ones (nothing lost or
//! duplicated after kill -9). Before it writes anything, the thread checks that the run
//! folder is still the one the run locked ([`PersistHooks::guard`]).
//!
//! Bounded memory (backpressure): one generation queued for the thread, and at most the
//! pool's threads + 1 generations handed over but not yet committed; a generation handed
//! over shares its designs' records and trajectories with the optimiser, and its checkpoint
//! waits as its bytes, serialised streaming (never as a JSON tree). The CSV views are
//! rewritten at most every [`VIEWS_MIN_INTERVAL`] (a generation within it skips them; the
//! archive is still updated) and at least that often while generations come: skipped views
//! are written by the first generation after the interval, or when it passes with none, so
//! a persister that falls behind writes the views of its latest generation four times a
//! second, never one per generation, and never leaves them behind; every generation's
//! shard, archive and checkpoint are always written, and the views of the last generation
//! handed over too (also when the run stops early), unless the caller says it writes the
//! final outputs itself ([`Persister::finish_with`], as `optimise` does after a run that
//! did not fail).
//!
//! Errors of the persister are kept and returned by the observer at the next generation, or
//! by [`Persister::finish`] at the end; a failed shard is never followed by its checkpoint.
//! The thread stops only once every task it handed to its pool has reported, also after an
//! error: nothing is written into the run folder after the run has returned.
//! The pool is not the evaluation pool, so the two cannot block each other; a shard's
//! designs are encoded in parallel and written in id order, so the bytes do not depend on
//! the thread count.

use super::archive::{Archive, Discards};
use super::checkpoint::Checkpoint;
use super::gripper::GripperInfo;
use super::observers::OutputsObserver;
use crate::fsutil::write_atomic;
use crate::optim::{Individual, Nsga2Settings, Nsga2State};
use crate::record::{Recorder, ShardEntry};
use crate::{Error, Result};
use argmin::core::observers::Observe;
use argmin::core::KV;
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

/// What the persister did in this process (seconds are wall time on its thread).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PersistStats {
    /// Generations persisted.
    pub generations: u64,
    /// Seconds on the persister thread updating the archive and writing the CSV views.
    pub outputs_s: f64,
    /// Of `outputs_s`, the archive's update (its hypervolume measured in the pool).
    pub archive_s: f64,
    /// Seconds writing shards (encoding, compression, framing, fsync), summed over the
    /// shards, which the pool writes several at a time.
    pub record_s: f64,
    /// Seconds committing generations (index line, checkpoint, the caller's `on_commit`).
    pub checkpoint_s: f64,
    /// Seconds serialising checkpoints in the pool (before their commit).
    pub checkpoint_pool_s: f64,
    /// CSV view writes (at most one per `VIEWS_MIN_INTERVAL`, and the last generation's).
    pub views_written: u64,
    /// Seconds on the persister thread writing the CSV views (part of `outputs_s`; the
    /// files are written in parallel in the pool).
    pub views_s: f64,
    /// The views' files' own seconds, summed (what one thread would take).
    pub views_files_s: f64,
    /// The longest file of each views write, summed (the least any pool could take).
    pub views_longest_s: f64,
    /// Generations whose CSV views were skipped (written less than `VIEWS_MIN_INTERVAL`
    /// after the previous views; a later write covers them).
    pub views_skipped: u64,
    /// Threads of the persister's pool.
    pub pool_threads: usize,
    /// Seconds the optimiser waited for the persister (backpressure and the final flush).
    pub wait_s: f64,
    /// Seconds the optimiser spent handing generations over (cloning the state).
    pub handover_s: f64,
}

impl PersistStats {
    fn add_views(&mut self, wall_s: f64, files: &[f64]) {
        self.views_written += 1;
        self.views_s += wall_s;
        self.views_files_s += files.iter().sum::<f64>();
        self.views_longest_s += files.iter().copied().fold(0.0, f64::max);
    }
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
    pub options: super::RunOptions,
    /// Wall seconds before this process started.
    pub wall_before: f64,
    /// Start of this process's run.
    pub start: Instant,
}

struct Job {
    state: Nsga2State<GripperInfo>,
    wall_s: f64,
}

/// A generation made durable (its shard and checkpoint written), as [`PersistHooks::on_commit`]
/// is told.
#[derive(Debug, Clone)]
pub struct Committed {
    /// The generation.
    pub generation: u64,
    /// Evaluations up to it.
    pub evaluations: u64,
    /// Wall seconds of the run up to it (over all processes).
    pub wall_s: f64,
    /// The checkpoint's content checksum.
    pub checkpoint_sha256: String,
    /// The run's discard causes up to it (empty without an outputs observer).
    pub discards: Discards,
}

/// The call after every commit (it writes run.json).
pub type OnCommit = Box<dyn FnMut(&Committed) -> Result<()> + Send>;

/// What a run adds to its persister: the run's id (in every checkpoint), a check before
/// every write that the run folder is still the one locked, and a call after every commit.
#[derive(Default)]
pub struct PersistHooks {
    /// The run's id.
    pub run_id: String,
    /// Called before the thread writes anything (and in the pool, before each shard); an
    /// error stops the persister (nothing more is written).
    pub guard: Option<Arc<dyn Fn() -> Result<()> + Send + Sync>>,
    /// Called after each generation's checkpoint is written; an error stops the persister.
    pub on_commit: Option<OnCommit>,
}

impl PersistHooks {
    fn check(&self) -> Result<()> {
        self.guard.as_ref().map_or(Ok(()), |g| g())
    }
}

/// What the persister thread receives: generations from the optimiser, finished shards from
/// its pool.
enum Msg {
    Job(Box<Job>),
    Shard {
        generation: u64,
        result: Result<Option<(ShardEntry, f64)>>,
    },
    /// A checkpoint's bytes and content checksum, serialised in the pool, and the seconds
    /// it took.
    Checkpoint {
        generation: u64,
        result: Result<(Vec<u8>, String)>,
        secs: f64,
    },
}

#[derive(Default)]
struct Shared {
    /// Last generation whose shard and checkpoint are durable.
    done: u64,
    /// First error (kept until handed to the optimiser).
    error: Option<Error>,
    /// The thread has stopped (error or closed and drained).
    stopped: bool,
    stats: PersistStats,
    /// Messages for the thread, in arrival order.
    inbox: VecDeque<Msg>,
    /// Generations in `inbox` (at most one: backpressure).
    queued: usize,
    /// No more generations will come.
    closed: bool,
    /// Write the last generation's views at the end if they were skipped (set on close).
    final_views: bool,
    /// Shard and checkpoint tasks spawned into the pool that have not reported yet: the
    /// thread waits for them before it stops, also after an error, so that nothing writes
    /// into the run folder once the run has returned (and released its lock).
    in_pool: usize,
}

/// Spawn `task` into `pool`, counted in [`Shared::in_pool`] until it has reported.
fn spawn_counted(pool: &rayon::ThreadPool, shared: &SharedState, task: impl FnOnce() + Send + 'static) {
    shared.0.lock().expect("persister lock").in_pool += 1;
    let sh = shared.clone();
    pool.spawn(move || {
        task();
        let (m, cv) = &*sh;
        m.lock().expect("persister lock").in_pool -= 1;
        cv.notify_all();
    });
}

type SharedState = Arc<(Mutex<Shared>, Condvar)>;

/// The CSV views (pareto, population, archive, history) are rewritten at most this often
/// while a run goes on (and always after its last generation): often enough to watch a
/// run, and at many cores not a rewrite every few milliseconds.
pub const VIEWS_MIN_INTERVAL: std::time::Duration = std::time::Duration::from_millis(250);

/// The background persister and its argmin observer (clone the handle into the executor).
#[derive(Clone)]
pub struct Persister {
    thread: Arc<Mutex<Option<JoinHandle<()>>>>,
    shared: SharedState,
    spec: Arc<CheckpointSpec>,
}

impl Persister {
    /// Start the thread. `outputs`: the outputs observer (archive, CSVs); `recorder`: the
    /// shard recorder (None when recording is off); `threads`: the run's thread count (the
    /// persister's pool gets a quarter of it, at least one).
    pub fn start(
        outputs: Option<OutputsObserver>,
        recorder: Option<Arc<Mutex<Recorder>>>,
        spec: CheckpointSpec,
        threads: usize,
    ) -> Result<Self> {
        Self::start_with(outputs, recorder, spec, threads, PersistHooks::default())
    }

    /// [`Persister::start`] with the run's [`PersistHooks`].
    pub fn start_with(
        outputs: Option<OutputsObserver>,
        recorder: Option<Arc<Mutex<Recorder>>>,
        spec: CheckpointSpec,
        threads: usize,
        hooks: PersistHooks,
    ) -> Result<Self> {
        // a quarter of the run's threads: enough to encode and compress beside the evaluation
        // at many cores, without oversubscribing a few (measured: 2 threads better with 1)
        let pool_threads = (threads / 4).max(1);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(pool_threads)
            .thread_name(|k| format!("gripopt-persist-{k}"))
            .build()?;
        let shared: SharedState = Arc::new((Mutex::new(Shared::default()), Condvar::new()));
        shared.0.lock().expect("persister lock").stats.pool_threads = pool_threads;
        let sh = shared.clone();
        let sp = spec.clone();
        let thread = std::thread::Builder::new()
            .name("gripopt-persist".into())
            .spawn(move || persist_loop(outputs, recorder, pool, sp, sh, hooks))
            .map_err(|e| Error::io(&spec.path, "cannot start the persister thread for", e))?;
        Ok(Persister { thread: Arc::new(Mutex::new(Some(thread))), shared, spec: Arc::new(spec) })
    }

    /// The last generation whose shard and checkpoint are durable (0: none yet).
    pub fn durable_generation(&self) -> u64 {
        self.shared.0.lock().map(|s| s.done).unwrap_or(0)
    }

    /// Hand generation `st.generation` over (blocks while one generation is already queued).
    /// The copy of the state shares each design's record and trajectory (`Arc`): about 200
    /// bytes a design, and the trajectories are freed once the shard is written.
    fn submit(&self, st: &Nsga2State<GripperInfo>) -> Result<()> {
        let (m, cv) = &*self.shared;
        if let Some(e) = m.lock().expect("persister lock").error.take() {
            return Err(e);
        }
        let t0 = Instant::now();
        let sp = &self.spec;
        let job = Job { state: st.clone(), wall_s: sp.wall_before + sp.start.elapsed().as_secs_f64() };
        let t1 = Instant::now();
        let mut s = m.lock().expect("persister lock");
        while s.queued >= 1 && !s.stopped && s.error.is_none() {
            s = cv.wait(s).expect("persister lock");
        }
        s.stats.handover_s += (t1 - t0).as_secs_f64();
        s.stats.wait_s += t1.elapsed().as_secs_f64();
        if let Some(e) = s.error.take() {
            return Err(e);
        }
        if s.stopped {
            return Err(Error::Optimiser("the persister thread stopped".into()));
        }
        s.inbox.push_back(Msg::Job(Box::new(job)));
        s.queued += 1;
        cv.notify_all();
        Ok(())
    }

    /// Close the inbox, wait for every queued generation to be durable, and return what
    /// the persister did, or its first error not yet reported. The CSV views of the last
    /// generation are written if they were skipped.
    pub fn finish(&self) -> Result<PersistStats> {
        self.finish_with(true)
    }

    /// [`Persister::finish`]; with `final_views` false, views skipped at the end are left
    /// to the caller (who writes every output of the final state anyway).
    pub fn finish_with(&self, final_views: bool) -> Result<PersistStats> {
        let t0 = Instant::now();
        {
            let mut s = self.shared.0.lock().expect("persister lock");
            s.final_views = final_views;
            s.closed = true;
            self.shared.1.notify_all();
        }
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
        Ok(self.submit(st)?)
    }
}

impl Observe<Nsga2State<GripperInfo>> for Persister {
    fn observe_init(
        &mut self,
        _name: &str,
        st: &Nsga2State<GripperInfo>,
        _kv: &KV,
    ) -> std::result::Result<(), argmin::core::Error> {
        self.observe_state(st)
    }
    fn observe_iter(&mut self, st: &Nsga2State<GripperInfo>, _kv: &KV) -> std::result::Result<(), argmin::core::Error> {
        self.observe_state(st)
    }
}

/// A written shard's index entry and seconds (None: nothing recorded), or its error.
type ShardResult = Result<Option<(ShardEntry, f64)>>;

/// A generation handed to the pool, waiting for its shard and its checkpoint's bytes
/// before it is committed.
struct Pending {
    generation: u64,
    /// None while the shard is being written (Some(Ok(None)): nothing to record).
    shard: Option<ShardResult>,
    evaluations: u64,
    wall_s: f64,
    discards: Discards,
    /// None while the checkpoint is being serialised; its bytes and content checksum.
    checkpoint: Option<Result<(Vec<u8>, String)>>,
}

/// What the persister thread does next.
enum Next {
    /// Handle a message.
    Msg(Msg),
    /// The views' deadline passed with nothing to handle: write the skipped views now.
    Views,
}

/// The next message; generations only while fewer than `max_pending` wait for their
/// shards and checkpoints (the pool's reports are always taken); [`Next::Views`] when
/// `views_due` passes first. None once closed and nothing is left to do.
fn next_msg(shared: &SharedState, pending: usize, max_pending: usize, views_due: Option<Instant>) -> Option<Next> {
    let (m, cv) = &**shared;
    let mut s = m.lock().expect("persister lock");
    loop {
        let pos = if pending < max_pending {
            (!s.inbox.is_empty()).then_some(0)
        } else {
            s.inbox.iter().position(|m| !matches!(m, Msg::Job(_)))
        };
        if let Some(k) = pos {
            let msg = s.inbox.remove(k).expect("position in the inbox");
            if matches!(msg, Msg::Job(_)) {
                s.queued -= 1;
                cv.notify_all();
            }
            return Some(Next::Msg(msg));
        }
        if s.closed && s.queued == 0 && pending == 0 {
            return None;
        }
        match views_due {
            Some(due) => {
                let now = Instant::now();
                if now >= due {
                    return Some(Next::Views);
                }
                s = cv.wait_timeout(s, due - now).expect("persister lock").0;
            }
            None => s = cv.wait(s).expect("persister lock"),
        }
    }
}

/// Write the views of `st`, a generation whose views were skipped, and count their time.
fn write_skipped_views(
    st: &Nsga2State<GripperInfo>,
    o: &OutputsObserver,
    pool: &rayon::ThreadPool,
    shared: &SharedState,
    hooks: &PersistHooks,
) -> Result<()> {
    hooks.check()?;
    let t = Instant::now();
    let files = pool.install(|| o.write_views(st))?;
    let mut s = shared.0.lock().expect("persister lock");
    s.stats.outputs_s += t.elapsed().as_secs_f64();
    s.stats.add_views(t.elapsed().as_secs_f64(), &files);
    Ok(())
}

/// The persister thread: handle generations and the pool's reports until closed and
/// drained, then stop (after waiting for every task still in the pool), keeping the first
/// error for the optimiser.
fn persist_loop(
    outputs: Option<OutputsObserver>,
    recorder: Option<Arc<Mutex<Recorder>>>,
    pool: rayon::ThreadPool,
    sp: CheckpointSpec,
    shared: SharedState,
    hooks: PersistHooks,
) {
    let mut worker = Worker {
        outputs,
        recorder,
        pool,
        sp,
        shared: shared.clone(),
        hooks,
        pending: VecDeque::new(),
        last_views: None,
        stale_views: None,
    };
    let res = worker.run();
    stop(&shared, res);
}

/// Mark the thread stopped once every task it handed to its pool has reported, keeping
/// `res`'s error.
fn stop(shared: &SharedState, res: Result<()>) {
    let (m, cv) = &**shared;
    let mut s = m.lock().expect("persister lock");
    // after an error, shards and checkpoints of later generations may still be in the pool:
    // wait for them (their results are dropped), so that none writes after the run returned
    while s.in_pool > 0 {
        s = cv.wait(s).expect("persister lock");
    }
    if let Err(e) = res {
        // later generations are dropped: nothing after a failed shard or checkpoint
        s.error = Some(e);
    }
    s.stopped = true;
    cv.notify_all();
}

/// The persister thread's state: what it writes with, and the generations in hand.
struct Worker {
    outputs: Option<OutputsObserver>,
    recorder: Option<Arc<Mutex<Recorder>>>,
    pool: rayon::ThreadPool,
    sp: CheckpointSpec,
    shared: SharedState,
    hooks: PersistHooks,
    /// Generations handed to the pool, in order, until they are committed.
    pending: VecDeque<Pending>,
    /// When the CSV views were last written.
    last_views: Option<Instant>,
    /// The latest generation whose views were skipped (written later).
    stale_views: Option<Nsga2State<GripperInfo>>,
}

impl Worker {
    /// Handle messages until closed and drained; then the views of the last generation, if
    /// they were skipped and the caller does not write them.
    fn run(&mut self) -> Result<()> {
        let max_pending = self.pool.current_num_threads() + 1;
        while let Some(next) = next_msg(&self.shared, self.pending.len(), max_pending, self.views_due()) {
            match next {
                Next::Views => {
                    self.write_stale_views()?;
                    continue;
                }
                Next::Msg(Msg::Job(job)) => self.take_generation(*job)?,
                Next::Msg(Msg::Shard { generation, result }) => {
                    if let Some(p) = self.pending.iter_mut().find(|p| p.generation == generation && p.shard.is_none()) {
                        p.shard = Some(result);
                    }
                }
                Next::Msg(Msg::Checkpoint { generation, result, secs }) => {
                    self.shared.0.lock().expect("persister lock").stats.checkpoint_pool_s += secs;
                    let p = self.pending.iter_mut().find(|p| p.generation == generation && p.checkpoint.is_none());
                    if let Some(p) = p {
                        p.checkpoint = Some(result);
                    }
                }
            }
            self.commit_ready()?;
        }
        let final_views = self.shared.0.lock().expect("persister lock").final_views;
        if let (Some(st), Some(o), true) = (self.stale_views.take(), &self.outputs, final_views) {
            write_skipped_views(&st, o, &self.pool, &self.shared, &self.hooks)?;
        }
        Ok(())
    }

    /// Skipped views are written once VIEWS_MIN_INTERVAL has passed since the last write, by
    /// the next generation or, if none comes by then, on their own: when that is.
    fn views_due(&self) -> Option<Instant> {
        self.last_views.filter(|_| self.stale_views.is_some()).map(|t| t + VIEWS_MIN_INTERVAL)
    }

    /// The views' deadline passed with nothing to handle: write the skipped views now.
    fn write_stale_views(&mut self) -> Result<()> {
        if let (Some(st), Some(o)) = (self.stale_views.take(), &self.outputs) {
            write_skipped_views(&st, o, &self.pool, &self.shared, &self.hooks)?;
        }
        self.last_views = Some(Instant::now());
        Ok(())
    }

    /// Generation `job`: update the archive and the views on this thread, hand its shard and
    /// its checkpoint to the pool, and keep it pending until both are done.
    fn take_generation(&mut self, mut job: Job) -> Result<()> {
        let g = job.state.generation;
        let t0 = Instant::now();
        let archive = self.update_archive(&job.state);
        // the shard's designs (with their trajectories) leave the state here
        let designs: Vec<Individual<GripperInfo>> = std::mem::take(&mut job.state.last_evaluated);
        let skipped = self.write_views_unless_recent(&job.state)?;
        let out_s = t0.elapsed().as_secs_f64();
        let shard = self.spawn_shard(g, designs);
        let mut s = self.shared.0.lock().expect("persister lock");
        s.stats.outputs_s += out_s;
        s.stats.views_skipped += skipped as u64;
        drop(s);
        let (evaluations, discards) =
            (job.state.evaluations, archive.as_ref().map(|a| a.discards.clone()).unwrap_or_default());
        let wall_s = job.wall_s;
        self.spawn_checkpoint(g, job.state, wall_s, archive);
        self.pending.push_back(Pending { generation: g, shard, evaluations, wall_s, discards, checkpoint: None });
        Ok(())
    }

    /// The archive updated with `state` (None without an outputs observer), in the
    /// persister's pool: its hypervolume is measured in parallel.
    fn update_archive(&self, state: &Nsga2State<GripperInfo>) -> Option<Archive> {
        let o = self.outputs.as_ref()?;
        let ta = Instant::now();
        let a = self.pool.install(|| o.update_archive(state));
        self.shared.0.lock().expect("persister lock").stats.archive_s += ta.elapsed().as_secs_f64();
        Some(a)
    }

    /// Rewrite the views of `state`, unless they were rewritten moments ago (true: skipped):
    /// a later generation (or the deadline, or the end) rewrites them; a persister that is
    /// behind still rewrites them every VIEWS_MIN_INTERVAL.
    fn write_views_unless_recent(&mut self, state: &Nsga2State<GripperInfo>) -> Result<bool> {
        let Some(o) = &self.outputs else {
            return Ok(false);
        };
        if self.last_views.is_some_and(|t: Instant| t.elapsed() < VIEWS_MIN_INTERVAL) {
            self.stale_views = Some(state.clone());
            return Ok(true);
        }
        self.hooks.check()?;
        let tv = Instant::now();
        let files = self.pool.install(|| o.write_views(state))?;
        self.shared.0.lock().expect("persister lock").stats.add_views(tv.elapsed().as_secs_f64(), &files);
        self.last_views = Some(Instant::now());
        self.stale_views = None;
        Ok(false)
    }

    /// Hand generation `g`'s shard to the pool (None: it reports when written), or
    /// Some(Ok(None)) when nothing is recorded.
    fn spawn_shard(&self, g: u64, designs: Vec<Individual<GripperInfo>>) -> Option<ShardResult> {
        let task = self.recorder.as_ref().and_then(|r| r.lock().expect("recorder lock").task(g));
        let Some(task) = task else {
            return Some(Ok(None));
        };
        let sh = self.shared.clone();
        let guard = self.hooks.guard.clone();
        spawn_counted(&self.pool, &self.shared, move || {
            let refs: Vec<&Individual<GripperInfo>> = designs.iter().collect();
            let result = guard.map_or(Ok(()), |g| g()).and_then(|_| task.write(&refs));
            drop(refs);
            drop(designs);
            let (m, cv) = &*sh;
            m.lock().expect("persister lock").inbox.push_back(Msg::Shard { generation: g, result });
            cv.notify_all();
        });
        None
    }

    /// Hand generation `g`'s checkpoint to the pool to be serialised (only its write is
    /// serial); it reports its bytes.
    fn spawn_checkpoint(&self, g: u64, state: Nsga2State<GripperInfo>, wall_s: f64, archive: Option<Archive>) {
        let (sh, spc) = (self.shared.clone(), self.sp.clone());
        let run_id = self.hooks.run_id.clone();
        spawn_counted(&self.pool, &self.shared, move || {
            let t = Instant::now();
            let result = Checkpoint::new(spc.problem_hash, spc.settings, spc.options, state, wall_s)
                .of_run(run_id, archive)
                .to_bytes_and_sha256(&spc.path);
            let (m, cv) = &*sh;
            m.lock().expect("persister lock").inbox.push_back(Msg::Checkpoint {
                generation: g,
                result,
                secs: t.elapsed().as_secs_f64(),
            });
            cv.notify_all();
        });
    }

    /// Commit, in generation order, every generation whose shard is durable and whose
    /// checkpoint is serialised.
    fn commit_ready(&mut self) -> Result<()> {
        while self.pending.front().is_some_and(|p| p.shard.is_some() && p.checkpoint.is_some()) {
            let p = self.pending.pop_front().expect("front");
            self.commit(p)?;
        }
        Ok(())
    }

    /// Generation `p`: its index line, then its checkpoint, then the caller's `on_commit`.
    fn commit(&mut self, p: Pending) -> Result<()> {
        let t = Instant::now();
        let shard = p.shard.expect("checked")?;
        // nothing of generation k is committed unless its checkpoint can follow
        let (checkpoint, checkpoint_sha256) = p.checkpoint.expect("checked")?;
        self.hooks.check()?;
        if let (Some((entry, secs)), Some(r)) = (shard, &self.recorder) {
            let mut s = self.shared.0.lock().expect("persister lock");
            s.stats.record_s += secs;
            drop(s);
            r.lock().expect("recorder lock").commit(entry, secs)?;
        }
        // again right before the checkpoint: the recorder's commit takes a while
        self.hooks.check()?;
        write_atomic(&self.sp.path, &checkpoint)?;
        if let Some(f) = self.hooks.on_commit.as_mut() {
            let (generation, evaluations, wall_s) = (p.generation, p.evaluations, p.wall_s);
            f(&Committed { generation, evaluations, wall_s, checkpoint_sha256, discards: p.discards })?;
        }
        let (m, cv) = &*self.shared;
        let mut s = m.lock().expect("persister lock");
        s.stats.checkpoint_s += t.elapsed().as_secs_f64();
        s.done = p.generation;
        s.stats.generations += 1;
        cv.notify_all();
        Ok(())
    }
}
