"""launch/radio.launch.py without a Crazyradio (CI has none): the bridge cannot open the
link and says so, naming the URI and the reason (crazyflie_bridge usb_links.cpp). The plain
node's load fails and the launch ends (exit code 1); the lifecycle node (where
rclcpp_lifecycle is installed) fails its configure and stays unconfigured, the launch running
for the operator to plug the dongle in and configure again (test_launch_lifecycle.py)."""

from __future__ import annotations

import time

from launch_check import Launch
from test_launch_lifecycle import lifecycle, lifecycle_built


def test_radio_without_crazyradio_reports_its_message(tmp_path):
    uri = 'radio://0/80/2M/E7E7E7E7E7?safelink=1'
    with Launch('radio.launch.py', [f'uri:={uri}'], tmp_path / 'launch.log') as launch:
        if lifecycle_built('crazyflie_bridge'):
            end = time.monotonic() + 60
            while time.monotonic() < end and launch.running() and 'configure failed' not in launch.output():
                time.sleep(0.2)
            out = launch.output()
            assert launch.running(), f'the launch ended (exit {launch.proc.poll()}):\n{out[-3000:]}'
            assert f'configure failed: cannot open {uri}: ' in out, out[-3000:]
            assert lifecycle('get', '/crazyflie_bridge').startswith('unconfigured [1]')
        else:
            code = launch.wait_exit(60)
            out = launch.output()
            assert code not in (None, 0), f'launch exit {code}:\n{out[-3000:]}'
            assert 'a node failed to start' in out
    assert 'Crazyradio for radio://0/80/2M/E7E7E7E7E7' in out, out[-3000:]
    assert 'no Crazyradio found (USB 1915:7777, 0 connected)' in out, out[-3000:]
    assert 'is the dongle plugged in?' in out
