"""`tactile params` (issue 33, item 4): each node's parameter schema from its
default_parameters(), as a markdown table or as a ROS 2 parameter file."""
import os
import subprocess

import yaml

TACTILE = os.environ["TACTILE_EXE"]


def params(*args):
    return subprocess.run([TACTILE, "params", *args], capture_output=True, text=True, timeout=60)


def listed_nodes():
    r = params()
    assert r.returncode == 0, r.stderr
    return {line.split()[0]: int(line.split()[1]) for line in r.stdout.splitlines()}


def test_without_node_lists_every_node_with_its_count():
    nodes = listed_nodes()
    assert {"tdorc_filter", "whisker_fsm", "crazyflie_bridge", "tactile_sim", "xplorer_mapping"} <= set(nodes)
    assert len(nodes) == 16
    assert all(n > 0 for n in nodes.values())


def test_unknown_node_is_exit_2_naming_the_known_ones():
    r = params("tdorc_filtr")
    assert r.returncode == 2, r.stdout + r.stderr
    assert r.stdout == ""
    assert "tactile params: error: unknown node 'tdorc_filtr' (known: crazyflie_bridge, " in r.stderr, r.stderr
    # nothing is printed for the known node given with it either
    r = params("tdorc_filter", "nope")
    assert r.returncode == 2 and r.stdout == ""


def test_markdown_is_one_table_row_per_parameter():
    nodes = listed_nodes()
    r = params("tdorc_filter", "--format", "markdown")
    assert r.returncode == 0, r.stderr
    rows = [line for line in r.stdout.splitlines() if line.startswith("| `")]
    assert len(rows) == nodes["tdorc_filter"]
    assert "| key | type | default | range | unit | live | source | description |" in r.stdout
    # where the value comes from: "paper: <paper and equation>", "choice" or "tuned: <measurement>"
    assert "| read-only | paper: 000 eq. 6-7, Methods: sliding window n = 100 | n, samples" in r.stdout


def test_yaml_is_a_parameter_file_of_every_key_at_its_default():
    nodes = listed_nodes()
    r = params("tdorc_filter", "tactile_depth", "--format", "yaml")
    assert r.returncode == 0, r.stderr
    doc = yaml.safe_load(r.stdout)  # PyYAML (YAML 1.1), as launch_ros reads parameter files
    tdorc = doc["/**/tdorc_filter"]["ros__parameters"]
    assert len(tdorc) == nodes["tdorc_filter"]
    assert len(doc["/**/tactile_depth"]["ros__parameters"]) == nodes["tactile_depth"]
    assert tdorc["window"] == 100 and isinstance(tdorc["window"], int)
    assert tdorc["contact_threshold"] == 20.0 and isinstance(tdorc["contact_threshold"], float)
    assert tdorc["mode"] == "tdorc"
    assert "    # n, samples in the least-squares drift window" in r.stdout
    assert "    # source: paper\n    # evidence: 000 eq. 6-7, Methods: sliding window n = 100\n    window: 100\n" in r.stdout


def test_every_nodes_yaml_reads_back_in_the_declared_types():
    # A double written "5" is an integer to ROS 2 (the wrong type) and YAML 1.1 reads
    # "2e-04" as a string: each key must come back in the type the table declares.
    python_type = {"bool": bool, "integer": int, "double": float, "string": str}
    for node in listed_nodes():
        md = params(node)
        assert md.returncode == 0, md.stderr
        declared = {}
        for line in md.stdout.splitlines():
            if line.startswith("| `"):
                cells = [c.strip() for c in line.split(" | ")]
                declared[cells[0].strip("|` ")] = cells[1]
        r = params(node, "--format", "yaml")
        assert r.returncode == 0, r.stderr
        section = yaml.safe_load(r.stdout)[f"/**/{node}"]["ros__parameters"]
        assert set(section) == set(declared), node
        for key, value in section.items():
            kind = declared[key]
            if kind.endswith(" array"):
                assert isinstance(value, list), f"{node}.{key}: {value!r}"
                items, kind = value, kind[:-len(" array")]
            else:
                items = [value]
            for v in items:
                assert type(v) is python_type[kind], f"{node}.{key}: {v!r} is not a {kind}"
