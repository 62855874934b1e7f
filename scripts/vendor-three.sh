#!/usr/bin/env bash
# Take three.js from the npm registry, by name and pinned version, into the live view's
# vendor folder (crates/trol-view/vendor/three), with its licence; print the files' SHA-256 sums for
# THIRD_PARTY.md. Run again to check that the embedded files are the registry's:
#   bash scripts/vendor-three.sh && git diff --exit-code crates/trol-view/vendor
set -euo pipefail
cd "$(dirname "$0")/.."
VERSION=0.187.0
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$work" && npm pack --silent "three@$VERSION" >/dev/null && tar xzf "three-$VERSION.tgz")
assets=crates/trol-view/vendor/three
cp "$work/package/build/three.module.js" "$work/package/build/three.core.js" "$assets/"
cp "$work/package/examples/jsm/controls/OrbitControls.js" "$assets/"
cp "$work/package/LICENSE" "$assets/LICENSE-three.js.txt"
(cd "$assets" && sha256sum three.module.js three.core.js OrbitControls.js LICENSE-three.js.txt)
