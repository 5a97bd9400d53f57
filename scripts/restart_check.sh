#!/usr/bin/env bash
# Agents that come back (docs/faults.md): for each seed, runs the scenario once uninterrupted and
# once with `mrslam_launch --restart 1`, killing (SIGKILL) a random agent at a random step of the
# second run; checks that the second run completes, that its numbers (summary.json without times
# and peer traffic, metrics.csv) equal the first's, that the summary counts one restart, and that nothing the run
# made is left in /dev/shm once the launcher has exited.
# The victim is killed at a moment drawn at random between 10% and 80% of the uninterrupted run's
# wall time after the launcher started (the launcher says after which step the agent died).
# With --realtime FACTOR both runs are in realtime mode at that factor: the numbers cannot be
# identical, so a seed passes instead when the victim is back at the newest step within 2 s of its
# restart and its position RMSE from 50 steps after it is back to the end is within 2x the
# uninterrupted run's over the same steps (n/a, not counted against it, when the run ended within
# those 50 steps).
# Usage: scripts/restart_check.sh [--seeds N] [--scenario FILE] [--out DIR] [--shm] [--draw SEED]
#                                 [--realtime FACTOR]
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
bin=${MRSLAM_BUILD_DIR:-$root/build}/bin
seeds=20
scenario=$root/config/swarm_8.yaml
out=$root/runs/restart-check
shm=()
mode=()
draw=1
while [[ $# -gt 0 ]]; do
  case $1 in
    --seeds) seeds=$2; shift 2 ;;
    --scenario) scenario=$(realpath "$2"); shift 2 ;;
    --out) out=$2; shift 2 ;;
    --shm) shm=(--shm); shift ;;
    --draw) draw=$2; shift 2 ;;
    --realtime) mode=(--set run.mode=realtime --set "run.realtime_factor=$2"); shift 2 ;;
    *) echo "restart_check.sh: error: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
python=/usr/bin/python3
robots=($("$python" -c "import yaml,sys; print(' '.join(r['id'] for r in yaml.safe_load(open(sys.argv[1]))['robots']))" "$scenario"))
mkdir -p "$out"
RANDOM=$draw  # the draw of victims and steps is reproducible

# The summary's numbers without what differs between any two runs (times, domain, restarts).
numbers() {
  "$python" - "$1" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
for k in ("wall_seconds", "evaluator_wall_seconds", "dds_domain", "cpu_seconds", "cpu_cores_mean", "peak_rss_mib"):
    s.pop(k, None)
for r in s["robots"].values():
    # Times, and the peer traffic: with shared raw measurements a restored agent is sent again what
    # its snapshot did not hold.
    for k in ("step_cpu_ms_median", "step_cpu_ms_p99", "latency_us_median", "latency_us_p99", "estimate_hop_us_median",
              "data_hop_us_median", "agent_overhead_us_median", "restarts", "restart_comeback_s",
              "peer_bytes_sent_per_s", "peer_bytes_received_per_s"):
        r.pop(k, None)
print(json.dumps(s, sort_keys=True))
PY
}

