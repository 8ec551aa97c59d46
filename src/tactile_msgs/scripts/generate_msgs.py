#!/usr/bin/env python3
"""Generate C++ message types, CDR serialization and a type registry from ROS 2 .msg files.

Standard library only: it runs at build time with the system python3.

Usage:
  generate_msgs.py --output-dir DIR [--no-types] MSG_FILE...

Every MSG_FILE must live in a directory `<pkg>/msg/<Type>.msg`; the package name is
taken from the path. Dependencies of a type (`pkg/Type`, or `Type` of the same
package) must be among the given files.

Output (under DIR):
  include/<pkg>/msg/<snake>.hpp               type headers (not with --no-types; in a
                                              ROS build rosidl provides them)
  include/tactile_msgs/cdr/<pkg>/<snake>.hpp  MessageTraits<T> specialisation
  include/tactile_msgs/cdr/serialization.hpp  umbrella header
  src/<pkg>__<snake>.cpp                      write/read implementations
  src/registry.cpp                            find_type() / all_types()
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Tuple

SEPARATOR = '=' * 80

# .msg primitive -> (C++ type, size in bytes / CDR alignment)
PRIMITIVES: Dict[str, Tuple[str, int]] = {
    'bool': ('bool', 1),
    'byte': ('uint8_t', 1),
    'char': ('uint8_t', 1),
    'int8': ('int8_t', 1),
    'uint8': ('uint8_t', 1),
    'int16': ('int16_t', 2),
    'uint16': ('uint16_t', 2),
    'int32': ('int32_t', 4),
    'uint32': ('uint32_t', 4),
    'int64': ('int64_t', 8),
    'uint64': ('uint64_t', 8),
    'float32': ('float', 4),
    'float64': ('double', 8),
}
INTEGER_TYPES = {'byte', 'char', 'int8', 'uint8', 'int16', 'uint16', 'int32', 'uint32',
                 'int64', 'uint64'}
FLOAT_TYPES = {'float32', 'float64'}

TYPE_RE = re.compile(
    r'^(?:(?P<pkg>[a-z][a-z0-9_]*)/)?(?P<base>[A-Za-z][A-Za-z0-9_]*)'
    r'(?:<=(?P<strbound>\d+))?'
    r'(?P<arr>\[(?P<arrbound><=)?(?P<arrsize>\d+)?\])?$')
NAME_RE = re.compile(r'^[A-Za-z][A-Za-z0-9_]*$')
CONST_RE = re.compile(r'^(?P<type>\S+)\s+(?P<name>[A-Z][A-Z0-9_]*)\s*=\s*(?P<value>.*)$')


class MsgError(Exception):
    pass


@dataclass
class FieldType:
    pkg: Optional[str]          # None for primitives and string
    base: str                   # primitive name, 'string' or message name
    string_bound: int = 0       # string<=N
    array: Optional[str] = None  # None, 'fixed', 'unbounded', 'bounded'
    array_size: int = 0         # N of T[N] or T[<=N]

    @property
    def is_primitive(self) -> bool:
        return self.pkg is None and self.base in PRIMITIVES

    @property
    def is_string(self) -> bool:
        return self.pkg is None and self.base == 'string'

    @property
    def is_message(self) -> bool:
        return self.pkg is not None

    @property
    def full_name(self) -> str:
        return f'{self.pkg}/{self.base}'


@dataclass
class Field:
    type: FieldType
    name: str
    default: Optional[str] = None


@dataclass
class Constant:
    type: str
    name: str
    value: str


@dataclass
class MsgSpec:
    pkg: str
    name: str
    text: str
    path: Path
    fields: List[Field] = field(default_factory=list)
    constants: List[Constant] = field(default_factory=list)

    @property
    def full_name(self) -> str:
        return f'{self.pkg}/{self.name}'

    @property
    def snake(self) -> str:
        return camel_to_snake(self.name)


def camel_to_snake(value: str) -> str:
    """Same conversion as rosidl (convert_camel_case_to_lower_case_underscore)."""
    value = re.sub(r'(.)([A-Z][a-z]+)', r'\1_\2', value)
    value = re.sub(r'([a-z0-9])([A-Z])', r'\1_\2', value)
    return value.lower()


def strip_comment(line: str) -> str:
    """Remove a trailing '#' comment that is not inside a quoted string."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            if ch == '\\':
                continue
            if ch == quote:
                quote = None
        elif ch in ('"', "'"):
            quote = ch
        elif ch == '#':
            return line[:i]
    return line


