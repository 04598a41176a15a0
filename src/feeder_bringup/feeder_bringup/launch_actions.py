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


"""Turn a launch_support plan into launch actions (imports launch and launch_ros)."""

from launch.actions import DeclareLaunchArgument, ExecuteProcess, LogInfo, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from .launch_support import executable_path, installed, LaunchArgumentError


def declare(arguments):
    """Return the DeclareLaunchArgument actions of an argument table."""
    return [DeclareLaunchArgument(name, default_value=default, description=text)
            for name, (default, text) in arguments.items()]


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


def from_plan(arguments, planner):
    """Return the entities: the declared arguments, then the plan made at launch time."""
    def launch_setup(context):
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
        return notes + actions(plan)

    return declare(arguments) + [OpaqueFunction(function=launch_setup)]
