//! Every relative link of the front door and the pages behind it leads somewhere: the
//! README, ARCHITECTURE.md, SOURCES.md and every page under `docs/` are read, and each
//! Markdown link that is not a web address or an in-page anchor must name a file or
//! directory of the checkout (its `#section` part aside).

use std::path::{Path, PathBuf};

/// The Markdown files a reader of the checkout follows links through.
fn pages(root: &Path) -> Vec<PathBuf> {
    let mut pages: Vec<PathBuf> = ["README.md", "ARCHITECTURE.md", "SOURCES.md"]
        .iter()
        .map(|p| root.join(p))
        .filter(|p| p.is_file())
        .collect();
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    pages.extend(docs);
    pages
}

/// The targets of the inline links `[text](target)` of `text`, outside code spans and
/// fenced blocks.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Code spans hold shell and Rust, whose `](` is not a link.
        let prose: String = line
            .split('`')
            .enumerate()
            .filter(|(i, _)| i % 2 == 0)
            .map(|(_, s)| s)
            .collect::<Vec<_>>()
            .join(" ");
        let mut rest = prose.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(end) = after.find(')') else { break };
            targets.push(after[..end].trim().to_string());
            rest = &after[end..];
        }
    }
    targets
}

fn is_local(target: &str) -> bool {
    !(target.is_empty()
        || target.starts_with('#')
        || target.contains("://")
        || target.starts_with("mailto:"))
}

#[test]
fn every_relative_link_of_the_docs_names_a_file_of_the_checkout() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut dead = Vec::new();
    let mut followed = 0;
    for page in pages(root) {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in link_targets(&text).into_iter().filter(|t| is_local(t)) {
            let file = target.split('#').next().unwrap_or_default();
            let resolved = page.parent().unwrap().join(file);
            followed += 1;
            if !resolved.exists() {
                dead.push(format!(
                    "{}: ({target})",
                    page.strip_prefix(root).unwrap().display()
                ));
            }
        }
    }
    assert!(
        followed > 20,
        "only {followed} relative links found: is the link reader broken?"
    );
    assert!(dead.is_empty(), "links to nothing: {dead:#?}");
}

#[test]
fn the_link_reader_finds_links_and_skips_code() {
    let text = "see [engines](docs/engines.md#mujoco) and [web](https://x.org)\n\
                `a[0](b)` is code\n```\n[not](a-link.md)\n```\n[last](../README.md)";
    assert_eq!(
        link_targets(text),
        vec![
            "docs/engines.md#mujoco".to_string(),
            "https://x.org".to_string(),
            "../README.md".to_string()
        ]
    );
    assert!(!is_local("https://x.org") && !is_local("#a") && is_local("docs/a.md"));
}
