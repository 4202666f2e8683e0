//! docs/real-walks.md's table is measured: the three general trackers on the real human
//! walks the binary carries, MuJoCo, without force and under 10, 20 and 30 N pushes, by
//! the commands the page shows, to the digits it prints. Needs the `mujoco` feature and
//! the published networks (skipped, saying so, without them; never in CI).

mod prereq;
mod readme;

use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const TEST: &str = "real_walks_board::the_real_walks_table_is_what_eval_prints";

/// The `(label, number)` cells of `tables.md`'s row `label`, after its first cell.
fn row(tables: &str, label: &str) -> Vec<String> {
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

#[test]
fn the_real_walks_table_is_what_eval_prints() {
    if !cfg!(feature = "mujoco") {
        return prereq::skip(TEST, "built without the `mujoco` feature");
    }
    let policies = [
        ("TWIST2", "twist2", "twist2/twist2_1017_25k.onnx", false),
        (
            "wbc-mjlab",
            "wbc-mjlab",
            "wbc-mjlab/wbc_g1_policy.onnx",
            false,
        ),
        ("FALCON", "falcon", "falcon/g1_29dof_falcon.onnx", true),
    ];
    let dir = tempfile::tempdir().unwrap();
    let mut measured = Vec::new();
    for (label, family, file, unchecked) in policies {
        let Some(network) = prereq::reference(TEST, file) else {
            return;
        };
        let out = dir.path().join(family);
        let mut c = Command::new(BIN);
        c.args(["eval", "--dataset", "real-walks", "--engine", "mujoco"])
            .args(["--policy", &format!("{family}:{}", network.display())])
            .args(["--settings", "no-force,push:10,push:20,push:30"])
            .arg("--out")
            .arg(&out);
        if unchecked {
            c.arg("--unchecked");
        }
        let o = c.output().unwrap();
        assert!(
            o.status.success(),
            "{label}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
        let fats = row(&tables, "average");
        let interval = row(
            &tables,
            "95 % interval (bootstrap over episodes within tasks)",
        );
        let survival = row(&tables, "Survival (mean)");
        measured.push(vec![
            label.to_string(),
            fats[0].clone(),
            interval[0].clone(),
            survival[0].clone(),
            fats[1].clone(),
            fats[2].clone(),
            fats[3].clone(),
            survival[3].clone(),
        ]);
    }
    readme::assert_readme_table("real-walks-board", &measured);
}
