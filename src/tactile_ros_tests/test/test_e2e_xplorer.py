"""End to end over DDS, paper 001: launch/sitl_xplorer.launch.py flies the box traversal
(xplorer_box_traversal, mission explore) through the rclcpp components (simulator,
xplorer_force_est, xplorer_fsm, xplorer_mapping; simulated time on /clock); the recorded
odometry, body wrench, arm IMUs and FSM states are evaluated by `tactile evaluate` (loop
closure, the contact map rebuilt by the mapping logic and measured as `tactile sim` does)
and compared with `tactile sim` of the same scenario in process:

- the loop closes over DDS whenever it closes in process (success per seed equal);
- the map's area accuracy is >= 0.97 (001: 96.72 %; the in-process SITL tests ask
  0.97-0.98) and within the in-process spread widened by AREA_MARGIN;
- the recorder lost at most 2 % of the body-wrench samples.

The pipeline's real-time factor and setpoint ages are reported in e2e_xplorer.json, not
asserted (README "End to end over DDS").
"""

from __future__ import annotations

import json
import os

import pytest

pytestmark = pytest.mark.e2e

from e2e import WORKSPACE, fly_over_dds, sim_in_process, spread

SCENARIO = WORKSPACE / 'config' / 'scenarios' / 'xplorer_box_traversal.yaml'
IN_PROCESS_SEEDS = [1, 2, 3, 4, 5]  # with the DDS seeds (2 s each)
DDS_SEEDS = [int(s) for s in os.environ.get('TACTILE_E2E_XPLORER_SEEDS', '1').split(',')]
FACTOR = float(os.environ.get('TACTILE_E2E_FACTOR', '2.0'))
AREA_MARGIN = 0.01
WRENCH_TOPIC = '/xplorer/wrench_body'


@pytest.fixture(scope='module')
def in_process(tmp_path_factory):
    out = tmp_path_factory.mktemp('in_process_xplorer')
    seeds = sorted(set(IN_PROCESS_SEEDS) | set(DDS_SEEDS))
    return {s: sim_in_process(SCENARIO, s, out / f'seed_{s}') for s in seeds}


@pytest.fixture(scope='module')
def report(tmp_path_factory):
    rows = {}
    yield rows
    path = tmp_path_factory.getbasetemp() / 'e2e_xplorer.json'
    path.write_text(json.dumps(rows, indent=2) + '\n')
    print(f'\nend to end over DDS (xplorer_box_traversal, factor {FACTOR}): {path}')
    for seed, r in rows.items():
        print(f'  seed {seed}: {json.dumps(r)}')


KEYS = ('loop_closed', 'loop_closure_time_s', 'map_area_accuracy', 'map_length_m', 'map_width_m',
        'turns_recontacted', 'final_state')


@pytest.mark.parametrize('seed', DDS_SEEDS)
def test_xplorer_box_over_dds_matches_in_process(seed, in_process, report, tmp_path):
    flight = fly_over_dds('sitl_xplorer.launch.py', SCENARIO, 'xplorer', seed, FACTOR,
                          tmp_path / 'dds', extra_args=[f'ply_file:={tmp_path / "map.ply"}'])
    dds = flight.metrics
    ref = in_process[seed]
    area = [m['xplorer']['map_area_accuracy'] for m in in_process.values()]
    report[seed] = {
        'dds': {k: dds['xplorer'].get(k) for k in KEYS} | {'success': dds['success']},
        'in_process': {k: ref['xplorer'].get(k) for k in KEYS} | {'success': ref['success']},
        'in_process_spread': {'map_area_accuracy': [min(area), max(area)],
                              'success': sum(m['success'] for m in in_process.values())},
        'pipeline': flight.sim_line,
        'wrench_samples': [dds['topics'].get(WRENCH_TOPIC, 0), ref['topics'].get(WRENCH_TOPIC, 0)],
        'wall_s': round(flight.wall_s, 1),
    }
    assert flight.sim_line, 'the simulator did not log its end line'
    assert dds['topics'].get(WRENCH_TOPIC, 0) >= 0.98 * ref['topics'][WRENCH_TOPIC]
    assert dds['success'] == ref['success']
    assert dds['xplorer']['loop_closed'] == ref['xplorer']['loop_closed']
    assert dds['xplorer']['map_area_accuracy'] >= 0.97
    lo, hi = spread(area, AREA_MARGIN)
    assert lo <= dds['xplorer']['map_area_accuracy'] <= hi
