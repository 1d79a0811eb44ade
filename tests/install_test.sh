#!/usr/bin/env bash
# Issue 16, item 7: cellwalk used from another project. Installs the build into a clean
# prefix, builds examples/render_city against the installed package (find_package), runs it;
# checks the pkg-config file compiles and links the same program; makes the .deb with CPack,
# installs it with dpkg (into a root of its own) and runs `cellwalk --version`.
#   install_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1 build=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix

cmake --install "$build" --prefix "$prefix" >/dev/null
test -x "$prefix/bin/cellwalk"
test -f "$prefix/include/cellwalk/runtime/walk.hpp"
test -f "$prefix/lib/cmake/cellwalk/cellwalkConfig.cmake"

launcher=""
command -v ccache >/dev/null && launcher="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
cmake -S "$src/examples/render_city" -B "$work/example" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" $launcher >/dev/null
ninja -C "$work/example" >/dev/null
# The example must not have found the build tree's headers: only the prefix was given.
if grep -q -- "-I$src/include" "$work/example/build.ninja"; then echo "example compiled against the source tree"; exit 1; fi
mkdir "$work/out"
EGL_PLATFORM=surfaceless "$work/example/render_city" "$work/out" 60
test -s "$work/out/city.png"

# pkg-config: the same program, by hand.
PKG_CONFIG_PATH="$prefix/lib/pkgconfig" c++ -O0 "$src/examples/render_city/main.cpp" -o "$work/by_pkgconfig" \
  $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs cellwalk)
EGL_PLATFORM=surfaceless "$work/by_pkgconfig" "$work/out" 30 >/dev/null

# The Debian package: made by CPack, installed with dpkg, its CLI runs.
(cd "$work" && cpack --config "$build/CPackConfig.cmake" -B "$work/deb" >/dev/null)
deb=$(ls "$work"/deb/cellwalk_*.deb)
# (Outputs are captured first: grep -q stops reading early, and under pipefail the writer's
# SIGPIPE would fail the test.)
info=$(dpkg-deb --info "$deb")
grep -q "Depends:.*libembree" <<<"$info"
# Installed with dpkg itself, into a root of its own whose package database is a copy of this
# machine's (so every Depends is checked against what is really installed, and nothing of the
# machine changes; --force-not-root lets a non-root CI user do it too).
install_root() {  # install_root DIR: an empty root with this machine's package list
  mkdir -p "$1/var/lib/dpkg/info" "$1/var/lib/dpkg/updates" "$1/var/log"
  cp /var/lib/dpkg/status "$1/var/lib/dpkg/status"
}
root=$work/root
install_root "$root"
dpkg --root="$root" --force-not-root -i "$deb" >"$work/dpkg.log" 2>&1 || { tail -20 "$work/dpkg.log"; exit 1; }
version=$("$root/usr/bin/cellwalk" --version)
grep -q "^cellwalk 0\." <<<"$version"
dpkg --root="$root" --force-not-root -r cellwalk >>"$work/dpkg.log" 2>&1 || { tail -20 "$work/dpkg.log"; exit 1; }
test ! -e "$root/usr/bin/cellwalk"
# The check can fail: with a dependency missing from the database, dpkg refuses the package.
bare=$work/bare
install_root "$bare"
awk -v RS= -v ORS='\n\n' '!/^Package: libembree-dev\n/' /var/lib/dpkg/status >"$bare/var/lib/dpkg/status"
if dpkg --root="$bare" --force-not-root -i "$deb" >"$work/bare.log" 2>&1; then
  echo "dpkg installed the package without libembree-dev"; exit 1
fi
grep -q "depends on libembree-dev" "$work/bare.log"
echo "install: prefix, find_package, pkg-config and .deb ($(du -h "$deb" | cut -f1), dpkg -i and -r) all work"
