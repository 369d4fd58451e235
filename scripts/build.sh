#!/usr/bin/env bash
# Configures and builds moslam. Usage: scripts/build.sh [release|asan|tsan|debug]
#   release  -> build/        (the default; -O2, -Wall -Wextra -Werror)
#   asan     -> build-asan/   (AddressSanitizer + UndefinedBehaviorSanitizer)
#   tsan     -> build-tsan/   (ThreadSanitizer)
#   debug    -> build-debug/
set -euo pipefail
cd "$(dirname "$0")/.."

kind="${1:-release}"
case "$kind" in
  release) dir=build; args=(-DCMAKE_BUILD_TYPE=Release) ;;
  asan) dir=build-asan; args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DMOSLAM_SANITIZE=address,undefined
                               -DMOSLAM_BUILD_BENCHMARKS=OFF) ;;
  tsan) dir=build-tsan; args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DMOSLAM_SANITIZE=thread
                               -DMOSLAM_BUILD_BENCHMARKS=OFF) ;;
  debug) dir=build-debug; args=(-DCMAKE_BUILD_TYPE=Debug) ;;
  *) echo "usage: $0 [release|asan|tsan|debug]" >&2; exit 2 ;;
esac

jobs="${MOSLAM_JOBS:-$(nproc)}"
cmake -S . -B "$dir" "${args[@]}" >/dev/null
cmake --build "$dir" -j "$jobs"
echo "build: $dir ready"
