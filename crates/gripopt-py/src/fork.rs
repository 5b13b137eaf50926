//! Evaluation in a process forked from one that used rayon's global pool (Python's
//! `multiprocessing` / `ProcessPoolExecutor` fork by default on Linux): a fork copies only
//! the forking thread, so the child's global pool has no worker threads and a parallel
//! evaluation there waits forever. In a fork child the package's parallel work runs in a
//! pool of its own, started in the child.

use std::sync::OnceLock;

/// The process id of the process that imported the native module.
static IMPORTED_IN: OnceLock<u32> = OnceLock::new();

/// Note the process that imports the module (at its import).
pub fn note_import() {
    let _ = IMPORTED_IN.set(std::process::id());
}

/// This process is not the one that imported the module: a fork of it.
pub fn in_fork_child() -> bool {
    IMPORTED_IN.get().is_some_and(|pid| *pid != std::process::id())
}

/// Where the package's parallel work runs: the current pool, or in a fork child a pool
/// started there (all cores, as the global pool; an explicit thread count builds its own
/// pool anyway). Made once for work done in several parts (a batch in chunks).
pub enum Pool {
    /// The current (global) pool.
    Current,
    /// A pool of this fork child.
    Own(rayon::ThreadPool),
}

impl Pool {
    /// The pool for this process.
    pub fn new() -> Self {
        if !in_fork_child() {
            return Pool::Current;
        }
        match rayon::ThreadPoolBuilder::new().build() {
            Ok(pool) => Pool::Own(pool),
            // no threads could be started: the caller's thread alone (never the dead pool)
            Err(_) => match rayon::ThreadPoolBuilder::new().num_threads(1).use_current_thread().build() {
                Ok(pool) => Pool::Own(pool),
                Err(_) => Pool::Current,
            },
        }
    }

    /// `run` in this pool.
    pub fn run<T: Send>(&self, run: impl FnOnce() -> T + Send) -> T {
        match self {
            Pool::Current => run(),
            Pool::Own(pool) => pool.install(run),
        }
    }
}

/// `run`, in a fork child in a rayon pool started here; else as it is, in the current pool.
pub fn fork_safe<T: Send>(run: impl FnOnce() -> T + Send) -> T {
    Pool::new().run(run)
}
