# Copyright 2026 The feeder authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""The README's interface tables say what the code declares (parameters, CLI, protocol, topics)."""

import pathlib
import re

from feeder_driver import params as driver_params
from feeder_driver import protocol
from feeder_monitor.params import FEED_PARAMS, MONITOR_PARAMS
from feeder_sim.params import PREDICTOR_PARAMS, STANDIN_PARAMS
import pytest
from throwmap.cli import build_parser

REPO = pathlib.Path(__file__).resolve().parents[1]
README = (REPO / 'README.md').read_text()


def table_after(marker):
    """First-column code names of the first table after ``marker``."""
    start = README.index(marker)
    lines = README[start:].split('\n')
    rows, seen_table = [], False
    for line in lines[1:]:
        if line.startswith('|'):
            seen_table = True
            rows.append(line)
        elif seen_table:
            break
    names = []
    for row in rows[2:]:
        names.extend(re.findall(r'`([^`]+)`', row.split('|')[1]))
    return names


@pytest.mark.parametrize('marker, specs', [
    ('**driver_node** (`feeder_driver`)', [s.name for s in driver_params.SPECS]),
    ('**standin_node** (`feeder_sim`', [s.name for s in STANDIN_PARAMS]),
    ('**predictor_node** (`feeder_sim`', [s.name for s in PREDICTOR_PARAMS]),
    ('**monitor_node** (`feeder_monitor`)', [s.name for s in MONITOR_PARAMS]),
    ('**feed_node** (`feeder_monitor`', [s.name for s in FEED_PARAMS]),
])
def test_parameter_tables_list_exactly_the_declared_parameters(marker, specs):
    assert sorted(table_after(marker)) == sorted(specs)


def test_driver_defaults_in_readme_are_the_declared_ones():
    start = README.index('**driver_node** (`feeder_driver`)')
    block = README[start:README.index('**standin_node**')]
    for spec in driver_params.SPECS:
        row = next(line for line in block.split('\n') if line.startswith(f'| `{spec.name}` |'))
        default = row.split('|')[3].strip().strip('`')
        default = '' if default == "''" else default     # an empty string, written ''
        expected = str(spec.default).lower() if isinstance(spec.default, bool) else str(
            spec.default)
        assert default == expected, spec.name


def test_cli_table_lists_every_subcommand():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == 'command')
    documented = {m.group(1) for m in re.finditer(r'^\| `throwmap ([a-z-]+)', README, re.M)}
    assert documented == set(sub.choices)


def test_protocol_table_lists_every_message_and_error_code():
    start = README.index('### Serial protocol')
    block = README[start:README.index('### Bags')]
    frames = set(re.findall(r'`([A-Z]+)[,`]', block))
    assert frames >= set(protocol.HOST_MESSAGES) | set(protocol.CONTROLLER_MESSAGES)
    for code in protocol.ERROR_CODES:
        assert code in block, code


def test_topics_of_the_contract_are_in_the_readme():
    contract = (REPO / 'docs' / 'interfaces.md').read_text()
    topics = set(re.findall(r'^\| `([a-z_/~]+)` \| [a-z_]+/', contract, re.M))
    assert topics
    start = README.index('### Topics and services')
    block = README[start:README.index('### Parameters')]
    for topic in topics:
        assert f'`{topic}`' in block, topic


def test_the_throwmap_cli_is_on_the_path():
    """README commands call `throwmap ...` after `. scripts/setup.sh`."""
    import shutil
    import subprocess
    exe = shutil.which('throwmap')
    assert exe, 'throwmap is not on PATH after scripts/setup.sh'
    out = subprocess.run([exe, 'grasp', str(REPO / 'scenes' / 'triangle.yaml'), '--json'],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert '"R_grasp"' in out.stdout
