//! The documentation's figure tables (`<!-- figures: NAME -->` … `<!-- /figures -->`, in
//! README.md or a page of `docs/`), read by the tests that re-derive them.
#![allow(dead_code)]

use std::path::Path;

/// README.md and every page of `docs/`, each with its text.
fn documents() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("README.md")];
    let mut pages: Vec<_> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    files.extend(pages);
    files
        .into_iter()
        .map(|f| {
            let text = std::fs::read_to_string(&f).unwrap();
            (f.display().to_string(), text)
        })
        .collect()
}

/// The rows of the documentation's table `name`: cells per row, header and separator
/// dropped. It must stand in exactly one document.
pub fn readme_table(name: &str) -> Vec<Vec<String>> {
    let open = format!("<!-- figures: {name} -->");
    let holding: Vec<(String, String)> = documents()
        .into_iter()
        .filter(|(_, text)| text.contains(&open))
        .collect();
    assert_eq!(
        holding.len(),
        1,
        "{open} must stand in exactly one of README.md and docs/*.md: {:?}",
        holding.iter().map(|(f, _)| f).collect::<Vec<_>>()
    );
    let body = holding[0].1.split_once(&open).unwrap().1;
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
        "the documentation's table `{name}` is not what was measured (rows printed above)"
    );
}

/// The cells after the first of `tables.md`'s row whose first cell is `label` (the task
/// table's first), bold and a † mark removed.
pub fn tables_row(tables: &str, label: &str) -> Vec<String> {
    let line = tables
        .lines()
        .find(|l| {
            l.trim_start_matches('|')
                .split('|')
                .next()
                .is_some_and(|c| c.trim().trim_matches('*') == label)
        })
        .unwrap_or_else(|| panic!("tables.md has no row {label}:\n{tables}"));
    line.trim_matches('|')
        .split('|')
        .skip(1)
        .map(|c| {
            c.trim()
                .trim_matches('*')
                .trim_end_matches(" †")
                .to_string()
        })
        .collect()
}
