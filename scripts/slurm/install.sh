#!/usr/bin/env bash
# Installs what the sharded-sweep scripts and their test need on Debian 12: Slurm's
# controller, node daemon and client commands, and MUNGE (its authentication), from
# Debian's packages (slurm-wlm 22.05). Idempotent. Not part of scripts/setup.sh: most
# users submit to their lab's cluster and need none of it; CI installs it for the test
# (src/tactile_cli/test/python/test_slurm_sweep.py) and scripts/slurm/local_cluster.sh.
# local_cluster.sh runs the daemons from a directory of its own and does not use the
# packages' services; on a machine with systemd, slurmctld and slurmd fail to start until
# /etc/slurm/slurm.conf exists, and munge's service starts with the key its package made.
set -euo pipefail
pkgs=(slurmctld slurmd slurm-client munge)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "slurm/install: Slurm and MUNGE present"
  exit 0
fi
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
echo "slurm/install: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
