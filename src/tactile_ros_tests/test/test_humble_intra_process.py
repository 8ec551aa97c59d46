"""The launch graphs start on ROS 2 Humble: no non-volatile publisher under intra-process.

The launch files compose each graph in one container with use_intra_process_comms: true.
Humble's rclcpp throws "intraprocess communication allowed only with volatile durability"
for a transient-local publisher or subscription created with intra-process on (rclcpp 16.x
publisher.hpp / subscription.hpp); Jazzy and Kilted accept it (rclcpp PR 2303), so the
graphs start on the distros tested here whether or not a component gets it wrong. Humble
cannot be built here, so these tests check the condition itself, on Kilted or Jazzy:

- test_launch_graph_has_no_non_volatile_intra_process_publisher: each launch file that
  composes components is started, and the test component IntraProcessQosProbe
  (intra_process_qos_probe.cpp) is loaded into its container with use_intra_process_comms
  true (composition_interfaces/LoadNode, as `ros2 component load` does). The probe looks
  every publisher of the graph up in the container's IntraProcessManager by its GID and
  fails to load, naming topic and node, if one that rclcpp delivers intra-process is not
  volatile. Its report (parameter `report`) must also show the graph's latched publishers
  (transient local, not intra-process) and a volatile publisher of the graph that is
  intra-process: the lookup itself works, so the test cannot pass by seeing nothing.
- test_every_component_is_checked: the launch cases above load every rclcpp component
  the workspace registers (ament index, rclcpp_components).
- test_no_transient_local_outside_ros_qos: the probe cannot tell an intra-process
  subscription from the graph, so the component sources must not name transient local
  (publisher or subscription) except through tactile_common/ros_qos.hpp's
  latched_publisher() and latched_subscription(), which turn intra-process off for that
  publisher or subscription.
"""

from __future__ import annotations

import os
import re

import pytest

from launch_check import CONFIG_DIR, WORKSPACE, Graph, Launch, unique_port, HAVE_TF2

PROBE_PLUGIN = 'tactile_ros_tests::IntraProcessQosProbe'

