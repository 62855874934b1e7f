#!/usr/bin/env bash
# Run every shell block of README.md's walk-through (between <!-- walk-through --> and
# <!-- /walk-through -->), as written, one after the other, from the repository's root, so
# the README cannot drift. `scripts/readme.sh docs/PAGE.md` does the same for a page of
# docs/, in an empty folder (a page's blocks make their own files there; nothing lands in
# the repository), with this build's `trol` (target/debug) first on PATH. HOME is a fresh folder (what the blocks install under ~ lands
# there), `cargo install` goes to a folder of its own (CARGO_INSTALL_ROOT) that is put on
# PATH, and cargo shares this repository's target folder. Python: `pip` and `python` are
# target/py's (made by scripts/test.sh), or the first on PATH.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
page=${1:-README.md}
[ -f "$page" ] || { echo "scripts/readme.sh: no page $page" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The blocks, NUL-separated.
awk '
  /<!-- walk-through -->/ { on = 1; next }
  /<!-- \/walk-through -->/ { on = 0 }
  on && /^```sh$/ { inblock = 1; next }
  on && inblock && /^```$/ { inblock = 0; printf "%c", 0; next }
  on && inblock { print }
' "$page" > "$work/blocks"

# The toolchain and the crates stay where they are; only HOME moves.
export RUSTUP_HOME="${RUSTUP_HOME:-$HOME/.rustup}" CARGO_HOME="${CARGO_HOME:-$HOME/.cargo}"
export HOME="$work/home" CARGO_INSTALL_ROOT="$work/cargo"
export CARGO_TARGET_DIR="$root/target"
export PATH="$CARGO_INSTALL_ROOT/bin:$PATH"
[ -x "$root/target/py/bin/python" ] && export PATH="$root/target/py/bin:$PATH"
unset TROL_CONFIG
mkdir -p "$HOME"
if [ "$page" != README.md ]; then
  export PATH="$root/target/debug:$PATH"
  mkdir -p "$work/folder"
  cd "$work/folder"
fi

# A block that serves the live view (`--view`, at its default address): the reader opens
# the page, as the block says to. Here that is what a page does as it loads: it opens the
# view's event stream (GET /events) and reads it until the program ends. So `trol demo
# --view` starts at once instead of waiting for a page, and the block passes only if the
# view sent the page the arm's state.
view_reader() {
  local tries=0
  until {
    printf 'GET /events HTTP/1.1\r\nHost: 127.0.0.1:8465\r\n\r\n' >&3 && cat <&3
  } 3<>/dev/tcp/127.0.0.1/8465 2>/dev/null; do
    tries=$((tries + 1))
    [ "$tries" -lt 1200 ] || return 1
    sleep 0.05
  done
}

n=0
while IFS= read -r -d '' block; do
  n=$((n + 1))
  echo "--- $page walk-through, block $n:"
  printf '%s\n' "$block" | sed 's/^/    /'
  reader=
  if [[ $block == *--view* ]]; then
    : > "$work/events"
    view_reader > "$work/events" 2>/dev/null &
    reader=$!
  fi
  if ! bash -euo pipefail -c "$block" > "$work/out" 2>&1; then
    cat "$work/out"
    [ -z "$reader" ] || kill "$reader" 2>/dev/null || true
    echo "$page walk-through: block $n failed" >&2
    exit 1
  fi
  if [ -n "$reader" ]; then
    kill "$reader" 2>/dev/null || true
    wait "$reader" 2>/dev/null || true
    if ! grep -q '^data: ' "$work/events"; then
      cat "$work/out"
      echo "$page walk-through: block $n served no view to the page that opened it" >&2
      exit 1
    fi
    echo "  > (the page that opened the view got $(grep -c '^data: ' "$work/events") updates)"
  fi
  tail -n 3 "$work/out" | sed 's/^/  > /'
done < "$work/blocks"
[ "$n" -gt 0 ] || { echo "$page walk-through: no blocks found" >&2; exit 1; }
echo "$page walk-through: $n passed, 0 failed"