def parse_type(token: str, pkg: str, where: str) -> FieldType:
    m = TYPE_RE.match(token)
    if not m:
        raise MsgError(f'{where}: cannot parse type {token!r}')
    tpkg, base = m.group('pkg'), m.group('base')
    ft = FieldType(pkg=None, base=base)
    if m.group('strbound') is not None:
        if tpkg or base != 'string':
            raise MsgError(f'{where}: only string can be bounded with <=, got {token!r}')
        ft.string_bound = int(m.group('strbound'))
    if tpkg is None and (base in PRIMITIVES or base == 'string'):
        ft.pkg = None
    else:
        if base == 'Header' and tpkg is None:
            tpkg = 'std_msgs'
        ft.pkg = tpkg or pkg
    if m.group('arr'):
        size = m.group('arrsize')
        if m.group('arrbound'):
            if size is None:
                raise MsgError(f'{where}: bounded array without size in {token!r}')
            ft.array, ft.array_size = 'bounded', int(size)
        elif size is not None:
            ft.array, ft.array_size = 'fixed', int(size)
            if ft.array_size == 0:
                raise MsgError(f'{where}: fixed array of size 0 in {token!r}')
        else:
            ft.array = 'unbounded'
    return ft


def parse_msg(path: Path) -> MsgSpec:
    path = Path(path)
    if path.suffix != '.msg' or path.parent.name != 'msg':
        raise MsgError(f'{path}: expected <pkg>/msg/<Type>.msg')
    pkg = path.resolve().parent.parent.name
    name = path.stem
    text = path.read_text(encoding='utf-8')
    spec = MsgSpec(pkg=pkg, name=name, text=text, path=path)
    names = set()
    for lineno, raw in enumerate(text.splitlines(), 1):
        where = f'{path}:{lineno}'
        stripped = raw.strip()
        if not stripped or stripped.startswith('#'):
            continue
        cm = CONST_RE.match(stripped)
        if cm and (cm.group('type') in PRIMITIVES or cm.group('type') == 'string'):
            ctype = cm.group('type')
            if ctype == 'string':
                value = cm.group('value').strip()  # ROS 2: the rest of the line
            else:
                value = strip_comment(cm.group('value')).strip()
            if not value:
                raise MsgError(f'{where}: constant {cm.group("name")} without value')
            spec.constants.append(Constant(ctype, cm.group('name'), value))
            if cm.group('name') in names:
                raise MsgError(f'{where}: duplicate name {cm.group("name")}')
            names.add(cm.group('name'))
            continue
        line = strip_comment(raw).strip()
        if not line:
            continue
        parts = line.split(None, 2)
        if len(parts) < 2:
            raise MsgError(f'{where}: expected "TYPE NAME [DEFAULT]", got {line!r}')
        ftype = parse_type(parts[0], pkg, where)
        fname = parts[1]
        if not NAME_RE.match(fname):
            raise MsgError(f'{where}: invalid field name {fname!r}')
        if fname in names:
            raise MsgError(f'{where}: duplicate name {fname}')
        names.add(fname)
        default = parts[2].strip() if len(parts) > 2 else None
        if default is not None and ftype.is_message:
            raise MsgError(f'{where}: message fields cannot have default values')
        spec.fields.append(Field(ftype, fname, default))
    return spec


# ----------------------------------------------------------------------------
# dependency resolution and definition text


def direct_deps(spec: MsgSpec) -> List[str]:
    out: List[str] = []
    for f in spec.fields:
        if f.type.is_message and f.type.full_name not in out:
            out.append(f.type.full_name)
    return out


def all_deps(spec: MsgSpec, specs: Dict[str, MsgSpec]) -> List[str]:
    """Transitive dependencies, depth first in field order, each once."""
    order: List[str] = []

    def visit(s: MsgSpec, stack: Tuple[str, ...]) -> None:
        for dep in direct_deps(s):
            if dep in stack:
                raise MsgError(f'circular dependency: {" -> ".join(stack + (dep,))}')
            if dep not in specs:
                raise MsgError(f'{s.path}: unknown type {dep} (give its .msg file)')
            if dep not in order:
                order.append(dep)
                visit(specs[dep], stack + (dep,))

    visit(spec, (spec.full_name,))
    return order


