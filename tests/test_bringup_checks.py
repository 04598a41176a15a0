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

"""
feeder_bringup's plans for feeders side by side, and launches that fail before starting.

Issue 23: the diagnostic analyzers for N feeders (item 1); every optional part checked while
planning, so that a failing launch starts nothing (item 2); the emulator's default pty link
per user and namespace (item 2); argument choices (item 3). Plan level, without ``launch``
(tests/test_launch_cli.py runs the same with the real ``ros2 launch``).
"""

import os
import stat

from feeder_common import diagnostics
import pytest
from test_bringup import BRINGUP, support  # noqa: F401 - the fixture
import yaml

PLANNERS = ('plan_sim', 'plan_hardware', 'plan_feeders')
STATUS_NODES = ('feeder_driver', 'feeder_sim', 'feeder_monitor')


def test_the_shipped_analyzers_are_the_default_feeders_ones(support):  # noqa: F811
    shipped = yaml.safe_load((BRINGUP / 'config' / 'diagnostic_analyzers.yaml').read_text())
    default = support.FEEDERS_ARGUMENTS['namespaces'][0].split(',')
    assert shipped == support.diagnostic_analyzers(default)


def matching(analyzers, name):
    """Return the analyzers (GenericAnalyzer startswith) that take a status name."""
    return [key for key, a in analyzers.items() if isinstance(a, dict) and
            any(name.startswith(prefix) for prefix in a['startswith'])]


def test_each_feeders_statuses_go_to_its_own_analyzer(support):  # noqa: F811
    spaces = ['feeder_1', 'feeder_2', 'line_2/feeder_10']
    analyzers = support.diagnostic_analyzers(spaces)['analyzers']['ros__parameters']
    for ns in spaces:
        for node in STATUS_NODES:
            name = f'{diagnostics.status_prefix("/" + ns, node)}: lifecycle'
            assert matching(analyzers, name) == [ns.replace('/', '_')], name
            assert diagnostics.namespace_of(name) == '/' + ns
    assert diagnostics.status_prefix('/', 'feeder_driver') == 'feeder_driver'


@pytest.mark.parametrize('planner', PLANNERS)
@pytest.mark.parametrize('given, words', [
    ({'rviz': 'true'}, 'rviz:=true but rviz2 is not installed'),
    ({'robot_state_publisher': 'true'},
     'robot_state_publisher:=true but robot_state_publisher is not installed'),
])
def test_an_optional_part_asked_for_and_missing_is_refused(support, planner, given,  # noqa
                                                           words):
    for package in ('rviz2', 'robot_state_publisher'):
        if support.installed(package):
            pytest.skip(f'{package} is installed here')
    with pytest.raises(support.LaunchArgumentError, match=words):
        getattr(support, planner)(given)


@pytest.mark.parametrize('planner', PLANNERS)
def test_a_record_directory_that_exists_is_refused(support, planner, tmp_path):  # noqa: F811
    record = tmp_path / 'bags'
    if planner == 'plan_feeders':
        (record / 'feeder_2').mkdir(parents=True)
    else:
        record.mkdir()
    with pytest.raises(support.LaunchArgumentError, match='exists; the recorder makes a new'):
        getattr(support, planner)({'record': str(record)})
    (tmp_path / 'file').write_text('')
    with pytest.raises(support.LaunchArgumentError, match='not a directory you can write to'):
        getattr(support, planner)({'record': str(tmp_path / 'file' / 'bag')})
    assert getattr(support, planner)({'record': str(tmp_path / 'new' / 'bag')})


def test_the_emulator_link_is_per_user_and_namespace(support, monkeypatch, tmp_path):  # noqa
    monkeypatch.delenv('XDG_RUNTIME_DIR', raising=False)
    from feeder_common import paths
    monkeypatch.setattr(paths.tempfile, 'gettempdir', lambda: str(tmp_path))

    def link(ns):
        plan = support.plan_hardware({'emulator': 'true', 'namespace': ns})
        emulator = next(s for s in plan if s.executable == 'controller_emulator')
        return emulator.arguments[emulator.arguments.index('--link') + 1]

    folder = tmp_path / f'feeder-{os.getuid()}'
    assert link('a') == str(folder / 'feeder-a-tty')
    assert link('line_2/b') == str(folder / 'feeder-line_2-b-tty')
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    folder.chmod(0o755)     # not private any more: refused, not used
    with pytest.raises(support.LaunchArgumentError, match='mode 0700'):
        link('a')
    runtime = tmp_path / 'run'
    runtime.mkdir(mode=0o700)
    monkeypatch.setenv('XDG_RUNTIME_DIR', str(runtime))
    assert link('a') == str(runtime / 'feeder' / 'feeder-a-tty')


def test_word_arguments_have_choices_their_defaults_among_them(support):  # noqa: F811
    tables = (support.SIM_ARGUMENTS, support.HARDWARE_ARGUMENTS, support.FEEDERS_ARGUMENTS)
    assert {'rviz', 'robot_state_publisher', 'emulator'} <= set(support.CHOICES)
    for name, choices in support.CHOICES.items():
        declared = [t[name] for t in tables if name in t]
        assert declared, name
        assert all(default in choices for default, _ in declared), name


@pytest.mark.parametrize('planner, given', [
    ('plan_sim', {}),
    ('plan_sim', {'record': '{tmp}/bag', 'sensor_radius': '0.2'}),
    ('plan_hardware', {'emulator': 'true', 'record': '{tmp}/bag'}),
    ('plan_hardware', {'emulator': 'true', 'sensor_radius': '0.25'}),
    ('plan_hardware', {'port': '/dev/ttyUSB0'}),
])
def test_each_planned_process_fits_its_declared_slot(support, planner, given,  # noqa: F811
                                                     tmp_path):
    """The launch files declare one action per slot up front; the plan fills them in order."""
    plan = getattr(support, planner)({k: v.format(tmp=tmp_path) for k, v in given.items()})
    slots = [spec.slot for spec in plan]
    order = support.PLAN_SLOTS[planner]
    assert slots == sorted(slots, key=order.index) and len(set(slots)) == len(slots)
    for spec in plan:
        place = support.SLOTS[spec.slot]
        assert (spec.package, spec.executable, spec.name, spec.ros) == \
            (place.package, place.executable, place.name, bool(place.name))
        assert len(spec.parameters) == place.parameters
        assert len(spec.arguments) == place.arguments
        assert spec.remappings == list(place.remappings)
    if 'emulator' in slots:
        emulator = plan[slots.index('emulator')].arguments
        radius = float(emulator[emulator.index('--sensor-radius') + 1])
        assert radius == pytest.approx(float(given.get('sensor_radius', 0)) or
                                       support.scene_geometry(
                                           support.resolve_scene('triangle'))[0])