# launch file, arguments, the container, the nodes to wait for, a topic the graph publishes
# once running (the simulator creates its sensor publishers on its first step), the
# component plugins it loads, its latched publishers {topic: node}, and a volatile topic of
# a component in the container that must read intra-process (None: the container runs
# without intra-process).
CASES = {
    'sitl_whisker': dict(
        launch='sitl_whisker.launch.py', args=['seed:=7'], container='/sitl_whisker_container',
        nodes=['/tactile_sim', '/whisker/left/tdorc_filter', '/whisker/right/tdorc_filter',
               '/tactile_depth', '/whisker_fsm'],
        ready='/whisker/depth',
        plugins={'tactile_sim::TactileSimComponent', 'tdorc_filter::TdorcFilterComponent',
                 'tactile_depth::TactileDepthComponent', 'tactile_fsm::WhiskerFsmComponent'},
        latched={'/sim/done': '/tactile_sim'}, intra=('/whisker/left/signal', '/whisker/left/tdorc_filter')),
    'sitl_explore': dict(
        launch='sitl_explore.launch.py', args=['seed:=3'], container='/sitl_explore_container',
        nodes=['/tactile_sim', '/tactile_depth', '/gpis_explorer'], ready='/whisker/depth',
        plugins={'tactile_sim::TactileSimComponent', 'tdorc_filter::TdorcFilterComponent',
                 'tactile_depth::TactileDepthComponent', 'gpis_explorer::GpisExplorerComponent'},
        latched={'/sim/done': '/tactile_sim', '/gpis/map': '/gpis_explorer', '/gpis/target': '/gpis_explorer'},
        intra=('/whisker/depth', '/tactile_depth')),
    'sitl_xplorer': dict(
        launch='sitl_xplorer.launch.py', args=['mission:=static_wrench'], container='/sitl_xplorer_container',
        nodes=['/tactile_sim', '/xplorer_force_est', '/xplorer_fsm', '/xplorer_mapping'],
        ready='/xplorer/wrench_body',
        plugins={'tactile_sim::TactileSimComponent', 'xplorer_force_est::XplorerForceEstComponent',
                 'tactile_fsm::XplorerFsmComponent', 'mapping_pcl::XplorerMapComponent'},
        latched={'/sim/done': '/tactile_sim'}, intra=('/xplorer/wrench_body', '/xplorer_force_est')),
    'sitl_wall_effect_navigation': dict(
        launch='sitl_wall_effect.launch.py', args=[], container='/sitl_wall_effect_container',
        nodes=['/tactile_sim', '/wall_effect_ekf', '/indi_controller', '/wall_effect_nav'],
        ready='/wall_effect/estimate',
        plugins={'tactile_sim::TactileSimComponent', 'wall_effect_ekf::WallEffectEkfComponent',
                 'wall_effect_ekf::IndiControlComponent', 'tactile_fsm::WallEffectNavComponent'},
        latched={'/sim/done': '/tactile_sim'}, intra=('/wall_effect/estimate', '/wall_effect_ekf')),
    'sitl_wall_effect_trajectory': dict(
        launch='sitl_wall_effect.launch.py',
        args=[f"scenario:={CONFIG_DIR / 'scenarios' / 'ducted_estimation.yaml'}", 'behaviour:=trajectory'],
        container='/sitl_wall_effect_container',
        nodes=['/tactile_sim', '/wall_effect_ekf', '/indi_controller', '/wall_trajectory'],
        ready='/wall_effect/setpoint',
        plugins={'tactile_sim::TactileSimComponent', 'wall_effect_ekf::WallEffectEkfComponent',
                 'wall_effect_ekf::IndiControlComponent', 'wall_effect_ekf::WallTrajectoryComponent'},
        latched={'/sim/done': '/tactile_sim'}, intra=('/wall_effect/setpoint', '/wall_trajectory')),
    'sitl_bridge': dict(
        launch='sitl.launch.py', args=['seed:=5', 'autostart:=true'], container='/sitl_bridge_container',
        nodes=['/crazyflie_bridge', '/whisker/left/tdorc_filter', '/tactile_depth', '/whisker_fsm'],
        ready='/whisker/left/signal',
        plugins={'crazyflie_bridge::CrazyflieBridgeComponent', 'tdorc_filter::TdorcFilterComponent',
                 'tactile_depth::TactileDepthComponent', 'tactile_fsm::WhiskerFsmComponent'},
        latched={}, intra=('/whisker/left/signal', '/whisker/left/tdorc_filter')),
    'bench_rig': dict(
        launch='bench_rig.launch.py', args=None, container='/bench_rig_container',
        nodes=['/whisker/left/whisker_driver', '/whisker/right/whisker_driver'],
        ready='/whisker/left/pressure',
        plugins={'whisker_driver::WhiskerDriverComponent', 'tdorc_filter::TdorcFilterComponent'},
        latched={}, intra=('/whisker/left/pressure', '/whisker/left/whisker_driver')),
    'sitl_localization': dict(
        launch='sitl_localization.launch.py', args=[], container='/whisker_localization_container',
        nodes=['/tactile_sim', '/whisker_localization'], ready='/whisker/localization',
        plugins={'tactile_sim::TactileSimComponent', 'whisker_localization::WhiskerLocalizationComponent'},
        latched={'/sim/done': '/tactile_sim'}, intra=('/whisker/localization', '/whisker_localization')),
}

# The vehicle's components also latch robot_description and, where tf2_ros is found (the
# Kilted extras overlay; not the Jazzy toolchain here), /tf_static.
for _case in CASES.values():
    for _vehicle in ('/tactile_sim', '/crazyflie_bridge'):
        if _vehicle in _case['nodes']:
            _case['latched']['/robot_description'] = _vehicle
            if HAVE_TF2:
                _case['latched']['/tf_static'] = _vehicle


# Where the ROS 2 installation has visualization_msgs (tactile_viz builds its component),
# every vehicle container (sitl_*, sitl, radio) also holds the visualization node, which
# latches the GPIS grids, and the simulator latches the arena on /sim/arena.
try:
    import visualization_msgs.msg  # noqa: F401
    _HAVE_VIZ = True
except ImportError:
    _HAVE_VIZ = False
if _HAVE_VIZ:
    for _case in CASES.values():
        if _case['launch'].startswith('sitl'):
            _case['nodes'].append('/visualization')
            _case['plugins'].add('tactile_viz::VisualizationComponent')
            _case['latched'].update({'/gpis/mean_grid': '/visualization', '/gpis/variance_grid': '/visualization'})
        if '/tactile_sim' in _case['nodes']:
            _case['latched']['/sim/arena'] = '/tactile_sim'


