#!/usr/bin/env bash
# The partition cuts too long for the suite (docs/faults.md, "Partitions"): paper_two_robots in
# realtime (factor 1, 160 steps of 0.65 s), r1 and r2 in network namespaces of their own, both
# linked to world_sim's; the link between them is cut at about step 30 for 5 s and for 40 s.
# Each run must score every step of both robots and show a rendezvous and a joint transform
# after the cut; prints one line of figures per robot and cut. Needs root (network namespaces).
# Usage: scripts/partitions.sh [CUT_S...]   (default: 5 40)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
test_bin=${MRSLAM_BUILD_DIR:-$root/build}/tests/partition_test
[ -x "$test_bin" ] || { echo "partitions.sh: $test_bin not found (build first: scripts/build.sh)" >&2; exit 1; }
cuts=("$@")
[ ${#cuts[@]} -gt 0 ] || cuts=(5 40)
status=0
for cut in "${cuts[@]}"; do
  [[ "$cut" =~ ^[0-9]+(\.[0-9]+)?$ ]] || { echo "partitions.sh: a cut is a number of seconds, not '$cut'" >&2; exit 2; }
  out=$(MRSLAM_PARTITION_CUT_S=$cut MRSLAM_PARTITION_STEPS=160 MRSLAM_PARTITION_FACTOR=1 \
    "$test_bin" --gtest_filter='PartitionTest.AgentsCutFromEachOther*' 2>&1) || status=1
  grep -E "^partition:|skipped|Failure|\[  (PASSED|FAILED|SKIPPED) " <<<"$out" || true
  [ $status = 0 ] || { echo "$out" | tail -n 40 >&2; }
done
exit $status
