#!/usr/bin/env bash
# Every test: Rust (the core, the arm, the API over the whole stack), the C programs against
# libtrol, the trol binary across processes, the live view in a real browser, and TROL for
# Python. Does its own set-up on a fresh machine with the Rust toolchain, a C compiler,
# Python 3.10 or later and Node.js: cargo fetches the crates, pip the Python packages (into
# target/py, a virtual environment), npm Playwright (into tests/browser/node_modules), and
# apt Debian's Chromium and libmodbus-dev if they are missing and this runs as root.
set -euo pipefail
# The utilities wrap their messages to $COLUMNS where it is set; the tests read them whole.
unset COLUMNS
cd "$(dirname "$0")/.."

# Every stage runs, even after one failed; the failures are listed at the end (and the
# script exits 1), so one flaky stage never hides the others. They are kept in a file, so
# that the stages of a lane (a subshell, below) count too.
FAILED=$(mktemp)
trap 'rm -f "$FAILED"' EXIT
# A stage that runs longer than 30 s says so every 30 s (a test program or a build may
# print nothing for minutes), so the script is never silent for long. In a lane the lanes'
# own ticker says it (TICKER=0).
stage() {
  local name=$1
  shift
  local started=$SECONDS ticker=
  echo "== scripts/test.sh: $name"
  if [ "${TICKER:-1}" != 0 ]; then
    (
      t=0
      while sleep 30 </dev/null >/dev/null 2>&1; do
        t=$((t + 30))
        echo "== scripts/test.sh: $name: still running (${t} s)"
      done
    ) &
    ticker=$!
  fi
  if "$@"; then
    echo "== scripts/test.sh: $name: passed ($((SECONDS - started)) s)"
  else
    echo "== scripts/test.sh: $name: FAILED ($((SECONDS - started)) s)"
    echo "$name" >> "$FAILED"
  fi
  if [ -n "$ticker" ]; then
    kill "$ticker" 2>/dev/null || true
    wait "$ticker" 2>/dev/null || true
  fi
}

