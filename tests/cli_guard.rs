//! The command line parses, calls the library and prints: no file under `src/cli` writes
//! a file itself, implements a policy, or grows past a screenful of logic. What a command
//! writes — a run, a report, a plan, a job script — is the library's, where the other
//! commands and the tests reach it too (a `dds` run that wrote its own `tables.md` was
//! found rebuilding what `pipeline::evaluate` does).

use std::path::{Path, PathBuf};

/// Lines a file of the command line may hold: its arguments with their help, the call,
/// and the printing.
const MAX_LINES: usize = 300;

/// Lines the whole command line may hold: about a thousand are its arguments and their
/// help, the rest the calls and the printing. It regrew from 3 589 to 5 060 lines in two
/// days once, orchestration coming with it; a new command's logic goes into the library.
/// 2 500 until `data check` (with `--rollout`) and `data import --format rollout` came,
/// whose gate, checks, rollouts and import live in the library: the 2 582 after them are
/// arguments, help and printing.
const MAX_TOTAL_LINES: usize = 2_600;

/// Calls that write, create or remove files. Writing to stdout or stderr is the CLI's
/// job and is not among them.
const WRITES: &[&str] = &[
    "fs::write(",
    "File::create(",
    "OpenOptions",
    "create_dir(",
    "create_dir_all(",
    "remove_file(",
    "remove_dir(",
    "remove_dir_all(",
    "fs::rename(",
    "fs::copy(",
    "atomic_file::",
    "write_atomic(",
];

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The CLI's files with their text, comment lines left out of the code checks.
fn cli_files() -> Vec<(PathBuf, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src/cli"), &mut files);
    files.sort();
    assert!(files.len() > 10, "src/cli holds {} files", files.len());
    files
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            (p.strip_prefix(root).unwrap().to_path_buf(), text)
        })
        .collect()
}

fn code_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim_start().starts_with("//"))
        .map(|(i, l)| (i + 1, l))
}

#[test]
fn no_file_of_the_command_line_exceeds_its_size() {
    let long: Vec<String> = cli_files()
        .iter()
        .filter(|(_, text)| text.lines().count() > MAX_LINES)
        .map(|(p, text)| format!("{} ({} lines)", p.display(), text.lines().count()))
        .collect();
    assert!(
        long.is_empty(),
        "over {MAX_LINES} lines: {long:?} — move what is not parsing, calling or printing into the library"
    );
}

#[test]
fn the_command_line_stays_within_its_budget() {
    let files = cli_files();
    let total: usize = files.iter().map(|(_, text)| text.lines().count()).sum();
    let mut largest: Vec<(usize, String)> = files
        .iter()
        .map(|(p, text)| (text.lines().count(), p.display().to_string()))
        .collect();
    largest.sort();
    largest.reverse();
    largest.truncate(5);
    assert!(
        total <= MAX_TOTAL_LINES,
        "src/cli holds {total} lines, over its {MAX_TOTAL_LINES} (largest: {largest:?}) — move what is not parsing, calling or printing into the library"
    );
}

#[test]
fn the_command_line_writes_no_file_itself() {
    let mut found = Vec::new();
    for (path, text) in cli_files() {
        for (n, line) in code_lines(&text) {
            if let Some(call) = WRITES.iter().find(|w| line.contains(*w)) {
                found.push(format!("{}:{n}: {call}", path.display()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "files written from src/cli (the library owns them): {found:#?}"
    );
}

#[test]
fn the_command_line_implements_no_policy() {
    let mut found = Vec::new();
    for (path, text) in cli_files() {
        for (n, line) in code_lines(&text) {
            let line = line.trim_start();
            if line.starts_with("impl") && line.contains("Policy for ") {
                found.push(format!("{}:{n}: {line}", path.display()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "policies implemented in src/cli (they belong in the library's policy or leaderboard modules): {found:#?}"
    );
}

/// The guard sees what it guards: a write and an over-long file, planted in text, are
/// caught by the same checks.
#[test]
fn the_checks_catch_what_they_look_for() {
    let planted = "fn f() {\n    std::fs::write(\"x\", \"y\").unwrap();\n}\n";
    let caught: Vec<_> = code_lines(planted)
        .filter(|(_, l)| WRITES.iter().any(|w| l.contains(w)))
        .collect();
    assert_eq!(caught.len(), 1);
    let commented = "// std::fs::write(\"x\", \"y\") is what the library does\n";
    assert_eq!(
        code_lines(commented)
            .filter(|(_, l)| WRITES.iter().any(|w| l.contains(w)))
            .count(),
        0
    );
}
