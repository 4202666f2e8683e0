//! ARCHITECTURE.md's module table lists exactly the modules of `src/`.

use std::collections::BTreeSet;

#[test]
fn architecture_module_table_matches_the_source_tree() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let listed: BTreeSet<String> = doc
        .lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split('`').next())
        .map(str::to_string)
        .collect();
    let lib = std::fs::read_to_string(root.join("src/lib.rs")).unwrap();
    let actual: BTreeSet<String> = lib
        .lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';').to_string())
        .collect();
    assert_eq!(listed, actual, "ARCHITECTURE.md module table vs src/lib.rs");
}
