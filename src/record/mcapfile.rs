//! The MCAP file setup shared by the shard writer and the verify recording: an in-memory
//! writer with gripopt's options (zstd chunks, summary with statistics, chunk and message
//! indexes), written to a temporary file with one call, synced and renamed into place.

use crate::{Error, Result};
use std::io::{Cursor, Write as _};
use std::path::{Path, PathBuf};

/// An MCAP writer framing the file in memory.
pub(super) type MemWriter = mcap::Writer<Cursor<Vec<u8>>>;

/// The temporary file beside `path` that [`finish`] renames into place.
pub(super) fn temporary(path: &Path) -> PathBuf {
    path.with_extension("mcap.tmp")
}

/// An MCAP error while writing `path`'s temporary file.
pub(super) fn error(tmp: &Path) -> impl Fn(mcap::McapError) -> Error + Copy + '_ {
    move |source| Error::Mcap { path: tmp.to_path_buf(), what: "cannot write".into(), source: source.into() }
}

/// A writer with zstd `level` (and `threads` zstd workers, 0 = on the calling thread);
/// chunks close only on `flush()` (one per design) or at 64 MiB.
pub(super) fn open(tmp: &Path, level: u32, threads: u32) -> Result<MemWriter> {
    mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(threads)
        .compression_level(level)
        .chunk_size(Some(64 << 20))
        .profile("")
        .library(format!("gripopt {}", env!("CARGO_PKG_VERSION")))
        .create(Cursor::new(Vec::with_capacity(1 << 20)))
        .map_err(error(tmp))
}

/// Finish `w`, write its bytes to `tmp` with one call, sync, and rename to `path`; the size
/// in bytes.
pub(super) fn finish(mut w: MemWriter, tmp: &Path, path: &Path) -> Result<u64> {
    w.finish().map_err(error(tmp))?;
    let bytes = w.into_inner().into_inner();
    let written = (|| {
        let mut f = std::fs::File::create(tmp).map_err(|e| Error::io(tmp, "cannot create", e))?;
        f.write_all(&bytes).map_err(|e| Error::io(tmp, "cannot write", e))?;
        f.sync_all().map_err(|e| Error::io(tmp, "cannot sync", e))?;
        drop(f);
        std::fs::rename(tmp, path).map_err(|e| Error::io(path, "cannot rename the temporary recording into place", e))
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(tmp); // nothing half-written left behind
    }
    written?;
    Ok(bytes.len() as u64)
}
