//! ARCHITECTURE.md's module tables list exactly the modules of `src/` (the `| module |`
//! table) and of the ipc crate (the `| ipc module |` table).

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
    std::fs::read_to_string(lib_rs)
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