def normalized_text(text: str) -> str:
    text = text.replace('\r\n', '\n')
    if not text.endswith('\n'):
        text += '\n'
    return text


def definition_text(spec: MsgSpec, specs: Dict[str, MsgSpec]) -> str:
    """Full definition as rosbag2 stores it with encoding ros2msg."""
    parts = [normalized_text(spec.text)]
    for dep in all_deps(spec, specs):
        parts.append(f'{SEPARATOR}\nMSG: {dep}\n{normalized_text(specs[dep].text)}')
    return ''.join(parts)


def min_size(spec: MsgSpec, specs: Dict[str, MsgSpec], memo: Dict[str, int]) -> int:
    """Lower bound of the serialized size (without alignment), used to bound sequence counts."""
    if spec.full_name in memo:
        return memo[spec.full_name]
    total = 0
    for f in spec.fields:
        t = f.type
        if t.array in ('unbounded', 'bounded'):
            total += 4
            continue
        if t.is_primitive:
            one = PRIMITIVES[t.base][1]
        elif t.is_string:
            one = 4
        else:
            one = min_size(specs[t.full_name], specs, memo)
        total += one * (t.array_size if t.array == 'fixed' else 1)
    memo[spec.full_name] = total
    return total


# ----------------------------------------------------------------------------
# C++ helpers


def cpp_type_of_element(t: FieldType) -> str:
    if t.is_primitive:
        return PRIMITIVES[t.base][0]
    if t.is_string:
        return 'std::string'
    return f'{t.pkg}::msg::{t.base}'


def cpp_field_type(t: FieldType) -> str:
    elem = cpp_type_of_element(t)
    if t.array == 'fixed':
        return f'std::array<{elem}, {t.array_size}>'
    if t.array in ('unbounded', 'bounded'):
        return f'std::vector<{elem}>'
    return elem


def cpp_string_literal(s: str) -> str:
    out = ['"']
    for ch in s:
        if ch in '"\\':
            out.append('\\' + ch)
        elif ch == '\n':
            out.append('\\n')
        elif ch == '\t':
            out.append('\\t')
        elif ord(ch) < 0x20:
            out.append('\\x%02x' % ord(ch))
        else:
            out.append(ch)
    out.append('"')
    return ''.join(out)


def unquote(value: str) -> str:
    value = value.strip()
    if len(value) >= 2 and value[0] == value[-1] and value[0] in ('"', "'"):
        body = value[1:-1]
        return re.sub(r'\\(.)', r'\1', body)
    return value


def cpp_scalar_literal(base: str, value: str, where: str) -> str:
    value = value.strip()
    if base == 'bool':
        v = value.lower()
        if v in ('true', '1'):
            return 'true'
        if v in ('false', '0'):
            return 'false'
        raise MsgError(f'{where}: invalid bool value {value!r}')
    if base == 'string':
        return cpp_string_literal(unquote(value))
    ctype = PRIMITIVES[base][0]
    try:
        if base in INTEGER_TYPES:
            iv = int(value, 0)
            bits = int(re.sub(r'\D', '', ctype))
            signed = not ctype.startswith('u')
            lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
            if not lo <= iv <= hi:
                raise MsgError(f'{where}: value {value} out of range for {base}')
            if base in ('int64',) and iv == lo:
                return f'static_cast<{ctype}>({iv + 1}LL - 1LL)'
            suffix = {'int64': 'LL', 'uint64': 'ULL', 'uint32': 'U'}.get(base, '')
            return f'static_cast<{ctype}>({iv}{suffix})'
        fv = float(value)
    except ValueError:
        raise MsgError(f'{where}: invalid {base} value {value!r}') from None
    lit = repr(fv)
    if lit in ('inf', '-inf', 'nan'):
        raise MsgError(f'{where}: non-finite default {value!r} not supported')
    if 'e' not in lit and '.' not in lit:
        lit += '.0'
    return lit + ('f' if base == 'float32' else '')


def parse_array_value(value: str, where: str) -> List[str]:
    value = value.strip()
    if not (value.startswith('[') and value.endswith(']')):
        raise MsgError(f'{where}: array default must be [a, b, ...], got {value!r}')
    body = value[1:-1].strip()
    if not body:
        return []
    items, cur, quote = [], [], None
    for ch in body:
        if quote:
            cur.append(ch)
            if ch == quote:
                quote = None
        elif ch in ('"', "'"):
            quote = ch
            cur.append(ch)
        elif ch == ',':
            items.append(''.join(cur).strip())
            cur = []
        else:
            cur.append(ch)
    items.append(''.join(cur).strip())
    return items


