//! `gripopt` command-line interface: a thin layer over the library.
//!
//! Exit codes (README, docs/cli.md): 0 done; 1 the run failed; 2 bad input (a file, field,
//! flag or folder that cannot be used as asked); 3 a check did not pass (`replay` did not
//! verify the recording, `moo-test`'s hypervolume median lies outside the reference band);
//! 130 interrupted by ctrl-c after the checkpoint of the current generation (resumable);
//! 141 the output pipe was closed by its reader (quietly, like a program ended by SIGPIPE).
//! With `--json`, a failed command also prints one object `{"error": …, "exit_code": N}`
//! on stdout.
//! A standard output that cannot be written (a full disk) is exit 1 with one line, never a
//! panic; no control character of a message reaches the terminal raw.

// Index loops mirror the formulas of MODEL.md, as in the library.
#![allow(clippy::needless_range_loop)]

mod cli;

use cli::out::EXIT_BROKEN_PIPE;
use std::io::Write as _;

/// Fix glibc's mmap threshold at 1 MiB. glibc raises it to the size of every large block
/// freed (up to 32 MiB; the trim threshold follows), after which large buffers — a shard's
/// bytes, a checkpoint's, the population's vectors — are carved from the per-thread arenas and
/// stay resident once freed; a fixed threshold returns them to the system when they are freed
/// (pop-1000 run: peak RSS 43 -> 36 MB at no measurable CPU cost; docs/benchmarks.md
/// "Memory (item 3)"). The per-thread arenas are kept: capping them would serialise the
/// evaluation threads' allocations on many cores.
fn fix_malloc_thresholds() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets an allocator parameter; it runs before any other thread starts
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
}

fn main() {
    fix_malloc_thresholds();
    // the CLI prints through `cli::out`, which never panics; an `eprintln!` elsewhere in the
    // CLI (a note, a warning) panics when stderr cannot be written (the library never prints):
    // end as `out` does, quietly for a closed pipe (`gripopt … | head -1`), else with one line
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.contains("Broken pipe") || text.contains("os error 32") {
            std::process::exit(EXIT_BROKEN_PIPE);
        }
        if let Some(why) = text.strip_prefix("failed printing to stdout: ") {
            let _ = writeln!(std::io::stderr(), "error: cannot write to standard output: {why}");
            std::process::exit(1);
        }
        if text.starts_with("failed printing to stderr") {
            std::process::exit(1);
        }
        default_hook(info);
    }));
    std::process::exit(cli::run());
}
