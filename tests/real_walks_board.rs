//! docs/real-walks.md's tables are measured: the three general trackers on the real human
//! walks the binary carries, MuJoCo, without force and under 10, 20 and 30 N pushes, and
//! under the force menu's events and payloads, by the commands the page shows, to the
//! digits it prints. Needs the `mujoco` feature and
//! the published networks (skipped, saying so, without them; never in CI).

mod prereq;
mod readme;

use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const TEST: &str = "real_walks_board::the_real_walks_table_is_what_eval_prints";

use readme::tables_row as row;

/// The three general trackers, each with its network's path under the reference folder
/// and whether it runs `--unchecked`.
const POLICIES: [(&str, &str, &str, bool); 3] = [
    ("TWIST2", "twist2", "twist2/twist2_1017_25k.onnx", false),
    (
        "wbc-mjlab",
        "wbc-mjlab",
        "wbc-mjlab/wbc_g1_policy.onnx",
        false,
    ),
    ("FALCON", "falcon", "falcon/g1_29dof_falcon.onnx", true),
];

/// Each policy's `tables.md` from the page's command with `settings`, or `None` after a
/// skip (no `mujoco` feature, no networks).
fn tables_of(test: &str, settings: &str) -> Option<Vec<(&'static str, String)>> {
    if !cfg!(feature = "mujoco") {
        prereq::skip(test, "built without the `mujoco` feature");
        return None;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut all = Vec::new();
    for (label, family, file, unchecked) in POLICIES {
        let network = prereq::reference(test, file)?;
        let out = dir.path().join(family);
        let mut c = Command::new(BIN);
        c.args(["eval", "--dataset", "real-walks", "--engine", "mujoco"])
            .args(["--policy", &format!("{family}:{}", network.display())])
            .args(["--settings", settings])
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
        all.push((
            label,
            std::fs::read_to_string(out.join("tables.md")).unwrap(),
        ));
    }
    Some(all)
}

#[test]
fn the_real_walks_table_is_what_eval_prints() {
    let Some(all) = tables_of(TEST, "no-force,push:10,push:20,push:30") else {
        return;
    };
    let mut measured = Vec::new();
    for (label, tables) in all {
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

/// The page's second table: the force menu's events and payloads on the same walks. The
/// tables order settings by name: the 20 N event, the 30 N side event, the 40 N event,
/// 2 kg, 5 kg.
#[test]
fn the_real_walks_menu_table_is_what_eval_prints() {
    const MENU: &str = "real_walks_board::the_real_walks_menu_table_is_what_eval_prints";
    let settings =
        "event:20@0:hand=both,event:40@0:hand=both,event:30@90:hand=right,payload:2,payload:5";
    let Some(all) = tables_of(MENU, settings) else {
        return;
    };
    let mut measured = Vec::new();
    for (label, tables) in all {
        let fats = row(&tables, "average");
        let survival = row(&tables, "Survival (mean)");
        let mut cells = vec![label.to_string()];
        cells.extend((0..5).map(|i| format!("{} ({})", fats[i], survival[i])));
        measured.push(cells);
    }
    readme::assert_readme_table("real-walks-menu", &measured);
}
