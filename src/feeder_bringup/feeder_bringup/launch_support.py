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
What the feeder's launch files start, as plain data (importable without ``launch``).

Each launch file declares the arguments of its table (:data:`SIM_ARGUMENTS`,
:data:`HARDWARE_ARGUMENTS`, :data:`FEEDERS_ARGUMENTS`) and turns the plan built here
(:func:`plan_sim`, :func:`plan_hardware`, :func:`plan_feeders`: lists of :class:`NodeSpec`)
into launch_ros actions (:mod:`feeder_bringup.launch_actions`). So the plan can be checked
where ``launch`` is not installed: every package, executable, config file and scene it names
exists in the install space, and it reads only declared arguments (:class:`Arguments`).

Every check is made while planning, before the plan is returned: a launch whose arguments
cannot work (an optional part asked for and not installed, a record directory that exists)
raises :class:`LaunchArgumentError` and starts nothing. :data:`CHOICES` lists the arguments
that take one of a few words (the launch files declare them with ``choices``).

The URDF needs the scene's numbers (the sensor radius and the arm's offset h): they come from
the throwmap CLI installed with the workspace (``throwmap design/grasp --json``), so the launch
process needs no numpy; a given ``sensor_radius`` skips the design.
"""

from dataclasses import dataclass, field
import json
import math
import os
import pathlib
import shutil
import subprocess
import xml.etree.ElementTree as ET

from ament_index_python.packages import (get_package_prefix, get_package_share_directory,
                                         PackageNotFoundError)
from feeder_common import auth, paths

# name: (default, description)
COMMON_ARGUMENTS = {
    'scene': ('triangle', 'an installed scene (share/feeder_bringup/scenes/<name>.yaml: '
              'triangle, bracket, experiment, house, rectangle, liftoff, hard/<name>) or a path'),
    'namespace': ('feeder', 'namespace of the feeder (every topic, service and node in it)'),
    'cycle_period': ('1.0', 's between cycles while enabled'),
    'realtime_priority': ('0', "SCHED_FIFO priority (1-99) of the feeder's nodes (needs an "
                          'rtprio limit or CAP_SYS_NICE); 0: the normal scheduler'),
    'sensor_radius': ('auto', "m; auto: throwmap's sensor design for the scene"),
    'record': ('', 'a new directory: record the feeder to a rosbag2 MCAP bag there'),
    'robot_state_publisher': ('auto', 'auto: start it where it is installed; true; false'),
    'rviz': ('false', 'true: start rviz2 with share/feeder_bringup/rviz/feeder.rviz'),
    'arm_length': ('0.4', 'm, length of the arm drawn in the robot model'),
    'key_file': ('', 'HMAC key file of the driver (or stand-in) and the monitor (mode 0600); '
                 'created with a new key when absent; empty: $ROS_HOME/feeder/hmac.key'),
    'speed_policy': ('', 'policy file of throwmap funnel (<scene>_funnel_policy.json): the '
                     "monitor chooses each cycle's release speed, the driver (or stand-in) "
                     'throws at it; empty: the fixed design'),
}
SIM_ARGUMENTS = dict(COMMON_ARGUMENTS)
HARDWARE_ARGUMENTS = dict(COMMON_ARGUMENTS, **{
    'port': ('/dev/ttyACM0', 'serial port of the controller (device or pyserial URL)'),
    'emulator': ('false', 'true: start controller_emulator on a pty and drive that'),
    'emulator_link': ('', 'path of the emulator pty (default: feeder-<namespace>-tty in the '
                      "user's runtime folder: $XDG_RUNTIME_DIR/feeder, else <tmp>/feeder-<uid>, "
                      'mode 0700)'),
})
FEEDERS_ARGUMENTS = dict(COMMON_ARGUMENTS, **{
    'namespaces': ('feeder_1,feeder_2,feeder_3', 'comma-separated namespaces: one simulated '
                   'feeder in each'),
})
del FEEDERS_ARGUMENTS['namespace']
# Arguments that take one of a few words: declared with these ``choices`` (ros2 launch refuses
# anything else before the launch starts, and -s lists them).
CHOICES = {
    'robot_state_publisher': ('auto', 'true', 'false'),
    'rviz': ('true', 'false'),
    'emulator': ('true', 'false'),
}

ARM_THICKNESS = 0.004   # m, as feeder_sim.markers draws it


class LaunchArgumentError(ValueError):
    """A launch argument is unusable; the text names it and the fix."""


# Transforms stay in the feeder's namespace (<ns>/tf), so feeders side by side, each with
# frames feeder_base, feeder_arm, feeder_sensor, never mix.
TF_REMAPPINGS = (('/tf', 'tf'), ('/tf_static', 'tf_static'))


@dataclass(frozen=True)
class Slot:
    """
    A place for one process in a launch file, fixed when the launch description is made.

    What the plan fills in at launch time has a fixed shape: ``parameters`` items (files and
    dicts), ``arguments`` items; so the launch file can declare the Node action up front (and
    ``ros2 launch -p`` shows it) and take the values from the plan.
    """

    package: str
    executable: str
    name: str = ''              # '' for a plain process (not a ROS node)
    parameters: int = 0
    arguments: int = 0
    remappings: tuple = ()


SLOTS = {
    'emulator': Slot('feeder_driver', 'controller_emulator', arguments=6),
    'driver': Slot('feeder_driver', 'driver_node', 'feeder_driver', parameters=2),
    'hardware': Slot('feeder_sim', 'standin_node', 'feeder_driver', parameters=2),
    'predictor': Slot('feeder_sim', 'predictor_node', 'feeder_sim', parameters=2),
    'monitor': Slot('feeder_monitor', 'monitor_node', 'feeder_monitor', parameters=2),
    'feed': Slot('feeder_monitor', 'feed_node', 'feeder_feed', parameters=1),
    'recorder': Slot('feeder_monitor', 'bag_recorder', 'feeder_bag_recorder', arguments=1),
    'robot_state_publisher': Slot('robot_state_publisher', 'robot_state_publisher',
                                  'robot_state_publisher', parameters=1,
                                  remappings=TF_REMAPPINGS),
    'rviz': Slot('rviz2', 'rviz2', 'rviz2', arguments=2, remappings=TF_REMAPPINGS),
}
# The slots of each launch file, in start order (a plan holds a subset, in this order).
PLAN_SLOTS = {
    'plan_sim': ('hardware', 'predictor', 'monitor', 'feed', 'recorder',
                 'robot_state_publisher', 'rviz'),
    'plan_hardware': ('emulator', 'driver', 'predictor', 'monitor', 'feed', 'recorder',
                      'robot_state_publisher', 'rviz'),
}


@dataclass
class NodeSpec:
    """One process: a ROS node (``ros``) or a plain executable of a package."""

    package: str
    executable: str
    name: str = ''
    namespace: str = ''
    parameters: list = field(default_factory=list)     # file paths and dicts, in order
    remappings: list = field(default_factory=list)
    arguments: list = field(default_factory=list)
    ros: bool = True
    slot: str = ''      # its place in the launch file (SLOTS)


def _spec(slot, ns='', parameters=(), arguments=()):
    """Return the NodeSpec of ``slot`` (SLOTS) with these parameters and arguments."""
    place = SLOTS[slot]
    if len(parameters) != place.parameters or len(arguments) != place.arguments:
        raise AssertionError(f'slot {slot}: {len(parameters)} parameter items and '
                             f'{len(arguments)} arguments, not {place}')
    return NodeSpec(place.package, place.executable, place.name, ns if place.name else '',
                    list(parameters), list(place.remappings), list(arguments),
                    ros=bool(place.name), slot=slot)


class Arguments:
    """The values of the declared launch arguments; reading an undeclared one is an error."""

    def __init__(self, declared, given):
        unknown = set(given) - set(declared)
        if unknown:
            raise LaunchArgumentError(f'unknown launch arguments {sorted(unknown)}; this launch '
                                      f'file takes {sorted(declared)}')
        self._values = {name: str(given.get(name, default))
                        for name, (default, _) in declared.items()}

    def __getitem__(self, name):
        if name not in self._values:
            raise KeyError(f'launch argument {name!r} is read but not declared')
        return self._values[name]

    def with_values(self, **values):
        out = Arguments.__new__(Arguments)
        out._values = dict(self._values, **{k: str(v) for k, v in values.items()})
        return out


def share(package):
    return pathlib.Path(get_package_share_directory(package))


def installed(package):
    """Whether ``package`` is in the ament index (e.g. robot_state_publisher, rviz2)."""
    try:
        get_package_prefix(package)
    except PackageNotFoundError:
        return False
    return True


def executable_path(package, executable):
    """Path of ``executable`` of ``package`` where ``ros2 run`` looks (lib/<package>)."""
    return pathlib.Path(get_package_prefix(package)) / 'lib' / package / executable


def installed_scenes():
    root = share('feeder_bringup') / 'scenes'
    return sorted(str(p.relative_to(root))[:-len('.yaml')] for p in root.rglob('*.yaml'))


def resolve_scene(scene):
    """Path of a scene given by name (an installed one, e.g. hard/fast_spin) or by path."""
    path = pathlib.Path(os.path.expanduser(scene))
    if path.suffix not in ('.yaml', '.yml'):
        found = share('feeder_bringup') / 'scenes' / f'{scene}.yaml'
        if found.is_file():
            return str(found)
        if not path.is_file():
            raise LaunchArgumentError(f'scene:={scene}: not an installed scene; installed: '
                                      f'{", ".join(installed_scenes())} (or give a path)')
    if not path.is_file():
        raise LaunchArgumentError(f'scene:={scene}: no such file; give an installed scene '
                                  f'({", ".join(installed_scenes())}) or a path')
    return str(path.resolve())


def number(args, name, minimum=None):
    try:
        value = float(args[name])
    except ValueError:
        raise LaunchArgumentError(f'{name}:={args[name]} is not a number') from None
    if not math.isfinite(value) or (minimum is not None and value < minimum):
        raise LaunchArgumentError(f'{name}:={args[name]} must be a finite number'
                                  + (f' >= {minimum}' if minimum is not None else ''))
    return value


def integer(args, name, minimum, maximum):
    text = args[name].strip()
    if not text.lstrip('-').isdigit() or not minimum <= int(text) <= maximum:
        raise LaunchArgumentError(f'{name}:={args[name]} must be an integer in '
                                  f'[{minimum}, {maximum}]')
    return int(text)


def _realtime_parameter(args):
    """{'realtime_priority': P} for every feeder node when asked for, else {}."""
    priority = integer(args, 'realtime_priority', 0, 99)
    return {'realtime_priority': priority} if priority else {}


def flag(args, name, choices=None):
    choices = choices or CHOICES.get(name, ('true', 'false'))
    value = args[name].strip().lower()
    if value not in choices:
        raise LaunchArgumentError(f'{name}:={args[name]}: use one of {", ".join(choices)}')
    return value


def namespace(text):
    ns = '/' + text.strip().strip('/')
    if ns == '/' or not all(part and (part[0].isalpha() or part[0] == '_') and
                            all(c.isalnum() or c == '_' for c in part)
                            for part in ns[1:].split('/')):
        raise LaunchArgumentError(f'namespace {text!r}: use names of letters, digits and _, '
                                  'e.g. feeder or line_2/feeder')
    return ns


_GEOMETRY = {}


def throwmap_json(*argv):
    exe = executable_path('throwmap', 'throwmap')
    cmd = [str(exe) if exe.exists() else (shutil.which('throwmap') or 'throwmap'), *argv,
           '--json']
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if proc.returncode != 0:
        raise LaunchArgumentError(f'{" ".join(cmd)} failed: {proc.stderr.strip()}')
    return json.loads(proc.stdout)


def scene_geometry(scene_path):
    """Return (designed sensor radius, arm offset h) of a scene, m, from the throwmap CLI."""
    if scene_path not in _GEOMETRY:
        grasp = throwmap_json('grasp', scene_path)
        design = throwmap_json('design', scene_path, '--quiet')
        _GEOMETRY[scene_path] = (float(design['sensor']['radius']), float(grasp['offset']))
    return _GEOMETRY[scene_path]


def robot_description(sensor_radius, arm_offset, arm_length=0.4, urdf=None):
    """
    Return the feeder's URDF with a scene's numbers written in (no xacro).

    The sensor joint sits at (sensor_radius, 0, arm_offset) on the arm; the arm's box is
    ``arm_length`` long, its top surface at z = arm_offset.
    """
    path = urdf or share('feeder_bringup') / 'urdf' / 'feeder.urdf'
    root = ET.parse(path).getroot()
    joint = root.find("joint[@name='feeder_sensor_joint']/origin")
    joint.set('xyz', f'{sensor_radius:.6g} 0 {arm_offset:.6g}')
    arm = root.find("link[@name='feeder_arm']/visual[@name='arm']")
    arm.find('origin').set('xyz', f'{arm_length / 2:.6g} 0 {arm_offset - ARM_THICKNESS / 2:.6g}')
    arm.find('geometry/box').set('size', f'{arm_length:.6g} 0.01 {ARM_THICKNESS:.6g}')
    return ET.tostring(root, encoding='unicode')


def emulator_link(ns):
    """Return the default pty link of ``ns``'s emulator, this user's (feeder_common.paths)."""
    try:
        return paths.emulator_link(ns)
    except paths.RuntimeDirError as exc:
        raise LaunchArgumentError(f'emulator_link: {exc}; give emulator_link:=PATH') from None


def diagnostic_analyzers(namespaces):
    """
    diagnostic_aggregator's parameters for feeders in ``namespaces``: one group per feeder.

    Status names carry the namespace (``feeder_1/feeder_driver: cycles``,
    feeder_common.diagnostics), so each feeder's statuses go under ``Feeders/<namespace>``
    (the name's prefix removed). The shipped config/diagnostic_analyzers.yaml is this for
    feeders.launch.py's default namespaces.
    """
    analyzers = {'path': 'Feeders'}
    for text in namespaces:
        ns = namespace(text)[1:]
        analyzers[ns.replace('/', '_')] = {
            'type': 'diagnostic_aggregator/GenericAnalyzer', 'path': ns,
            'startswith': [f'{ns}/'], 'remove_prefix': [f'{ns}/'], 'timeout': 5.0}
    return {'analyzers': {'ros__parameters': analyzers}}


def _key_parameter(args):
    """{'key_file': path} for the signing nodes; the file is made (mode 0600) when absent."""
    path = os.path.abspath(os.path.expanduser(args['key_file'] or auth.default_key_path()))
    try:
        auth.ensure_key(path)
    except (auth.KeyFileError, OSError) as exc:
        raise LaunchArgumentError(f'key_file:={args["key_file"]}: {exc}') from None
    return {'key_file': path}


def _speed_policy(args):
    """
    ({'speed_policy': path} for the monitor, {'release_speed_mode': ...} for the thrower).

    An empty ``speed_policy:=``: the fixed design, and the thrower's mode is left to its
    config file. A given file must exist (the monitor checks what it holds at configure).
    """
    if not args['speed_policy']:
        return {}, {}
    path = os.path.abspath(os.path.expanduser(args['speed_policy']))
    if not os.path.isfile(path):
        raise LaunchArgumentError(f'speed_policy:={args["speed_policy"]}: no such file ({path}); '
                                  'write one with throwmap funnel SCENE --speeds A:B:STEP --out '
                                  "DIR, or give speed_policy:='' for the fixed design")
    return {'speed_policy': path}, {'release_speed_mode': 'setpoint'}


def _sensor_parameter(args):
    """{'sensor_radius': R} for the nodes when given, else {} (they design it themselves)."""
    if args['sensor_radius'].strip().lower() == 'auto':
        return {}
    return {'sensor_radius': number(args, 'sensor_radius', minimum=0.0)}


def _record_directory(args):
    """Return the bag directory of ``record:=`` (absolute; '' for none), or refuse it."""
    if not args['record']:
        return ''
    path = os.path.abspath(os.path.expanduser(args['record']))
    if os.path.lexists(path):
        raise LaunchArgumentError(f'record:={args["record"]}: {path} exists; the recorder '
                                  'makes a new directory: give one that does not exist')
    parent = os.path.dirname(path)
    while not os.path.exists(parent):       # made by the recorder (BagWriter makes parents)
        parent = os.path.dirname(parent)
    if not os.path.isdir(parent) or not os.access(parent, os.W_OK | os.X_OK):
        raise LaunchArgumentError(f'record:={args["record"]}: cannot make {path} ({parent} is '
                                  'not a directory you can write to)')
    return path


def _optional(args, name, package):
    """Whether to start ``package`` for ``name:=`` (auto: where installed; true: insist)."""
    value = flag(args, name)
    if value == 'true' and not installed(package):
        raise LaunchArgumentError(
            f'{name}:=true but {package} is not installed (not in the ament index: '
            f'AMENT_PREFIX_PATH); install ros-kilted-{package.replace("_", "-")} or give '
            f'{name}:={"auto" if "auto" in CHOICES[name] else "false"}')
    return value == 'true' or (value == 'auto' and installed(package))


def _common_nodes(args, ns, scene):
    """Predictor, monitor, feed_node, recorder, robot_state_publisher, rviz2 of one feeder."""
    sensor = _sensor_parameter(args)
    rt = _realtime_parameter(args)
    record = _record_directory(args)
    want_rsp = _optional(args, 'robot_state_publisher', 'robot_state_publisher')
    want_rviz = _optional(args, 'rviz', 'rviz2')
    arm_length = number(args, 'arm_length', minimum=0.01)
    nodes = [
        _spec('predictor', ns, [str(share('feeder_sim') / 'config' / 'predictor.yaml'),
                                {'scene': scene, **sensor, **rt}]),
        _spec('monitor', ns, [str(share('feeder_monitor') / 'config' / 'monitor.yaml'),
                              {'scene': scene, **sensor, **rt, **_key_parameter(args),
                               **_speed_policy(args)[0]}]),
        # The cell's "give me a part" action (~/feed_part), checking the monitor's signature.
        _spec('feed', ns, [{**rt, **_key_parameter(args)}]),
    ]
    if record:
        # It records the feeder's namespace (+ /diagnostics, /tf, /tf_static): its own bag.
        nodes.append(_spec('recorder', ns, arguments=[record]))
    if want_rsp:
        radius = sensor.get('sensor_radius') or scene_geometry(scene)[0]
        urdf = robot_description(radius, scene_geometry(scene)[1], arm_length)
        nodes.append(_spec('robot_state_publisher', ns, [{'robot_description': urdf}]))
    if want_rviz:
        nodes.append(_spec('rviz', ns, arguments=[
            '-d', str(share('feeder_bringup') / 'rviz' / 'feeder.rviz')]))
    return nodes


def plan_sim(given):
    """Plan the simulated feeder: the hardware stand-in, predictor, monitor (+ options)."""
    args = given if isinstance(given, Arguments) else Arguments(SIM_ARGUMENTS, given)
    ns = namespace(args['namespace'])
    scene = resolve_scene(args['scene'])
    hardware = _spec('hardware', ns, [str(share('feeder_sim') / 'config' / 'standin.yaml'),
                                      {'scene': scene,
                                       'cycle_period': number(args, 'cycle_period', 0.005),
                                       **_sensor_parameter(args), **_realtime_parameter(args),
                                       **_key_parameter(args), **_speed_policy(args)[1]}])
    return [hardware] + _common_nodes(args, ns, scene)


def plan_hardware(given):
    """Plan the real feeder: driver_node on a port or the emulator's pty, predictor, monitor."""
    args = Arguments(HARDWARE_ARGUMENTS, given)
    ns = namespace(args['namespace'])
    scene = resolve_scene(args['scene'])
    common = _common_nodes(args, ns, scene)     # its checks first: they cost no design
    nodes = []
    port = args['port']
    if flag(args, 'emulator') == 'true':
        port = args['emulator_link'] or emulator_link(ns)
        # The sensor radius always given (the design's for auto, as the emulator would make it
        # itself): the emulator's command line has one shape, which the launch file declares.
        radius = _sensor_parameter(args).get('sensor_radius') or scene_geometry(scene)[0]
        nodes.append(_spec('emulator', arguments=[
            '--scene', scene, '--link', port, '--sensor-radius', f'{radius:.9g}']))
    nodes.append(_spec('driver', ns, [
        str(share('feeder_driver') / 'config' / 'driver.yaml'),
        {'port': port, 'cycle_period': number(args, 'cycle_period', 0.005),
         **_realtime_parameter(args), **_key_parameter(args), **_speed_policy(args)[1]}]))
    return nodes + common


def plan_feeders(given):
    """Plan several simulated feeders side by side, one per namespace, in one domain."""
    args = Arguments(FEEDERS_ARGUMENTS, given)
    names = [n.strip() for n in args['namespaces'].split(',') if n.strip()]
    if not names:
        raise LaunchArgumentError('namespaces:= is empty; give e.g. feeder_1,feeder_2')
    spaces = [namespace(n) for n in names]
    if len(set(spaces)) != len(spaces):
        raise LaunchArgumentError(f'namespaces:={args["namespaces"]} names one twice')
    record = args['record']
    nodes = []
    for ns in spaces:
        one = Arguments(SIM_ARGUMENTS, {
            name: args[name] for name in SIM_ARGUMENTS if name != 'namespace'})
        one = one.with_values(namespace=ns,
                              record=os.path.join(record, ns[1:].replace('/', '_'))
                              if record else '')
        nodes += plan_sim(one)
    return nodes
