#!/usr/bin/env bash
# Runs every Google Benchmark target of the workspace (never part of the tests)
# and writes one JSON file per benchmark into OUT_DIR (default: out/bench),
# then the `tactile sim` figures of issue 18 (BENCH_SIM_ONLY=1: only those).
#
# `scripts/bench.sh gpis [OUT_DIR]`: only the GPIS at ground scale (issue 36): the
# local solver's update (2000 and 10,000 points) next to the exact C++ solver, numpy/scipy
# and scikit-learn, its error against the exact GP, one summary line per size
# ("gpis online update, 10000 points: ..."); gpis_explorer README, "Local solver".
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
only=""
if [[ "${1:-}" == gpis ]]; then
  only=gpis
  shift
fi
out="${1:-out/bench}"
mkdir -p "$out"
[[ -d install ]] || { echo "bench: build first (scripts/test.sh or colcon build)" >&2; exit 1; }
set +u
# shellcheck disable=SC1091
source install/setup.bash
set -u
# One BLAS thread: the GPIS benchmarks compare per-core CPU time with numpy (below).
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
if [[ "$only" == gpis ]]; then
  b=install/gpis_explorer/lib/gpis_explorer/bench_gpis
  [[ -x "$b" ]] || { echo "bench: no $b (build gpis_explorer)" >&2; exit 1; }
  py=python3
  [[ -x .venv/bin/python ]] && py=.venv/bin/python
  echo "== bench_gpis: exact and local solver at 2000 / 10000 points"
  "$b" --benchmark_filter='BM_Update/(2000/200/1/40|10000/400/1/40)|BM_UpdateIncremental/(2000/200/40|10000/400/40)|BM_LocalUpdate' \
    --benchmark_out="$out/bench_gpis_online.json" --benchmark_out_format=json
  echo "== gpis_explorer at ground scale: local vs exact C++ vs numpy/scipy vs scikit-learn"
  "$py" src/gpis_explorer/scripts/bench_numpy_compare.py "$b" --online --cpp-json "$out/bench_gpis_online.json" \
    | tee "$out/gpis_online.txt"
  echo "load: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores; $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)"
  exit 0
fi
for b in install/*/lib/*/bench_*; do
  [[ -x "$b" ]] || continue
  [[ "${BENCH_SIM_ONLY:-0}" == 1 ]] && break  # only the tactile sim figures below
  name="$(basename "$b")"
  echo "== $name"
  "$b" --benchmark_out="$out/$name.json" --benchmark_out_format=json
done

