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

"""Parameter tables of monitor_node and feed_node (ROS-free; specs of feeder_common)."""

from feeder_common.params import DIAGNOSTIC_PERIOD, KEY_FILE, ParamSpec, REALTIME_PRIORITY

MONITOR_PARAMS = (
    ParamSpec('autostart', True, 'configure and activate at start-up; false: wait for '
              '~/change_state (ros2 lifecycle set)', read_only=True),
    ParamSpec('scene', '', "scene YAML the feeder runs (the same file as the sim's); must load",
              read_only=True, constraints='a file throwmap.load_scene accepts'),
    REALTIME_PRIORITY,
    ParamSpec('sensor_radius', 0.0, 'arm coordinate x of the proximity sensor, m; 0: the '
              "analysis's choice (as the sim's default)", minimum=0.0, maximum=10.0),
    ParamSpec('warmup_cycles', -1, 'completed throws after a (re)start before a detection '
              'counts; -1: the proven warm-up of the analysis', minimum=-1, maximum=1_000_000,
              constraints='-1 or >= the proven warm-up at sensor_radius'),
    ParamSpec('settle_cycles', -1, 'throws after a (re)start before the detection-pattern '
              'checks apply; -1: the longest transient of the analysis basin', minimum=-1,
              maximum=1_000_000),
    ParamSpec('silence_margin', 1.5, 'a stretch without detection may last this factor times '
              'the longest one in the limit-set orbit before it is an anomaly', minimum=1.0,
              maximum=100.0),
    ParamSpec('early_margin_cycles', 2, 'a detection may come this many cycles sooner than '
              'the shortest gap of the orbit', minimum=0, maximum=1000),
    ParamSpec('run_margin_cycles', 0, 'a run of detections may be this much longer than the '
              'longest run of the orbit', minimum=0, maximum=1000),
    ParamSpec('orbit_throws', 20000, 'length of the limit-set orbit the pattern rules are read '
              'from', minimum=1000, maximum=1_000_000, read_only=True),
    ParamSpec('max_report_age', 1.0, 'a cycle report sampled more than this long ago (or this far '
              'in the future) is refused as stale: an anomaly, never ready, s (clocks of driver '
              'and monitor must agree to well within it)', minimum=0.01, maximum=60.0),
    KEY_FILE,
    ParamSpec('driver_node', 'feeder_driver', 'the node whose signed cycle reports are judged '
              "(relative to the monitor's namespace, or absolute); a report not signed by it "
              'under key_file is an anomaly', read_only=True,
              constraints='not empty', max_length=256),
    ParamSpec('ready_deadline', 1.0, 'edge1_ready is published at least this often, s (every '
              'judged cycle, and every quarter of it when idle, with a fresh signed sent '
              'time): its offered deadline and liveliness lease; a reader that sees either '
              'lapse, or a sent time older than this, must take the statement as false',
              minimum=0.02, maximum=60.0, read_only=True),
    ParamSpec('speed_policy', '', 'policy file of throwmap funnel (<scene>_funnel_policy.json; '
              "docs/funnel.md); '': the fixed design (the warm-up and the limit set's rules). "
              "Set: each cycle is judged by the policy's knowledge and the next release speed "
              'is published, signed, on release_speed_setpoint (for a driver in '
              'release_speed_mode setpoint)', read_only=True, max_length=4096,
              constraints='made for the scene, its goal edge, h, speed and the sensor_radius'),
    DIAGNOSTIC_PERIOD,
)

FEED_PARAMS = (
    REALTIME_PRIORITY,
    ParamSpec('driver_node', 'feeder_driver', 'the node whose ~/trigger_cycle fires the cycles '
              "and whose signed cycle reports say a cycle failed (relative to this node's "
              'namespace, or absolute)', read_only=True, constraints='not empty',
              max_length=256),
    ParamSpec('monitor_node', 'feeder_monitor', 'the monitor whose signed verdicts prove a part '
              "ready (relative to this node's namespace, or absolute)", read_only=True,
              constraints='not empty', max_length=256),
    KEY_FILE,
    ParamSpec('max_statement_age', 1.0, 'a verdict or statement of the monitor sent longer ago '
              'than this is not taken as proof, s; with no statement this fresh a goal is '
              'refused (the monitor is not tracking)', minimum=0.05, maximum=60.0),
    ParamSpec('max_report_age', 1.0, 'a cycle report sampled longer ago than this is ignored, s',
              minimum=0.01, maximum=60.0),
    ParamSpec('verdict_timeout', 10.0, 'a fired cycle without its verdict this long ends the goal '
              "as a serial fault, s (more than the driver's cycle_timeout_s)", minimum=0.1,
              maximum=3600.0),
)
