#!/usr/bin/env bash
# Install TROL's C API: libtrol.so, libtrol.a, trol.h and the pkg-config file trol.pc.
#
#   bash scripts/install-c.sh                 # into /usr/local
#   bash scripts/install-c.sh --prefix ~/.local
#
# Then: cc app.c $(pkg-config --cflags --libs trol)
# (with a prefix pkg-config does not search: PKG_CONFIG_PATH=PREFIX/lib/pkgconfig; and at
# run time LD_LIBRARY_PATH=PREFIX/lib, or link PREFIX/lib/libtrol.a statically).
#
# It builds the libraries with `cargo build --release -p trol-c` first; TROL_LIB_DIR names a
# folder that has them already (the tests use target/debug).
set -euo pipefail
cd "$(dirname "$0")/.."

prefix=/usr/local
while [ $# -gt 0 ]; do
  case "$1" in
    --prefix) prefix="${2:?--prefix needs a folder}"; shift 2 ;;
    --prefix=*) prefix="${1#--prefix=}"; shift ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    *) echo "install-c.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

libs="${TROL_LIB_DIR:-}"
if [ -z "$libs" ]; then
  cargo build --release --locked -p trol-c
  # Where cargo put them: CARGO_TARGET_DIR when it is set (relative to this folder).
  libs="${CARGO_TARGET_DIR:-target}/release"
fi
for f in libtrol.so libtrol.a; do
  [ -f "$libs/$f" ] || { echo "install-c.sh: $libs/$f is missing" >&2; exit 1; }
done

version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -1)
install -d "$prefix/lib/pkgconfig" "$prefix/include"
install -m 644 "$libs/libtrol.a" "$prefix/lib/libtrol.a"
install -m 755 "$libs/libtrol.so" "$prefix/lib/libtrol.so"
install -m 644 include/trol.h "$prefix/include/trol.h"
# The prefix is where trol.pc lies, so that the folder can be moved (a release's tarball).
cat > "$prefix/lib/pkgconfig/trol.pc" <<EOF
prefix=\${pcfiledir}/../..
libdir=\${prefix}/lib
includedir=\${prefix}/include

Name: trol
Description: TROL, the TU Vienna Robot Control Library: the C API (the manual's names)
Version: $version
Cflags: -I\${includedir}
Libs: -L\${libdir} -ltrol
Libs.private: -lpthread -ldl -lm
EOF
echo "installed libtrol $version into $prefix (lib, include, lib/pkgconfig/trol.pc)"
