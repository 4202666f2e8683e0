//! The library's units form layers, and its rooms stack from the ground up.
//!
//! A *room* is a directory under `src/` (`files`, `sim`, `policy`, `eval`, `report`,
//! `campaign`, `dds`); its *units* are the submodules its `mod.rs` declares `pub mod`, and
//! the room's own `mod.rs` with its private submodules is a unit too (`eval` is the
//! evaluation's vocabulary, `policy` the `Policy` trait and its adapters). The graph's
//! edges are the `crate::` paths in a unit's code (comments left out), so no unit reaches
//! a unit that reaches back to it; the runner and the run directory (`eval::results`) both
//! sit on `eval` and never name each other, and `eval::results` writes machine files
//! without the `report` that renders them. Rooms are ordered — a room uses only rooms
//! below it — but for the few edges named in [`UPWARD`], each with its reason.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The rooms, from the ground up.
const ROOMS: [&str; 7] = [
    "files", "sim", "policy", "eval", "report", "campaign", "dds",
];

/// The edges from a unit to a room above its own, and why each is there. The test fails
/// when one of them disappears too, so this list cannot outlive its reasons.
const UPWARD: [(&str, &str, &str); 4] = [
    (
        "sim::motion",
        "eval::metrics",
        "a dataset's description uses the percentile that the regime thresholds use",
    ),
    (
        "sim::motion",
        "policy::network_kernels",
        "a reference motion stored in a policy's ONNX file is read with the pinned kernels",
    ),
    (
        "sim::motion",
        "policy::onnx_export",
        "…and its metadata says which joints and rate the stored motion has",
    ),
    (
        "eval::pipeline",
        "report",
        "a run's tables.md is written as the evaluation ends",
    ),
];

/// Each unit and the units its code names as `crate::room::unit` or `crate::room`.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut code_of: BTreeMap<String, String> = BTreeMap::new();
    for entry in std::fs::read_dir(&src).unwrap() {
        let room_dir = entry.unwrap().path();
        let room = room_dir.file_name().unwrap().to_str().unwrap().to_string();
        if !room_dir.is_dir() || room == "cli" {
            continue;
        }
        let units: BTreeSet<String> = std::fs::read_to_string(room_dir.join("mod.rs"))
            .unwrap()
            .lines()
            .filter_map(|l| l.strip_prefix("pub mod "))
            .map(|l| l.trim_end_matches(';').to_string())
            .collect();
        for child in std::fs::read_dir(&room_dir).unwrap() {
            let path = child.unwrap().path();
            let stem = path.file_stem().unwrap().to_str().unwrap().to_string();
            let unit = if units.contains(&stem) {
                format!("{room}::{stem}")
            } else {
                room.clone()
            };
            collect_code(&path, code_of.entry(unit).or_default());
        }
    }
    let units: BTreeSet<String> = code_of.keys().cloned().collect();
    code_of
        .iter()
        .map(|(unit, code)| {
            let uses = code
                .split("crate::")
                .skip(1)
                .filter_map(|rest| {
                    let mut parts = rest.split("::").map(|p| {
                        p.chars()
                            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                            .collect::<String>()
                    });
                    let room = parts.next()?;
                    let nested = format!("{room}::{}", parts.next().unwrap_or_default());
                    [nested, room].into_iter().find(|u| units.contains(u))
                })
                .filter(|u| u != unit)
                .collect();
            (unit.clone(), uses)
        })
        .collect()
}

/// The code of a module file or directory, without comment lines.
fn collect_code(path: &Path, out: &mut String) {
    if path.is_dir() {
        for entry in std::fs::read_dir(path).unwrap() {
            collect_code(&entry.unwrap().path(), out);
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        for line in std::fs::read_to_string(path).unwrap().lines() {
            if !line.trim_start().starts_with("//") {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
}

/// A cycle through `from`, as the path of units, if there is one.
fn cycle_from(graph: &BTreeMap<String, BTreeSet<String>>, from: &str) -> Option<Vec<String>> {
    fn walk(
        graph: &BTreeMap<String, BTreeSet<String>>,
        target: &str,
        at: &str,
        path: &mut Vec<String>,
        seen: &mut BTreeSet<String>,
    ) -> bool {
        for next in &graph[at] {
            if next == target {
                path.push(next.clone());
                return true;
            }
            if seen.insert(next.clone()) {
                path.push(next.clone());
                if walk(graph, target, next, path, seen) {
                    return true;
                }
                path.pop();
            }
        }
        false
    }
    let mut path = vec![from.to_string()];
    walk(graph, from, from, &mut path, &mut BTreeSet::new()).then_some(path)
}

fn room_of(unit: &str) -> usize {
    let room = unit.split("::").next().unwrap();
    ROOMS
        .iter()
        .position(|r| *r == room)
        .unwrap_or_else(|| panic!("{room} is not one of the rooms {ROOMS:?}"))
}

#[test]
fn no_unit_reaches_back_to_itself() {
    let graph = graph();
    assert!(graph.len() > 30, "read the units: {:?}", graph.keys());
    let cycles: Vec<String> = graph
        .keys()
        .filter_map(|m| cycle_from(&graph, m))
        .map(|c| c.join(" → "))
        .collect();
    assert!(cycles.is_empty(), "import cycles:\n{}", cycles.join("\n"));
}

#[test]
fn rooms_use_only_the_rooms_below_them_but_for_the_named_edges() {
    let graph = graph();
    let upward: BTreeSet<(String, String)> = graph
        .iter()
        .flat_map(|(from, tos)| tos.iter().map(move |to| (from.clone(), to.clone())))
        .filter(|(from, to)| room_of(to) > room_of(from))
        .collect();
    let named: BTreeSet<(String, String)> = UPWARD
        .iter()
        .map(|(from, to, _)| (from.to_string(), to.to_string()))
        .collect();
    let unnamed: Vec<_> = upward.difference(&named).collect();
    assert!(
        unnamed.is_empty(),
        "units reach a room above their own (rooms from the ground up: {ROOMS:?}): {unnamed:?}"
    );
    let gone: Vec<_> = named.difference(&upward).collect();
    assert!(
        gone.is_empty(),
        "named upward edges that no longer exist (take them off UPWARD): {gone:?}"
    );
}

#[test]
fn runner_and_results_sit_on_evaluation_and_results_never_renders() {
    let graph = graph();
    for (from, to) in [
        ("eval::results", "eval::runner"),
        ("eval::runner", "eval::results"),
        ("eval::results", "report"),
        ("eval::results", "eval::pipeline"),
        ("eval::runner", "eval::pipeline"),
    ] {
        assert!(!graph[from].contains(to), "{from} imports {to}");
    }
    for unit in ["eval::runner", "eval::results"] {
        assert!(
            graph[unit].contains("eval"),
            "{unit} does not use the evaluation vocabulary"
        );
    }
}

#[test]
fn the_cycle_finder_finds_a_planted_cycle() {
    let mut graph = graph();
    graph
        .get_mut("eval")
        .unwrap()
        .insert("eval::results".into());
    let cycle = cycle_from(&graph, "eval").expect("a planted cycle is found");
    assert_eq!(cycle.first(), cycle.last());
}
