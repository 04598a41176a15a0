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
Issue 23: the monitor as a lifecycle node (item 7b), one analysis per parameter file (item 4).

The real MonitorNode runs in-process (own context, own domain) beside a test node that reads
edge1_ready and edge1_verdict through DDS (what a consumer gets, not what the node tried to
send: a lifecycle publisher drops what it is given while inactive) and calls the parameter
service as ``ros2 param load`` does: one SetParameters request, which rclpy's service applies
one parameter at a time. Cycles are signed reports of a simulated triangle (throwmap.PartOnArm
at the designed sensor), given to the node's subscription callbacks as a subscriber receives
them.
"""

import pathlib
import sys
import time

from feeder_common import auth, messages
from feeder_common.messages import check_verdict
from feeder_interfaces.msg import Verdict
import pytest
from rcl_interfaces.srv import SetParameters
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from throwmap import analyse, load_scene, PartOnArm

REPO = pathlib.Path(__file__).resolve().parents[3]
# tests/: the domain picker and the wire form of messages (test support, in no package)
sys.path.insert(0, str(REPO / 'tests'))
from feeder_testing import reserve_domain_id  # noqa: E402, I100
from hostile_messages import wire  # noqa: E402

TRIANGLE = str(REPO / 'scenes' / 'triangle.yaml')
NS = '/lifecycle'
MONITOR = f'{NS}/feeder_monitor'
SUCCESS = TransitionCallbackReturn.SUCCESS
# The test's own QoS (written out here, not taken from the code under test).
LATCHED = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
RELIABLE = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


class Calls:
    """Count the calls of module functions of feeder_monitor.monitor_node (monkeypatched)."""

    def __init__(self, monkeypatch, *names):
        from feeder_monitor import monitor_node
        self.n = dict.fromkeys(names, 0)
        for name in names:
            monkeypatch.setattr(monitor_node, name, self._counted(name,
                                                                  getattr(monitor_node, name)))

    def _counted(self, name, fn):
        def call(*args, **kwargs):
            self.n[name] += 1
            return fn(*args, **kwargs)
        return call


class Harness:
    """The monitor and a test node in one context; the monitor's callbacks; what readers got."""

    def __init__(self, key_file, autostart=False, **params):
        from feeder_monitor.monitor_node import MonitorNode
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=reserve_domain_id())
        overrides = {'scene': TRIANGLE, 'autostart': autostart, 'key_file': str(key_file),
                     **params}
        self.node = MonitorNode(context=self.ctx, namespace=NS, parameter_overrides=[
            Parameter(k, value=v) for k, v in overrides.items()])
        self.test = rclpy.create_node('lifecycle_test', context=self.ctx)
        self.key = auth.load_key(key_file)
        self.ready, self.verdicts = [], []
        self.test.create_subscription(Verdict, f'{NS}/edge1_ready', self.ready.append, LATCHED)
        self.test.create_subscription(Verdict, f'{NS}/edge1_verdict', self.verdicts.append,
                                      RELIABLE)
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)
        self.executor.add_node(self.test)
        self.signer = messages.CycleSigner(self.key, f'{NS}/feeder_driver')
        scene = load_scene(TRIANGLE)
        sensor = analyse(scene).sensor
        self.part = PartOnArm(scene, *scene.default_start(), sensor.radius, sensor.footprint)
        self.seq = 0

    def spin(self, seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)

    def spin_until(self, cond, timeout, what):
        end = time.monotonic() + timeout
        while not cond():
            assert time.monotonic() < end, f'timed out waiting for {what}'
            self.executor.spin_once(timeout_sec=0.01)

    def callbacks(self):
        """Return the monitor's subscription callbacks by topic (they exist once configured)."""
        return {sub.topic_name.rpartition('/')[2]: sub.callback
                for sub in self.node.subscriptions}

    def cycle(self):
        """One cycle of the simulated part: fired, proximity, signed cycle_status."""
        on = self.callbacks()
        self.seq += 1
        seq, stamp, detected = self.seq, time.time_ns(), self.part.throw().detected
        on['cycle_fired'](wire(self.signer.cycle_fired(seq, stamp, 'test')))
        on['proximity'](wire(messages.proximity(stamp, detected, 0.02)))
        on['cycle_status'](wire(self.signer.cycle_status(seq, True, '', detected, stamp,
                                                         'test')))
        self.executor.spin_once(timeout_sec=0)

    def checked(self, msgs=None):
        """check_verdict of each statement (or ``msgs``) as a consumer would call it."""
        now = self.test.get_clock().now().nanoseconds
        return [check_verdict(m, self.key, MONITOR, now, 3600.0)
                for m in (self.ready if msgs is None else msgs)]

    def cycle_until_ready(self, limit=400):
        """Cycle until a verdict is ready; return the cycles it took."""
        n = len(self.verdicts)
        for k in range(1, limit + 1):
            self.cycle()
            self.spin_until(lambda: len(self.verdicts) >= n + k, 5.0, f'verdict {self.seq}')
            if self.verdicts[-1].ready:
                self.spin_until(lambda: self.ready and self.ready[-1].seq == self.seq, 5.0,
                                'the ready statement')
                return k
        raise AssertionError(f'no ready in {limit} cycles')

    def set_parameters(self, values):
        """One SetParameters request (as ros2 param load sends); {name: result}."""
        client = self.test.create_client(SetParameters, f'{MONITOR}/set_parameters')
        try:
            self.spin_until(client.service_is_ready, 10.0, 'the parameter service')
            future = client.call_async(SetParameters.Request(parameters=[
                Parameter(k, value=v).to_parameter_msg() for k, v in values.items()]))
            self.spin_until(future.done, 10.0, 'set_parameters')
            return dict(zip(values, future.result().results))
        finally:
            self.test.destroy_client(client)

    def close(self):
        self.executor.shutdown()
        self.test.destroy_node()
        self.node.destroy_node()
        rclpy.shutdown(context=self.ctx)