def cpp_default(f: Field, where: str) -> str:
    """Brace initialiser of a member (value-initialised when there is no default)."""
    t = f.type
    if f.default is None:
        return '{}'
    if t.array:
        items = parse_array_value(f.default, where)
        if t.array == 'fixed' and len(items) != t.array_size:
            raise MsgError(f'{where}: {len(items)} default values for {f.name}[{t.array_size}]')
        if t.array == 'bounded' and len(items) > t.array_size:
            raise MsgError(f'{where}: too many default values for {f.name}')
        lits = ', '.join(cpp_scalar_literal(t.base, x, where) for x in items)
        if t.is_string:
            lits = ', '.join(f'std::string({cpp_scalar_literal(t.base, x, where)})' for x in items)
        return '{{' + lits + '}}' if t.array == 'fixed' else '{' + lits + '}'
    return '{' + cpp_scalar_literal(t.base, f.default, where) + '}'


HEADER_NOTE = '// Generated by tactile_msgs/scripts/generate_msgs.py from {src}. Do not edit.\n'


def guard(*parts: str) -> str:
    return '__'.join(p.upper() for p in parts) + '_HPP_'


def emit_type_header(spec: MsgSpec) -> str:
    g = guard(spec.pkg, 'msg', spec.snake)
    includes = {'<array>', '<cstdint>', '<memory>', '<string>', '<vector>'}
    dep_includes = sorted({f'"{d.split("/")[0]}/msg/{camel_to_snake(d.split("/")[1])}.hpp"'
                           for d in direct_deps(spec)})
    lines = [HEADER_NOTE.format(src=f'{spec.pkg}/msg/{spec.name}.msg'),
             f'#ifndef {g}', f'#define {g}', '']
    lines += [f'#include {i}' for i in sorted(includes)]
    lines += [f'#include {i}' for i in dep_includes]
    lines += ['', f'namespace {spec.pkg}', '{', 'namespace msg', '{', '']
    lines += [f'/// {spec.pkg}/msg/{spec.name} (ROS-free stand-in with the layout of rosidl\'s C++ type).',
              f'struct {spec.name}', '{',
              f'  using Type = {spec.name};',
              f'  using SharedPtr = std::shared_ptr<{spec.name}>;',
              f'  using ConstSharedPtr = std::shared_ptr<const {spec.name}>;',
              f'  using UniquePtr = std::unique_ptr<{spec.name}>;',
              f'  using ConstUniquePtr = std::unique_ptr<const {spec.name}>;',
              f'  using WeakPtr = std::weak_ptr<{spec.name}>;',
              f'  using ConstWeakPtr = std::weak_ptr<const {spec.name}>;',
              '']
    for c in spec.constants:
        where = f'{spec.path}: constant {c.name}'
        if c.type == 'string':
            lines.append(f'  static constexpr const char * {c.name} = '
                         f'{cpp_string_literal(unquote(c.value))};')
        else:
            lines.append(f'  static constexpr {PRIMITIVES[c.type][0]} {c.name} = '
                         f'{cpp_scalar_literal(c.type, c.value, where)};')
    if spec.constants:
        lines.append('')
    for f in spec.fields:
        where = f'{spec.path}: field {f.name}'
        lines.append(f'  {cpp_field_type(f.type)} {f.name}{cpp_default(f, where)};')
    if spec.fields:
        lines.append('')
    cmp = ' &&\n           '.join(f'{f.name} == other.{f.name}' for f in spec.fields) or 'true'
    lines += [f'  bool operator==(const {spec.name} & other) const',
              '  {',
              f'    return {cmp};' if spec.fields else '    (void)other;\n    return true;',
              '  }',
              f'  bool operator!=(const {spec.name} & other) const {{return !(*this == other);}}',
              '};', '',
              f'}}  // namespace msg', f'}}  // namespace {spec.pkg}', '', f'#endif  // {g}', '']
    return '\n'.join(lines)


def cdr_header_path(spec: MsgSpec) -> str:
    return f'tactile_msgs/cdr/{spec.pkg}/{spec.snake}.hpp'


