#!/usr/bin/env bash
# Sets up, builds and runs the whole test suite. Usage: scripts/test.sh [release|asan|tsan]
# Shared data (../shared, or MOSLAM_SHARED) is used when present; tests that need it skip
# with a message otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."

kind="${1:-release}"
scripts/setup.sh
t0=$(date +%s)
scripts/build.sh "$kind"
t1=$(date +%s)
case "$kind" in
  release) dir=build ;;
  *) dir="build-$kind" ;;
esac
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# Suppressions for reports inside system libraries (each file says which and why).
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/scripts/lsan_suppressions.txt}"
export TSAN_OPTIONS="${TSAN_OPTIONS:-suppressions=$PWD/scripts/tsan_suppressions.txt}"
labels=()
if [[ "$kind" == tsan ]]; then
  # Mesa's llvmpipe (the synthetic scenes' renderer) rasterizes in worker threads of its own;
  # libOSMesa is not built with ThreadSanitizer, so its hand-overs are invisible to it and a
  # mutex it destroys after its workers used it reads as a race inside the library (measured:
  # 4 reports per synthetic sequence). Rendering in the calling thread keeps that work in the
  # threads moslam starts, which are what this build checks. OpenCV's TBB workers: the same, in
  # src/moslam/testing/serial_opencv.cc.
  export LP_NUM_THREADS=0
  # It runs the tests whose code runs in several threads (label `threads`) only.
  labels=(-L threads)
fi
# MOSLAM_TIMING_FILE (.ci/run): where the build's and the tests' seconds are appended, also when
# a test fails.
timing() {
  local rc=$?
  [[ -n "${MOSLAM_TIMING_FILE:-}" ]] &&
    echo "$kind: build $((t1 - t0)) s, tests $(($(date +%s) - t1)) s (exit $rc)" >> "$MOSLAM_TIMING_FILE"
  return 0
}
trap timing EXIT
ctest --test-dir "$dir" --output-on-failure -j "${MOSLAM_JOBS:-$(nproc)}" "${labels[@]}"
