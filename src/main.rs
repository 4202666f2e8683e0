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
            let text = cli::flags::as_flags(&thorarena::files::log_text::causes_once(e.as_ref()));
            eprintln!(
                "error: {}",
                thorarena::files::log_text::printable_lines(&text)
            );
            std::process::ExitCode::FAILURE
        }
    }
}
