"""Unit tests of scripts/generate_msgs.py (parser, type mapping, definition text, errors)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest
from rosbags.typesys import get_types_from_msg

PKG_DIR = Path(__file__).resolve().parent.parent
SCRIPT = PKG_DIR / 'scripts' / 'generate_msgs.py'

spec = importlib.util.spec_from_file_location('generate_msgs', SCRIPT)
gen = importlib.util.module_from_spec(spec)
sys.modules['generate_msgs'] = gen
spec.loader.exec_module(gen)


def write(root: Path, pkg: str, name: str, text: str) -> Path:
    path = root / pkg / 'msg' / f'{name}.msg'
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


FEATURES = """# leading comment
uint8 A = 3   # constant with comment
int64 NEG=-5
string GREETING = hello # world
float64 w 1
bool flag true
string<=5 short_name "abc"
int8[<=4] bounded [1, -2]
float32[3] fixed [1.5, 2, 3]
Inner inner
other_pkg/Leaf[] leaves
uint32[] counts
"""


@pytest.fixture()
def tree(tmp_path):
    files = [
        write(tmp_path, 'my_pkg', 'Features', FEATURES),
        write(tmp_path, 'my_pkg', 'Inner', 'other_pkg/Leaf leaf\n'),
        write(tmp_path, 'other_pkg', 'Leaf', 'float64 x  # metres'),  # no final newline
    ]
    return tmp_path, files


def test_camel_to_snake_like_rosidl():
    assert gen.camel_to_snake('WhiskerPressure') == 'whisker_pressure'
    assert gen.camel_to_snake('PointCloud2') == 'point_cloud2'
    assert gen.camel_to_snake('Point32') == 'point32'
    assert gen.camel_to_snake('ArmImuArray') == 'arm_imu_array'
    assert gen.camel_to_snake('FsmState') == 'fsm_state'


def test_parse_features(tree):
    _, files = tree
    s = gen.parse_msg(files[0])
    assert (s.pkg, s.name) == ('my_pkg', 'Features')
    assert [(c.type, c.name, c.value) for c in s.constants] == [
        ('uint8', 'A', '3'), ('int64', 'NEG', '-5'), ('string', 'GREETING', 'hello # world')]
    by_name = {f.name: f for f in s.fields}
    assert list(by_name) == ['w', 'flag', 'short_name', 'bounded', 'fixed', 'inner', 'leaves',
                             'counts']
    assert by_name['short_name'].type.string_bound == 5
    assert (by_name['bounded'].type.array, by_name['bounded'].type.array_size) == ('bounded', 4)
    assert (by_name['fixed'].type.array, by_name['fixed'].type.array_size) == ('fixed', 3)
    assert by_name['inner'].type.full_name == 'my_pkg/Inner'
    assert by_name['leaves'].type.full_name == 'other_pkg/Leaf'
    assert by_name['counts'].type.array == 'unbounded'


def test_type_header_mapping(tree):
    _, files = tree
    h = gen.emit_type_header(gen.parse_msg(files[0]))
    assert 'namespace my_pkg' in h and 'struct Features' in h
    assert 'static constexpr uint8_t A = static_cast<uint8_t>(3);' in h
    assert 'static constexpr int64_t NEG = static_cast<int64_t>(-5LL);' in h
    assert 'static constexpr const char * GREETING = "hello # world";' in h
    assert 'double w{1.0};' in h
    assert 'bool flag{true};' in h
    assert 'std::string short_name{"abc"};' in h
    assert 'std::vector<int8_t> bounded{static_cast<int8_t>(1), static_cast<int8_t>(-2)};' in h
    assert 'std::array<float, 3> fixed{{1.5f, 2.0f, 3.0f}};' in h
    assert 'my_pkg::msg::Inner inner{};' in h
    assert 'std::vector<other_pkg::msg::Leaf> leaves{};' in h
    assert '#include "other_pkg/msg/leaf.hpp"' in h
    assert 'using SharedPtr = std::shared_ptr<Features>;' in h


def test_definition_text_and_rosbags_parse(tree):
    _, files = tree
    specs = gen.load_specs([str(f) for f in files])
    text = gen.definition_text(specs['my_pkg/Features'], specs)
    sep = '=' * 80
    assert text.startswith(FEATURES + sep + '\nMSG: my_pkg/Inner\nother_pkg/Leaf leaf\n')
    assert text.endswith(sep + '\nMSG: other_pkg/Leaf\nfloat64 x  # metres\n')
    assert text.count('MSG: other_pkg/Leaf') == 1
    types = get_types_from_msg(text, 'my_pkg/msg/Features')
    assert set(types) == {'my_pkg/msg/Features', 'my_pkg/msg/Inner', 'other_pkg/msg/Leaf'}
    consts, fields = types['my_pkg/msg/Features']
    assert [c[0] for c in consts] == ['A', 'NEG', 'GREETING']
    assert [f[0] for f in fields] == ['w', 'flag', 'short_name', 'bounded', 'fixed', 'inner',
                                      'leaves', 'counts']


def test_min_size(tree):
    _, files = tree
    specs = gen.load_specs([str(f) for f in files])
    # w 8 + flag 1 + short_name 4 + bounded 4 + fixed 12 + inner 8 + leaves 4 + counts 4
    assert gen.min_size(specs['my_pkg/Features'], specs, {}) == 45


@pytest.mark.parametrize('text, message', [
    ('float64\n', 'expected "TYPE NAME'),
    ('float64[<=] x\n', 'bounded array without size'),
    ('int33x! y\n', 'cannot parse type'),
    ('uint8 x\nuint8 x\n', 'duplicate name'),
    ('uint8 x 300\n', 'out of range'),
    ('bool b maybe\n', 'invalid bool'),
    ('float64[2] v [1, 2, 3]\n', '3 default values'),
    ('Missing m\n', 'unknown type my_pkg/Missing'),
])
def test_errors(tmp_path, text, message):
    path = write(tmp_path, 'my_pkg', 'Bad', text)
    with pytest.raises(gen.MsgError, match=message):
        specs = gen.load_specs([str(path)])
        gen.emit_type_header(specs['my_pkg/Bad'])


def test_circular_dependency(tmp_path):
    a = write(tmp_path, 'p', 'A', 'B b\n')
    b = write(tmp_path, 'p', 'B', 'A a\n')
    with pytest.raises(gen.MsgError, match='circular'):
        gen.load_specs([str(a), str(b)])


def test_cli_writes_outputs_and_reports_errors(tree, tmp_path):
    _, files = tree
    out = tmp_path / 'out'
    listed = subprocess.run([sys.executable, str(SCRIPT), '--output-dir', str(out),
                             '--list-outputs'] + [str(f) for f in files],
                            check=True, capture_output=True, text=True).stdout.split(';')
    subprocess.run([sys.executable, str(SCRIPT), '--output-dir', str(out)] +
                   [str(f) for f in files], check=True)
    assert all(Path(p).is_file() for p in listed)
    assert (out / 'include' / 'my_pkg' / 'msg' / 'features.hpp').is_file()
    assert (out / 'include' / 'tactile_msgs' / 'cdr' / 'other_pkg' / 'leaf.hpp').is_file()
    bad = subprocess.run([sys.executable, str(SCRIPT), '--output-dir', str(out), str(files[0])],
                         capture_output=True, text=True)
    assert bad.returncode == 1 and 'unknown type' in bad.stderr
