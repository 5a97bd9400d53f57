#!/usr/bin/env bash
# Agents that come back (docs/faults.md): for each seed, runs the scenario once uninterrupted and
# once with `mrslam_launch --restart 1`, killing (SIGKILL) a random agent at a random step of the
# second run; checks that the second run completes, that its numbers (summary.json without times,
# metrics.csv) equal the first's, that the summary counts one restart, and that nothing the run
# made is left in /dev/shm once the launcher has exited.
# The victim is killed once the launcher's progress shows a step drawn at random in the first 90%
# of the run (the progress is printed every 2 s, so the kill comes up to about 2 s later; the
# launcher says after which step the agent died).
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
steps=$("$python" -c "import yaml,sys; print(yaml.safe_load(open(sys.argv[1]))['run']['steps'])" "$scenario")
robots=($("$python" -c "import yaml,sys; print(' '.join(r['id'] for r in yaml.safe_load(open(sys.argv[1]))['robots']))" "$scenario"))
mkdir -p "$out"
RANDOM=$draw  # the draw of victims and steps is reproducible

# The summary's numbers without what differs between any two runs (times, domain, restarts).
numbers() {
  "$python" - "$1" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
for k in ("wall_seconds", "evaluator_wall_seconds", "dds_domain", "cpu_seconds", "cpu_cores_mean"):
    s.pop(k, None)
for r in s["robots"].values():
    for k in ("step_cpu_ms_median", "step_cpu_ms_p99", "latency_us_median", "latency_us_p99", "restarts",
              "restart_comeback_s"):
        r.pop(k, None)
print(json.dumps(s, sort_keys=True))
PY
}

# Port files in /dev/shm of the DDS domain $1 (Fast DDS names them after the port; the ports of
# domain d are 7400 + 250 d .. 7400 + 250 d + 249) that no process holds open.
unheld_shm_of_domain() {
  local first=$((7400 + 250 * $1)) f port
  for f in /dev/shm/fastrtps_port* /dev/shm/sem.fastrtps_port*; do
    [[ -e $f ]] || continue
    port=${f##*fastrtps_port}
    port=${port%_mutex}
    ((port >= first && port < first + 250)) || continue
    fuser -s "$f" 2>/dev/null || echo "${f#/dev/shm/}"
  done
}

# Waits until the launcher's progress (its log, every 2 s off a terminal) shows step $2 or more;
# false if the launcher $1 ended first.
wait_for_step() {
  local log=$3 step
  while kill -0 "$1" 2>/dev/null; do
    step=$(grep -o '^step [0-9]*/' "$log" 2>/dev/null | tail -1 | tr -dc '0-9')
    [[ -n $step && $step -ge $2 ]] && return 0
    sleep 0.1
  done
  return 1
}

failures=0
printf 'seed robot drawn_step killed_after_step completed identical restarts comeback_s shm_left\n' | tee "$out/table.txt"
for ((seed = 1; seed <= seeds; ++seed)); do
  victim=${robots[$((RANDOM % ${#robots[@]}))]}
  drawn=$((1 + RANDOM % (steps * 9 / 10)))
  plain=$out/plain/seed-$seed
  again=$out/restart/seed-$seed
  rm -rf "$plain" "$again"
  mkdir -p "$plain" "$again"
  "$bin/mrslam_launch" --scenario "$scenario" --seed "$seed" --out "$plain" --no-plots "${shm[@]}" \
    >"$plain/launch.log" 2>&1 || { echo "seed $seed: the uninterrupted run failed ($plain/launch.log)" >&2; exit 1; }
  "$bin/mrslam_launch" --scenario "$scenario" --seed "$seed" --out "$again" --no-plots --restart 1 "${shm[@]}" \
    >"$again/launch.log" 2>&1 &
  launcher=$!
  pid=""
  if wait_for_step "$launcher" "$drawn" "$again/launch.log"; then
    for child in $(pgrep -P "$launcher" || true); do
      if tr '\0' ' ' <"/proc/$child/cmdline" 2>/dev/null | grep -q -- "--robot $victim "; then pid=$child; fi
    done
  fi
  [[ -n $pid ]] && kill -9 "$pid"
  completed=yes
  wait "$launcher" || completed=no
  domain=$(grep -o 'DDS domain [0-9]*' "$again/launch.log" | head -1 | tr -dc '0-9')
  after=$(unheld_shm_of_domain "$domain" | grep -c . || true)
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
  printf '%s %s %s %s %s %s %s %s %s\n' "$seed" "$victim" "$drawn" "$step" "$completed" "$identical" "$restarts" \
    "$comeback" "$after" |
    tee -a "$out/table.txt"
  if [[ $completed != yes || $identical != yes || $restarts != 1 || $comeback == - || $after != 0 || -z $pid ]]; then
    failures=$((failures + 1))
  fi
done
echo "restart_check: $((seeds - failures)) of $seeds seeds passed (table: $out/table.txt)"
[[ $failures -eq 0 ]]
