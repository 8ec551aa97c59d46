#!/usr/bin/env bash
# Installs everything the workspace needs on Debian 12 (bookworm):
#   - Debian packages: compilers, the required libraries and colcon;
#   - a Python virtual environment in .venv/ with the test and tool dependencies.
# Idempotent: when every package is already present it only checks and returns
# (a few seconds). Run as root or with sudo available.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

DEB_PACKAGES=(
  build-essential cmake ninja-build pkg-config git ccache
  python3 python3-venv python3-pip
  libeigen3-dev libpcl-dev libopencv-dev libusb-1.0-0-dev libgeographiclib-dev
  libyaml-cpp-dev libsqlite3-dev sqlite3 libgtest-dev libgmock-dev googletest libbenchmark-dev
  libzstd-dev liblz4-dev libdeflate-dev libpng-dev zlib1g-dev libssl-dev libopenblas-dev
  libcli11-dev nlohmann-json3-dev libfmt-dev libspdlog-dev
  colcon python3-colcon-core python3-colcon-cmake python3-colcon-ros
  python3-colcon-bash python3-colcon-defaults python3-colcon-library-path
  python3-colcon-metadata python3-colcon-output python3-colcon-package-information
  python3-colcon-package-selection python3-colcon-parallel-executor
  python3-colcon-recursive-crawl python3-colcon-test-result python3-colcon-pkg-config
)

missing=()
for p in "${DEB_PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "setup: installing Debian packages: ${missing[*]}"
  SUDO=""
  if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
else
  echo "setup: Debian packages present"
fi

# Python environment for tests and tools. Pinned in scripts/requirements.txt.
venv="$here/.venv"
req="$here/scripts/requirements.txt"
stamp="$venv/.requirements.sha256"
want="$(sha256sum "$req" | cut -d' ' -f1)"
if [[ ! -x "$venv/bin/python" ]]; then
  echo "setup: creating Python virtual environment in .venv"
  python3 -m venv "$venv"
fi
if [[ ! -f "$stamp" || "$(cat "$stamp")" != "$want" ]]; then
  echo "setup: installing Python packages from scripts/requirements.txt"
  "$venv/bin/python" -m pip install -q --upgrade pip >/dev/null
  "$venv/bin/python" -m pip install -q -r "$req"
  echo "$want" > "$stamp"
else
  echo "setup: Python environment up to date"
fi
