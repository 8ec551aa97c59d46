#!/usr/bin/env bash
# Builds the libFuzzer harnesses with clang (ASan + UBSan) and runs each for SECONDS
# (default 60; 0 = build only). Installs clang if missing.
#
# Every harness's stored corpus (src/<pkg>/fuzz/corpus/<target>/: seeds and every past
# finding) is also replayed by the normal test suite (test <target>_corpus, built with the
# normal compiler: tactile_add_fuzzer in TactileCommon.cmake), so the harnesses compile in
# every build. Here the fuzzer reads the stored corpus and writes what it discovers to
# build/fuzz/corpus/<target>/; a crash, leak or OOM input is written to
# build/fuzz/findings/ and makes the script fail: fix it, then copy the input into the
# stored corpus as its regression test.
# Usage: scripts/fuzz.sh [SECONDS]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
seconds="${1:-60}"
if ! command -v clang++ >/dev/null || [[ ! -d /usr/lib/llvm-14/lib/clang ]]; then
  SUDO=""; [[ $(id -u) -ne 0 ]] && SUDO="sudo"
  $SUDO apt-get install -y -qq clang libclang-rt-14-dev >/dev/null
fi
scripts/setup.sh >/dev/null
# shellcheck disable=SC1091
source .venv/bin/activate
out="$here/build/fuzz"
mkdir -p "$out/findings"
export CC=clang CXX=clang++
# ccache where installed, keyed relative to the workspace, so a rebuild (CI after CI, another
# clone) takes seconds instead of ~7 minutes.
launcher=()
if command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$here}" CCACHE_NOHASHDIR=1
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
log="$out/build.log"
# Every library is built with the fuzzer's coverage instrumentation and the sanitizers, not
# only the harness: libFuzzer is blind to (and ASan silent in) uninstrumented code, which
# is where the parsers under test live (fuzz_mcap saw 31 PCs, its harness alone, without).
san="-fsanitize=fuzzer-no-link,address,undefined"
export ASAN_OPTIONS=detect_leaks=0  # for anything the build itself runs
if ! colcon build --packages-up-to whisker_driver tactile_msgs crazyflie_bridge tactile_bag tactile_sim --build-base "$out/build" \
  --install-base "$out/install" --event-handlers console_cohesion+ summary- \
  --cmake-args -DBUILD_TESTING=OFF -DTACTILE_BUILD_BENCHMARKS=OFF -DTACTILE_FUZZ=ON "${launcher[@]}" \
  "-DCMAKE_CXX_FLAGS=$san" "-DCMAKE_C_FLAGS=$san" \
  -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined -DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=address,undefined \
  -DWHISKER_DRIVER_FUZZ=ON -DTACTILE_MSGS_FUZZ=ON -DCRAZYFLIE_BRIDGE_FUZZ=ON -DTACTILE_BAG_FUZZ=ON -DTACTILE_SIM_FUZZ=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo >"$log" 2>&1; then
  grep -E "error|Error" "$log" | head -40 >&2
  echo "fuzz.sh: the clang build failed (full log: $log)" >&2
  exit 1
fi
echo "== fuzz targets built with clang ($out/build)"
[[ "$seconds" == 0 ]] && exit 0

status=0
for h in whisker_driver/fuzz_frame_parser:512 tactile_msgs/fuzz_cdr:4096 crazyflie_bridge/fuzz_crtp:64 \
         tactile_bag/fuzz_mcap:65536 tactile_bag/fuzz_sqlite:65536 tactile_sim/fuzz_scenario:4096; do
  target="${h%%:*}"; len="${h##*:}"
  pkg="${target%%/*}"; name="${target##*/}"
  exe="$out/build/$pkg/$name"
  work="$out/corpus/$name"
  mkdir -p "$work"
  dirs=("$work")
  [[ -d "src/$pkg/fuzz/corpus/$name" ]] && dirs+=("src/$pkg/fuzz/corpus/$name")
  echo "== $name for ${seconds}s"
  set +e
  ASAN_OPTIONS= nice -n 10 "$exe" "${dirs[@]}" -max_total_time="$seconds" -max_len="$len" -rss_limit_mb=2048 \
    -artifact_prefix="$out/findings/$name-" -print_final_stats=1 >"$out/$name.log" 2>&1
  rc=$?
  set -e
  grep -E "^Done|stat::number_of_executed_units|ERROR|SUMMARY|Test unit written" "$out/$name.log" || true
  if [[ $rc -ne 0 ]]; then
    echo "fuzz.sh: $name found a failure (exit $rc; log $out/$name.log, input in $out/findings/)" >&2
    status=1
  fi
done
exit $status
