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
feeder_bringup without ``launch``.

Every launch file's plan against the install space, the URDF (a tree whose frames are the ones
the topics name) and the RViz config.
"""

import ast
import math
import os
import pathlib
import tempfile
import xml.etree.ElementTree as ET

from feeder_common import frames, qos
from feeder_testing import INSTALL, install_env
import pytest
import yaml

BRINGUP = INSTALL / 'feeder_bringup' / 'share' / 'feeder_bringup'
LAUNCH_FILES = {'sim.launch.py': ('SIM_ARGUMENTS', 'plan_sim'),
                'hardware.launch.py': ('HARDWARE_ARGUMENTS', 'plan_hardware'),
                'feeders.launch.py': ('FEEDERS_ARGUMENTS', 'plan_feeders')}
OPTIONAL = {'robot_state_publisher', 'rviz2'}       # no wheels: left out where absent
# A record directory that does not exist (a plan refuses one that does).
NEW = os.path.join(tempfile.gettempdir(), f'feeder-test-bringup-{os.getpid()}')


@pytest.fixture(scope='module')
def support():
    """feeder_bringup.launch_support, finding packages in the workspace's install space."""
    import os
    env = install_env(INSTALL)
    old = os.environ.get('AMENT_PREFIX_PATH')
    os.environ['AMENT_PREFIX_PATH'] = env['AMENT_PREFIX_PATH']
    # (feeder_bringup's source tree is on sys.path by pytest.ini)
    from feeder_bringup import launch_support
    yield launch_support
    if old is None:
        os.environ.pop('AMENT_PREFIX_PATH')
    else:
        os.environ['AMENT_PREFIX_PATH'] = old


def check_plan(plan):
    """Every package, executable, parameter file and scene the plan names is installed."""
    for spec in plan:
        if spec.package in OPTIONAL:
            continue
        pkg = INSTALL / spec.package
        assert (pkg / 'share' / spec.package / 'package.xml').is_file(), spec.package
        assert (pkg / 'lib' / spec.package / spec.executable).is_file(), spec.executable
        for p in spec.parameters:
            if isinstance(p, str):
                assert pathlib.Path(p).is_file() and str(INSTALL) in p, p
            elif 'scene' in p:
                assert pathlib.Path(p['scene']).is_file() and str(INSTALL) in p['scene']
        if spec.ros:
            assert spec.namespace.startswith('/') and spec.name


@pytest.mark.parametrize('launch_file', sorted(LAUNCH_FILES))
def test_each_launch_file_declares_the_table_it_plans_with(launch_file):
    """The launch file passes one table to both the declarations and the plan."""
    source = (BRINGUP / 'launch' / launch_file).read_text()
    tree = ast.parse(source)
    table, planner = LAUNCH_FILES[launch_file]
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call) and
             getattr(n.func, 'id', '') == 'from_plan']
    assert len(calls) == 1
    assert [a.id for a in calls[0].args] == [table, planner]
    assert 'generate_launch_description' in source
    compile(source, launch_file, 'exec')


@pytest.mark.parametrize('planner, given', [
    ('plan_sim', {}),
    ('plan_sim', {'scene': 'experiment', 'namespace': 'line_2/feeder', 'record': f'{NEW}/x',
                  'sensor_radius': '0.27', 'cycle_period': '1', 'robot_state_publisher': 'auto'}),
    ('plan_sim', {'scene': 'hard/slow_release'}),
    ('plan_hardware', {}),
    ('plan_hardware', {'emulator': 'true', 'namespace': 'bench'}),
    ('plan_feeders', {}),
])
def test_every_plan_names_only_installed_things(support, planner, given):
    plan = getattr(support, planner)(given)
    check_plan(plan)
    assert plan


