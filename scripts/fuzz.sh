#!/usr/bin/env bash
# Builds the libFuzzer harnesses of moslam's parsers (fuzz/, docs/ROBUSTNESS.md "Fuzzing the
# parsers") with Debian's clang, AddressSanitizer and UndefinedBehaviorSanitizer, and runs them.
# Usage: scripts/fuzz.sh [TARGET|all] [SECONDS]      (defaults: all, 600 s per target)
#   build-fuzz/corpus/<target>/    what libFuzzer learnt (kept between runs)
#   build-fuzz/findings/<target>/  crashes, leaks, timeouts and out-of-memory inputs
#   build-fuzz/logs/<target>.log   libFuzzer's output with its final statistics
# A finding is fixed in the parser and then committed to fuzz/regressions/<target>/ (as text
# where it is text), where the fuzz/corpus test replays it in every build.
set -euo pipefail
cd "$(dirname "$0")/.."

which="${1:-all}"
seconds="${2:-600}"
dir=build-fuzz
targets=(settings tum_list kitti_calib kitti_times trajectory model_card vocabulary map)
if [[ "$which" != all ]]; then
  if [[ ! " ${targets[*]} " =~ " $which " ]]; then
    echo "fuzz.sh: unknown target '$which'; one of: ${targets[*]}" >&2
    exit 2
  fi
  targets=("$which")
fi

CC="${CC:-clang}" CXX="${CXX:-clang++}" cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DMOSLAM_BUILD_FUZZERS=ON \
  -DMOSLAM_SANITIZE=address,undefined -DMOSLAM_WERROR=OFF -DMOSLAM_BUILD_TESTS=OFF \
  -DMOSLAM_BUILD_BENCHMARKS=OFF -DMOSLAM_BUILD_APPS=OFF >/dev/null
cmake --build "$dir" -j "${MOSLAM_JOBS:-$(nproc)}" --target moslam_fuzz_seeds \
  "${targets[@]/#/fuzz_}"
rm -rf "$dir/seeds"
"$dir/fuzz/moslam_fuzz_seeds" . "$dir/seeds"

# UBSan findings abort (so libFuzzer keeps the input); leaks are findings too.
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/scripts/lsan_suppressions.txt}"
status=0
for t in "${targets[@]}"; do
  mkdir -p "$dir/corpus/$t" "$dir/findings/$t" "$dir/logs" "fuzz/regressions/$t"
  echo "fuzz.sh: $t for $seconds s"
  if ! "$dir/fuzz/fuzz_$t" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
      -print_final_stats=1 -artifact_prefix="$dir/findings/$t/" \
      "$dir/corpus/$t" "$dir/seeds/$t" "fuzz/regressions/$t" >"$dir/logs/$t.log" 2>&1; then
    echo "fuzz.sh: $t found something: $dir/findings/$t/ ($dir/logs/$t.log)" >&2
    status=1
  fi
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb" "$dir/logs/$t.log" |
    sort -u | sed "s/^/fuzz.sh: $t /" || true
done
exit $status
