//! File-system helpers shared by the layers that write files (record, run). No layer
//! dependencies besides the error type.

use crate::{Error, Result};
use std::io::Write;
use std::path::Path;

/// Write `bytes` to `path` atomically: a temporary file in the same folder, fsync, rename,
/// fsync of the folder. Errors name the file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let tmp = dir.join(format!(".{}.tmp", path.file_name().and_then(|s| s.to_str()).unwrap_or("checkpoint")));
    {
        let mut f = std::fs::File::create(&tmp).map_err(|e| Error::io(&tmp, "cannot create", e))?;
        f.write_all(bytes).map_err(|e| Error::io(&tmp, "cannot write", e))?;
        f.sync_all().map_err(|e| Error::io(&tmp, "cannot sync", e))?;
    }
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, "cannot rename the temporary file into place", e))?;
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}