def test_the_plans_start_what_the_issue_asks(support):
    sim = support.plan_sim({})
    names = [(s.executable, s.name, s.namespace) for s in sim if s.package not in OPTIONAL]
    assert names == [('standin_node', 'feeder_driver', '/feeder'),
                     ('predictor_node', 'feeder_sim', '/feeder'),
                     ('monitor_node', 'feeder_monitor', '/feeder'),
                     ('feed_node', 'feeder_feed', '/feeder')]
    feed = next(s for s in sim if s.executable == 'feed_node')
    monitor = next(s for s in sim if s.executable == 'monitor_node')
    assert feed.parameters[0]['key_file'] == monitor.parameters[1]['key_file']
    assert sim[0].parameters[0].endswith('/feeder_sim/config/standin.yaml')
    assert sim[1].parameters[0].endswith('/feeder_sim/config/predictor.yaml')
    assert sim[0].parameters[1]['cycle_period'] == 1.0
    recorded = support.plan_sim({'record': f'{NEW}/bag1'})
    assert any(s.executable == 'bag_recorder' and s.arguments == [f'{NEW}/bag1']
               for s in recorded)
    hw = support.plan_hardware({'emulator': 'true'})
    emulator = next(s for s in hw if s.executable == 'controller_emulator')
    driver = next(s for s in hw if s.executable == 'driver_node')
    assert not emulator.ros
    link = emulator.arguments[emulator.arguments.index('--link') + 1]
    assert driver.parameters[1]['port'] == link
    assert support.plan_hardware({'port': '/dev/ttyUSB3'})[0].parameters[1]['port'] == \
        '/dev/ttyUSB3'
    three = support.plan_feeders({'namespaces': 'a,b,c', 'record': f'{NEW}/bags'})
    assert sorted({s.namespace for s in three}) == ['/a', '/b', '/c']
    assert sorted(s.arguments[0] for s in three if s.executable == 'bag_recorder') == \
        [f'{NEW}/bags/a', f'{NEW}/bags/b', f'{NEW}/bags/c']


@pytest.mark.parametrize('planner, given, words', [
    ('plan_sim', {'scene': 'nope'}, 'not an installed scene; installed: bracket'),
    ('plan_sim', {'scene': '/tmp/missing.yaml'}, 'no such file'),
    ('plan_sim', {'cycle_period': 'fast'}, 'cycle_period:=fast is not a number'),
    ('plan_sim', {'cycle_period': '0.001'}, '>= 0.005'),
    ('plan_sim', {'namespace': 'a b'}, 'namespace'),
    ('plan_sim', {'rviz': 'yes'}, 'rviz:=yes: use one of true, false'),
    ('plan_sim', {'port': '/dev/ttyACM0'}, "unknown launch arguments ['port']"),
    ('plan_feeders', {'namespaces': 'a,a'}, 'names one twice'),
    ('plan_sim', {'realtime_priority': '100'}, 'realtime_priority:=100 must be an integer in '
     '[0, 99]'),
    ('plan_hardware', {'realtime_priority': 'high'}, 'realtime_priority:=high must be an '
     'integer'),
])
def test_bad_launch_arguments_say_what_to_give(support, planner, given, words):
    with pytest.raises(support.LaunchArgumentError, match=words.replace('[', r'\[')):
        getattr(support, planner)(given)


@pytest.mark.parametrize('planner', ['plan_sim', 'plan_hardware', 'plan_feeders'])
def test_realtime_priority_reaches_every_feeder_node_and_only_when_asked(support, planner):
    def feeder_nodes(plan):
        return [s for s in plan if s.package.startswith('feeder_') and s.ros]
    asked = feeder_nodes(getattr(support, planner)({'realtime_priority': '40'}))
    assert len(asked) >= 3
    assert all(s.parameters[-1]['realtime_priority'] == 40 for s in asked)
    default = feeder_nodes(getattr(support, planner)({}))
    assert all('realtime_priority' not in s.parameters[-1] for s in default)


@pytest.mark.parametrize('planner, thrower', [('plan_sim', 'standin_node'),
                                              ('plan_hardware', 'driver_node'),
                                              ('plan_feeders', 'standin_node')])
def test_a_speed_policy_reaches_the_monitor_and_sets_the_thrower_to_setpoints(
        support, planner, thrower, tmp_path):
    policy = tmp_path / 'triangle_funnel_policy.json'
    policy.write_text('{}')     # the monitor checks what it holds, at configure
    plan = getattr(support, planner)({'speed_policy': str(policy)})
    monitors = [s for s in plan if s.executable == 'monitor_node']
    throwers = [s for s in plan if s.executable == thrower]
    assert monitors and len(monitors) == len(throwers)
    assert all(s.parameters[-1]['speed_policy'] == str(policy) for s in monitors)
    assert all(s.parameters[-1]['release_speed_mode'] == 'setpoint' for s in throwers)
    plain = getattr(support, planner)({})
    assert all('speed_policy' not in s.parameters[-1] and
               'release_speed_mode' not in s.parameters[-1]
               for s in plain if s.executable in ('monitor_node', thrower))
    with pytest.raises(support.LaunchArgumentError, match='no such file.*throwmap funnel'):
        getattr(support, planner)({'speed_policy': str(tmp_path / 'missing.json')})


def test_reading_an_undeclared_argument_is_an_error(support):
    args = support.Arguments(support.SIM_ARGUMENTS, {})
    with pytest.raises(KeyError, match='not declared'):
        args['port']


# ---- URDF --------------------------------------------------------------------------------

