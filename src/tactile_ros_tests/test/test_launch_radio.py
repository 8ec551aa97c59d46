"""launch/radio.launch.py without a Crazyradio (CI has none): the bridge cannot open the
link, and the launch ends (exit code 1) with the bridge's message naming the URI and the
reason (crazyflie_bridge usb_links.cpp)."""

from __future__ import annotations

from launch_check import Launch


def test_radio_without_crazyradio_exits_with_its_message(tmp_path):
    uri = 'radio://0/80/2M/E7E7E7E7E7?safelink=1'
    with Launch('radio.launch.py', [f'uri:={uri}'], tmp_path / 'launch.log') as launch:
        code = launch.wait_exit(60)
        out = launch.output()
    assert code not in (None, 0), f'launch exit {code}:\n{out[-3000:]}'
    assert 'a node failed to start' in out
    assert 'Crazyradio for radio://0/80/2M/E7E7E7E7E7' in out, out[-3000:]
    assert 'no Crazyradio found (USB 1915:7777, 0 connected)' in out, out[-3000:]
    assert 'is the dongle plugged in?' in out
