#!/usr/bin/env bash
# Installs what is missing, builds, runs every test (unit and multi-process), then a short run of
# each fuzzing harness (scripts/fuzz.sh; longer runs: scripts/fuzz.sh --seconds N).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${MRSLAM_BUILD_DIR:-$root/build}
bash "$root/scripts/setup.sh"
bash "$root/scripts/build.sh"
(cd "$build" && ctest --output-on-failure -j "$(nproc)" --timeout 600)
bash "$root/scripts/fuzz.sh" --seconds 20
