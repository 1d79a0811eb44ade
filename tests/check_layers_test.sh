#!/usr/bin/env bash
# scripts/check-layers can fail: on a copy of the tree with one upward include planted (the
# store including the renderer) it must exit 1 and name the file; on the tree itself, 0.
#   tests/check_layers_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1 build=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cp -r "$src/src" "$src/include" "$src/experiments" "$tmp/"
bash "$src/scripts/check-layers" "$build" "$tmp" >/dev/null
sed -i '0,/^#include "cellwalk\//s||#include "cellwalk/render/renderer.hpp"\n#include "cellwalk/|' "$tmp/src/store/world.cpp"
if out=$(bash "$src/scripts/check-layers" "$build" "$tmp" 2>&1); then
  echo "check-layers passed a tree where src/store includes the renderer"; exit 1
fi
grep -q "src/store/world.cpp:.*cellwalk/render/renderer.hpp" <<<"$out" || { echo "unexpected report: $out"; exit 1; }
echo "planted include caught: $(grep renderer.hpp <<<"$out")"