# The GPIS update side by side with numpy/scipy and scikit-learn on the same
# kernel and data (docs/gpis_explorer_results.md, "Benchmarks"): the C++ figures from
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
# peer from the same run. This VM's speed moves by 20-40 % from one minute to the next, so
# the figures are taken in BENCH_SIM_ROUNDS (default 5; BENCH_SIM_REPEAT is read as the
# same) interleaved rounds, each round running every measurement once, and reported as the
# median and range over the rounds, the --jobs 2 speed-up as the median of each round's own
# ratio (both runs of one round see the same machine). Per round:
#  - recording on one core: `tactile sim --trials 10 --jobs 1` (one worker thread)
#    recorded vs --no-bag, as simulated time / wall time and / CPU time (user + sys);
#  - one run of the scenario as a command: the same for `--trials 1`, process start included;
#  - --jobs 2 vs --jobs 1 for the 10 trials, next to what the machine gives two
#    independent single-threaded processes (`--trials 5 --jobs 1` twice at once vs once
#    alone): the ceiling of any 2-worker speed-up on this machine and workload.
# The pictures are off (--no-png): they are not part of recording. Every round's figures
# are kept in OUT_DIR/sim_rounds.tsv.
echo "== tactile sim: recording, --jobs 1 vs --jobs 2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
scenario="${BENCH_SIM_SCENARIO:-config/scenarios/whisker_three_baffles_fsm.yaml}"
trials="${BENCH_SIM_TRIALS:-10}"
rounds="${BENCH_SIM_ROUNDS:-${BENCH_SIM_REPEAT:-5}}"
[[ -f "$scenario" ]] || { echo "bench: no scenario file '$scenario' (BENCH_SIM_SCENARIO)" >&2; exit 1; }
run_sim() {  # run_sim NAME ARGS...: prints "wall_s cpu_s" of one `tactile sim ARGS`
  local name="$1"; shift
  rm -rf "${tmp:?}/$name"
  local TIMEFORMAT="%R %U %S"  # bash's time keyword: wall, user, sys of the command
  # The command's stderr goes to its own file (the `time` report to another), so a failed
  # run's message is printed here; the caller's guard below stops the script.
  if ! { time tactile sim "$scenario" --out "$tmp/$name" --quiet --no-png "$@" >/dev/null 2>"$tmp/$name.err"; } \
      2>"$tmp/$name.time"; then
    echo "bench: tactile sim $scenario $* failed:" >&2
    cat "$tmp/$name.err" >&2
    return 1
  fi
  awk '{printf "%.3f %.3f\n", $1, $2 + $3}' "$tmp/$name.time"
}
pair() {  # pair: the slower wall time of two `--trials 5 --jobs 1` processes started together
  local a b pid status=0
  run_sim pa --trials 5 --jobs 1 >"$tmp/pa.out" & pid=$!
  run_sim pb --trials 5 --jobs 1 >"$tmp/pb.out" || status=1
  wait "$pid" || status=1
  read -r a _ <"$tmp/pa.out" || true
  read -r b _ <"$tmp/pb.out" || true
  [[ "$status" == 0 && -n "$a" && -n "$b" ]] || return 1
  awk -v a="$a" -v b="$b" 'BEGIN { print (a > b ? a : b) }'
}
sim_s="$(python3 -c 'import sys,yaml; print(yaml.safe_load(open(sys.argv[1]))["duration_s"])' "$scenario" 2>/dev/null \
  || sed -n 's/^duration_s: *\([0-9.]*\).*/\1/p' "$scenario")"
table="$out/sim_rounds.tsv"
printf 'round\tw1\tc1\twn\tcn\tw2\tc2\twb\tcb\two\tco\tws\twp\tload\n' >"$table"
for ((r = 1; r <= rounds; r++)); do
  # A failed run prints its message (run_sim) and leaves its figures empty: the guard stops.
  w1="" wn="" w2="" wb="" wo="" ws="" wp=""
  read -r w1 c1 < <(run_sim jobs1 --trials "$trials" --jobs 1) || true
  read -r wn cn < <(run_sim jobs1_nobag --trials "$trials" --jobs 1 --no-bag) || true
  read -r w2 c2 < <(run_sim jobs2 --trials "$trials" --jobs 2) || true
  read -r wb cb < <(run_sim bag) || true
  read -r wo co < <(run_sim nobag --no-bag) || true
  read -r ws _ < <(run_sim single5 --trials 5 --jobs 1) || true
  wp="$(pair)" || wp=""
  for v in "$w1" "$wn" "$w2" "$wb" "$wo" "$ws" "$wp"; do
    [[ -n "$v" ]] || { echo "bench: a tactile sim run of round $r failed (above)" >&2; exit 1; }
  done
  printf '%d\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$r" "$w1" "$c1" "$wn" "$cn" "$w2" "$c2" \
    "$wb" "$cb" "$wo" "$co" "$ws" "$wp" "$(cut -d' ' -f1 /proc/loadavg)" >>"$table"
done
py=python3
[[ -x .venv/bin/python ]] && py=.venv/bin/python
"$py" src/tactile_cli/bench/bench_sim_summary.py "$table" --sim-s "$sim_s" --trials "$trials" \
  --scenario "$(basename "$scenario" .yaml)" | tee "$out/sim_summary.txt"
echo "load: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
