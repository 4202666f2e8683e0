//! `ipc/layout.json` — the layout every other language checks itself against — is what
//! this build's Rust types say. Regenerate it with `THORARENA_BLESS=1 cargo test -p
//! thorarena-ipc --test layout_file` after a deliberate layout change (and bump
//! `PROTOCOL_VERSION`).

#[test]
fn layout_json_matches_the_rust_types() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("layout.json");
    let now = thorarena_ipc::describe::layout_json();
    if std::env::var_os("THORARENA_BLESS").is_some() {
        std::fs::write(&path, &now).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == now,
        "{} is stale: rerun with THORARENA_BLESS=1 after a deliberate layout change",
        path.display()
    );
}
