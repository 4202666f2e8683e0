//! The `thorarena` binary: the command line over the `thorarena` library. Errors here are
//! `anyhow` chains printed once, at the top; the library's are typed.

mod cli;

fn main() -> std::process::ExitCode {
    let cli = <cli::Cli as clap::Parser>::try_parse().unwrap_or_else(|e| {
        if !e.use_stderr() {
            e.exit() // --help, --version
        }
        // clap quotes the values it refuses: shown, never run by the terminal.
        let text = e.render().to_string();
        eprint!("{}", thorarena::files::log_text::printable_lines(&text));
        std::process::exit(e.exit_code())
    });
    match cli::run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            // The library names what a user set by its field; the terminal shows the flag.
            // An outside name quoted in it (a file's, a policy's) may hold escape
            // sequences: they are shown, never run by the terminal.
            let text = cli::flags::as_flags(&chain_text(&e));
            eprintln!(
                "error: {}",
                thorarena::files::log_text::printable_lines(&text)
            );
            std::process::ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by `: `, each cause once: the library's typed errors
/// name their cause in their own message (`{path}: {source}`), which the chain would
/// otherwise print a second time ("No space left on device (os error 28): No space left
/// on device (os error 28)").
fn chain_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            if !text.is_empty() {
                text += ": ";
            }
            text += &cause;
        }
    }
    text
}
