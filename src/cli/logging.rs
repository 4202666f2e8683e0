//! Where the library's messages go: the library logs through the `log` facade and never
//! prints; the command line shows them on stderr, warnings marked as such.
//!
//! `THORARENA_LOG` (`error`, `warn`, `info`, `debug`, `trace`, `off`) sets the level;
//! the default, `info`, shows warnings and the policy server's connection news.

use log::{Level, LevelFilter, Log, Metadata, Record};

/// Environment variable setting the level.
pub const LOG_ENV: &str = "THORARENA_LOG";

struct Stderr;

impl Log for Stderr {
    fn enabled(&self, metadata: &Metadata) -> bool {
        // Only our own crates: dependencies' chatter stays out of a benchmark's output.
        metadata.level() <= log::max_level() && metadata.target().starts_with("thorarena")
    }

    fn log(&self, record: &Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        match record.level() {
            Level::Error => eprintln!("error: {}", record.args()),
            Level::Warn => eprintln!("warning: {}", record.args()),
            Level::Info => eprintln!("{}", record.args()),
            Level::Debug | Level::Trace => {
                eprintln!("[{}] {}", record.target(), record.args())
            }
        }
    }

    fn flush(&self) {}
}

/// Installs the stderr logger at the level `THORARENA_LOG` names (default `info`); an
/// unreadable level is said once and the default used.
pub fn init() {
    let level = match std::env::var(LOG_ENV) {
        Ok(v) => v.parse::<LevelFilter>().unwrap_or_else(|_| {
            eprintln!("warning: {LOG_ENV}={v:?} is not a level (error, warn, info, debug, trace, off); using info");
            LevelFilter::Info
        }),
        Err(_) => LevelFilter::Info,
    };
    if log::set_logger(&Stderr).is_ok() {
        log::set_max_level(level);
    }
}
