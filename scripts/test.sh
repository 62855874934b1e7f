#!/usr/bin/env bash
# Every test: Rust (the core, the arm, the API over the whole stack), the C programs against
# libtrol, the trol binary across processes, the live view in a real browser, and TROL for
# Python. Does its own set-up on a fresh machine with the Rust toolchain, a C compiler,
# Python 3.10 or later and Node.js: cargo fetches the crates, pip the Python packages (into
# target/py, a virtual environment), npm Playwright (into tests/browser/node_modules), and
# apt Debian's Chromium and libmodbus-dev if they are missing and this runs as root.
set -euo pipefail
cd "$(dirname "$0")/.."

# Every stage runs, even after one failed; the failures are listed at the end (and the
# script exits 1), so one flaky stage never hides the others.
FAILED=()
stage() {
  local name=$1
  shift
  local started=$SECONDS
  echo "== scripts/test.sh: $name"
  if "$@"; then
    echo "== scripts/test.sh: $name: passed ($((SECONDS - started)) s)"
  else
    echo "== scripts/test.sh: $name: FAILED ($((SECONDS - started)) s)"
    FAILED+=("$name")
  fi
}

# The live view's browser test (crates/trol-cli/tests/view.rs): headless Chromium driven by
# Playwright.
browser_setup() {
  if [ ! -x /usr/bin/chromium ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
      apt-get update && apt-get install -y --no-install-recommends chromium
    else
      echo "scripts/test.sh: the view's test needs Chromium at /usr/bin/chromium:" \
        "sudo apt-get install chromium" >&2
      return 1
    fi
  fi
  (cd tests/browser && npm ci --no-audit --no-fund --loglevel=error)
}
stage "browser set-up (Chromium, Playwright)" browser_setup

# libmodbus, the anchor of `trol bench pty` (its test runs the anchor where the headers are).
modbus_setup() {
  if [ ! -f /usr/include/modbus/modbus.h ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
      apt-get update && apt-get install -y --no-install-recommends libmodbus-dev
    else
      echo "scripts/test.sh: note: without libmodbus-dev the pty bench's test checks only" \
        "that it says how to get it (sudo apt-get install libmodbus-dev)" >&2
    fi
  fi
}
stage "libmodbus set-up (the pty bench's anchor)" modbus_setup

stage "cargo test --workspace" cargo test --workspace --no-fail-fast
# The client with its live view (a feature the utilities and libtrol leave out).
stage "cargo test -p trol --features view" cargo test -p trol --features view --test api

# TROL for Python (crates/trol-py, outside the cargo workspace): build and install the
# package, run its tests against the embedded simulator and `trol sim` over a pty, and check
# its type stubs against the module.
PY="$PWD/target/py/bin/python"
python_setup() {
  python3 -m venv target/py &&
    "$PY" -m pip install --quiet --upgrade pip &&
    "$PY" -m pip install --quiet maturin pytest pytest-timeout numpy mypy &&
    echo "   building TROL for Python (the Rust extension: a minute or two)" &&
    "$PY" -m pip install --quiet ./crates/trol-py
}
stage "Python: virtual environment and TROL for Python" python_setup
stage "Python: pytest" bash -c "cd crates/trol-py && TROL_BIN='$PWD/target/debug/trol' '$PY' -m pytest -q"
stage "Python: stubs (mypy.stubtest)" bash -c "cd /tmp && '$PY' -m mypy.stubtest trol"

# CTU Prague's own MARS 8 client (ctu-crs, from the package registry; its camera import
# stubbed) drives `trol sim --mars` across the unit's variants (tests/ctu, docs/mars.md).
ctu() {
  "$PY" -m pip install --quiet --no-deps ctu-crs==1.0.6 ctu-mars-control-unit==0.1.3 &&
    "$PY" -m pip install --quiet pyyaml pyserial &&
    TROL_BIN="$PWD/target/debug/trol" "$PY" -m pytest -q tests/ctu
}
stage "CTU's ctu-crs against trol sim --mars" ctu

# `trol urdf` in another simulator: MuJoCo (from the package registry) loads it, and its
# kinematics are TROL's (tests/urdf).
mujoco_urdf() {
  "$PY" -m pip install --quiet mujoco pybullet &&
    TROL_BIN="$PWD/target/debug/trol" "$PY" -m pytest -q tests/urdf
}
stage "the URDF in MuJoCo and pybullet" mujoco_urdf

# The README's walk-through, every block as written (install, demo, interp, the simulator as
# a process, a C program through pkg-config, Rust, Python, completions and man pages).
stage "the README's walk-through" bash scripts/readme.sh

if [ ${#FAILED[@]} -gt 0 ]; then
  echo "scripts/test.sh: ${#FAILED[@]} stage(s) failed:"
  printf '  - %s\n' "${FAILED[@]}"
  exit 1
fi
echo "scripts/test.sh: every stage passed"
