//! ARCHITECTURE.md's module tables list exactly the rooms of `src/` and their public units
//! (the `| module |` table: `eval`, `eval::runner`, …) and the modules of the ipc crate (the
//! `| ipc module |` table).

use std::collections::BTreeSet;
use std::path::Path;

/// The first-column names of the table whose header row starts with `header`.
fn table(doc: &str, header: &str) -> BTreeSet<String> {
    doc.lines()
        .skip_while(|l| !l.starts_with(header))
        .skip(2) // header and separator rows
        .take_while(|l| l.starts_with('|'))
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split('`').next())
        .map(str::to_string)
        .collect()
}

fn modules(lib_rs: &Path) -> BTreeSet<String> {
    public_children(lib_rs)
        .into_iter()
        .flat_map(|room| {
            let room_mod = lib_rs.parent().unwrap().join(&room).join("mod.rs");
            let units = if room_mod.exists() {
                public_children(&room_mod)
            } else {
                Vec::new()
            };
            let nested: Vec<String> = units.iter().map(|u| format!("{room}::{u}")).collect();
            std::iter::once(room).chain(nested)
        })
        .collect()
}

/// The `pub mod` names a module file declares.
fn public_children(file: &Path) -> Vec<String> {
    std::fs::read_to_string(file)
        .unwrap()
        .lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';').to_string())
        .collect()
}

#[test]
fn architecture_module_tables_match_the_source_trees() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    assert_eq!(
        table(&doc, "| module |"),
        modules(&root.join("src/lib.rs")),
        "ARCHITECTURE.md module table vs src/lib.rs"
    );
    assert_eq!(
        table(&doc, "| ipc module |"),
        modules(&root.join("ipc/src/lib.rs")),
        "ARCHITECTURE.md ipc module table vs ipc/src/lib.rs"
    );
}

/// The library never prints: its news goes through `log`, and the binary (`src/cli/`,
/// `src/main.rs`) decides what reaches the terminal.
#[test]
fn library_code_never_prints() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut offenders = Vec::new();
    let mut stack = vec![root.join("src"), root.join("ipc/src")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                if !path.ends_with("src/cli") {
                    stack.push(path);
                }
                continue;
            }
            if path.ends_with("src/main.rs") || path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            // Unit tests (after `#[cfg(test)]`) may print.
            let code = text.split("#[cfg(test)]").next().unwrap_or("");
            for (i, line) in code.lines().enumerate() {
                if ["println!", "eprintln!", "print!(", "eprint!("]
                    .iter()
                    .any(|m| line.contains(m) && !line.trim_start().starts_with("//"))
                {
                    offenders.push(format!("{}:{}", path.display(), i + 1));
                }
            }
        }
    }
    assert!(offenders.is_empty(), "library code prints: {offenders:?}");
}