def load_probe(g: Graph, container: str, timeout: float = 30.0):
    """LoadNode of the probe into `container` with use_intra_process_comms true; returns
    (success, error_message)."""
    from composition_interfaces.srv import LoadNode
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    request = LoadNode.Request(package_name='tactile_ros_tests', plugin_name=PROBE_PLUGIN)
    request.extra_arguments = [Parameter(name='use_intra_process_comms', value=ParameterValue(
        type=ParameterType.PARAMETER_BOOL, bool_value=True))]
    response = g.call(LoadNode, container + '/_container/load_node', request, timeout=timeout)
    return response.success, response.error_message


def parse_report(lines) -> dict[tuple[str, str], tuple[str, bool]]:
    out = {}
    for line in lines:
        topic, node, durability, intra = line.split('|')
        out[(topic, node)] = (durability, intra == '1')
    return out


def pty_devices():
    """Two pseudo terminals for bench_rig's whisker drivers (no frames are needed: the
    drivers' publishers exist from construction)."""
    import tty
    fds, names = [], []
    for _ in range(2):
        master, slave = os.openpty()
        tty.setraw(slave)
        fds += [master, slave]
        names.append(os.ttyname(slave))
    return fds, names


@pytest.mark.parametrize('case', sorted(CASES))
def test_launch_graph_has_no_non_volatile_intra_process_publisher(case, tmp_path):
    c = CASES[case]
    args = list(c['args'] or [])
    fds = []
    if case == 'bench_rig':
        fds, (left, right) = pty_devices()
        args = [f'left_device:={left}', f'right_device:={right}']
    if c['launch'] == 'sitl.launch.py':
        args.append(f'port:={unique_port(19950)}')
    if c['launch'] == 'sitl_xplorer.launch.py':
        args.append(f"ply_file:={tmp_path / 'map.ply'}")  # the mapper writes it at shutdown
    try:
        with Launch(c['launch'], args, tmp_path / 'launch.log') as launch, Graph() as g:
            g.wait_for_nodes([c['container']] + c['nodes'], launch)
            for topic in c['latched']:
                g.wait_for_topic(topic)
            g.wait_for_topic(c['ready'])
            ok, error = load_probe(g, c['container'])
            assert ok, f'{case}: {error}'
            report = parse_report(g.get_parameters('/intra_process_qos_probe', ['report'])['report'])
    finally:
        for fd in fds:
            os.close(fd)
    for topic, node in c['latched'].items():
        assert report.get((topic, node)) == ('transient_local', False), (
            f'{case}: {topic} of {node}: {report.get((topic, node))} (want transient local, not intra-process)')
    if c['intra'] is not None:
        assert report.get(c['intra']) == ('volatile', True), (
            f'{case}: {c["intra"]}: {report.get(c["intra"])}: the probe must see this volatile '
            f'publisher as intra-process, else its lookup sees nothing')


def registered_plugins() -> set[str]:
    """Every rclcpp component the workspace's packages register (ament index)."""
    from ament_index_python import get_resource, get_resources
    ours = {p.name for p in (WORKSPACE / 'src').iterdir() if (p / 'package.xml').exists()}
    plugins = set()
    for pkg in get_resources('rclcpp_components'):
        if pkg not in ours or pkg == 'tactile_ros_tests':
            continue
        content, _ = get_resource('rclcpp_components', pkg)
        plugins |= {line.split(';')[0] for line in content.splitlines() if line.strip()}
    return plugins


def test_every_component_is_checked():
    registered = registered_plugins()
    covered = set().union(*(c['plugins'] for c in CASES.values()))
    assert registered, 'no rclcpp components of the workspace in the ament index'
    assert registered - covered == set(), f'components no launch case loads: {sorted(registered - covered)}'


# Component sources: src/<pkg>/src/ros/*.cpp and headers beside them.
TRANSIENT_LOCAL = re.compile(r'transient_local\s*\(|TransientLocal|DURABILITY_TRANSIENT_LOCAL')


def test_no_transient_local_outside_ros_qos():
    sources = sorted((WORKSPACE / 'src').glob('*/src/ros/*.[ch]pp'))
    assert sources, 'no component sources found'
    offenders = []
    for f in sources:
        for n, line in enumerate(f.read_text().splitlines(), 1):
            if TRANSIENT_LOCAL.search(line):
                offenders.append(f'{f.relative_to(WORKSPACE)}:{n}: {line.strip()}')
    assert not offenders, (
        'transient local in a component: create latched publishers with tactile_common::latched_publisher '
        '(tactile_common/ros_qos.hpp: intra-process off, which ROS 2 Humble requires):\n' + '\n'.join(offenders))

