#!/usr/bin/env bash
# Runs every Google Benchmark target of the workspace (never part of the tests)
# and writes one JSON file per benchmark into OUT_DIR (default: out/bench),
# then the `tactile sim` figures of issue 18 (BENCH_SIM_ONLY=1: only those).
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
  [[ "${BENCH_SIM_ONLY:-0}" == 1 ]] && break  # only the tactile sim figures below
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

# Issue 18: parallel trials and the cost of recording, each figure next to its
# peer from the same run. Wall time of `tactile sim --trials 10` on one worker
# and on two; the recorded and unrecorded real-time factor of one run, as
# simulated time / CPU time (user + sys) of the process, which a machine shared
# with other work does not inflate, and as simulated time / wall time.
echo "== tactile sim: --jobs 1 vs --jobs 2, recorded vs not"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
scenario="${BENCH_SIM_SCENARIO:-config/scenarios/whisker_three_baffles_fsm.yaml}"
trials="${BENCH_SIM_TRIALS:-10}"
measure() {  # measure NAME ARGS...: prints "wall_s cpu_s" of `tactile sim ARGS`
  local name="$1"; shift
  local TIMEFORMAT="%R %U %S"  # bash's time keyword: wall, user, sys of the command
  { time tactile sim "$scenario" --out "$tmp/$name" --quiet "$@" >/dev/null 2>"$tmp/$name.err" \
      || { cat "$tmp/$name.err" >&2; exit 1; }; } 2>"$tmp/$name.time"
  awk '{printf "%.3f %.3f\n", $1, $2 + $3}' "$tmp/$name.time"
}
sim_s="$(python3 -c 'import sys,yaml; print(yaml.safe_load(open(sys.argv[1]))["duration_s"])' "$scenario" 2>/dev/null \
  || sed -n 's/^duration_s: *\([0-9.]*\).*/\1/p' "$scenario")"
read -r w1 c1 < <(measure jobs1 --trials "$trials" --jobs 1 --no-png)
read -r w2 c2 < <(measure jobs2 --trials "$trials" --jobs 2 --no-png)
read -r wb cb < <(measure bag --no-png)
read -r wn cn < <(measure nobag --no-png --no-bag)
awk -v s="$sim_s" -v t="$trials" -v w1="$w1" -v c1="$c1" -v w2="$w2" -v c2="$c2" \
    -v wb="$wb" -v cb="$cb" -v wn="$wn" -v cn="$cn" -v sc="$(basename "$scenario" .yaml)" 'BEGIN {
  printf "%s, %d trials of %.0f s: --jobs 1 %.2f s wall (%.2f s CPU), --jobs 2 %.2f s wall (%.2f s CPU): %.2fx faster\n",
         sc, t, s, w1, c1, w2, c2, w1 / w2
  printf "%s, one run of %.0f s: recorded %.0fx real time per CPU s (%.0fx per wall s), not recorded %.0fx (%.0fx): recording costs %.0f %% of the CPU time\n",
         sc, s, s / cb, s / wb, s / cn, s / wn, 100 * (cb - cn) / cb
}'
echo "load: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
