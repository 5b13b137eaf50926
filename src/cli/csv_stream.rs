//! A trajectory CSV written while the simulation runs (`simulate --csv`): each sample goes
//! to a temporary file beside the output as it comes, so a long simulation holds no
//! trajectory in memory; the file takes its name only once complete and synced (the
//! output path never holds a partial file). The temporary file is removed when the
//! simulation fails, when the stream is dropped unfinished, and on ctrl-c.

use anyhow::Result;
use gripopt::AtomicFile;
use gripopt::Column;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Rows of numbers streamed to a CSV file with a `#` title, a `# units:` line and a header.
pub struct CsvStream {
    path: PathBuf,
    out: Option<AtomicFile>,
    rows: u64,
    error: Option<std::io::Error>,
}

impl CsvStream {
    /// Starts the CSV `path` (written as `.NAME.tmp` beside it until [`finish`](Self::finish)):
    /// its title line, units and header.
    pub fn create(path: &Path, title: &str, columns: &[Column]) -> Result<Self> {
        // the one atomic, link-refusing write of the library
        let file = AtomicFile::create(path)?;
        let tmp = file.temporary_path().to_path_buf();
        remove_on_ctrl_c(&tmp);
        let mut s = CsvStream { path: path.to_path_buf(), out: Some(file), rows: 0, error: None };
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
        if let Some(e) = self.error.take() {
            return Err(gripopt::Error::io(&self.path, "cannot write", e).into());
        }
        out.commit()?;
        Ok(self.rows)
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
