#!/usr/bin/env bash
# Runs clang-tidy (the root .clang-tidy) over the project's own sources, those tracked by git,
# with the compile commands of a build (scripts/build.sh writes build/compile_commands.json).
# The code generated from the IDL lives in the build tree and is not checked. Exits non-zero on
# any finding. Usage: scripts/tidy.sh [FILE...]   (default: every tracked .cc file)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${MRSLAM_BUILD_DIR:-$root/build}
tidy=$(command -v clang-tidy || command -v clang-tidy-14 || true)
if [[ -z "$tidy" ]]; then
  echo "tidy.sh: clang-tidy is not installed (scripts/setup.sh installs it)" >&2
  exit 2
fi
if [[ ! -f "$build/compile_commands.json" ]]; then
  echo "tidy.sh: $build/compile_commands.json is missing; run scripts/build.sh first" >&2
  exit 2
fi
cd "$root"
if [[ $# -gt 0 ]]; then
  files=("$@")
else
  mapfile -t files < <(git ls-files '*.cc')
fi
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# One file per clang-tidy process, as many at once as there are cores; findings go to the log.
printf '%s\n' "${files[@]}" |
  xargs -P "$(nproc)" -I{} sh -c '"$0" -p "$1" --quiet "$2" 2>/dev/null || true' "$tidy" "$build" {} >"$log"
if grep -qE '(warning|error):' "$log"; then
  grep -E -A3 '(warning|error):' "$log" >&2
  echo "tidy.sh: $(grep -cE '(warning|error):' "$log") findings in ${#files[@]} files" >&2
  exit 1
fi
echo "tidy.sh: ${#files[@]} files, no findings"
