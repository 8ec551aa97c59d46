"""The package tactile_bringup installs launch/ and config/ (issue 35 item 7):
`ros2 launch tactile_bringup <file>` runs from a directory outside the workspace, and the
installed launch file takes its parameter files and scenarios from the installed
share/tactile_bringup/config, not from the source tree."""

from __future__ import annotations

from pathlib import Path

from launch_check import WORKSPACE, Graph, Launch


def share_dir() -> Path:
    from ament_index_python.packages import get_package_share_directory
    return Path(get_package_share_directory('tactile_bringup'))


def test_installed_files_are_the_workspace_ones():
    share = share_dir()
    assert WORKSPACE not in share.parents or share.parts[len(WORKSPACE.parts)].startswith('install'), share
    for sub in ('launch', 'config'):
        source = sorted(p.relative_to(WORKSPACE / sub) for p in (WORKSPACE / sub).rglob('*')
                        if p.is_file() and '__pycache__' not in p.parts)
        installed = sorted(p.relative_to(share / sub) for p in (share / sub).rglob('*')
                           if p.is_file() and '__pycache__' not in p.parts)
        assert installed == source, (sub, set(source) ^ set(installed))


def test_ros2_launch_tactile_bringup_from_any_directory(tmp_path):
    share = share_dir()
    with Launch('sitl_whisker.launch.py', ['seed:=7', 'real_time_factor:=2.0'],
                tmp_path / 'launch.log', package='tactile_bringup', cwd=tmp_path) as launch, \
            Graph() as g:
        g.wait_for_nodes(['/tactile_sim', '/whisker/left/tdorc_filter', '/tactile_depth',
                          '/whisker_fsm'], launch)
        assert g.wait_for_topic('/whisker/depth') == 'tactile_msgs/msg/TactileDepth'
        sim = g.get_parameters('/tactile_sim', ['scenario', 'tactile.parameter_sources'])
        fsm = g.get_parameters('/whisker_fsm', ['tactile.parameter_sources'])
    scenario = share / 'config' / 'scenarios' / 'whisker_three_baffles_fsm.yaml'
    assert sim['scenario'] == str(scenario)
    assert str(share / 'config' / 'tactile_fsm.yaml') in fsm['tactile.parameter_sources'], fsm
