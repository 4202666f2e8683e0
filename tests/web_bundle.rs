//! The front-end bundle compiled into the binary (`web/bundle/`) is exactly what
//! `npm run build --prefix web` makes from `web/src/` and the lockfile's three.js,
//! Chart.js and esbuild: rebuilt into a temporary directory and compared byte for byte.
//! A page script edited without rebuilding, or a bundle edited by hand, fails here.

use std::path::Path;
use std::process::Command;

mod prereq;

#[test]
fn the_committed_bundle_is_what_the_lockfile_builds() {
    const TEST: &str = "web_bundle::the_committed_bundle_is_what_the_lockfile_builds";
    let web = Path::new(env!("CARGO_MANIFEST_DIR")).join("web");
    if !web.join("node_modules/esbuild").is_dir() {
        return prereq::skip(
            TEST,
            "web/node_modules/esbuild is missing (npm ci --prefix web, or run ./test.sh)",
        );
    }
    let out_dir = tempfile::tempdir().unwrap();
    let out = Command::new("npm")
        .args(["run", "--silent", "build", "--prefix"])
        .arg(&web)
        .arg("--")
        .arg(format!("--outdir={}", out_dir.path().display()))
        .output()
        .expect("npm runs");
    assert!(
        out.status.success(),
        "npm run build failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in ["report.js", "view.js"] {
        let built = std::fs::read(out_dir.path().join(name)).unwrap();
        let committed = std::fs::read(web.join("bundle").join(name)).unwrap();
        assert!(
            built == committed,
            "web/bundle/{name} differs from what the lockfile builds ({} vs {} bytes): \
             run `npm run build --prefix web` and commit web/bundle",
            committed.len(),
            built.len()
        );
    }
}
