#!/usr/bin/env bash
# Puts MuJoCo 3.17.0 — the version the `mujoco` feature's bindings (mujoco-rs 7.0.0) are
# made for — where cargo can link it, and prints the variable to export:
#
#   eval "$(tools/mujoco-lib.sh)" && cargo build --release --features mujoco
#
# The library comes from the PyPI wheel `mujoco==3.17.0` (it depends only on libc), installed
# with pip into target/mujoco-3.17.0/ (not into any environment: its Python package is not
# used). target/mujoco-3.17.0/lib/ then holds `libmujoco.so` and its soname
# `libmujoco.so.3.17.0`; builds link against it and carry it as their rpath (build.rs).
# Python ≥ 3.10 with pip is the only prerequisite.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
version=3.17.0
wheel_dir="$root/target/mujoco-$version/wheel"
lib_dir="$root/target/mujoco-$version/lib"
so="$wheel_dir/mujoco/libmujoco.so.$version"
if [ ! -f "$so" ]; then
    python="${PYTHON:-python3}"
    if [ -x "$root/.venv/bin/python" ]; then python="$root/.venv/bin/python"; fi
    echo "mujoco-lib.sh: installing the wheel mujoco==$version into $wheel_dir" >&2
    "$python" -m pip install --quiet --no-deps --target "$wheel_dir" "mujoco==$version" >&2 || {
        echo "mujoco-lib.sh: could not install mujoco==$version with pip ($python); the MuJoCo backend needs exactly this version" >&2
        exit 1
    }
fi
if [ ! -f "$so" ]; then
    echo "mujoco-lib.sh: the wheel has no $so" >&2
    exit 1
fi
mkdir -p "$lib_dir"
ln -sf "$so" "$lib_dir/libmujoco.so"
ln -sf "$so" "$lib_dir/libmujoco.so.$version"
echo "export MUJOCO_DYNAMIC_LINK_DIR=$lib_dir"
