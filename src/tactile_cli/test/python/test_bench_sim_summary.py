"""The summary of scripts/bench.sh's interleaved `tactile sim` rounds (issue 18 figures),
checked against figures computed by hand from a made-up rounds table."""
import importlib.util
import pathlib

import pytest

_PATH = pathlib.Path(__file__).resolve().parents[2] / "bench" / "bench_sim_summary.py"
_spec = importlib.util.spec_from_file_location("bench_sim_summary", _PATH)
summary = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(summary)

HEADER = "round\tw1\tc1\twn\tcn\tw2\tc2\twb\tcb\two\tco\tws\twp\tload\n"


def write(tmp_path, rows):
    p = tmp_path / "rounds.tsv"
    p.write_text(HEADER + "".join("\t".join(str(v) for v in r) + "\n" for r in rows))
    return p


def test_figures_are_medians_of_rounds_and_the_jobs_ratio_is_per_round(tmp_path, capsys):
    # Three rounds of 10 trials x 75 s = 750 s simulated. Recorded --jobs 1 wall 1.6, 0.75, 1.0 s
    # -> 469x, 1000x, 750x: median 750x, 2 of 3 >= 500x. --jobs 2 wall 1.0, 0.375, 0.5 s: the
    # per-round ratios 1.6, 2.0, 2.0 (median 2.00x, 2 of 3 >= 1.8x); a ratio of the medians
    # (1.0 / 0.5 = 2.0) would hide the slow round.
    rows = [
        (1, 1.6, 1.5, 1.0, 1.0, 1.0, 1.6, 0.25, 0.2, 0.15, 0.1, 0.8, 0.9, "1.0"),
        (2, 0.75, 0.7, 0.6, 0.6, 0.375, 0.8, 0.1, 0.1, 0.1, 0.1, 0.4, 0.4, "0.5"),
        (3, 1.0, 1.0, 0.8, 0.75, 0.5, 1.0, 0.15, 0.1, 0.1, 0.1, 0.5, 0.5, "0.7"),
    ]
    p = write(tmp_path, rows)
    assert summary.main([str(p), "--sim-s", "75", "--trials", "10", "--scenario", "s"]) == 0
    out = capsys.readouterr().out
    assert "3 interleaved rounds" in out
    assert "750x (469x-1000x) real time per wall s" in out
    assert "2 of 3 rounds >= 500x" in out
    assert "each round's ratio: 2.00x (1.60x-2.00x); 2 of 3 rounds >= 1.8x" in out
    # ceiling 2 * ws / wp: 2*0.8/0.9 = 1.78, 2.0, 2.0
    assert "alone): 2.00x (1.78x-2.00x)" in out
    # recording share (c1 - cn) / c1: 33 %, 14 %, 25 % -> median 25 %
    assert "recording costs 25 % (14 %-33 %)" in out


def test_a_failed_run_names_the_file_line_and_round(tmp_path):
    p = tmp_path / "rounds.tsv"
    p.write_text(HEADER + "1\t1.0\t1.0\t1.0\t1.0\t0.5\t1.0\t0.1\t0.1\t0.1\t0.1\t0.5\t0.5\t0.1\n"
                 "2\t\t\t\t\t\t\t\t\t\t\t\t\t0.1\n")
    with pytest.raises(SystemExit, match=r"rounds.tsv:3: round 2: missing or bad figure"):
        summary.main([str(p), "--sim-s", "75", "--trials", "10"])


def test_no_rounds_is_an_error(tmp_path):
    p = write(tmp_path, [])
    with pytest.raises(SystemExit, match="no rounds"):
        summary.main([str(p), "--sim-s", "75", "--trials", "10"])


def test_a_zero_cpu_time_is_named_not_divided_by(tmp_path):
    p = write(tmp_path, [(1, 1.0, 0.0, 1.0, 1.0, 0.5, 1.0, 0.1, 0.1, 0.1, 0.1, 0.5, 0.5, "0.1")])
    with pytest.raises(SystemExit, match=r"rounds.tsv:2: round 1: c1 not positive"):
        summary.main([str(p), "--sim-s", "75", "--trials", "10"])
