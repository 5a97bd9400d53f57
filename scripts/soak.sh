#!/usr/bin/env bash
# The soak (docs/faults.md, "The soak"): runs many seeds of a scenario end to end with
# mrslam_launch, optionally beside a CPU hog on every core, and checks that no seed failed and
# that nothing was left behind: no process of the soak and no new file in /dev/shm.
# Usage: scripts/soak.sh [--seeds N] [--hog] [--shm] [--scenario FILE] [--out DIR]
#   --seeds N      seeds 1..N (default 200)
#   --hog          stress-ng --cpu <cores> beside the runs (scripts/setup.sh installs stress-ng)
#   --shm          the runs use the shared-memory transport too (mrslam_launch --shm)
#   --scenario F   default config/paper_two_robots.yaml
#   --out DIR      default a new temporary folder (kept, printed)
# Prints one line of figures (seeds, failed seeds, seconds per seed, leftovers) and exits 1 if a
# seed failed, a Fast DDS assertion was logged or anything was left behind.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bin=${MRSLAM_BUILD_DIR:-$root/build}/bin
seeds=200
hog=0
shm=()
scenario=$root/config/paper_two_robots.yaml
out=""
usage() { echo "soak.sh: usage: scripts/soak.sh [--seeds N] [--hog] [--shm] [--scenario FILE] [--out DIR]" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case $1 in
    --seeds) seeds=${2:-}; shift 2 || usage
      [[ "$seeds" =~ ^[1-9][0-9]*$ ]] || { echo "soak.sh: --seeds must be a positive integer, not '$seeds'" >&2; exit 2; } ;;
    --hog) hog=1; shift ;;
    --shm) shm=(--shm); shift ;;
    --scenario) scenario=${2:-}; shift 2 || usage ;;
    --out) out=${2:-}; shift 2 || usage ;;
    *) usage ;;
  esac
done
[ -x "$bin/mrslam_launch" ] || { echo "soak.sh: $bin/mrslam_launch not found (build first: scripts/build.sh)" >&2; exit 1; }
[ -r "$scenario" ] || { echo "soak.sh: scenario '$scenario' not readable" >&2; exit 2; }
[ -n "$out" ] || out=$(mktemp -d /tmp/mrslam-soak.XXXXXX)
mkdir -p "$out"
out=$(cd "$out" && pwd)

shm_files() { find /dev/shm -maxdepth 1 \( -name 'fastrtps_*' -o -name 'sem.fastrtps_*' \) -printf '%f\n' | sort; }
shm_files >"$out/shm_before.txt"

hog_pid=""
stop_hog() { if [ -n "$hog_pid" ]; then kill "$hog_pid" 2>/dev/null || true; wait "$hog_pid" 2>/dev/null || true; hog_pid=""; fi; }
trap stop_hog EXIT
if [ "$hog" = 1 ]; then
  command -v stress-ng >/dev/null || { echo "soak.sh: stress-ng not found (scripts/setup.sh installs it)" >&2; exit 1; }
  stress-ng --cpu "$(nproc)" --quiet >"$out/stress-ng.log" 2>&1 &
  hog_pid=$!
fi

start=$(date +%s.%N)
set +e
"$bin/mrslam_launch" --scenario "$scenario" --seeds "1..$seeds" --no-plots --out "$out/runs" "${shm[@]}" \
  >"$out/launch.log" 2>&1
code=$?
set -e
end=$(date +%s.%N)
stop_hog

# Leftovers: a process still running from the soak's folder, a /dev/shm file that was not there before.
sleep 1
leftover_procs=$(pgrep -fc -- "$out/runs" || true)
shm_files >"$out/shm_after.txt"
leftover_shm=$(comm -13 "$out/shm_before.txt" "$out/shm_after.txt" | wc -l)
failed=$(/usr/bin/python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["failed_seeds"]))' \
  "$out/runs/aggregate.json" 2>/dev/null || echo "?")
asserts=$( (grep -l "Assertion" "$out"/runs/seed-*/logs/*.log 2>/dev/null || true) | wc -l)
slowest=$( (grep -ho "finished in [0-9.]* s" "$out/launch.log" || true) | awk '{print $3}' | sort -g | tail -1)
per_seed=$(awk -v a="$start" -v b="$end" -v n="$seeds" 'BEGIN {printf "%.2f", (b - a) / n}')
echo "soak.sh: $(basename "$scenario") seeds 1..$seeds$([ "$hog" = 1 ] && echo ", stress-ng --cpu $(nproc) beside")$([ ${#shm[@]} -gt 0 ] && echo ", --shm"):" \
  "launcher exit $code, failed seeds $failed, seeds with a Fast DDS assertion $asserts," \
  "wall $per_seed s per seed (slowest ${slowest:-?} s), leftover processes $leftover_procs, new /dev/shm files $leftover_shm;" \
  "folder $out"
[ "$code" = 0 ] && [ "$failed" = 0 ] && [ "$asserts" = 0 ] && [ "$leftover_procs" = 0 ] && [ "$leftover_shm" = 0 ]
