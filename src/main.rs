//! The `thorarena` binary: everything lives in the library's `cli` module.

fn main() -> std::process::ExitCode {
    match thorarena::cli::run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