# Two lanes of stages side by side (each a function), where both mostly wait: each lane's
# output goes to a file of its own and is printed whole when the lane ends, so the two never
# interleave; meanwhile every 30 s a line says which stage each lane is at.
lanes() {
  local dir started=$SECONDS ticker pid_a pid_b
  dir=$(mktemp -d)
  (
    TICKER=0 "$1"
    echo $((SECONDS - started)) > "$dir/a.end"
  ) > "$dir/a" 2>&1 &
  pid_a=$!
  (
    TICKER=0 "$2"
    echo $((SECONDS - started)) > "$dir/b.end"
  ) > "$dir/b" 2>&1 &
  pid_b=$!
  (
    t=0
    while sleep 30 </dev/null >/dev/null 2>&1; do
      t=$((t + 30))
      echo "== scripts/test.sh: two lanes still running (${t} s):" \
        "[$(grep '^== ' "$dir/a" | tail -n 1 | cut -c 21-)]" \
        "[$(grep '^== ' "$dir/b" | tail -n 1 | cut -c 21-)]"
    done
  ) &
  ticker=$!
  wait "$pid_b" || true
  echo "== scripts/test.sh: lane \"$2\" ended after $(cat "$dir/b.end" 2>/dev/null || echo ?) s; its output:"
  cat "$dir/b"
  wait "$pid_a" || true
  echo "== scripts/test.sh: lane \"$1\" ended after $(cat "$dir/a.end" 2>/dev/null || echo ?) s; its output:"
  cat "$dir/a"
  kill "$ticker" 2>/dev/null || true
  wait "$ticker" 2>/dev/null || true
  rm -rf "$dir"
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

# The controllers' own tests run in one process each (the backends against their twins, the
# conformance suite, the API over the embedded line): they wait on simulated arms far more than
# they compute (the conformance suite: 28 s of CPU in 273 s), so they run six at a time, with
# every package's unit tests (a few seconds in all). Everything else starts processes of its
# own (trol sim, gateways, C programs, a browser) and keeps the default of one test per core:
# eight at once starved the links of those processes on this 2-core machine.
#
# Both halves are `cargo test --workspace` with the test programs named (`--test NAME`), so
# that cargo resolves every crate's features as the build above did and builds nothing:
# `cargo test -p trol-rapl ...` resolves them for those packages alone (serde, rustix, memchr
# and more with other features), and rebuilt TROL's crates for 78 s while the other lane ran.
IN_PROCESS=(trol-conformance trol-rapl trol-mars trol-c500c trol)
# The integration tests of the packages in IN_PROCESS (`in`) or of every other package
# (`rest`), one `--test NAME` per line. cargo selects a test by its name in every package, so
# a name both halves have stops the script with what to rename.
test_programs() {
  cargo metadata --format-version 1 --no-deps | python3 -c '
import json, sys
half, ours = sys.argv[1], set(sys.argv[2:])
names = {True: set(), False: set()}
for p in json.load(sys.stdin)["packages"]:
    for t in p["targets"]:
        if "test" in t["kind"]:
            names[p["name"] in ours].add(t["name"])
both = names[True] & names[False]
if both:
    sys.exit("scripts/test.sh: the test programs %s are in a package of IN_PROCESS and in"
             " another: rename one (cargo selects a test by its name in every package)"
             % ", ".join(sorted(both)))
for name in sorted(names[half == "in"]):
    print("--test\n" + name)
' "$1" "${IN_PROCESS[@]}"
}
in_process() {
  local programs
  programs=$(test_programs in) || return 1
  # shellcheck disable=SC2086 # one word per line
  cargo test --workspace --no-fail-fast --lib --bins $programs -- \
    --test-threads "${TROL_TEST_THREADS:-6}"
}
the_rest() {
  local programs rc=0
  programs=$(test_programs rest) || return 1
  # shellcheck disable=SC2086 # one word per line
  cargo test --workspace --no-fail-fast $programs || rc=$?
  # The doctests of every package (each a few lines; they ran with their package before).
  cargo test --workspace --doc || rc=$?
  return $rc
}

# While the in-process tests wait on their simulated arms, the CPU they leave idle builds
# ahead, at the lowest priority, what later stages build in release, each as its stage builds
# it (so the stage finds it built): the `trol` the README's walk-through installs, libtrol,
# the pick example, the Python wheel. Release builds take cargo's lock on target/release,
# not the tests' target/debug. The builds ahead are stopped when the tests end (their whole
# process group: cargo and its compilers): what they finished stays built, their stages
# build the rest. So a busy machine, where the lowest priority gets next to no CPU, loses
# nothing by them. Their output: target/builds-ahead.log.
build_ahead() {
  cargo build --release --locked -p trol-cli &&
    cargo build --release --locked -p trol-c &&
    cargo build --release -p trol --example pick &&
    CARGO_TARGET_DIR="$PWD/target" bash scripts/wheel.sh
}
in_process_with_builds_ahead() {
  local ahead rc=0
  # setsid (util-linux) gives the builds a process group to stop; without it, none go ahead.
  if ! command -v setsid >/dev/null 2>&1; then
    in_process
    return
  fi
  mkdir -p target
  export -f build_ahead
  setsid nice -n 19 bash -c build_ahead > target/builds-ahead.log 2>&1 < /dev/null &
  ahead=$!
  in_process || rc=$?
  if kill -0 "$ahead" 2>/dev/null; then
    kill -TERM -- "-$ahead" 2>/dev/null || true
    echo "   the builds ahead were stopped with the tests; their stages build what is left"
  fi
  wait "$ahead" 2>/dev/null || true
  grep -E "Finished|scripts/wheel.sh: /" target/builds-ahead.log | sed 's/^ */   built ahead: /' || true
  return $rc
}
# The client with its live view (a feature the utilities and libtrol leave out): the tests
# the feature changes (the whole suite ran above without it).
client_view() {
  cargo test -p trol --features view --test api "$@" -- \
    robots_from_a_config_file the_watchdog_halts_the_arm_when_the_application_falls_silent
}
# The client without its backends, and with each alone: each builds and its own tests pass.
client_features() {
  cargo test -p trol --no-default-features --lib "$@" &&
    for feature in sim rapl mars c500c; do
      cargo test -p trol --no-default-features --features "$feature" --lib "$@" || return 1
    done
}

# TROL for Python (crates/trol-py, outside the cargo workspace): scripts/wheel.sh builds it
# as a binary wheel (maturin, into target/wheels); the wheel goes into a fresh virtual
# environment with no Rust toolchain on PATH, where the package's tests (against the embedded
# simulator and `trol sim` over a pty), the examples and the stub check run.
PY="$PWD/target/py/bin/python"
# Runs a command with every folder that holds cargo or rustc taken off PATH (and rustup's
# and cargo's homes unset), so that nothing in it can build Rust.
no_rust() {
  local dir kept=() joined
  local IFS=:
  for dir in $PATH; do
    [ -n "$dir" ] && [ ! -x "$dir/cargo" ] && [ ! -x "$dir/rustc" ] && kept+=("$dir")
  done
  joined="${kept[*]}"
  env -u CARGO_HOME -u RUSTUP_HOME -u CARGO_TARGET_DIR PATH="$joined" "$@"
}
python_setup() {
  CARGO_TARGET_DIR="$PWD/target" bash scripts/wheel.sh &&
    rm -rf target/py &&
    python3 -m venv target/py &&
    no_rust bash -c '! command -v cargo && ! command -v rustc' >/dev/null &&
    no_rust "$PY" -m pip install --quiet --disable-pip-version-check \
      target/wheels/trol_robot-*.whl pytest pytest-timeout pytest-xdist numpy mypy matplotlib &&
    # The module is the wheel's, not the source tree's.
    no_rust "$PY" -c 'import trol, sys; assert "/target/py/" in trol.__file__, trol.__file__; print("   trol for Python from", trol.__file__)'
}
# Two at a time (pytest-xdist) where the lanes run side by side on an idle machine: they
# wait on `trol sim` processes far more than they compute (130 s one at a time, 72 s two).
python_tests() {
  local workers=()
  [ "${SIDE_BY_SIDE:-0}" = 1 ] && workers=(-n 2)
  (cd crates/trol-py && TROL_BIN="$PWD/../../target/debug/trol" no_rust "$PY" -m pytest -q "${workers[@]}")
}
python_examples() {
  local root=$PWD plots
  plots=$(mktemp -d)
  local rc=0
  (cd examples && no_rust "$PY" pick.py) &&
    (cd "$plots" && no_rust "$PY" "$root/examples/plot_motion.py" && test -s motion.png) || rc=$?
  rm -rf "$plots"
  return $rc
}

# CTU Prague's own MARS 8 client (ctu-crs, from the package registry; its camera import
# stubbed) drives `trol sim --mars` across the unit's variants (tests/ctu, docs/mars.md).
ctu() {
  # Their dependencies first: installed after them, pip would report the camera package it
  # lacks as an ERROR (harmless: the camera import is stubbed).
  "$PY" -m pip install --quiet pyyaml pyserial &&
    "$PY" -m pip install --quiet --no-deps ctu-crs==1.0.6 ctu-mars-control-unit==0.1.3 &&
    TROL_BIN="$PWD/target/debug/trol" "$PY" -m pytest -q tests/ctu
}

# `trol urdf` in another simulator: MuJoCo (from the package registry) loads it, and its
# kinematics are TROL's (tests/urdf).
mujoco_urdf() {
  "$PY" -m pip install --quiet mujoco pybullet &&
    TROL_BIN="$PWD/target/debug/trol" "$PY" -m pytest -q tests/urdf
}

# `trol ros2` against a real DDS peer: Eclipse Cyclone DDS, the DDS under ROS 2's
# rmw_cyclonedds, from the package registry, on loopback only (tests/ros2, docs/ros2.md).
# Two at a time where the lanes run side by side (each test on a DDS domain of its own, apart
# from the other worker's: 94 s one at a time, about 50 s two).
ros2_dds() {
  local workers=()
  [ "${SIDE_BY_SIDE:-0}" = 1 ] && workers=(-n 2)
  "$PY" -m pip install --quiet cyclonedds==11.0.1 &&
    TROL_ROS2_BIN="$PWD/target/debug/trol-ros2" "$PY" -m pytest -q "${workers[@]}" tests/ros2 \
      --ignore=tests/ros2/rclpy
}

# `trol ros2` against ROS 2's own rclpy on ROS 2's default middleware, Fast DDS (ROS 2
# Jazzy's packages from PyPI, in a virtual environment of their own, about 250 MB; control_msgs's
# actions generated there by rosidl once), on loopback only (tests/ros2/rclpy, docs/ros2.md).
ROS2_PY="$PWD/target/ros2py/bin/python"
ros2_rclpy() {
  local workers=()
  [ "${SIDE_BY_SIDE:-0}" = 1 ] && workers=(-n 2)
  { [ -x "$ROS2_PY" ] || python3 -m venv target/ros2py; } &&
    "$ROS2_PY" -m pip install --quiet --disable-pip-version-check -r tests/ros2/rclpy/requirements.txt &&
    bash tests/ros2/rclpy/control_msgs.sh target/ros2py &&
    env -u RMW_IMPLEMENTATION TROL_ROS2_BIN="$PWD/target/debug/trol-ros2" TROL_BIN="$PWD/target/debug/trol" \
      "$ROS2_PY" -m pytest -q -p no:cacheprovider "${workers[@]}" tests/ros2/rclpy
}

# What the two lanes run is built first, while nothing else runs: the workspace's test
# programs, then every program, library and example of the workspace (`trol`, `trol ros2`,
# libtrol, the examples the C tests link). The second command resolves features as the first
# did (dev-dependencies are in play for the whole workspace where examples are built), so it
# adds only what the test build leaves out: `trol-ros2` and libtrol.so and .a, a few seconds.
# (`cargo build -p trol-ros2` alone resolved rustix, serde, clap and regex otherwise and
# rebuilt them: 32 s.) The client with its view and with each feature alone is built by its
# stage: it puts nothing in place that a test starts. After this, the tests build nothing that
# a test starts (`TROL_TEST_BUILT=1`: crates/trol-cli/tests/cli builds no program; the C
# tests' `cargo build --workspace --lib --examples` finds libtrol up to date).
build_tests() {
  cargo test --workspace --no-run && cargo build --workspace --bins --lib --examples
}
stage "build the test programs (cargo test --workspace --no-run, cargo build --workspace ...)" build_tests
export TROL_TEST_BUILT=1

# The two lanes. The first: the tests that start processes, one test per core, then the
# client with its view and with each feature alone. The second: the in-process controllers six
# at a time, then Python and ROS 2 (both two tests at a time where the lanes run side by
# side), CTU's client and MuJoCo. Each takes about 10 minutes of an idle run, so on an idle
# machine they run side by side (an idle .ci/run: 825 s, against 1,571 s one after the other
# before the lanes and the changes since). On a busy one they run one after
# the other, as every loaded run before them did: side by side under two busy loops, the
# processes of the first lane were starved for seconds at a time (a gateway that took over
# 20 s to start, a 1998 host's link that timed out waiting for ENQ), because the second
# lane's tests and its builds ahead then take the CPU share those processes had
# (docs/performance.md, "Two lanes on an idle machine"). `TROL_TEST_LANES=1` runs them side
# by side, `=0` in turn, whatever the machine does.
#
# How busy the machine is: the share of its CPU time, in percent, that went to anything but
# idling over 3 s (from /proc/stat; this script runs nothing meanwhile). 100 where it cannot
# tell.
busy_percent() {
  local cpu user nice system idle iowait irq softirq steal rest t0 b0 t1 b1
  [ -r /proc/stat ] || { echo 100; return; }
  read -r cpu user nice system idle iowait irq softirq steal rest < /proc/stat
  b0=$((user + nice + system + irq + softirq + steal))
  t0=$((b0 + idle + iowait))
  sleep 3
  read -r cpu user nice system idle iowait irq softirq steal rest < /proc/stat
  b1=$((user + nice + system + irq + softirq + steal))
  t1=$((b1 + idle + iowait))
  if [ $((t1 - t0)) -le 0 ]; then echo 100; else echo $((100 * (b1 - b0) / (t1 - t0))); fi
}
side_by_side_if_idle() {
  local busy
  case "${TROL_TEST_LANES:-auto}" in
    1) SIDE_BY_SIDE=1 lanes "$@" ;;
    0)
      "$1" || true
      "$2" || true
      ;;
    *)
      busy=$(busy_percent)
      if [ "$busy" -lt 25 ]; then
        echo "== scripts/test.sh: the machine is idle (${busy} % busy over 3 s): two lanes side by side"
        SIDE_BY_SIDE=1 lanes "$@"
      else
        echo "== scripts/test.sh: the machine is busy (${busy} % busy over 3 s): the lanes one after the other"
        "$1" || true
        "$2" || true
      fi
      ;;
  esac
}
processes() {
  stage "cargo test --workspace: the tests that start processes (one test per core)" the_rest
  stage "cargo test -p trol --features view" client_view
  stage "the client's features one by one" client_features
  stage "trol ros2 against ROS 2's rclpy on Fast DDS" ros2_rclpy
}
in_process_then_python() {
  stage "cargo test --workspace: the in-process controllers (six tests at a time)" \
    in_process_with_builds_ahead
  stage "Python: the wheel, in a virtual environment without Rust" python_setup
  stage "Python: pytest" python_tests
  stage "Python: the examples (pick.py, plot_motion.py)" python_examples
  stage "Python: stubs (mypy.stubtest)" bash -c "cd /tmp && '$PY' -m mypy.stubtest trol"
  stage "CTU's ctu-crs against trol sim --mars" ctu
  stage "the URDF in MuJoCo and pybullet" mujoco_urdf
  stage "trol ros2 against Cyclone DDS" ros2_dds
}
side_by_side_if_idle processes in_process_then_python

# The README's walk-through, every block as written (install, demo, interp, the simulator as
# a process, a C program through pkg-config, Rust, Python, completions and man pages).
stage "the README's walk-through" bash scripts/readme.sh
# A page of docs/ whose first hour starts a simulated controller: its block, as written, in
# an empty folder (docs/c500.md's is run by crates/trol-cli/tests/c500_first_hour.rs).
stage "docs/mars.md's first hour" bash scripts/readme.sh docs/mars.md
stage "docs/c500c.md's first hour" bash scripts/readme.sh docs/c500c.md

if [ -s "$FAILED" ]; then
  echo "scripts/test.sh: $(wc -l < "$FAILED") stage(s) failed:"
  sed 's/^/  - /' "$FAILED"
  exit 1
fi
echo "scripts/test.sh: every stage passed"
