#!/usr/bin/env bash
# The flake hunt (issue 68, item 0): every test program that starts processes or waits on a
# simulated controller, run N times in a row under two busy loops (the load a busy 2-core
# machine has), the failures counted, each failing run's output kept.
#
#   bash scripts/soak-tests.sh N                  # every such program, N runs each
#   bash scripts/soak-tests.sh N cli rapl bench   # only the programs with these names
#
# Prints one line per program (runs, failures, the first failing run's log) and a total;
# exits 1 if any run failed. Logs go to target/soak/. The programs are built once, first
# (cargo test --workspace --no-run); each runs as cargo runs it (from its crate's folder).
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:?usage: bash scripts/soak-tests.sh N [PROGRAM ...]}
shift
case $runs in '' | *[!0-9]*) echo "N must be a whole number, not '$runs'" >&2; exit 2 ;; esac
only=("$@")
out=target/soak
mkdir -p "$out"

# Pure computation (no process, no simulated controller, no clock): not what a flake hunt
# is for. Every other integration test program of the workspace is.
pure=" trol-a465/arm trol-a465/kinematics trol-a465/lines trol-a465/motion trol-a465/urdf
  trol-proto/fuzz_seeds trol-proto/link trol-proto/properties trol-proto/records
  trol-proto/transaction trol-proto/vectors trol-mars/plan trol-c/header trol-cli/help "

echo "soak: building the test programs" >&2
cargo test --workspace --no-run --message-format=json 2>"$out/build.log" |
  python3 -c '
import json, sys
for line in sys.stdin:
    try:
        m = json.loads(line)
    except ValueError:
        continue
    t = m.get("target", {})
    if m.get("reason") == "compiler-artifact" and m.get("executable") and t.get("kind") == ["test"]:
        pkg = m["package_id"].split("#")[0].rstrip("/").split("/")[-1]
        print(pkg.split("@")[0], t["name"], m["executable"], m["manifest_path"])
' >"$out/programs.txt"

busy=()
for _ in 1 2; do
  (while :; do :; done) &
  busy+=($!)
done
trap 'kill "${busy[@]}" 2>/dev/null || true' EXIT

total=0
failed=0
printf '%-34s %5s %8s  %s\n' program runs failures "first failing log" | tee "$out/summary.txt"
while read -r pkg name exe manifest; do
  case $pure in *" $pkg/$name "*) continue ;; esac
  if ((${#only[@]})); then
    hit=
    for o in "${only[@]}"; do [[ $name == "$o" || $pkg == "$o" ]] && hit=1; done
    [[ -n $hit ]] || continue
  fi
  fails=0
  first=
  for ((r = 1; r <= runs; r++)); do
    log="$out/$pkg.$name.$r.log"
    # A run that hangs is a failure too: 30 minutes is far beyond any program's loaded time.
    if (cd "$(dirname "$manifest")" && timeout 1800 "$exe") >"$log" 2>&1; then
      rm -f "$log"
    else
      fails=$((fails + 1))
      first=${first:-$log}
    fi
  done
  total=$((total + runs))
  failed=$((failed + fails))
  printf '%-34s %5d %8d  %s\n' "$pkg/$name" "$runs" "$fails" "${first:--}" | tee -a "$out/summary.txt"
done <"$out/programs.txt"
printf 'soak: %d runs, %d failed, under two busy loops on %s cores (load %s)\n' \
  "$total" "$failed" "$(nproc)" "$(cut -d' ' -f1-3 /proc/loadavg)" | tee -a "$out/summary.txt"
((failed == 0))
