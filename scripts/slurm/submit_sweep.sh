#!/usr/bin/env bash
# Submits a sharded `tactile sweep` to Slurm: an array job of M shards, then the merge
# (--dependency=afterok: it runs only when every shard succeeded). Prints the two job ids.
#
#   scripts/slurm/submit_sweep.sh FAMILY COUNT SEED M OUT [-- tactile sweep args...]
#   e.g. scripts/slurm/submit_sweep.sh baffles_mocap 10000 5000 100 /shared/sweep -- --no-bag --config /shared/config
#
# OUT must be on a file system every node sees. Results: OUT/merged/{table,summary}.{csv,md,json};
# each shard's log in OUT/logs/. Extra sbatch options (partition, time, account) through
# the SBATCH_* environment variables Slurm reads (e.g. SBATCH_PARTITION, SBATCH_TIMELIMIT).
# A shard that failed: fix, then `sbatch --array=K scripts/slurm/sweep.sbatch FAMILY COUNT
# SEED M OUT ...` and `sbatch scripts/slurm/merge.sbatch M OUT`.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
if (($# < 5)); then
  echo "usage: $0 FAMILY COUNT SEED M OUT [-- tactile sweep args...]" >&2
  exit 2
fi
what="$1" count="$2" seed="$3" shards="$4" out="$5"
shift 5
if (($# > 0)) && [[ "$1" == "--" ]]; then shift; fi
if ! [[ "$shards" =~ ^[1-9][0-9]*$ ]]; then
  echo "submit_sweep: M must be a positive whole number, got '$shards'" >&2
  exit 2
fi
mkdir -p "$out/logs"
out="$(cd "$out" && pwd)"
# Arguments that are not --config go to the shards only; --config DIR to both.
merge_args=()
args=("$@")
for ((i = 0; i < ${#args[@]}; ++i)); do
  if [[ "${args[i]}" == "--config" ]] && ((i + 1 < ${#args[@]})); then merge_args+=(--config "${args[i + 1]}"); fi
done
array_id="$(sbatch --parsable --array="1-$shards" --output="$out/logs/shard_%a.out" \
  "$here/sweep.sbatch" "$what" "$count" "$seed" "$shards" "$out" "$@")"
array_id="${array_id%%;*}"
merge_id="$(sbatch --parsable --dependency="afterok:$array_id" --output="$out/logs/merge.out" \
  "$here/merge.sbatch" "$shards" "$out" "${merge_args[@]}")"
merge_id="${merge_id%%;*}"
echo "shards: job $array_id (array 1-$shards), merge: job $merge_id -> $out/merged"
