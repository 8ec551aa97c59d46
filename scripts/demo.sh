#!/usr/bin/env bash
# The main job: builds what it needs and runs the demo of the workspace.
# Usage: scripts/demo.sh [OUT_DIR]   (default: out/demo)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
out="${1:-out/demo}"

scripts/setup.sh
# shellcheck disable=SC1091
source .venv/bin/activate
export MAKEFLAGS="-j$(nproc)"
colcon build --packages-up-to tactile_cli --event-handlers console_cohesion- summary+
set +u
# shellcheck disable=SC1091
source install/setup.bash
set -u
rm -rf "$out"
tactile demo --config config --out "$out"
