//! The library's top-level modules form layers: no module reaches, through `crate::`
//! paths in its code, a module that reaches back to it. In particular the runner and the
//! run directory (`results`) both sit on `evaluation` and never name each other, and
//! `results` writes machine files without the `report` that renders them.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Each top-level library module and the top-level modules its code names as `crate::x`
/// (comments and doc comments left out; `crate::data_dir` and other root items are not
/// modules).
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut modules = BTreeMap::new();
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        if ["lib", "main", "cli"].contains(&name.as_str()) {
            continue;
        }
        let mut text = String::new();
        collect_code(&path, &mut text);
        modules.insert(name, text);
    }
    let names: BTreeSet<String> = modules.keys().cloned().collect();
    modules
        .iter()
        .map(|(name, code)| {
            let uses = code
                .split("crate::")
                .skip(1)
                .map(|rest| {
                    rest.chars()
                        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                        .collect::<String>()
                })
                .filter(|m| m != name && names.contains(m))
                .collect();
            (name.clone(), uses)
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

/// A cycle through `from`, as the path of modules, if there is one.
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

#[test]
fn no_module_reaches_back_to_itself() {
    let graph = graph();
    assert!(graph.len() > 15, "read the modules: {:?}", graph.keys());
    let cycles: Vec<String> = graph
        .keys()
        .filter_map(|m| cycle_from(&graph, m))
        .map(|c| c.join(" → "))
        .collect();
    assert!(cycles.is_empty(), "import cycles:\n{}", cycles.join("\n"));
}

#[test]
fn runner_and_results_sit_on_evaluation_and_results_never_renders() {
    let graph = graph();
    for (from, to) in [
        ("results", "runner"),
        ("runner", "results"),
        ("results", "report"),
        ("results", "benchmark"),
        ("runner", "benchmark"),
    ] {
        assert!(!graph[from].contains(to), "{from} imports {to}");
    }
    for module in ["runner", "results"] {
        assert!(
            graph[module].contains("evaluation"),
            "{module} does not use the evaluation vocabulary"
        );
    }
}

#[test]
fn the_cycle_finder_finds_a_planted_cycle() {
    let mut graph = graph();
    graph
        .get_mut("evaluation")
        .unwrap()
        .insert("results".into());
    let cycle = cycle_from(&graph, "evaluation").expect("a planted cycle is found");
    assert_eq!(cycle.first(), cycle.last());
}
