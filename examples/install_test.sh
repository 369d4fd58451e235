#!/usr/bin/env bash
# ctest install/find_package: installs moslam into a temporary prefix, builds examples/ against
# it with find_package, runs it on a short synthetic sequence, and compiles and runs a one-file
# program with `pkg-config --cflags --libs moslam`.
# Usage: examples/install_test.sh BUILD_DIR MOSLAM_BINARY (from the repository root).
set -euo pipefail
build="$1"
moslam="$2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
prefix="$tmp/prefix"

cmake --install "$build" --prefix "$prefix" >/dev/null
test -f "$prefix/include/moslam/moslam.h"
test -f "$prefix/lib/cmake/moslam/moslamConfig.cmake"
test -f "$prefix/lib/pkgconfig/moslam.pc"

# 24 frames at 320x240: enough to initialize a map and track, a few seconds to render.
"$moslam" synth --preset w_xyz --seed 3 --frames 24 --width 320 --height 240 \
  --out "$tmp/seq" >/dev/null 2>&1

cmake -S examples -B "$tmp/example" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$tmp/example" -j 2 >/dev/null
out="$("$tmp/example/track_rgbd" "$tmp/seq" "$tmp/seq/settings.yaml" \
  data/vocab/moslam_orb.mvoc "$tmp/trajectory.txt" 2>/dev/null)"
echo "example: $out"
[[ "$out" =~ ^([0-9]+)\ of\ 24\ frames ]] || { echo "unexpected output" >&2; exit 1; }
(( BASH_REMATCH[1] >= 20 )) || { echo "too few frames tracked" >&2; exit 1; }
test "$(grep -vc '^#' "$tmp/trajectory.txt")" -ge 20

# A one-file program through pkg-config: a missing settings file is an InputError naming it.
cat >"$tmp/one_file.cc" <<'PROGRAM'
#include <iostream>
#include <moslam/moslam.h>
int main() {
  moslam::api::SlamOptions options;
  options.settings = "missing_settings.yaml";
  try {
    moslam::api::Slam slam(options);
  } catch (const moslam::InputError& e) {
    std::cout << e.what() << "\n";
    return 0;
  }
  return 1;
}
PROGRAM
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
# shellcheck disable=SC2046
g++ -O1 "$tmp/one_file.cc" -o "$tmp/one_file" $(pkg-config --cflags --libs moslam)
"$tmp/one_file" | grep -q "missing_settings.yaml"
echo "pkg-config program: ok"
