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
