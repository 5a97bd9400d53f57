#!/usr/bin/env bash
# Builds the libFuzzer harnesses (tests/fuzz/) with clang, ASan and UBSan into build-fuzz/ and
# runs each for SECONDS (default 20) over its seed corpus: tests/fuzz/corpus/<name>/ for the
# message fuzzers, config/ and tests/common/bad_scenarios/ for the scenario fuzzer. A crash, a
# sanitizer report, a leak, an input slower than 10 s or above 2 GiB fails the script; the input
# is kept in build-fuzz/artifacts/.
# Usage: scripts/fuzz.sh [--seconds N]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${MRSLAM_FUZZ_BUILD_DIR:-$root/build-fuzz}
seconds=20
if [ "${1:-}" = "--seconds" ]; then
  seconds=${2:?--seconds needs a value}
  [[ "$seconds" =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: --seconds must be a positive integer, not '$seconds'" >&2; exit 2; }
elif [ $# -gt 0 ]; then
  echo "fuzz.sh: usage: scripts/fuzz.sh [--seconds N]" >&2
  exit 2
fi
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (scripts/setup.sh installs it)" >&2; exit 1; }

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DMRSLAM_FUZZ=ON \
  -DMRSLAM_BUILD_TESTS=OFF -DMRSLAM_BUILD_BENCHMARKS=OFF "${launcher[@]}" >/dev/null
cmake --build "$build" -j "$(nproc)" --target scenario_fuzzer sensor_sample_fuzzer peer_message_fuzzer

mkdir -p "$build/artifacts"
run() {  # name, seed corpus folders...
  local name=$1
  shift
  local work="$build/corpus/$name"
  mkdir -p "$work"
  echo "fuzz.sh: $name for ${seconds} s"
  "$build/fuzz/$name" "$work" "$@" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="$build/artifacts/$name-" -print_final_stats=1 2>"$build/$name.log" ||
    { tail -n 40 "$build/$name.log" >&2; echo "fuzz.sh: $name failed (log: $build/$name.log)" >&2; return 1; }
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb" "$build/$name.log" | sed "s/^/fuzz.sh: $name /"
}
run scenario_fuzzer "$root/config" "$root/tests/common/bad_scenarios"
run sensor_sample_fuzzer "$root/tests/fuzz/corpus/sensor_sample"
run peer_message_fuzzer "$root/tests/fuzz/corpus/peer_message"
echo "fuzz.sh: no crash, leak, hang or out-of-memory in ${seconds} s per harness"
