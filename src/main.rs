//! The `thorarena` binary: the command line over the `thorarena` library. Errors here are
//! `anyhow` chains printed once, at the top; the library's are typed.

mod cli;

fn main() -> std::process::ExitCode {
    match cli::run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