def emit_cdr_header(spec: MsgSpec, specs: Dict[str, MsgSpec]) -> str:
    g = guard('tactile_msgs', 'cdr', spec.pkg, spec.snake)
    cpp = f'{spec.pkg}::msg::{spec.name}'
    dep_includes = sorted({f'"{cdr_header_path(specs[d])}"' for d in direct_deps(spec)})
    lines = [HEADER_NOTE.format(src=f'{spec.pkg}/msg/{spec.name}.msg'),
             f'#ifndef {g}', f'#define {g}', '',
             '#include <cstddef>', '#include <string>', '',
             f'#include "{spec.pkg}/msg/{spec.snake}.hpp"',
             '#include "tactile_msgs/cdr/cdr_stream.hpp"']
    lines += [f'#include {i}' for i in dep_includes]
    lines += ['', 'namespace tactile_msgs', '{', 'namespace cdr', '{', '',
              'template<>',
              f'struct MessageTraits<{cpp}>',
              '{',
              f'  static constexpr const char * type_name = "{spec.pkg}/msg/{spec.name}";',
              f'  /// Lower bound of the CDR size of one {spec.name} (bounds sequence counts when reading).',
              f'  static constexpr std::size_t min_serialized_size = {min_size(spec, specs, {})};',
              '  /// Full ros2msg definition text (own .msg text, then every dependency).',
              '  static const std::string & definition();',
              f'  static void write(CdrWriter & w, const {cpp} & msg);',
              f'  static void read(CdrReader & r, {cpp} & msg);',
              '};', '',
              '}  // namespace cdr', '}  // namespace tactile_msgs', '', f'#endif  // {g}', '']
    return '\n'.join(lines)


def raw_literal(text: str) -> str:
    delim = 'tmsgdef'
    while f'){delim}"' in text:
        delim += 'x'
    return f'R"{delim}({text}){delim}"'


def element_write(t: FieldType, expr: str) -> str:
    if t.is_primitive:
        return f'w.write({expr});'
    if t.is_string:
        return f'w.write_string({expr}, {t.string_bound});'
    return f'MessageTraits<{cpp_type_of_element(t)}>::write(w, {expr});'


def element_read(t: FieldType, expr: str) -> str:
    if t.is_primitive:
        return f'r.read({expr});'
    if t.is_string:
        return f'r.read_string({expr}, {t.string_bound});'
    return f'MessageTraits<{cpp_type_of_element(t)}>::read(r, {expr});'


def element_min_size(t: FieldType, specs: Dict[str, MsgSpec]) -> str:
    if t.is_primitive:
        return str(PRIMITIVES[t.base][1])
    if t.is_string:
        return '4'
    return f'MessageTraits<{cpp_type_of_element(t)}>::min_serialized_size'


def emit_cdr_source(spec: MsgSpec, specs: Dict[str, MsgSpec]) -> str:
    cpp = f'{spec.pkg}::msg::{spec.name}'
    defn = definition_text(spec, specs)
    w_lines: List[str] = []
    r_lines: List[str] = []
    for f in spec.fields:
        t = f.type
        m = f'msg.{f.name}'
        r_lines.append(f'  r.enter("{f.name}");')
        if t.array is None:
            w_lines.append(f'  {element_write(t, m)}')
            r_lines.append(f'  {element_read(t, m)}')
        elif t.is_primitive:
            if t.array == 'fixed':
                w_lines.append(f'  w.write_array({m}.data(), {m}.size());')
                r_lines.append(f'  r.read_array({m}.data(), {m}.size());')
            else:
                bound = t.array_size if t.array == 'bounded' else 0
                w_lines.append(f'  w.write_sequence({m}, {bound});')
                r_lines.append(f'  r.read_sequence({m}, {bound});')
        else:
            if t.array == 'fixed':
                w_lines.append(f'  for (const auto & e : {m}) {{{element_write(t, "e")}}}')
                r_lines += [f'  for (std::size_t i = 0; i < {m}.size(); ++i) {{',
                            '    r.index(i);',
                            f'    {element_read(t, m + "[i]")}',
                            '  }']
            else:
                bound = t.array_size if t.array == 'bounded' else 0
                w_lines += [f'  w.write_count({m}.size(), {bound});',
                            f'  for (const auto & e : {m}) {{{element_write(t, "e")}}}']
                r_lines += [f'  {m}.resize(r.read_count({element_min_size(t, specs)}, {bound}));',
                            f'  for (std::size_t i = 0; i < {m}.size(); ++i) {{',
                            '    r.index(i);',
                            f'    {element_read(t, m + "[i]")}',
                            '  }']
        r_lines.append('  r.leave();')
    if not spec.fields:
        w_lines.append('  (void)w;\n  (void)msg;')
        r_lines.append('  (void)r;\n  (void)msg;')
    lines = [HEADER_NOTE.format(src=f'{spec.pkg}/msg/{spec.name}.msg'),
             f'#include "{cdr_header_path(spec)}"', '',
             'namespace tactile_msgs', '{', 'namespace cdr', '{', '',
             f'const std::string & MessageTraits<{cpp}>::definition()',
             '{',
             f'  static const std::string text = {raw_literal(defn)};',
             '  return text;',
             '}', '',
             f'void MessageTraits<{cpp}>::write(CdrWriter & w, const {cpp} & msg)',
             '{'] + w_lines + ['}', '',
             f'void MessageTraits<{cpp}>::read(CdrReader & r, {cpp} & msg)',
             '{'] + r_lines + ['}', '',
             '}  // namespace cdr', '}  // namespace tactile_msgs', '']
    return '\n'.join(lines)