def urdf_tree(text):
    root = ET.fromstring(text)
    assert root.tag == 'robot'
    links = {link.get('name') for link in root.findall('link')}
    joints = {j.get('name'): j for j in root.findall('joint')}
    children = [j.find('child').get('link') for j in joints.values()]
    parents = [j.find('parent').get('link') for j in joints.values()]
    assert len(children) == len(set(children)), 'a link with two parents'
    assert set(children) | set(parents) <= links
    roots = links - set(children)
    assert roots == {frames.BASE_FRAME}, roots
    return root, links, joints


def origin(joint):
    o = joint.find('origin')
    return ([float(v) for v in o.get('xyz').split()], [float(v) for v in o.get('rpy').split()])


def test_the_urdf_relates_base_arm_and_sensor(support):
    root, links, joints = urdf_tree((BRINGUP / 'urdf' / 'feeder.urdf').read_text())
    assert links == {frames.BASE_FRAME, frames.ARM_LINK, frames.SENSOR_FRAME}
    arm = joints[frames.ARM_JOINT]
    assert arm.get('type') == 'revolute'
    assert arm.find('parent').get('link') == frames.BASE_FRAME
    assert arm.find('child').get('link') == frames.ARM_LINK
    axis = tuple(float(v) for v in arm.find('axis').get('xyz').split())
    assert axis == frames.ARM_AXIS
    limit = arm.find('limit')
    assert float(limit.get('lower')) < 0 < float(limit.get('upper'))
    assert float(limit.get('velocity')) > 5.6        # the triangle's release speed, rad/s
    sensor = joints['feeder_sensor_joint']
    assert sensor.get('type') == 'fixed'
    assert sensor.find('parent').get('link') == frames.ARM_LINK
    assert sensor.find('child').get('link') == frames.SENSOR_FRAME
    # The Range's beam (the sensor frame's x, REP 117) points up through the arm.
    _, (roll, pitch, yaw) = origin(sensor)
    x_axis = (math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw),
              -math.sin(pitch))
    assert x_axis == pytest.approx((0.0, 0.0, 1.0), abs=1e-9)


def test_the_scenes_numbers_are_written_in(support):
    text = support.robot_description(0.3, -0.01, 0.5,
                                     urdf=BRINGUP / 'urdf' / 'feeder.urdf')
    root, _, joints = urdf_tree(text)
    xyz, _ = origin(joints['feeder_sensor_joint'])
    assert xyz == [0.3, 0.0, -0.01]
    arm = root.find("link[@name='feeder_arm']/visual[@name='arm']")
    size = [float(v) for v in arm.find('geometry/box').get('size').split()]
    top = float(arm.find('origin').get('xyz').split()[2]) + size[2] / 2
    assert size[0] == 0.5 and top == pytest.approx(-0.01)


def test_the_launch_urdf_has_the_triangles_design(support):
    """sensor_radius:=auto asks the throwmap CLI; it agrees with the library."""
    from throwmap import analyse, load_scene
    scene = str(BRINGUP / 'scenes' / 'triangle.yaml')
    radius, h = support.scene_geometry(scene)
    sc = load_scene(scene)
    assert radius == pytest.approx(analyse(sc).sensor.radius, abs=1e-12)
    assert h == pytest.approx(sc.h)


def test_urdf_parser_py_reads_it_where_installed():
    urdf = pytest.importorskip('urdf_parser_py.urdf', reason='urdf_parser_py not installed')
    robot = urdf.URDF.from_xml_string((BRINGUP / 'urdf' / 'feeder.urdf').read_text())
    assert robot.get_root() == frames.BASE_FRAME
    assert robot.get_chain(frames.BASE_FRAME, frames.SENSOR_FRAME, joints=False) == \
        [frames.BASE_FRAME, frames.ARM_LINK, frames.SENSOR_FRAME]
    assert robot.joint_map[frames.ARM_JOINT].axis == list(frames.ARM_AXIS)


# ---- RViz --------------------------------------------------------------------------------

def test_the_rviz_config_shows_the_feeder_in_feeder_base():
    config = yaml.safe_load((BRINGUP / 'rviz' / 'feeder.rviz').read_text())
    vm = config['Visualization Manager']
    assert vm['Global Options']['Fixed Frame'] == frames.BASE_FRAME
    displays = {d['Class'].split('/')[-1]: d for d in vm['Displays']}
    assert {'RobotModel', 'MarkerArray', 'Range', 'TF'} <= set(displays)
    assert displays['RobotModel']['Description Topic']['Value'] == 'robot_description'
    markers = displays['MarkerArray']['Topic']
    assert markers['Value'] == 'markers'
    # The subscriptions match the publishers' QoS (latched markers; sensor data).
    assert markers['Durability Policy'] == 'Transient Local' and \
        qos.MARKERS.durability.name == 'TRANSIENT_LOCAL'
    assert displays['Range']['Topic']['Value'] == 'proximity'
