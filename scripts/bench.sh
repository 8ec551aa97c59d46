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
# peer from the same run. Every measurement is taken BENCH_SIM_REPEAT times (default
# 3) and the fastest is reported (the least disturbed by other work on the machine).
#  - recording on one core: `tactile sim --trials 10 --jobs 1` (one worker thread)
#    recorded vs --no-bag, as simulated time / wall time and / CPU time (user + sys);
#  - one run of the scenario as a command: the same for `--trials 1`, process start included;
#  - --jobs 2 vs --jobs 1 for the 10 trials, next to what the machine gives two
#    independent single-threaded processes (`--trials 5 --jobs 1` twice at once vs once
#    alone): the ceiling of any 2-worker speed-up on this machine and workload.
# The pictures are off (--no-png): they are not part of recording.
echo "== tactile sim: recording, --jobs 1 vs --jobs 2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
scenario="${BENCH_SIM_SCENARIO:-config/scenarios/whisker_three_baffles_fsm.yaml}"
trials="${BENCH_SIM_TRIALS:-10}"
repeat="${BENCH_SIM_REPEAT:-3}"
run_sim() {  # run_sim NAME ARGS...: prints "wall_s cpu_s" of one `tactile sim ARGS`
  local name="$1"; shift
  rm -rf "${tmp:?}/$name"
  local TIMEFORMAT="%R %U %S"  # bash's time keyword: wall, user, sys of the command
  { time tactile sim "$scenario" --out "$tmp/$name" --quiet --no-png "$@" >/dev/null 2>"$tmp/$name.err" \
      || { cat "$tmp/$name.err" >&2; exit 1; }; } 2>"$tmp/$name.time"
  awk '{printf "%.3f %.3f\n", $1, $2 + $3}' "$tmp/$name.time"
}
measure() {  # measure NAME ARGS...: the fastest (by wall time) of $repeat runs
  local best="" w c
  for ((r = 0; r < repeat; r++)); do
    read -r w c < <(run_sim "$@")
    if [[ -z "$best" ]] || awk -v a="$w" -v b="${best%% *}" 'BEGIN { exit !(a < b) }'; then best="$w $c"; fi
  done
  echo "$best"
}
pair() {  # pair: the slower wall time of two `--trials 5 --jobs 1` processes started together (fastest of $repeat)
  local best="" a b w
  for ((r = 0; r < repeat; r++)); do
    run_sim pa --trials 5 --jobs 1 >"$tmp/pa.out" & local pid=$!
    run_sim pb --trials 5 --jobs 1 >"$tmp/pb.out"
    wait "$pid"
    read -r a _ <"$tmp/pa.out"; read -r b _ <"$tmp/pb.out"
    w="$(awk -v a="$a" -v b="$b" 'BEGIN { print (a > b ? a : b) }')"
    if [[ -z "$best" ]] || awk -v a="$w" -v b="$best" 'BEGIN { exit !(a < b) }'; then best="$w"; fi
  done
  echo "$best"
}
sim_s="$(python3 -c 'import sys,yaml; print(yaml.safe_load(open(sys.argv[1]))["duration_s"])' "$scenario" 2>/dev/null \
  || sed -n 's/^duration_s: *\([0-9.]*\).*/\1/p' "$scenario")"
read -r w1 c1 < <(measure jobs1 --trials "$trials" --jobs 1)
read -r wn cn < <(measure jobs1_nobag --trials "$trials" --jobs 1 --no-bag)
read -r w2 c2 < <(measure jobs2 --trials "$trials" --jobs 2)
read -r wb cb < <(measure bag)
read -r wo co < <(measure nobag --no-bag)
read -r ws _ < <(measure single5 --trials 5 --jobs 1)
wp="$(pair)"
awk -v s="$sim_s" -v t="$trials" -v w1="$w1" -v c1="$c1" -v wn="$wn" -v cn="$cn" -v w2="$w2" -v c2="$c2" \
    -v wb="$wb" -v cb="$cb" -v wo="$wo" -v co="$co" -v ws="$ws" -v wp="$wp" -v rep="$repeat" \
    -v sc="$(basename "$scenario" .yaml)" 'BEGIN {
  printf "%s (%.0f s simulated), fastest of %d:\n", sc, s, rep
  printf "  recorded on one core (--trials %d --jobs 1): %.0fx real time (%.2f s wall), %.0fx per CPU s; not recorded %.0fx (%.2f s), %.0fx per CPU s: recording costs %.0f %% of the CPU time\n",
         t, t * s / w1, w1, t * s / c1, t * s / wn, wn, t * s / cn, 100 * (c1 - cn) / c1
  printf "  one run as a command (process start included): recorded %.0fx real time (%.0fx per CPU s), not recorded %.0fx (%.0fx)\n",
         s / wb, s / cb, s / wo, s / co
  printf "  --trials %d: --jobs 1 %.2f s wall, --jobs 2 %.2f s wall (%.2f s CPU): %.2fx faster; two independent 1-job processes of 5 trials: %.2f s alone, %.2f s side by side: the machine gives %.2fx for 2 workers\n",
         t, w1, w2, c2, w1 / w2, ws, wp, 2 * ws / wp
}'
echo "load: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