def emit_umbrella(specs: Dict[str, MsgSpec]) -> str:
    g = guard('tactile_msgs', 'cdr', 'serialization')
    lines = [HEADER_NOTE.format(src='all message files'),
             '/// All generated MessageTraits, serialize()/deserialize() and the type registry.',
             f'#ifndef {g}', f'#define {g}', '',
             '#include "tactile_msgs/cdr/cdr_stream.hpp"',
             '#include "tactile_msgs/cdr/registry.hpp"']
    lines += [f'#include "{cdr_header_path(s)}"' for _, s in sorted(specs.items())]
    lines += ['', f'#endif  // {g}', '']
    return '\n'.join(lines)


def emit_registry(specs: Dict[str, MsgSpec]) -> str:
    lines = [HEADER_NOTE.format(src='all message files'),
             '#include <string_view>', '#include <vector>', '',
             '#include "tactile_msgs/cdr/serialization.hpp"', '',
             'namespace tactile_msgs', '{', 'namespace cdr', '{', '',
             'const std::vector<TypeInfo> & all_types()', '{',
             '  static const std::vector<TypeInfo> types = {']
    for s in sorted(specs.values(), key=lambda x: f'{x.pkg}/msg/{x.name}'):
        cpp = f'{s.pkg}::msg::{s.name}'
        lines.append(f'    TypeInfo{{MessageTraits<{cpp}>::type_name, '
                     f'MessageTraits<{cpp}>::definition()}},')
    lines += ['  };', '  return types;', '}', '',
              '}  // namespace cdr', '}  // namespace tactile_msgs', '']
    return '\n'.join(lines)


