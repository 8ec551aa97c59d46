"""Node parameter files under `--config DIR` (issue 32, item 2).

A missing, empty, directory or misnamed `<node>.yaml` ran the node on its
compiled defaults without a word: with `tdorc_filter.yaml` removed the
three-baffle course went from a success to a collision with exit status 0,
and `tactile demo` ran the same way. Every case is now an error (exit 1) that
names the file and the reason, before anything is flown or written.
"""
import os
import shutil
import subprocess
from pathlib import Path

import pytest

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = Path(os.environ["TACTILE_CONFIG_DIR"])
SCENARIO = CONFIG / "scenarios" / "whisker_three_baffles_fsm.yaml"


def config_copy(tmp_path):
    """The repository's node parameter files and parameter profiles (not the scenarios) in a
    temporary directory."""
    d = tmp_path / "config"
    d.mkdir()
    for f in CONFIG.glob("*.yaml"):
        shutil.copy(f, d / f.name)
    shutil.copytree(CONFIG / "profiles", d / "profiles")
    return d


def break_file(path, case):
    if case == "missing":
        path.unlink()
    elif case == "empty":
        path.write_text("# parameters of TDORC\n")
    elif case == "directory":
        path.unlink()
        path.mkdir()
    elif case == "misnamed":  # the section names another node (a typo)
        path.write_text(path.read_text().replace("/**/tdorc_filter:", "/**/tdorc_filtr:"))
    else:
        raise ValueError(case)


REASONS = {
    "missing": "parameter file of node /whisker/left/tdorc_filter missing (no such file)",
    "empty": "empty parameter file: expected a 'tdorc_filter:' (or '/**/tdorc_filter:') section",
    "directory": "parameter file of node /whisker/left/tdorc_filter is not a file (a directory)",
    "misnamed": "no section for node /whisker/left/tdorc_filter",
}


@pytest.mark.parametrize("case", sorted(REASONS))
def test_broken_parameter_file_is_an_error_naming_file_and_reason(tmp_path, case):
    cfg = config_copy(tmp_path)
    target = cfg / "tdorc_filter.yaml"
    break_file(target, case)
    out = tmp_path / "out"
    r = subprocess.run([TACTILE, "--config", str(cfg), "sim", str(SCENARIO), "--out", str(out), "--quiet",
                        "--no-png"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 1, r.stdout + r.stderr
    assert f"tactile: error: {target}: {REASONS[case]}" in r.stderr, r.stderr
    assert not (out / "metrics.json").exists()


# The other commands that read --config DIR and run the whisker front end: `demo`
# ran on defaults too; `sweep` wrote a table of N "error" rows and exited 0.
@pytest.mark.parametrize("command", [["demo", "--hover", "30", "--seed", "7"],
                                     ["sweep", "rooms", "--count", "2", "--seed", "1003", "--no-bag", "--quiet"]])
def test_other_commands_with_a_missing_parameter_file_fail(tmp_path, command):
    cfg = config_copy(tmp_path)
    break_file(cfg / "tdorc_filter.yaml", "missing")
    r = subprocess.run([TACTILE, "--config", str(cfg), *command, "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 1, r.stdout + r.stderr
    assert f"{cfg / 'tdorc_filter.yaml'}: {REASONS['missing']}" in r.stderr, r.stderr


def test_intact_copy_flies_the_course(tmp_path):
    """The copy itself is complete: the same command succeeds with it (the errors above are the file's)."""
    cfg = config_copy(tmp_path)
    out = tmp_path / "out"
    r = subprocess.run([TACTILE, "--config", str(cfg), "sim", str(SCENARIO), "--out", str(out), "--quiet",
                        "--no-png"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    assert (out / "metrics.json").exists()