@pytest.fixture
def key_file(tmp_path):
    path = tmp_path / 'hmac.key'
    auth.ensure_key(path)
    return path


@pytest.fixture
def make(key_file):
    made = []

    def make_harness(**kwargs):
        made.append(Harness(key_file, **kwargs))
        return made[-1]

    try:
        yield make_harness
    finally:
        for h in made:
            h.close()


def test_the_monitor_states_a_ready_only_while_active(make, monkeypatch):
    calls = Calls(monkeypatch, 'analyse', 'scene_analysis')
    h = make()
    node = h.node
    # Unconfigured: no analysis, nothing judged, nothing on edge1_ready.
    assert node.lifecycle_state == 'unconfigured'
    assert calls.n == {'analyse': 0, 'scene_analysis': 0}
    assert h.callbacks() == {}
    h.spin(0.3)
    assert node.count_publishers(f'{NS}/edge1_ready') == 0 and not h.ready

    # Configure: the analysis runs (once), the interface exists; inactive, nothing is judged.
    assert node.trigger_configure() == SUCCESS
    assert node.lifecycle_state == 'inactive'
    assert calls.n == {'analyse': 1, 'scene_analysis': 1}
    assert set(h.callbacks()) == {'proximity', 'cycle_status', 'cycle_fired',
                                  'transition_event'}
    for _ in range(5):
        h.cycle()
    h.spin(0.5)
    assert node.count_publishers(f'{NS}/edge1_ready') == 1
    assert not h.ready and not h.verdicts

    # Activate: judging from a fresh start, the statement false until a cycle proves the goal.
    assert node.trigger_activate() == SUCCESS
    h.spin_until(lambda: h.ready, 5.0, 'the first statement')
    first = h.ready[0]
    assert (first.seq, first.ready, first.state) == (0, False, Verdict.STATE_WARMING_UP)
    assert h.checked()[0].authentic
    cycles = h.cycle_until_ready()
    assert cycles > 1
    assert h.checked()[-1].ready_now

    # Deactivate: a final false statement, then silence; cycles are not judged.
    n_verdicts = len(h.verdicts)
    assert node.trigger_deactivate() == SUCCESS
    h.spin_until(lambda: not h.ready[-1].ready, 5.0, 'the final false statement')
    last = h.ready[-1]
    assert last.state == Verdict.STATE_ANOMALY and 'deactivated' in last.anomaly
    assert h.checked([last])[0].authentic
    n_ready = len(h.ready)
    for _ in range(30):
        h.cycle()
    h.spin(0.6)         # the idle republish (every 0.25 s) stops too
    assert len(h.ready) == n_ready and len(h.verdicts) == n_verdicts

    # Activate again: warming up from the start, the first ready no sooner than before.
    assert node.trigger_activate() == SUCCESS
    h.spin_until(lambda: len(h.ready) > n_ready, 5.0, 'the statement on activation')
    assert (h.ready[n_ready].ready, h.ready[n_ready].state) == (False,
                                                                Verdict.STATE_WARMING_UP)
    rules = node._monitor.rules
    assert h.cycle_until_ready() > max(rules.warmup_cycles, rules.settle_cycles)

    # Deactivate and clean up: unconfigured, no edge1_ready writer; no ready was ever stated
    # but by an active monitor about a ready verdict.
    assert node.trigger_deactivate() == SUCCESS
    h.spin_until(lambda: not h.ready[-1].ready, 5.0, 'the final false statement')
    assert node.trigger_cleanup() == SUCCESS
    assert node.lifecycle_state == 'unconfigured'
    assert h.callbacks() == {}
    h.spin_until(lambda: node.count_publishers(f'{NS}/edge1_ready') == 0, 5.0,
                 'the writer to go')
    h.spin(0.3)
    ready_seqs = {v.seq for v in h.verdicts if v.ready}
    assert all(m.seq in ready_seqs for m in h.ready if m.ready)
    assert not h.ready[-1].ready
    assert node.trigger_shutdown() == SUCCESS
    assert node.lifecycle_state == 'finalized' and node.finished()


