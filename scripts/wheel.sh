#!/usr/bin/env bash
# Build TROL for Python as a binary wheel into target/wheels/ (issue 44, item 1).
#
#   bash scripts/wheel.sh            # target/wheels/trol_robot-0.1.0-cp310-abi3-manylinux_2_NN_x86_64.whl
#   pip install target/wheels/trol_robot-*.whl
#
# One wheel serves CPython 3.10 and later (PyO3's abi3). It carries the whole library: the
# native module links TROL's Rust crates in (the client, the embedded simulator, the live
# view), so it needs no libtrol.so, no Rust toolchain and no compiler where it is installed.
# maturin (from the package registry, pinned below, into target/maturin) builds it with the
# crate's Cargo.lock as it is (--locked), stripped, and tags it with the lowest manylinux
# glibc it runs on (maturin checks the symbols the module uses).
#
# Honours CARGO_TARGET_DIR (else crates/trol-py/target) and PYTHON (the interpreter that
# makes maturin's environment; else python3).
set -euo pipefail
cd "$(dirname "$0")/.."
MATURIN_VERSION=1.16.0
out=${WHEEL_DIR:-$PWD/target/wheels}
venv=$PWD/target/maturin
# The install counts once it has finished (target/maturin/.installed): one stopped halfway
# (scripts/test.sh stops its builds ahead when their time is up) is made again.
if [ ! -f "$venv/.installed" ] || [ ! -x "$venv/bin/maturin" ] ||
  ! "$venv/bin/maturin" --version | grep -q " $MATURIN_VERSION\$"; then
  echo "scripts/wheel.sh: installing maturin $MATURIN_VERSION into target/maturin"
  rm -rf "$venv"
  "${PYTHON:-python3}" -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "maturin==$MATURIN_VERSION"
  touch "$venv/.installed"
fi
mkdir -p "$out"
rm -f "$out"/trol_robot-*.whl
echo "scripts/wheel.sh: building the wheel (release build of the Rust extension; a few minutes the first time)"
started=$SECONDS
# maturin prints cargo's progress (one line per crate compiled), so a long first build
# is never silent.
"$venv/bin/maturin" build --release --locked --strip \
  --manifest-path crates/trol-py/Cargo.toml --out "$out" \
  --interpreter "$venv/bin/python"
wheel=$(ls "$out"/trol_robot-*.whl)
echo "scripts/wheel.sh: $wheel ($(du -k "$wheel" | cut -f1) KiB, $((SECONDS - started)) s)"