def emit_testing(specs: Dict[str, MsgSpec]) -> str:
    """Deterministic filler used by the tests and the rosbags peer test.

    Values are derived from a counter k that starts at 1 and advances once per primitive,
    string and sequence length, visiting fields depth first in .msg order:
      bool -> k odd; integers -> (k * 2654435761) mod 2^bits (two's complement for signed);
      float32/float64 -> (-1)^k * (k + 0.25); string -> "s<k>" (cut to its bound);
      sequence length -> k % 3 + 1 (cut to its bound); fixed arrays -> N elements.
    test/test_rosbags_peer.py implements the same rule over rosbags' type store.

    With a non-zero `seed` (Filler::random(seed)) the values are pseudo-random instead
    (splitmix64): finite floats of any sign and magnitude, integers over their whole range,
    strings of 0, 1-20 or 100-300 printable characters, sequences of 0-5 or 100-300 elements (cut to their
    bound). The ROS 2 stage compares the CDR bytes of such messages with rclcpp's.
    """
    g = guard('tactile_msgs', 'cdr', 'testing')
    ordered = sorted(specs.values(), key=lambda x: f'{x.pkg}/msg/{x.name}')
    lines = [HEADER_NOTE.format(src='all message files'),
             '// Test support: fills every field of a message with deterministic, non-trivial values.',
             f'#ifndef {g}', f'#define {g}', '',
             '#include <cstddef>', '#include <cstdint>', '#include <string>', '#include <tuple>',
             '#include <type_traits>', '',
             '#include "tactile_msgs/cdr/serialization.hpp"', '',
             'namespace tactile_msgs', '{', 'namespace cdr', '{', 'namespace testing', '{', '',
             'struct Filler',
             '{',
             '  uint64_t k = 1;',
             '  uint64_t seed = 0;  // non-zero: pseudo-random values (splitmix64 state)',
             '  static Filler random(uint64_t s)',
             '  {',
             '    Filler f;',
             '    f.seed = s == 0 ? 1 : s;',
             '    return f;',
             '  }',
             '  uint64_t next()',
             '  {',
             '    uint64_t z = (seed += 0x9E3779B97F4A7C15ULL);',
             '    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;',
             '    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;',
             '    return z ^ (z >> 31);',
             '  }',
             '  template<class T>',
             '  void prim(T & v)',
             '  {',
             '    if (seed != 0) {',
             '      const uint64_t r = next();',
             '      if constexpr (std::is_same<T, bool>::value) {',
             '        v = (r & 1U) == 1U;',
             '      } else if constexpr (std::is_floating_point<T>::value) {',
             '        // mantissa in [-1, 1) times 10^e, e in [-8, 8): finite in float and double',
             '        const double m = static_cast<double>(r >> 11) / 9007199254740992.0 * 2.0 - 1.0;',
             '        const int e = static_cast<int>(next() % 16) - 8;',
             '        double p = 1.0;',
             '        for (int i = 0; i < (e < 0 ? -e : e); ++i) {p *= 10.0;}',
             '        v = static_cast<T>(e < 0 ? m / p : m * p);',
             '      } else {',
             '        v = static_cast<T>(r);  // modulo 2^bits',
             '      }',
             '      return;',
             '    }',
             '    if constexpr (std::is_same<T, bool>::value) {',
             '      v = (k % 2) == 1;',
             '    } else if constexpr (std::is_floating_point<T>::value) {',
             '      v = static_cast<T>(((k % 2) == 1 ? -1.0 : 1.0) * (static_cast<double>(k) + 0.25));',
             '    } else {',
             '      v = static_cast<T>(k * 2654435761ULL);  // modulo 2^bits',
             '    }',
             '    ++k;',
             '  }',
             '  template<class V>',
             '  void prim_at(V & v, std::size_t i)',
             '  {',
             '    typename V::value_type t{};',
             '    prim(t);',
             '    v[i] = t;',
             '  }',
             '  void str(std::string & s, std::size_t bound)',
             '  {',
             '    if (seed != 0) {',
             '      const uint64_t r = next();',
             '      std::size_t n = static_cast<std::size_t>(',
             '        r % 4 == 0 ? 0 : (r % 4 == 1 ? 100 + (r >> 8) % 201 : 1 + (r >> 8) % 20));',
             '      if (bound != 0 && n > bound) {n = bound;}',
             '      s.resize(n);',
             '      for (auto & c : s) {c = static_cast<char>(32 + next() % 95);}',
             '      return;',
             '    }',
             '    s = "s" + std::to_string(k++);',
             '    if (bound != 0 && s.size() > bound) {s.resize(bound);}',
             '  }',
             '  std::size_t count(std::size_t bound)',
             '  {',
             '    if (seed != 0) {',
             '      const uint64_t r = next();',
             '      std::size_t n = static_cast<std::size_t>(r % 4 == 0 ? 100 + (r >> 8) % 201 : (r >> 8) % 6);',
             '      return (bound != 0 && n > bound) ? bound : n;',
             '    }',
             '    std::size_t n = static_cast<std::size_t>(k++ % 3 + 1);',
             '    return (bound != 0 && n > bound) ? bound : n;',
             '  }',
             '};', '',
             'template<class T>', 'struct Fill;', '']
    decls: List[str] = []
    defs: List[str] = []
    for s in ordered:
        cpp = f'{s.pkg}::msg::{s.name}'
        body: List[str] = []
        for f in s.fields:
            t = f.type
            m = f'msg.{f.name}'

            def elem(expr: str, idx: Optional[str] = None) -> str:
                if t.is_primitive:
                    return f'f.prim_at({m}, {idx});' if idx else f'f.prim({expr});'
                if t.is_string:
                    return f'f.str({expr}, {t.string_bound});'
                return f'Fill<{cpp_type_of_element(t)}>::fill(f, {expr});'
            if t.array is None:
                body.append(f'    {elem(m)}')
            else:
                if t.array != 'fixed':
                    bound = t.array_size if t.array == 'bounded' else 0
                    body.append(f'    {m}.resize(f.count({bound}));')
                body.append(f'    for (std::size_t i = 0; i < {m}.size(); ++i) {{'
                            f'{elem(m + "[i]", "i")}}}')
        if not s.fields:
            body.append('    (void)f;\n    (void)msg;')
        decls += ['template<>', f'struct Fill<{cpp}>', '{',
                  f'  static void fill(Filler & f, {cpp} & msg);', '};', '']
        defs += [f'inline void Fill<{cpp}>::fill(Filler & f, {cpp} & msg)', '{'] + \
            [x[2:] for x in body] + ['}', '']
    lines += decls + defs
    lines += ['/// A message of type T filled by a fresh Filler (k starts at 1).',
              'template<class T>', 'T make_filled()', '{', '  Filler f;', '  T msg{};',
              '  Fill<T>::fill(f, msg);', '  return msg;', '}', '',
              '/// A message of type T with pseudo-random values (Filler::random(seed)).',
              'template<class T>', 'T make_random(uint64_t seed)', '{',
              '  Filler f = Filler::random(seed);', '  T msg{};',
              '  Fill<T>::fill(f, msg);', '  return msg;', '}', '',
              '/// Every generated type.',
              'using AllTypes = std::tuple<']
    lines.append(',\n'.join(f'  {s.pkg}::msg::{s.name}' for s in ordered) + '>;')
    lines += ['', '}  // namespace testing', '}  // namespace cdr', '}  // namespace tactile_msgs',
              '', f'#endif  // {g}', '']
    return '\n'.join(lines)


