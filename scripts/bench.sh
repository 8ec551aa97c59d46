#!/usr/bin/env bash
# Runs every Google Benchmark target of the workspace (never part of the tests)
# and writes one JSON file per benchmark into OUT_DIR (default: out/bench).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
out="${1:-out/bench}"
mkdir -p "$out"
[[ -d install ]] || { echo "bench: build first (scripts/test.sh or colcon build)" >&2; exit 1; }
set +u
# shellcheck disable=SC1091
source install/setup.bash
set -u
for b in install/*/lib/*/bench_*; do
  [[ -x "$b" ]] || continue
  name="$(basename "$b")"
  echo "== $name"
  "$b" --benchmark_out="$out/$name.json" --benchmark_out_format=json
done
# The ROS 2 face (not a Google Benchmark): pressure -> depth / setpoint latency and CPU of
# the whisker pipeline in a component container, with and without intra-process
# communication (src/tactile_ros_tests/README.md). Only when ROS 2 is sourced and the ROS
# build (scripts/ros2_test.sh) exists.
if [[ -n "${ROS_DISTRO:-}" && -f install_ros/setup.bash ]]; then
  echo "== bench_ros_latency"
  set +u
  # shellcheck disable=SC1091
  source install_ros/setup.bash
  set -u
  python3 src/tactile_ros_tests/bench/bench_ros_latency.py --json "$out/bench_ros_latency.json"
fi
