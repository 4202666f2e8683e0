//! Test prerequisites that may be missing on a developer's machine: the published
//! reference artifacts, Python packages, a C++ compiler, a browser.
//!
//! A test whose prerequisite is missing calls [`skip`] and returns. Locally that is
//! printed and appended to `$THORARENA_SKIP_LOG` (set by `./test.sh`), whose closing line
//! counts it as skipped, not passed. In CI (`CI=true`) it fails the test: no README claim
//! may rest on a test that did not run. Shared by the root crate's and `ipc/`'s tests
//! (`#[path]`-included there).
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Environment variable naming the published reference artifacts (see docs/policies.md,
/// "Reference artifacts"); default `../shared/reference` beside the checkout.
pub const REFERENCE_ENV: &str = "THORARENA_REFERENCE";

/// Records that `test` could not run because `reason`; panics under `CI=true`.
pub fn skip(test: &str, reason: &str) {
    if std::env::var("CI").is_ok_and(|v| v == "true" || v == "1") {
        panic!("{test}: prerequisite missing in CI: {reason}");
    }
    eprintln!("SKIPPED {test}: {reason}");
    if let Some(log) = std::env::var_os("THORARENA_SKIP_LOG") {
        let line = format!("{test}\t{}\n", reason.replace('\n', " "));
        let appended = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&log)
            .and_then(|mut f| f.write_all(line.as_bytes()));
        if let Err(e) = appended {
            panic!("{test}: cannot record the skip in {log:?}: {e}");
        }
    }
}

/// The reference artifacts' directory: `$THORARENA_REFERENCE`, else `../shared/reference`
/// beside the workspace root.
pub fn reference_dir() -> PathBuf {
    match std::env::var_os(REFERENCE_ENV) {
        Some(dir) => PathBuf::from(dir),
        None => workspace_root().join("../shared/reference"),
    }
}

/// A file or folder of the reference artifacts, or `None` after [`skip`] when absent.
pub fn reference(test: &str, relative: &str) -> Option<PathBuf> {
    let path = reference_dir().join(relative);
    if path.exists() {
        Some(path)
    } else {
        skip(
            test,
            &format!(
                "{} is absent (the published reference artifacts; set {REFERENCE_ENV})",
                path.display()
            ),
        );
        None
    }
}

/// `true` when `python3 -c "import <modules>"` works; otherwise [`skip`]s with the
/// install line and returns `false`.
pub fn python_modules(test: &str, modules: &[&str], install: &str) -> bool {
    python_imports(test, Path::new("python3"), modules, install)
}

/// `true` when `<python> -c "import <modules>"` works; otherwise [`skip`]s with `install`.
fn python_imports(test: &str, python: &Path, modules: &[&str], install: &str) -> bool {
    let import = format!("import {}", modules.join(", "));
    let ok = Command::new(python)
        .args(["-c", &import])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        skip(
            test,
            &format!(
                "`{} -c \"{import}\"` fails ({install}, or run ./test.sh)",
                python.display()
            ),
        );
    }
    ok
}

/// The workspace root: the manifest directory of the root crate, the parent of `ipc/`'s.
fn workspace_root() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if manifest.ends_with("ipc") {
        manifest.parent().map(PathBuf::from).unwrap_or(manifest)
    } else {
        manifest
    }
}

/// Unitree's Python SDK (unitree_sdk2_python, the directory to put on `PYTHONPATH`) when
/// it is among the reference artifacts and Python's `cyclonedds` imports; otherwise
/// [`skip`]s and returns `None`.
pub fn unitree_sdk(test: &str) -> Option<PathBuf> {
    let sdk = reference(test, "unitree_sdk2_python/unitree_sdk2py")?;
    if !python_modules(
        test,
        &["cyclonedds", "numpy"],
        "pip install -r tools/requirements-dev.txt",
    ) {
        return None;
    }
    sdk.parent().map(std::path::Path::to_path_buf)
}

/// The Python of the deployment-code environment (`.venv-deploy`, which `./test.sh` makes
/// from `tools/requirements-deploy.txt`: holosoma's inference package and the Unitree SDK
/// binding it drives the robot through), or `$THORARENA_DEPLOY_PYTHON`, when
/// `holosoma_inference` and `unitree_interface` import with it; otherwise [`skip`]s and
/// returns `None`.
pub fn deploy_python(test: &str) -> Option<PathBuf> {
    let python = match std::env::var_os("THORARENA_DEPLOY_PYTHON") {
        Some(python) => PathBuf::from(python),
        None => workspace_root().join(".venv-deploy/bin/python"),
    };
    let modules = ["holosoma_inference", "unitree_interface"];
    let install = "./test.sh makes .venv-deploy from tools/requirements-deploy.txt";
    python_imports(test, &python, &modules, install).then_some(python)
}