# Realtime: the victim's position RMSE over the steps from 50 after the step it was back at ($3)
# to the end, in the restarted run's metrics ($1) over the uninterrupted run's ($2).
error_ratio() {
  "$python" - "$1" "$2" "$3" "$4" <<'PY'
import csv, math, sys
def rmse(path, robot, first):
    e = [float(r["position_err_m"]) for r in csv.DictReader(open(path)) if r["robot"] == robot and int(r["step"]) >= first]
    return math.sqrt(sum(x * x for x in e) / len(e)) if e else float("nan")
again, plain, back, robot = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
ratio = rmse(again, robot, back + 50) / rmse(plain, robot, back + 50)
print("n/a" if math.isnan(ratio) else "%.2f" % ratio)  # n/a: the run ended within 50 steps
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

failures=0
check=identical
[[ ${#mode[@]} -gt 0 ]] && check=error_ratio
printf 'seed robot drawn_s killed_after_step completed %s restarts comeback_s shm_left\n' "$check" |
  tee "$out/table.txt"
for ((seed = 1; seed <= seeds; ++seed)); do
  victim=${robots[$((RANDOM % ${#robots[@]}))]}
  permille=$((100 + RANDOM % 701))
  plain=$out/plain/seed-$seed
  again=$out/restart/seed-$seed
  rm -rf "$plain" "$again"
  mkdir -p "$plain" "$again"
  "$bin/mrslam_launch" --scenario "$scenario" --seed "$seed" --out "$plain" --no-plots "${shm[@]}" "${mode[@]}" \
    >"$plain/launch.log" 2>&1 || { echo "seed $seed: the uninterrupted run failed ($plain/launch.log)" >&2; exit 1; }
  "$bin/mrslam_launch" --scenario "$scenario" --seed "$seed" --out "$again" --no-plots --restart 1 "${shm[@]}" \
    "${mode[@]}" >"$again/launch.log" 2>&1 &
  launcher=$!
  drawn=$("$python" -c "import json,sys; print('%.2f' % (json.load(open(sys.argv[1]))['wall_seconds'] * int(sys.argv[2]) / 1000))" \
    "$plain/summary.json" "$permille")
  sleep "$drawn"
  pid=""
  for child in $(pgrep -P "$launcher" || true); do
    if tr '\0' ' ' <"/proc/$child/cmdline" 2>/dev/null | grep -q -- "--robot $victim "; then pid=$child; fi
  done
  if [[ -n $pid ]]; then kill -9 "$pid" 2>/dev/null || pid=""; fi
  completed=yes
  wait "$launcher" || completed=no
  domain=$(grep -o 'DDS domain [0-9]*' "$again/launch.log" | head -1 | tr -dc '0-9')
  after=$(unheld_shm_of_domain "$domain" | grep -c . || true)
  step=$(grep -o 'after step [0-9]*' "$again/launch.log" | head -1 | grep -o '[0-9]*$' || echo "-")
  identical=no
  restarts=-
  comeback=-
  back=$(grep -o 'is back at step [0-9]*' "$again/launch.log" | head -1 | grep -o '[0-9]*$' || true)
  if [[ $completed == yes && $check == error_ratio ]]; then
    identical=-
    [[ -n $back ]] && identical=$(error_ratio "$again/metrics.csv" "$plain/metrics.csv" "$back" "$victim")
  elif [[ $completed == yes ]]; then
    if [[ $(numbers "$plain/summary.json") == "$(numbers "$again/summary.json")" ]] &&
      cmp -s "$plain/metrics.csv" "$again/metrics.csv"; then identical=yes; fi
  fi
  if [[ $completed == yes ]]; then
    read -r restarts comeback < <("$python" -c "import json,sys; r = json.load(open(sys.argv[1]))['robots'][sys.argv[2]]
print(r['restarts'], ','.join('%.2f' % s for s in r['restart_comeback_s']) or '-')" "$again/summary.json" "$victim")
  fi
  [[ -z $pid ]] && step="not-killed"
  printf '%s %s %s %s %s %s %s %s %s\n' "$seed" "$victim" "$drawn" "$step" "$completed" "$identical" "$restarts" \
    "$comeback" "$after" |
    tee -a "$out/table.txt"
  passed=yes
  if [[ $check == error_ratio ]]; then
    "$python" -c "import sys; sys.exit(0 if float(sys.argv[1]) <= 2.0 and float(sys.argv[2]) <= 2.0 else 1)" \
      "$([[ $identical == n/a ]] && echo 0 || echo "${identical/-/nan}")" "${comeback/-/nan}" 2>/dev/null || passed=no
  elif [[ $identical != yes ]]; then
    passed=no
  fi
  if [[ $passed != yes || $completed != yes || $restarts != 1 || $comeback == - || $after != 0 || -z $pid ]]; then
    failures=$((failures + 1))
  fi
done
echo "restart_check: $((seeds - failures)) of $seeds seeds passed (table: $out/table.txt)"
[[ $failures -eq 0 ]]
