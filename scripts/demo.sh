#!/usr/bin/env bash
# The main job: installs what is missing, builds, runs the default scenario
# (config/paper_two_robots.yaml) end to end as separate processes — world_sim, one robot_agent
# per robot, the evaluator — prints the summary and writes plots.
# Usage: scripts/demo.sh [OUT_DIR] [extra mrslam_launch flags, e.g. --seeds 1..5]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${MRSLAM_BUILD_DIR:-$root/build}
out=${1:-$root/runs/demo}
shift || true
bash "$root/scripts/setup.sh"
bash "$root/scripts/build.sh"
"$build/bin/mrslam_launch" --scenario "$root/config/paper_two_robots.yaml" --out "$out" "$@"
