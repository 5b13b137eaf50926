//! `gripopt` command-line interface: a thin layer over the library.

mod cli;

/// The error and its causes on one line, each cause once: the library's errors name their
/// file and often repeat their source's text, which anyhow's `{:#}` would print twice.
fn message(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let s = cause.to_string();
        let s = s.trim();
        if !msg.contains(s) {
            if !msg.is_empty() {
                msg.push_str(": ");
            }
            msg.push_str(s);
        }
    }
    msg
}

fn main() {
    if let Err(e) = cli::run() {
        eprintln!("error: {}", message(&e));
        std::process::exit(2);
    }
}
