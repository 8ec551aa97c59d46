"""Independent check of mapping_pcl's PLY files: plyfile (PyPI) and PCL's own
reader open the ASCII and binary little-endian files with the expected point
count and bounds, computed here from the box definition (not from the C++)."""
import math
import os
import subprocess

import numpy as np
import pytest
from plyfile import PlyData

TOOL = os.environ.get("MAPPING_PLY_TOOL")

# The box written by mapping_ply_tool (test/mapping_ply_tool.cpp).
CENTER = np.array([1.5, -0.5, 0.7])
SIZE = np.array([1.22, 0.08, 0.5])
SPACING = 0.02


def expected_counts():
    return [max(2, math.ceil(s / SPACING - 1e-9) + 1) for s in SIZE]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    if not TOOL:
        pytest.skip("MAPPING_PLY_TOOL not set (run through ctest)")
    prefix = str(tmp_path_factory.mktemp("ply") / "box")
    subprocess.run([TOOL, "box", prefix], check=True)
    return {"ascii": prefix + "_ascii.ply", "binary": prefix + "_binary.ply"}


@pytest.mark.parametrize("fmt", ["ascii", "binary"])
def test_plyfile_reads_count_and_bounds(files, fmt):
    ply = PlyData.read(files[fmt])
    assert ply.text == (fmt == "ascii")
    if fmt == "binary":
        assert ply.byte_order == "<"
    v = ply["vertex"]
    n = expected_counts()
    assert len(v) == n[0] * n[1] * n[2] == 62 * 5 * 26
    xyz = np.stack([v["x"], v["y"], v["z"]], axis=1).astype(np.float64)
    assert xyz.dtype == np.float64 and v["x"].dtype == np.float32
    np.testing.assert_allclose(xyz.min(axis=0), CENTER - SIZE / 2, atol=1e-6)
    np.testing.assert_allclose(xyz.max(axis=0), CENTER + SIZE / 2, atol=1e-6)
    # Grid spacing along x is size / (n - 1).
    xs = np.unique(np.round(xyz[:, 0], 6))
    np.testing.assert_allclose(np.diff(xs), SIZE[0] / (n[0] - 1), atol=1e-5)
    comments = " ".join(ply.comments)
    assert "frame map" in comments and "units m" in comments


def test_ascii_and_binary_hold_the_same_points(files):
    a = PlyData.read(files["ascii"])["vertex"]
    b = PlyData.read(files["binary"])["vertex"]
    for c in "xyz":
        np.testing.assert_array_equal(a[c], b[c])  # 9 significant digits round-trip float32


@pytest.mark.parametrize("fmt", ["ascii", "binary"])
def test_pcl_reads_the_file(files, fmt):
    out = subprocess.run([TOOL, "read", files[fmt]], check=True, capture_output=True, text=True).stdout.split()
    n = expected_counts()
    assert int(out[0]) == n[0] * n[1] * n[2]
    vals = np.array([float(x) for x in out[1:]])
    np.testing.assert_allclose(vals[:3], CENTER - SIZE / 2, atol=1e-5)
    np.testing.assert_allclose(vals[3:], CENTER + SIZE / 2, atol=1e-5)
