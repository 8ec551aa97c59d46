"""The ROS-free standard message definitions equal the installed ROS 2 distro's .msg files.

Without ROS the workspace generates its C++ types and CDR code for the standard messages it
uses from src/tactile_msgs/ros_free_std/ (see src/tactile_msgs/README.md: the layouts follow
the distro the ROS 2 stage tests against). Here each of those files is compared, field by
field and constant by constant, with share/<pkg>/msg/<Name>.msg of the sourced distro,
parsed by the same parser the generator uses.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest
from ament_index_python.packages import get_package_share_directory

from conftest import WORKSPACE

MSGS = WORKSPACE / 'src' / 'tactile_msgs'
spec = importlib.util.spec_from_file_location('generate_msgs', MSGS / 'scripts' / 'generate_msgs.py')
gen = importlib.util.module_from_spec(spec)
sys.modules['generate_msgs'] = gen
spec.loader.exec_module(gen)

ROS_FREE = sorted((MSGS / 'ros_free_std').glob('*/msg/*.msg'))
# Packages a ROS 2 toolchain may lack (the Jazzy toolchain here has no visualization_msgs;
# the ROS build then makes no CDR code for their types).
OPTIONAL_PACKAGES = {'visualization_msgs'}


def layout(path: Path):
    s = gen.parse_msg(path)
    fields = [(f.type.full_name if f.type.is_message else f.type.base, f.type.array, f.type.array_size,
               f.type.string_bound, f.name, f.default) for f in s.fields]
    constants = [(c.type, c.name, c.value) for c in s.constants]
    return fields, constants


def test_ros_free_definitions_found():
    assert len(ROS_FREE) >= 25, MSGS


@pytest.mark.parametrize('path', ROS_FREE, ids=lambda p: f'{p.parent.parent.name}/{p.stem}')
def test_same_layout_as_installed_distro(path):
    pkg = path.parent.parent.name
    if pkg in OPTIONAL_PACKAGES:
        try:
            get_package_share_directory(pkg)
        except LookupError:
            pytest.skip(f'{pkg} is not in this ROS 2 installation (optional: tactile_msgs/README.md)')
    installed = Path(get_package_share_directory(pkg)) / 'msg' / path.name
    assert installed.is_file(), f'{installed} not installed'
    ours, theirs = layout(path), layout(installed)
    assert ours[0] == theirs[0], f'{pkg}/{path.stem}: fields differ from {installed}'
    assert ours[1] == theirs[1], f'{pkg}/{path.stem}: constants differ from {installed}'
