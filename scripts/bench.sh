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
# One BLAS thread: the GPIS benchmarks compare per-core CPU time with numpy (below).
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
for b in install/*/lib/*/bench_*; do
  [[ -x "$b" ]] || continue
  name="$(basename "$b")"
  echo "== $name"
  "$b" --benchmark_out="$out/$name.json" --benchmark_out_format=json
done

# The GPIS update side by side with numpy/scipy and scikit-learn on the same
# kernel and data (gpis_explorer README, "Benchmarks"): the C++ figures from
# the JSON just written, the peers timed now, ratios and agreement printed.
gpis_json="$out/bench_gpis.json"
if [[ -f "$gpis_json" ]]; then
  py=python3
  [[ -x .venv/bin/python ]] && py=.venv/bin/python
  echo "== gpis_explorer: C++ vs numpy/scipy vs scikit-learn"
  OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}" "$py" src/gpis_explorer/scripts/bench_numpy_compare.py \
    install/gpis_explorer/lib/gpis_explorer/bench_gpis --cpp-json "$gpis_json" | tee "$out/gpis_peers.txt"
fi
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
