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
# 1. SITL: the whiskered Crazyflie flies the paper's data-collection protocol
#    (hover, forward until the TDORC signal reports contact, sweep along the wall).
tactile sim config/scenarios/whisker_sweep.yaml --config config --out "$out/sitl_whisker_sweep"
# 2. The same against glass with the flow-deck state estimate, three seeded trials.
tactile sim config/scenarios/whisker_sweep_glass.yaml --config config --out "$out/sitl_whisker_sweep_glass" \
  --trials 3 --quiet
# 3. Whisker signal chain: simulated free flight and contact, replayed through TDORC.
tactile demo --config config --out "$out/whisker_signals"
