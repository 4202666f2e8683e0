#!/usr/bin/env bash
# ThorArena's test command (README, "Two commands"): sets up what the tests need, runs the
# Rust and Python suites, and ends with one line counting passed, failed and skipped.
#
# Set-up, each step only when needed (a second run reuses everything):
#   - Python packages into the project-local virtual environment .venv/ (never system-wide):
#     tools/requirements.txt (MuJoCo cross-check), tools/requirements-dev.txt (ruff, mypy),
#     and the policy client ./adapters/python[policies,test], editable;
#   - deployment code run unchanged against `thorarena dds` (tools/requirements-deploy.txt:
#     holosoma's inference package and Unitree's SDK binding) into .venv-deploy/, an
#     environment of its own; if that fails, its test counts as skipped;
#   - the front end's node packages (web/node_modules: esbuild, playwright-core);
#   - g++, make and chromium through apt-get, only if missing and only when run as root;
#     otherwise the tests that need them are counted as skipped and the line says so;
#   - MuJoCo 3.17.0's library from the PyPI wheel into target/mujoco-3.17.0/
#     (tools/mujoco-lib.sh), so the tests build with the `mujoco` feature (the MuJoCo
#     backend); without it they build without, and its tests count as skipped.
# A test whose prerequisite is missing is counted as skipped here; under CI=true it fails.
#
# `./test.sh --reference-tests-only` runs only the test files that use the published
# reference artifacts (those naming `prereq::reference`, `reference_dir`, `THORARENA_REFERENCE` or
# `shared/reference`): CI runs them a second time without the artifacts, to show they skip.
set -uo pipefail
cd "$(dirname "$0")"
rust_targets=(--workspace)
py_targets=(tools/tests adapters/python/tests)
if [ "${1:-}" = --reference-tests-only ]; then
    rust_targets=()
    for f in $(grep -lE 'prereq::(reference|unitree_sdk)|reference_dir|THORARENA_REFERENCE|shared/reference' tests/*.rs); do
        rust_targets+=(--test "$(basename "$f" .rs)")
    done
    mapfile -t py_targets < <(grep -lE 'THORARENA_REFERENCE|shared.*reference|reference MJCF' tools/tests/*.py adapters/python/tests/*.py)
elif [ $# != 0 ]; then
    echo "usage: ./test.sh [--reference-tests-only]"; exit 2
fi
root=$PWD
logs=$root/target/test-logs
mkdir -p "$logs"
say() { printf '== %s\n' "$*"; }

say "system tools (g++, make, chromium)"
missing=()
command -v g++ >/dev/null || missing+=(g++)
command -v make >/dev/null || missing+=(make)
[ -x "${THORARENA_CHROMIUM:-/usr/bin/chromium}" ] || missing+=(chromium)
if ((${#missing[@]})); then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        say "installing ${missing[*]} with apt-get (its output: $logs/apt-get.log)"
        { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"; } \
            > "$logs/apt-get.log" 2>&1 \
            || { tail -n 20 "$logs/apt-get.log"; say "apt-get could not install ${missing[*]}; tests that need them will not run"; }
    else
        say "missing ${missing[*]} (not root: not installing); tests that need them count as skipped"
    fi
fi

say "python packages in .venv"
if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv || { echo "python3 -m venv failed (Debian: apt-get install python3-venv)"; exit 1; }
fi
want=$(cat tools/requirements.txt tools/requirements-dev.txt adapters/python/pyproject.toml | sha256sum)
if [ "$(cat .venv/.thorarena-setup 2>/dev/null)" != "$want" ]; then
    .venv/bin/python -m pip install --quiet --disable-pip-version-check \
        -r tools/requirements.txt -r tools/requirements-dev.txt -e './adapters/python[policies,test]' \
        || { echo "pip install into .venv failed"; exit 1; }
    echo "$want" > .venv/.thorarena-setup
fi
export VIRTUAL_ENV=$root/.venv
export PATH=$root/.venv/bin:$PATH

say "deployment code in .venv-deploy (tools/requirements-deploy.txt)"
want=$(sha256sum < tools/requirements-deploy.txt)
if [ "$(cat .venv-deploy/.thorarena-setup 2>/dev/null)" != "$want" ]; then
    { [ -x .venv-deploy/bin/python ] || python3 -m venv .venv-deploy; } \
        && .venv-deploy/bin/python -m pip install --quiet --disable-pip-version-check \
            -r tools/requirements-deploy.txt > "$logs/pip-deploy.log" 2>&1 \
        && echo "$want" > .venv-deploy/.thorarena-setup \
        || { tail -n 20 "$logs/pip-deploy.log"; say "could not set up .venv-deploy: the deployment-code test counts as skipped"; }
fi

say "front end node packages (web/node_modules)"
if command -v npm >/dev/null; then
    want=$(sha256sum < web/package-lock.json)
    if [ "$(cat web/node_modules/.thorarena-setup 2>/dev/null)" != "$want" ]; then
        npm ci --prefix web --no-audit --no-fund --loglevel=error \
            || { echo "npm ci --prefix web failed"; exit 1; }
        echo "$want" > web/node_modules/.thorarena-setup
    fi
else
    say "node/npm missing: the bundle check and the browser test count as skipped"
fi

say "MuJoCo 3.17.0 library (tools/mujoco-lib.sh)"
features=()
if mujoco_env=$(tools/mujoco-lib.sh); then
    eval "$mujoco_env"
    features=(--features thorarena/mujoco)
else
    say "no MuJoCo 3.17.0 library: building without the mujoco feature (its tests count as skipped)"
fi

say "rust tests (cargo test --release ${rust_targets[*]} ${features[*]}; the first build takes 10 to 20 min on 2 cores)"
export THORARENA_SKIP_LOG=$logs/skipped.tsv
: > "$THORARENA_SKIP_LOG"
cargo test --release "${rust_targets[@]}" "${features[@]}" --no-fail-fast 2>&1 | tee "$logs/cargo-test.log"
rust_rc=${PIPESTATUS[0]}

say "python tests (pytest ${py_targets[*]})"
python -m pytest -q -rsfE --confcutdir=. "${py_targets[@]}" 2>&1 | tee "$logs/pytest.log"
py_rc=${PIPESTATUS[0]}

# One closing line for both suites. Rust tests that skipped ran as passed: take them out.
read -r rust_passed rust_failed <<< "$(awk '/^test result:/ {p += $4; f += $6} END {print p + 0, f + 0}' "$logs/cargo-test.log")"
rust_skipped=$(wc -l < "$THORARENA_SKIP_LOG")
py_last=$(grep -E '^=*[ ]*[0-9]+ (passed|failed|skipped|error)' "$logs/pytest.log" | tail -n 1)
count() { grep -Eo "[0-9]+ $1" <<< "$py_last" | grep -Eo '[0-9]+' || echo 0; }
py_passed=$(count passed); py_failed=$(( $(count failed) + $(count error) )); py_skipped=$(count skipped)
passed=$((rust_passed - rust_skipped + py_passed))
failed=$((rust_failed + py_failed))
skipped=$((rust_skipped + py_skipped))
if ((rust_skipped)); then
    say "skipped rust tests (prerequisite missing):"
    sed 's/^/   /' "$THORARENA_SKIP_LOG"
fi
if [ "$rust_rc" != 0 ] && [ "$rust_failed" = 0 ]; then
    echo "cargo test exited $rust_rc without a failing test (a build error?): see $logs/cargo-test.log"
    failed=$((failed + 1))
fi
if [ "$py_rc" != 0 ] && [ "$py_failed" = 0 ]; then
    echo "pytest exited $py_rc without a failing test: see $logs/pytest.log"
    failed=$((failed + 1))
fi
# Every failed test by name, just above the closing line: "SUITE: TEST" (the Rust suite is
# the test binary's source, e.g. tests/sweep.rs).
awk '/^     Running / {suite = ($2 == "unittests") ? $3 : $2} /^   Doc-tests / {suite = "doc-tests " $2}
     /^test .* \.\.\. FAILED$/ {name = $0; sub(/^test /, "", name); sub(/ \.\.\. FAILED$/, "", name); print suite ": " name}' \
    "$logs/cargo-test.log" > "$logs/failed.txt"
grep -E '^(FAILED|ERROR) ' "$logs/pytest.log" | sed -E 's/^(FAILED|ERROR) //; s/ - .*$//' >> "$logs/failed.txt"
if [ -s "$logs/failed.txt" ]; then
    say "failed tests:"
    sed 's/^/   /' "$logs/failed.txt"
fi
echo "tests: $passed passed, $failed failed, $skipped skipped" | tee "$logs/closing.txt"
[ "$failed" = 0 ]