def test_a_scene_the_analysis_refuses_fails_the_configure_with_the_reason(make, tmp_path):
    lost = tmp_path / 'lost_from_start.yaml'
    short_arm = (REPO / 'tests' / 'scenes' / 'short_arm.yaml').read_text()
    assert 'start: {edge: 1, R: 0.12}' in short_arm
    lost.write_text(short_arm.replace('start: {edge: 1, R: 0.12}', 'start: {edge: 1, R: 0.32}'))
    h = make(scene=str(lost))
    assert h.node.trigger_configure() == TransitionCallbackReturn.FAILURE
    assert h.node.lifecycle_state == 'unconfigured'
    assert h.node.configure_error.startswith('scene ') and str(lost) in h.node.configure_error
    assert 'the part was lost at throw 1 (first contact at x' in h.node.configure_error
    assert h.callbacks() == {} and h.node.count_publishers(f'{NS}/edge1_ready') == 0


def test_a_rule_the_analysis_rejects_fails_the_configure_and_a_good_one_configures(make):
    h = make(warmup_cycles=0)       # accepted unconfigured (a range only): no analysis yet
    assert h.node.trigger_configure() == TransitionCallbackReturn.FAILURE
    assert 'below the proven warm-up of 1' in h.node.configure_error
    assert h.set_parameters({'warmup_cycles': 3})['warmup_cycles'].successful
    assert h.node.trigger_configure() == SUCCESS
    assert h.node._rules_now.warmup_cycles == 3


def test_a_parameter_file_costs_one_analysis(make, monkeypatch):
    from feeder_common.node import autostart
    h = make(autostart=True, ready_deadline=60.0)     # no idle republish in this test
    autostart(h.node)       # configure + activate, as the run helper does
    h.spin_until(lambda: h.ready, 5.0, 'the first statement')
    calls = Calls(monkeypatch, 'scene_analysis', 'rules_from_analysis')
    n_ready = len(h.ready)
    # Every rule parameter of config/monitor.yaml in one request, the sensor moved.
    batch = {'sensor_radius': 0.28, 'warmup_cycles': 2, 'settle_cycles': 90,
             'silence_margin': 2.0, 'early_margin_cycles': 1, 'run_margin_cycles': 1}
    results = h.set_parameters(batch)
    assert all(r.successful for r in results.values()), results
    h.spin(0.3)
    assert calls.n['scene_analysis'] == 1
    # Each parameter is checked against the rules when it is set (rclpy sets them one at a
    # time); the apply of each reuses them.
    assert calls.n['rules_from_analysis'] <= len(batch)
    rules = h.node._monitor.rules
    assert (rules.sensor_radius, rules.warmup_cycles, rules.settle_cycles) == (0.28, 2, 90)
    # One new statement for the whole file: false, warming up again.
    assert len(h.ready) == n_ready + 1
    assert (h.ready[-1].ready, h.ready[-1].state) == (False, Verdict.STATE_WARMING_UP)

    # A bad value is still refused when it is set, with its reason; the rest of the file
    # applies, without another analysis.
    results = h.set_parameters({'warmup_cycles': 0, 'silence_margin': 3.0})
    assert not results['warmup_cycles'].successful
    assert 'below the proven warm-up of 1' in results['warmup_cycles'].reason
    assert results['silence_margin'].successful
    h.spin(0.3)
    assert calls.n['scene_analysis'] == 1
    assert h.node._monitor.rules.warmup_cycles == 2


def test_new_part_lowers_the_ready_and_the_next_one_waits_for_the_settling(make):
    from std_srvs.srv import Trigger
    h = make()
    client = h.test.create_client(Trigger, f'{MONITOR}/new_part')
    h.spin_until(client.service_is_ready, 10.0, 'the new_part service')

    def new_part():
        future = client.call_async(Trigger.Request())
        h.spin_until(future.done, 10.0, 'new_part')
        return future.result()

    assert 'unconfigured, not active' in new_part().message
    assert h.node.trigger_configure() == SUCCESS and h.node.trigger_activate() == SUCCESS
    h.spin_until(lambda: h.ready, 5.0, 'the first statement')
    first = h.cycle_until_ready()
    assert h.ready[-1].ready
    reply = new_part()
    assert reply.success and 'start again' in reply.message
    h.spin_until(lambda: not h.ready[-1].ready, 5.0, 'the ready to drop')
    assert h.ready[-1].state == Verdict.STATE_WARMING_UP and not h.ready[-1].anomaly
    assert h.checked()[-1].authentic
    # The part is the same here, so only the settling stands between it and the next ready.
    rules = h.node._monitor.rules
    assert h.cycle_until_ready() > rules.settle_cycles >= 1 and first > rules.settle_cycles

    assert h.node.trigger_deactivate() == SUCCESS
    reply = new_part()
    assert not reply.success and 'inactive, not active' in reply.message
