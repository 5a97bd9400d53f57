#!/usr/bin/env bash
# Configures and builds mrslam into build/ (Release, all cores). Extra arguments go to cmake's
# configure step, e.g. scripts/build.sh -DMRSLAM_SANITIZER=address
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${MRSLAM_BUILD_DIR:-$root/build}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build "$build" -j "$(nproc)"