def write_file(path: Path, content: str) -> None:
    # Always (re)writes, so the build system sees fresh outputs after every run.
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + '.tmp')
    tmp.write_text(content, encoding='utf-8')
    os.replace(tmp, path)


def load_specs(files: List[str]) -> Dict[str, MsgSpec]:
    specs: Dict[str, MsgSpec] = {}
    for f in files:
        spec = parse_msg(Path(f))
        if spec.full_name in specs:
            raise MsgError(f'{f}: type {spec.full_name} given twice '
                           f'(also {specs[spec.full_name].path})')
        specs[spec.full_name] = spec
    for spec in specs.values():
        all_deps(spec, specs)  # raises on unknown or circular dependencies
    return specs


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--output-dir', required=True)
    ap.add_argument('--no-types', action='store_true',
                    help='do not write type headers (ROS build: rosidl provides them)')
    ap.add_argument('--print-definition', metavar='PKG/TYPE',
                    help='print the definition text of one type and exit')
    ap.add_argument('--list-outputs', action='store_true',
                    help='print the files that would be written (CMake list) and exit')
    ap.add_argument('files', nargs='+')
    args = ap.parse_args(argv)
    try:
        specs = load_specs(args.files)
        if args.print_definition:
            sys.stdout.write(definition_text(specs[args.print_definition], specs))
            return 0
        out = Path(args.output_dir)
        inc = out / 'include'
        if args.list_outputs:
            paths = []
            for spec in specs.values():
                if not args.no_types:
                    paths.append(inc / spec.pkg / 'msg' / f'{spec.snake}.hpp')
                paths.append(inc / cdr_header_path(spec))
                paths.append(out / 'src' / f'{spec.pkg}__{spec.snake}.cpp')
            paths.append(inc / 'tactile_msgs' / 'cdr' / 'serialization.hpp')
            paths.append(out / 'src' / 'registry_table.cpp')
            paths.append(inc / 'tactile_msgs' / 'cdr' / 'testing.hpp')
            sys.stdout.write(';'.join(p.as_posix() for p in paths))
            return 0
        for spec in specs.values():
            if not args.no_types:
                write_file(inc / spec.pkg / 'msg' / f'{spec.snake}.hpp', emit_type_header(spec))
            write_file(inc / cdr_header_path(spec), emit_cdr_header(spec, specs))
            write_file(out / 'src' / f'{spec.pkg}__{spec.snake}.cpp',
                             emit_cdr_source(spec, specs))
        write_file(inc / 'tactile_msgs' / 'cdr' / 'serialization.hpp', emit_umbrella(specs))
        write_file(out / 'src' / 'registry_table.cpp', emit_registry(specs))
        write_file(inc / 'tactile_msgs' / 'cdr' / 'testing.hpp', emit_testing(specs))
    except (MsgError, OSError, KeyError) as e:
        print(f'generate_msgs.py: error: {e}', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
