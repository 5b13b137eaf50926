//! A run folder's lock: the folder lock of [`crate::fsutil::lock`], which every command that
//! writes into a folder (a run, a sweep's, a benchmark's) holds.

pub use crate::fsutil::lock::{LockHolder, RunLock, LOCK_FILE};
