#!/usr/bin/env bash
# Builds the whole workspace and runs every test (C++ gtest, Python peer tests).
# Usage: scripts/test.sh            (from anywhere; works on a fresh Debian 12 clone)
# Exit status is non-zero when the build or any test fails.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"

scripts/setup.sh
# shellcheck disable=SC1091
source .venv/bin/activate
export MAKEFLAGS="-j$(nproc)"
# ccache (installed by setup.sh), keyed relative to the workspace as the ROS and fuzz builds
# are, so a fresh clone (CI after CI) rebuilds in ~2 minutes instead of ~20 on 2 cores.
if command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$here}" CCACHE_NOHASHDIR=1
  export CMAKE_C_COMPILER_LAUNCHER="${CMAKE_C_COMPILER_LAUNCHER:-ccache}"
  export CMAKE_CXX_COMPILER_LAUNCHER="${CMAKE_CXX_COMPILER_LAUNCHER:-ccache}"
fi

colcon build --event-handlers console_cohesion- summary+

status=0
colcon test --event-handlers console_cohesion- summary+ --return-code-on-test-failure || status=$?

# Per-test results of every package (failures with their output), then one plain summary line.
summary="$(colcon test-result --verbose --all 2>&1)" || true
echo "$summary" | grep -v '^build/.*: [0-9]* tests, 0 errors, 0 failures' || true
line="$(echo "$summary" | grep -E '^Summary: [0-9]+ tests' | tail -n 1)"
total=$(echo "$line" | sed -E 's/Summary: ([0-9]+) tests.*/\1/')
errors=$(echo "$line" | sed -E 's/.* ([0-9]+) errors?,.*/\1/')
failures=$(echo "$line" | sed -E 's/.* ([0-9]+) failures?,.*/\1/')
skipped=$(echo "$line" | sed -E 's/.* ([0-9]+) skipped.*/\1/')
failed=$((errors + failures))
passed=$((total - failed - skipped))
if [[ -z "$total" || "$total" -eq 0 ]]; then
  echo "no test results found" >&2
  exit 1
fi
if (( failed > 0 )); then status=1; fi
echo "${passed} passed, ${failed} failed, ${skipped} skipped"
exit "$status"
