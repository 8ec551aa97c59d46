#!/usr/bin/env bash
# Builds the libFuzzer harnesses with clang (ASan + UBSan) and runs each for
# SECONDS (default 60). Not part of the tests. Installs clang if missing.
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
mkdir -p "$out"
export CC=clang CXX=clang++
colcon build --packages-up-to whisker_driver tactile_msgs crazyflie_bridge tactile_bag --build-base "$out/build" \
  --install-base "$out/install" --event-handlers console_cohesion- summary- \
  --cmake-args -DBUILD_TESTING=OFF -DTACTILE_BUILD_BENCHMARKS=OFF \
  -DWHISKER_DRIVER_FUZZ=ON -DTACTILE_MSGS_FUZZ=ON -DCRAZYFLIE_BRIDGE_FUZZ=ON -DTACTILE_BAG_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
for h in "$out/build/whisker_driver/fuzz_frame_parser:512" "$out/build/tactile_msgs/fuzz_cdr:4096" \
         "$out/build/crazyflie_bridge/fuzz_crtp:64" "$out/build/tactile_bag/fuzz_mcap:65536"; do
  exe="${h%%:*}"; len="${h##*:}"
  corpus="$out/corpus/$(basename "$exe")"
  mkdir -p "$corpus"
  if [[ "$(basename "$exe")" == fuzz_mcap && -z "$(ls -A "$corpus")" ]]; then
    # seed: small mcap files of every chunk compression
    for c in "" zstd lz4; do
      d="$(mktemp -d)"; rmdir "$d"
      "$out/install/tactile_bag/bin/tactile_bag_tool" write-sample "$d" --storage mcap ${c:+--compression $c} >/dev/null
      cp "$d"/*.mcap "$corpus/seed_${c:-none}.mcap"; rm -rf "$d"
    done
  fi
  echo "== $(basename "$exe") for ${seconds}s"
  "$exe" "$corpus" -max_total_time="$seconds" -max_len="$len" -rss_limit_mb=2048 2>&1 | grep -E "^Done|ERROR|SUMMARY" || true
done
