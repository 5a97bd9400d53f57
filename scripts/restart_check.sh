#!/usr/bin/env bash
# Agents that come back (docs/faults.md): for each seed, runs the scenario once uninterrupted and
# once with `mrslam_launch --restart 1`, killing (SIGKILL) a random agent at a random moment of the
# second run; checks that the second run completes, that its numbers (summary.json without times,
# metrics.csv) equal the first's, that the summary counts one restart, and that nothing the run
# made is left in /dev/shm once the launcher has exited.
# Usage: scripts/restart_check.sh [--seeds N] [--scenario FILE] [--out DIR] [--shm] [--draw SEED]
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
bin=${MRSLAM_BUILD_DIR:-$root/build}/bin
seeds=20
scenario=$root/config/swarm_8.yaml
out=$root/runs/restart-check
shm=()
draw=1
while [[ $# -gt 0 ]]; do
  case $1 in
    --seeds) seeds=$2; shift 2 ;;
    --scenario) scenario=$(realpath "$2"); shift 2 ;;
    --out) out=$2; shift 2 ;;
    --shm) shm=(--shm); shift ;;
    --draw) draw=$2; shift 2 ;;
    *) echo "restart_check.sh: error: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
python=/usr/bin/python3
robots=($("$python" -c "import yaml,sys; print(' '.join(r['id'] for r in yaml.safe_load(open(sys.argv[1]))['robots']))" "$scenario"))
mkdir -p "$out"
RANDOM=$draw  # the draw of victims and moments is reproducible

# The summary's numbers without what differs between any two runs (times, domain, restarts).
numbers() {
  "$python" - "$1" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
for k in ("wall_seconds", "evaluator_wall_seconds", "dds_domain"):
    s.pop(k, None)
for r in s["robots"].values():
    for k in ("step_cpu_ms_median", "step_cpu_ms_p99", "restarts", "restart_comeback_s"):
        r.pop(k, None)
print(json.dumps(s, sort_keys=True))
PY
}

# Files in /dev/shm that no process holds open.
unheld_shm() {
  for f in /dev/shm/*; do
    [[ -e $f ]] || continue
    fuser -s "$f" 2>/dev/null || echo "${f#/dev/shm/}"
  done | sort
}

failures=0
printf 'seed robot moment_s killed_after_step completed identical restarts comeback_s shm_left\n' | tee "$out/table.txt"
for ((seed = 1; seed <= seeds; ++seed)); do
  victim=${robots[$((RANDOM % ${#robots[@]}))]}
  fraction=$((5 + RANDOM % 86))  # percent of the uninterrupted run's wall time
  plain=$out/plain/seed-$seed
  again=$out/restart/seed-$seed
  rm -rf "$plain" "$again"
  mkdir -p "$plain" "$again"
  "$bin/mrslam_launch" --scenario "$scenario" --seed "$seed" --out "$plain" --no-plots "${shm[@]}" \
    >"$plain/launch.log" 2>&1 || { echo "seed $seed: the uninterrupted run failed ($plain/launch.log)" >&2; exit 1; }
  wall=$("$python" -c "import json,sys; print(json.load(open(sys.argv[1]))['wall_seconds'])" "$plain/summary.json")
  moment=$("$python" -c "print(round($wall * $fraction / 100, 2))")
  before=$(unheld_shm)
  "$bin/mrslam_launch" --scenario "$scenario" --seed "$seed" --out "$again" --no-plots --restart 1 "${shm[@]}" \
    >"$again/launch.log" 2>&1 &
  launcher=$!
  # The moment counts from the launcher's start; the victim is found among its children.
  sleep "$moment"
  pid=""
  for child in $(pgrep -P "$launcher" || true); do
    if tr '\0' ' ' <"/proc/$child/cmdline" 2>/dev/null | grep -q -- "--robot $victim "; then pid=$child; fi
  done
  [[ -n $pid ]] && kill -9 "$pid"
  completed=yes
  wait "$launcher" || completed=no
  after=$(comm -13 <(echo "$before") <(unheld_shm) | grep -c . || true)
  step=$(grep -o 'after step [0-9]*' "$again/launch.log" | head -1 | grep -o '[0-9]*$' || echo "-")
  identical=no
  restarts=-
  comeback=-
  if [[ $completed == yes ]]; then
    if [[ $(numbers "$plain/summary.json") == "$(numbers "$again/summary.json")" ]] &&
      cmp -s "$plain/metrics.csv" "$again/metrics.csv"; then identical=yes; fi
    read -r restarts comeback < <("$python" -c "import json,sys; r = json.load(open(sys.argv[1]))['robots'][sys.argv[2]]
print(r['restarts'], ','.join('%.2f' % s for s in r['restart_comeback_s']) or '-')" "$again/summary.json" "$victim")
  fi
  [[ -z $pid ]] && step="not-killed"
  printf '%s %s %s %s %s %s %s %s %s\n' "$seed" "$victim" "$moment" "$step" "$completed" "$identical" "$restarts" \
    "$comeback" "$after" |
    tee -a "$out/table.txt"
  if [[ $completed != yes || $identical != yes || $restarts != 1 || $comeback == - || $after != 0 || -z $pid ]]; then
    failures=$((failures + 1))
  fi
done
echo "restart_check: $((seeds - failures)) of $seeds seeds passed (table: $out/table.txt)"
[[ $failures -eq 0 ]]
