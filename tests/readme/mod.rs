//! README's figure tables (`<!-- figures: NAME -->` … `<!-- /figures -->`), read by the
//! tests that re-derive them.
#![allow(dead_code)]

use std::path::Path;

/// The rows of README's table `name`: cells per row, header and separator dropped.
pub fn readme_table(name: &str) -> Vec<Vec<String>> {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    let open = format!("<!-- figures: {name} -->");
    let body = readme
        .split_once(&open)
        .unwrap_or_else(|| panic!("README has no {open}"))
        .1;
    let body = body.split_once("<!-- /figures -->").unwrap().0;
    body.lines()
        .filter(|l| l.starts_with('|'))
        .skip(2)
        .map(|l| {
            l.trim_matches('|')
                .split('|')
                .map(|c| c.trim().trim_matches('*').to_string())
                .collect()
        })
        .collect()
}

/// Asserts that README's table `name` is `measured` (cells per row, as [`readme_table`]
/// reads them), printing every measured row first, so a changed table is mended from one
/// run.
pub fn assert_readme_table(name: &str, measured: &[Vec<String>]) {
    for row in measured {
        eprintln!("| {} |", row.join(" | "));
    }
    assert_eq!(
        readme_table(name),
        measured,
        "README's table `{name}` is not what was measured (rows printed above)"
    );
}
