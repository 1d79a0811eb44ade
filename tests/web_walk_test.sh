#!/usr/bin/env bash
# Issue 21: the browser client in a real browser. `cellwalk serve --web` serves a generated city;
# headless Chromium (Debian's, driven by playwright-core from web/node_modules) loads the page,
# walks a recorded path and hands back every 15th frame; `cellwalk compare --captured` renders
# the same frames natively and measures the difference. A second walk under a budget too small
# for the city must stay within it, refusing what does not fit. Exit 77 (ctest's skip) with a
# reason where Node, Chromium or the npm packages are missing.
#   web_walk_test.sh SOURCE_DIR CELLWALK_BINARY
set -euo pipefail
src=$1
cw=$2
command -v node >/dev/null || { echo "SKIP: node is not installed (scripts/setup installs it)"; exit 77; }
node_major=$(node -p 'process.versions.node.split(".")[0]')
need=$(node -p "require('$src/web/package.json').engines.node.replace(/[^0-9]/g, '')")
[ "$node_major" -ge "$need" ] || { echo "SKIP: Node.js $node_major is older than the $need the browser client's tools need"; exit 77; }
[ -x "${CHROMIUM:-/usr/bin/chromium}" ] || { echo "SKIP: Chromium is not installed (scripts/setup installs Debian's chromium)"; exit 77; }
[ -d "$src/web/node_modules/playwright-core" ] || { echo "SKIP: web/node_modules is missing (scripts/setup runs npm ci in web/)"; exit 77; }

dir=$(mktemp -d)
server=""
cleanup() {
  if [ -n "$server" ]; then kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; fi
  rm -rf "$dir"
}
trap cleanup EXIT

"$cw" generate city --objects 150 --seed 5 -o "$dir/city.cwscene" >/dev/null
"$cw" build "$dir/city.cwscene" -o "$dir/city.cww" >/dev/null
"$cw" pvs "$dir/city.cww" --engine conservative --cells grid:30 >/dev/null
"$cw" path "$dir/city.cww" --kind normal --frames 150 -o "$dir/normal.path" >/dev/null

"$cw" serve "$dir/city.cww" --web --web-root "$src/web" --seconds 600 --quiet >"$dir/serve.log" 2>&1 &
server=$!
for _ in $(seq 100); do grep -q "browser client at" "$dir/serve.log" && break; sleep 0.1; done
url=$(grep -o "http://127.0.0.1:[0-9]*/" "$dir/serve.log") || { cat "$dir/serve.log"; echo "FAIL: the server did not say where it serves"; exit 1; }

rc=0
node "$src/web/test/walk.mjs" --url "$url" --path "$dir/normal.path" --out "$dir/full" --every 15 || rc=$?
[ "$rc" = 77 ] && exit 77
[ "$rc" = 0 ] || { echo "FAIL: the walk failed"; exit 1; }
"$cw" compare "$dir/city.cww" --path "$dir/normal.path" --captured "$dir/full" -o "$dir/compare" --images 0 >/dev/null
node "$src/web/test/budget_walk_check.mjs" full "$dir/full/captured.json" "$dir/compare/captured-fidelity.json"

node "$src/web/test/walk.mjs" --url "$url" --path "$dir/normal.path" --out "$dir/tight" --every 0 --budget 3
node "$src/web/test/budget_walk_check.mjs" tight "$dir/tight/captured.json"
echo "web walk: passed"
