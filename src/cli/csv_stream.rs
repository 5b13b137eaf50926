//! A trajectory CSV written while the simulation runs (`simulate --csv`): each sample goes
//! to a temporary file beside the output as it comes, so a long simulation holds no
//! trajectory in memory; the file takes its name only once complete and synced (the
//! output path never holds a partial file). The temporary file is removed when the
//! simulation fails, when the stream is dropped unfinished, and on ctrl-c.

use anyhow::Result;
use gripopt::Column;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Rows of numbers streamed to a CSV file with a `#` title, a `# units:` line and a header.
pub struct CsvStream {
    path: PathBuf,
    tmp: PathBuf,
    out: Option<BufWriter<File>>,
    rows: u64,
    error: Option<std::io::Error>,
}

impl CsvStream {
    /// Starts the CSV `path` (written as `.NAME.tmp` beside it until [`finish`](Self::finish)):
    /// its title line, units and header.
    pub fn create(path: &Path, title: &str, columns: &[Column]) -> Result<Self> {
        let name = path.file_name().map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let tmp = path.with_file_name(format!(".{name}.tmp"));
        // never a file opened through a link (or a file) left at the temporary name
        if std::fs::symlink_metadata(&tmp).is_ok_and(|m| !m.is_dir()) {
            let _ = std::fs::remove_file(&tmp);
        }
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(|e| gripopt::Error::io(path, "cannot create (its temporary file beside it)", e))?;
        remove_on_ctrl_c(&tmp);
        let mut s = CsvStream { path: path.to_path_buf(), tmp, out: Some(BufWriter::new(file)), rows: 0, error: None };
        let units: Vec<String> = columns.iter().map(|(n, u, _)| format!("{n} [{u}]")).collect();
        let names: Vec<&str> = columns.iter().map(|c| c.0).collect();
        s.write(&format!("# gripopt {title}\n# units: {}\n{}\n", units.join(" "), names.join(",")));
        Ok(s)
    }

    /// One row, each value as `{:e}` (the first write error is kept for [`finish`](Self::finish)).
    pub fn row(&mut self, values: &[f64]) {
        let line: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
        self.write(&(line.join(",") + "\n"));
        self.rows += 1;
    }

    fn write(&mut self, text: &str) {
        if self.error.is_some() {
            return;
        }
        if let Some(out) = self.out.as_mut() {
            if let Err(e) = out.write_all(text.as_bytes()) {
                self.error = Some(e);
            }
        }
    }

    /// Flushes and syncs the file and gives it its name; the number of rows written. An
    /// error names the output path, and no file is left at either name.
    pub fn finish(mut self) -> Result<u64> {
        let out = self.out.take().expect("a stream is finished once");
        let done = match self.error.take() {
            Some(e) => Err(e),
            None => out.into_inner().map_err(|e| e.into_error()).and_then(|f| f.sync_all()),
        }
        .and_then(|_| std::fs::rename(&self.tmp, &self.path));
        if let Err(e) = done {
            let _ = std::fs::remove_file(&self.tmp);
            return Err(gripopt::Error::io(&self.path, "cannot write", e).into());
        }
        if let Some(d) = self.path.parent().filter(|p| !p.as_os_str().is_empty()) {
            let _ = File::open(d).and_then(|d| d.sync_all());
        }
        Ok(self.rows)
    }
}

impl Drop for CsvStream {
    /// Unfinished (the simulation failed): the temporary file goes.
    fn drop(&mut self) {
        if self.out.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// ctrl-c during the simulation: the temporary file goes, and the process ends (exit 130,
/// as a shell reports an interrupted command).
fn remove_on_ctrl_c(tmp: &Path) {
    let tmp = tmp.to_path_buf();
    // this process's only handler: `simulate` runs one simulation
    let _ = ctrlc::set_handler(move || {
        let _ = std::fs::remove_file(&tmp);
        let _ = writeln!(std::io::stderr(), "\nctrl-c: stopped (no CSV written)");
        std::process::exit(130);
    });
}
