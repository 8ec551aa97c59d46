"""A sharded `tactile sweep` on a real Slurm (issue 36): a single-node cluster (munged,
slurmctld, slurmd from Debian's packages, started by scripts/slurm/local_cluster.sh in a
directory of its own) runs scripts/slurm/submit_sweep.sh's array job of shards and the
dependent merge; the merged table and summary equal the single-machine sweep of the same
seeds, timings and provenance aside.

Skipped, saying why, where Slurm or MUNGE is not installed (scripts/slurm/install.sh);
with TACTILE_REQUIRE_SLURM=1 (CI) a missing Slurm is a failure instead."""
import csv
import json
import os
import pathlib
import shutil
import socket
import subprocess
import tempfile
import time

import pytest

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = os.environ["TACTILE_CONFIG_DIR"]
REPO = pathlib.Path(__file__).resolve().parents[4]
SLURM = REPO / "scripts" / "slurm"
TOOLS = ["munged", "mungekey", "slurmctld", "slurmd", "sbatch", "squeue", "sinfo"]


def _which(tool):
    return shutil.which(tool) or shutil.which(tool, path="/usr/sbin:/usr/bin")


def _require_slurm():
    missing = [t for t in TOOLS if not _which(t)]
    if missing:
        why = f"Slurm/MUNGE not installed ({', '.join(missing)} missing): scripts/slurm/install.sh"
        if os.environ.get("TACTILE_REQUIRE_SLURM") == "1":
            pytest.fail(why)
        pytest.skip(why)


def _free_port_pair():
    """A port p with p and p + 1 free (slurmctld, slurmd)."""
    for _ in range(50):
        with socket.socket() as s:
            s.bind(("", 0))
            p = s.getsockname()[1]
        if p >= 65535:
            continue
        try:
            with socket.socket() as s:
                s.bind(("", p + 1))
            return p
        except OSError:
            continue
    pytest.fail("no two consecutive free TCP ports")


def _table(path):
    """table.csv rows without the wall_time_s column (a timing)."""
    rows = list(csv.reader(open(path)))
    col = rows[0].index("wall_time_s")
    return [r[:col] + r[col + 1:] for r in rows]


def _summary(path):
    j = json.loads(pathlib.Path(path).read_text())
    for k in ("date", "machine", "load_average_at_start", "jobs", "wall_time_s", "merged_shards"):
        j.pop(k, None)
    return j


def test_sharded_sweep_on_a_local_slurm_cluster(tmp_path):
    _require_slurm()
    count, seed, shards = 6, 7000, 3
    args = ["--no-bag", "--config", CONFIG]
    subprocess.run([TACTILE, "sweep", "baffles_mocap", "--count", str(count), "--seed", str(seed), "--quiet",
                    "--out", str(tmp_path / "local"), *args], check=True, capture_output=True, text=True)

    # A short directory: MUNGE's socket path must fit a sockaddr_un (108 bytes).
    cluster = pathlib.Path(tempfile.mkdtemp(prefix="tslurm"))
    env = dict(os.environ, SLURM_LOCAL_PORT=str(_free_port_pair()), TACTILE=TACTILE)
    env["PATH"] = env.get("PATH", "") + ":/usr/sbin"
    start = subprocess.run([str(SLURM / "local_cluster.sh"), "start", str(cluster)], env=env, capture_output=True,
                           text=True, timeout=120)
    assert start.returncode == 0, start.stderr
    env["SLURM_CONF"] = str(cluster / "etc" / "slurm.conf")
    try:
        out = tmp_path / "slurm"
        sub = subprocess.run([str(SLURM / "submit_sweep.sh"), "baffles_mocap", str(count), str(seed), str(shards),
                              str(out), "--", *args], env=env, capture_output=True, text=True, timeout=60)
        assert sub.returncode == 0, sub.stderr
        # "shards: job A (array 1-3), merge: job B -> OUT/merged"
        words = sub.stdout.split()
        array_id, merge_id = words[2], words[7].rstrip(",")
        assert array_id.isdigit() and merge_id.isdigit(), sub.stdout
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline:
            q = subprocess.run(["squeue", "-h", "-j", f"{array_id},{merge_id}", "-o", "%i %T"], env=env,
                               capture_output=True, text=True)
            if q.returncode == 0 and not q.stdout.strip():
                break
            time.sleep(0.5)
        else:
            pytest.fail(f"the Slurm jobs did not finish in 300 s: {q.stdout}")
        logs = out / "logs"
        for k in range(1, shards + 1):
            # Each shard ran as its own array task and flew exactly its share.
            log = (logs / f"shard_{k}.out").read_text()
            assert f"shard_{k}" in log, log
            rec = json.loads((out / f"shard_{k}" / "shard.json").read_text())
            assert rec["shard"] == k and rec["shards"] == shards
            assert rec["indices"] == list(range(k - 1, count, shards))
            assert len(rec["rows"]) == len(rec["indices"])
        assert (logs / "merge.out").exists(), os.listdir(logs)
        merged = out / "merged"
        assert (merged / "summary.json").exists(), (logs / "merge.out").read_text()
        local = tmp_path / "local"
        assert _table(local / "table.csv") == _table(merged / "table.csv")
        assert (local / "table.md").read_text() == (merged / "table.md").read_text()
        assert _summary(local / "summary.json") == _summary(merged / "summary.json")
        assert len(json.loads((merged / "summary.json").read_text())["merged_shards"]) == shards
        assert (local / "scenarios" / "index.json").read_bytes() == (merged / "scenarios" / "index.json").read_bytes()
        assert sorted(os.listdir(local / "runs")) == sorted(os.listdir(merged / "runs"))
    finally:
        subprocess.run([str(SLURM / "local_cluster.sh"), "stop", str(cluster)], env=env, capture_output=True,
                       timeout=60)
        shutil.rmtree(cluster, ignore_errors=True)
