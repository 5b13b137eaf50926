//! The MCAP file setup shared by the shard writer and the verify recording: an in-memory
//! writer with gripopt's options (zstd chunks, summary with statistics, chunk and message
//! indexes), written with one call through the one atomic, link-refusing write
//! ([`crate::fsutil::write_atomic`]: a temporary file synced and renamed into place).

use crate::error::{Error, Result};
use mcap::records::MessageHeader;
use std::io::Cursor;
use std::path::{Path, PathBuf};

/// An MCAP writer framing the file in memory.
pub(super) type MemWriter = mcap::Writer<Cursor<Vec<u8>>>;

/// The temporary file beside `path` that [`finish`] renames into place (`.NAME.tmp`).
pub(super) fn temporary(path: &Path) -> PathBuf {
    crate::fsutil::atomic::temporary(path)
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

/// Add the JSON schema `schema` named `name`.
pub(super) fn add_json_schema(w: &mut MemWriter, name: &str, schema: &serde_json::Value, tmp: &Path) -> Result<u16> {
    let data = serde_json::to_vec(schema).expect("a JSON value serialises");
    w.add_schema(name, "jsonschema", &data).map_err(error(tmp))
}

/// Add the schema of one of the Foxglove SDK's message types.
pub(super) fn add_foxglove_schema(w: &mut MemWriter, schema: Option<foxglove::Schema>, tmp: &Path) -> Result<u16> {
    let s = schema.expect("the SDK's message types have schemas");
    w.add_schema(&s.name, &s.encoding, &s.data).map_err(error(tmp))
}

/// Add a channel for each of `topics`, with the (schema id, message encoding) of the same
/// index in `schemas`, in order; their channel ids.
pub(super) fn add_channels(
    w: &mut MemWriter,
    topics: &[&str],
    schemas: &[(u16, &str)],
    tmp: &Path,
) -> Result<Vec<u16>> {
    let none = std::collections::BTreeMap::new();
    let add = |(topic, (schema, encoding)): (&&str, &(u16, &str))| w.add_channel(*schema, topic, encoding, &none);
    topics.iter().zip(schemas).map(add).collect::<std::result::Result<_, _>>().map_err(error(tmp))
}

/// Write every design's messages — (index into `channels`, log time, bytes) — in order,
/// numbered per channel, each design closing its chunk.
pub(super) fn write_designs<D, M>(w: &mut MemWriter, channels: &[u16], designs: D, tmp: &Path) -> Result<()>
where
    D: IntoIterator<Item = M>,
    M: IntoIterator<Item = (usize, u64, Vec<u8>)>,
{
    let mut seq = vec![0u32; channels.len()];
    for messages in designs {
        for (c, t_ns, data) in messages {
            seq[c] += 1;
            let header =
                MessageHeader { channel_id: channels[c], sequence: seq[c], log_time: t_ns, publish_time: t_ns };
            w.write_to_known_channel(&header, &data).map_err(error(tmp))?;
        }
        w.flush().map_err(error(tmp))?; // one chunk per design
    }
    Ok(())
}

/// Finish `w` and write its bytes to `path` atomically with one call (`tmp` names the
/// file in the errors of the finish); the size in bytes.
pub(super) fn finish(mut w: MemWriter, tmp: &Path, path: &Path) -> Result<u64> {
    w.finish().map_err(error(tmp))?;
    let bytes = w.into_inner().into_inner();
    crate::fsutil::write_atomic(path, &bytes)?;
    Ok(bytes.len() as u64)
}
