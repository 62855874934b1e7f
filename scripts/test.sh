#!/usr/bin/env bash
# Every test: Rust (the core, the arm, the API over the whole stack), the C programs against
# libtrol, the trol binary across processes, and TROL for Python. Does its own set-up on a
# fresh machine with the Rust toolchain, a C compiler and Python 3.10 or later: cargo fetches
# the crates, pip the Python packages (into target/py, a virtual environment).
set -euo pipefail
cd "$(dirname "$0")/.."

cargo test --workspace

# TROL for Python (crates/trol-py, outside the cargo workspace): build and install the
# package, run its tests against the embedded simulator and `trol sim` over a pty, and check
# its type stubs against the module.
python3 -m venv target/py
PY="$PWD/target/py/bin/python"
"$PY" -m pip install --quiet --upgrade pip
"$PY" -m pip install --quiet maturin pytest pytest-timeout numpy mypy
"$PY" -m pip install --quiet ./crates/trol-py
(cd crates/trol-py && TROL_BIN="$PWD/../../target/debug/trol" "$PY" -m pytest -q)
(cd /tmp && "$PY" -m mypy.stubtest trol)

# The README's walk-through, every block as written (install, demo, interp, the simulator as
# a process, a C program through pkg-config, Rust, Python, completions and man pages).
bash scripts/readme.sh
