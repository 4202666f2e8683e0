//! The documentation's figures (README.md, docs/) are measured, not typed: every table between `<!-- figures: NAME -->`
//! and `<!-- /figures -->` is re-derived here (or, for the TWIST2 walks, in
//! `tests/twist2_reference.rs`) with the command the page shows beside it, and must match to
//! the digits the page prints.

use std::path::Path;
use std::process::Command;

mod readme;
use readme::readme_table;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Runs the documented command on the sample; returns `tables.md`.
fn eval_sample(policy: &str, out: &Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["eval", "--dataset"])
        .arg(Path::new(ROOT).join("data/sample"))
        .args(["--policy", policy, "--out"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read_to_string(out.join("tables.md")).unwrap()
}

/// The two numbers of `tables.md`'s row whose first cell is `label` (task table first).
fn row(tables: &str, label: &str) -> [String; 2] {
    let cells = readme::tables_row(tables, label);
    [cells[0].clone(), cells[1].clone()]
}

#[test]
fn the_baseline_table_is_what_eval_prints() {
    let dir = tempfile::tempdir().unwrap();
    let balance = eval_sample("balance", &dir.path().join("balance"));
    let hold = eval_sample("hold", &dir.path().join("hold"));
    let table = readme_table("baselines-sample");
    assert_eq!(table.len(), 8, "six tasks, the average and survival");
    for readme_row in &table {
        let label = readme_row[0].as_str();
        let shown = readme_row[1..].to_vec();
        let tables_label = if label == "survival" {
            "Survival (mean)"
        } else {
            label
        };
        let [bf, bn] = row(&balance, tables_label);
        let [hf, hn] = row(&hold, tables_label);
        assert_eq!(
            shown,
            [bf, bn, hf, hn],
            "docs/policies.md's `{label}` row differs from `thorarena eval` (balance force, no force, hold force, no force)"
        );
    }
}

/// README's "What the scores mean" quotes balance's FATS under force on the sample and its
/// bootstrap interval: both as `thorarena eval --policy balance` prints them.
#[test]
fn the_readmes_interval_sentence_is_what_eval_prints() {
    let readme = std::fs::read_to_string(Path::new(ROOT).join("README.md")).unwrap();
    let flat = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    let quoted = flat
        .split_once("under force balance scores ")
        .and_then(|(_, rest)| rest.split_once(')'))
        .map(|(sentence, _)| sentence.to_string())
        .expect("README quotes balance's score under force on the sample");
    let dir = tempfile::tempdir().unwrap();
    let tables = eval_sample("balance", &dir.path().join("balance"));
    let [fats, _] = row(&tables, "average");
    let [interval, _] = row(
        &tables,
        "95 % interval (bootstrap over episodes within tasks)",
    );
    assert_eq!(
        quoted,
        format!("{fats}, interval {interval}"),
        "README's sentence differs from `thorarena eval --policy balance`'s tables.md"
    );
}
