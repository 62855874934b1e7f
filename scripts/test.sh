#!/usr/bin/env bash
# Every test: Rust (the core, the arm, the API over the whole stack), the C programs against
# libtrol, the trol binary across processes, the live view in a real browser, and TROL for
# Python. Does its own set-up on a fresh machine with the Rust toolchain, a C compiler,
# Python 3.10 or later and Node.js: cargo fetches the crates, pip the Python packages (into
# target/py, a virtual environment), npm Playwright (into tests/browser/node_modules), and
# apt Debian's Chromium if it is missing and this runs as root.
set -euo pipefail
cd "$(dirname "$0")/.."

# The live view's browser test (crates/trol-cli/tests/view.rs): headless Chromium driven by
# Playwright.
if [ ! -x /usr/bin/chromium ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update && apt-get install -y --no-install-recommends chromium
  else
    echo "scripts/test.sh: the view's test needs Chromium at /usr/bin/chromium:" \
      "sudo apt-get install chromium" >&2
    exit 1
  fi
fi
(cd tests/browser && npm ci --no-audit --no-fund --loglevel=error)

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

# CTU Prague's own MARS 8 client (ctu-crs, from the package registry; its camera import
# stubbed) drives `trol sim --mars` across the unit's variants (tests/ctu, docs/mars.md).
"$PY" -m pip install --quiet --no-deps ctu-crs==1.0.6 ctu-mars-control-unit==0.1.3
"$PY" -m pip install --quiet pyyaml pyserial
TROL_BIN="$PWD/target/debug/trol" "$PY" -m pytest -q tests/ctu

# The README's walk-through, every block as written (install, demo, interp, the simulator as
# a process, a C program through pkg-config, Rust, Python, completions and man pages).
bash scripts/readme.sh
