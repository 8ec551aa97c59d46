#!/usr/bin/env bash
# Reproduce src/tactile_depth/models/default_model.json (paper 000 tactile-depth sensor
# model) from the SITL: fly the whiteboard and glass datasets (12 flights each, seeds
# 1..12), train the MLP and the baselines, write the model and the Table 1/S1-style report.
#
#   tools/reproduce_default_model.sh [OUT_DIR]      (default: a new temporary directory)
#
# Needs `tactile` on PATH (a built and sourced workspace: source <install>/setup.bash) and
# a Python with numpy, scikit-learn and rosbags (the workspace's .venv). Builds nothing.
# Environment: TACTILE_CONFIG_DIR (default: the repository's config/), PYTHON (default
# python3), MODEL_OUT (default: OUT_DIR/default_model.json; set it to the package's
# models/default_model.json to update the shipped file).
set -euo pipefail

TOOLS="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "${TOOLS}/../../.." && pwd)"
CONFIG="${TACTILE_CONFIG_DIR:-${REPO}/config}"
PY="${PYTHON:-python3}"
OUT="${1:-$(mktemp -d -t tactile_depth_model.XXXXXX)}"
MODEL_OUT="${MODEL_OUT:-${OUT}/default_model.json}"

command -v tactile >/dev/null || { echo "tactile not on PATH: source the workspace's install/setup.bash" >&2; exit 1; }
mkdir -p "${OUT}"
echo "output directory: ${OUT}"

for ds in whiteboard glass; do
  "${PY}" "${TOOLS}/make_dataset.py" --scenario "${CONFIG}/scenarios/depth_${ds}.yaml" --flights 12 \
    --first-seed 1 --out "${OUT}/${ds}" --config "${CONFIG}" --no-keep-runs | grep -v '^outputs in'
done

"${PY}" "${TOOLS}/train_depth_model.py" \
  --dataset "whiteboard=${OUT}/whiteboard/dataset.npz" --dataset "glass=${OUT}/glass/dataset.npz" \
  --train-on all --seed 0 --input calibrated --out "${OUT}/report" --model-out "${MODEL_OUT}"

echo "model:  ${MODEL_OUT}"
echo "report: ${OUT}/report/report.md, ${OUT}/report/report.json"
