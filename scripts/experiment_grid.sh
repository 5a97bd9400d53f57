#!/usr/bin/env bash
# Paper B's experiment grid in one command: runs build/bin/mrslam_grid (the pure cores
# in-process: World + one filter per robot, no DDS) on config/dynamic_world.yaml for dynamism
# 5..80 % x speed 0.1..0.9 m/s x N runs x 150 frames, filters ekf, ekf_ela and fastslam, then
# plots the heat maps. Writes DIR/grid.csv, DIR/tables.md and DIR/plots/grid_*.png.
# Usage: scripts/experiment_grid.sh --out DIR [--runs N] [more mrslam_grid flags, e.g. --multi-process]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${MRSLAM_BUILD_DIR:-$root/build}
out=""
runs=10
extra=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) out=${2:?--out needs a folder}; shift 2 ;;
    --runs) runs=${2:?--runs needs a number}; shift 2 ;;
    -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
    *) extra+=("$1"); shift ;;
  esac
done
if [[ -z "$out" ]]; then
  echo "experiment_grid.sh: --out DIR is required" >&2
  exit 2
fi
if [[ ! -x "$build/bin/mrslam_grid" ]]; then
  echo "experiment_grid.sh: $build/bin/mrslam_grid is missing; run scripts/build.sh first" >&2
  exit 1
fi
# Exit code 3: some runs failed; the others are in grid.csv and get their plots and tables.
status=0
"$build/bin/mrslam_grid" --scenario "$root/config/dynamic_world.yaml" --out "$out" --runs "$runs" \
  --threads "$(nproc)" "${extra[@]}" || status=$?
if [[ $status -ne 0 && $status -ne 3 ]]; then exit "$status"; fi
/usr/bin/python3 "$root/scripts/plot_grid.py" "$out"
cat "$out/tables.md"
exit "$status"
