#!/usr/bin/env bash
# Installs the Debian packages mrslam needs, only those that are missing (idempotent).
# Runs apt-get update at most once; as root directly, otherwise through sudo.
set -euo pipefail

packages=(
  g++ cmake make pkg-config git ca-certificates
  libfastrtps-dev fastddsgen fastdds-tools openssl libssl-dev
  libyaml-cpp-dev libspdlog-dev libeigen3-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-numpy python3-matplotlib
  iproute2 procps clang-format clang-tidy clang libclang-rt-14-dev
  libcpp-httplib-dev chromium chromium-driver cyclonedds-dev cyclonedds-tools stress-ng
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
  sudo_cmd=()
elif command -v sudo >/dev/null 2>&1; then
  sudo_cmd=(sudo)
else
  echo "setup: missing packages (${missing[*]}) and neither root nor sudo available" >&2
  exit 1
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "setup: done"
