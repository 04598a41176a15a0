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
Turn a launch_support plan into launch actions (imports launch and launch_ros).

sim.launch.py and hardware.launch.py declare their processes up front, one Node (or
ExecuteProcess) action per slot of :data:`launch_support.PLAN_SLOTS`, so ``ros2 launch -p``
shows them; their values are the plan's. The first action after the arguments,
:class:`PlanFeeder`, makes the plan from the given arguments at launch time: every check runs
there, before any process starts, and a refused argument ends the launch with nothing started.
A slot the plan leaves empty (no recorder, no rviz2...) is skipped by its condition.
feeders.launch.py starts a number of feeders only known at launch time: its nodes come from
an OpaqueFunction (``-p`` shows that one action).
"""

import atexit
import shutil
import tempfile

from launch import Condition, Substitution
from launch.action import Action
from launch.actions import DeclareLaunchArgument, ExecuteProcess, LogInfo, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from launch_ros.substitutions import ExecutableInPackage
import yaml

from .launch_support import (CHOICES, executable_path, installed, LaunchArgumentError,
                             PLAN_SLOTS, SLOTS)

PLAN = 'feeder_bringup_plan'        # the launch context's global holding the plan, by slot


def declare(arguments):
    """Return the DeclareLaunchArgument actions of an argument table (with their choices)."""
    return [DeclareLaunchArgument(name, default_value=default, description=text,
                                  **({'choices': list(CHOICES[name])} if name in CHOICES
                                     else {}))
            for name, (default, text) in arguments.items()]


def _plan(arguments, planner, context):
    """Return the plan for the launch arguments; a refused one ends the launch."""
    given = {name: LaunchConfiguration(name).perform(context) for name in arguments}
    try:
        plan = planner(given)
    except LaunchArgumentError as exc:
        raise RuntimeError(f'feeder_bringup: {exc}') from None
    notes = []
    if given.get('robot_state_publisher', '').lower() == 'auto' and \
            not installed('robot_state_publisher'):
        notes.append(LogInfo(msg='feeder_bringup: robot_state_publisher is not installed: '
                                 'no robot model or transforms (robot_state_publisher:=auto)'))
    return plan, notes


def actions(plan):
    """Node / ExecuteProcess actions of a plan (a list of NodeSpec)."""
    out = []
    for spec in plan:
        if not spec.ros:
            out.append(ExecuteProcess(
                cmd=[str(executable_path(spec.package, spec.executable)), *spec.arguments],
                name=spec.executable, output='screen'))
            continue
        out.append(Node(package=spec.package, executable=spec.executable, name=spec.name,
                        namespace=spec.namespace, parameters=list(spec.parameters),
                        remappings=list(spec.remappings), arguments=list(spec.arguments),
                        output='screen'))
    return out


class PlanFeeder(Action):
    """Plan at launch time (checking every argument) for the slot actions that follow."""

    def __init__(self, arguments, planner, **kwargs):
        super().__init__(**kwargs)
        self.arguments = arguments
        self.planner = planner
        self.slots = PLAN_SLOTS[planner.__name__]

    def describe(self):
        return f'PlanFeeder({self.planner.__name__}: slots {", ".join(self.slots)})'

    __str__ = describe      # what ros2 launch -p prints

    def execute(self, context):
        plan, notes = _plan(self.arguments, self.planner, context)
        by_slot = {}
        for spec in plan:
            if spec.slot not in self.slots or spec.slot in by_slot:
                raise RuntimeError(f'feeder_bringup: plan slot {spec.slot!r} is not one of '
                                   f'{self.slots} or comes twice')
            by_slot[spec.slot] = spec
        folder = tempfile.mkdtemp(prefix='feeder_launch_params_')
        atexit.register(shutil.rmtree, folder, True)
        context.extend_globals({PLAN: {'specs': by_slot, 'folder': folder}})
        return notes


def _planned(context, slot):
    return context.get_locals_as_dict()[PLAN]['specs'].get(slot)


class Planned(Substitution):
    """A value of the launch-time plan: a slot's namespace, parameters item or argument."""

    def __init__(self, slot, what, index=None):
        super().__init__()
        self.slot, self.what, self.index = slot, what, index

    def describe(self):
        index = '' if self.index is None else f'[{self.index}]'
        return f"Planned('{self.slot}'.{self.what}{index})"

    def perform(self, context):
        spec = _planned(context, self.slot)
        if self.what == 'namespace':
            return spec.namespace
        value = getattr(spec, self.what)[self.index]
        if self.what == 'parameters' and isinstance(value, dict):
            # A dict of the plan as a parameters file (as launch_ros writes one for a dict).
            folder = context.get_locals_as_dict()[PLAN]['folder']
            with tempfile.NamedTemporaryFile('w', dir=folder, suffix='.yaml',
                                             delete=False) as f:
                yaml.safe_dump({'/**': {'ros__parameters': value}}, f)
            return f.name
        return str(value)


def slot_action(slot):
    """Return the Node (or ExecuteProcess) action of ``slot``, run where the plan fills it."""
    place = SLOTS[slot]
    condition = Condition(predicate=lambda context: _planned(context, slot) is not None)
    arguments = [Planned(slot, 'arguments', i) for i in range(place.arguments)]
    if not place.name:
        return ExecuteProcess(cmd=[ExecutableInPackage(place.executable, place.package),
                                   *arguments],
                              name=place.executable, output='screen', condition=condition)
    return Node(package=place.package, executable=place.executable, name=place.name,
                namespace=Planned(slot, 'namespace'),
                parameters=[Planned(slot, 'parameters', i) for i in range(place.parameters)]
                or None,
                remappings=list(place.remappings), arguments=arguments or None,
                output='screen', condition=condition)


def from_plan(arguments, planner):
    """
    Return the entities of a launch file: its declared arguments, then what it starts.

    For a planner with slots (PLAN_SLOTS), :class:`PlanFeeder` and one action per slot;
    otherwise an OpaqueFunction that makes the plan's actions at launch time.
    """
    if planner.__name__ in PLAN_SLOTS:
        return declare(arguments) + [PlanFeeder(arguments, planner)] + [
            slot_action(slot) for slot in PLAN_SLOTS[planner.__name__]]

    def launch_setup(context):
        plan, notes = _plan(arguments, planner, context)
        return notes + actions(plan)

    return declare(arguments) + [OpaqueFunction(function=launch_setup)]
