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
Issue 23 item 4: a parameter file loaded into the predictor costs one analysis, not more.

``ros2 param load`` sends the whole file in one set_parameters request, and rclpy's service
sets the parameters one at a time (one on-set and one post-set callback each). The real
PredictorNode runs in-process (own context, own domain); the analyses are counted by wrapping
throwmap.scene_analysis where the node calls it, and the latched ``predicted/analysis``
messages by wrapping its publisher. Measured before the fix (sim_node, 2026-11-26): only
``sensor_radius`` of the file leads to an analysis, so one request cost one analysis, but
every request that named ``sensor_radius`` redid it and republished it, also when the radius
did not change (the same file loaded again: this test failed with ``[0.28, 0.28]``).
"""

import pathlib
import sys
import time

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
import yaml

REPO = pathlib.Path(__file__).resolve().parents[3]
sys.path.insert(0, str(REPO / 'tests'))
from feeder_testing import reserve_domain_id  # noqa: E402, I100

TRIANGLE = str(REPO / 'scenes' / 'triangle.yaml')
CONFIG = REPO / 'src' / 'feeder_sim' / 'config' / 'predictor.yaml'
NS = '/batch'


class Predictor:
    """The predictor and a client of its set_parameters service, in one context."""

    def __init__(self, analyses):
        from feeder_common.node import autostart
        from feeder_sim.predictor_node import PredictorNode
        from rcl_interfaces.srv import SetParameters
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=reserve_domain_id())
        self.node = PredictorNode(context=self.ctx, namespace=NS, parameter_overrides=[
            Parameter('scene', value=TRIANGLE)])
        autostart(self.node)
        self.configured_analyses = len(analyses)
        pub = next(p for p in self.node.publishers if p.topic_name == f'{NS}/predicted/analysis')
        self.published, publish = [], pub.publish

        def record(msg):
            self.published.append(msg)
            publish(msg)

        pub.publish = record
        self.client_node = rclpy.create_node('batch_client', context=self.ctx)
        self.client = self.client_node.create_client(
            SetParameters, f'{NS}/feeder_sim/set_parameters')
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)
        self.executor.add_node(self.client_node)
        assert self.client.wait_for_service(timeout_sec=10.0)

    def set_parameters(self, values):
        """Set ``values`` (name -> value) in one request, as ros2 param load does."""
        from rcl_interfaces.srv import SetParameters
        request = SetParameters.Request()
        request.parameters = [Parameter(n, value=v).to_parameter_msg()
                              for n, v in values.items()]
        future = self.client.call_async(request)
        self.executor.spin_until_future_complete(future, timeout_sec=10.0)
        assert future.done(), 'set_parameters: no answer within 10 s'
        results = future.result().results
        assert [r.successful for r in results] == [True] * len(values), \
            [r.reason for r in results]
        # Anything the request deferred (timers, tasks) runs now.
        end = time.monotonic() + 0.3
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.05)

    def close(self):
        self.executor.shutdown()
        self.client_node.destroy_node()
        self.node.destroy_node()
        rclpy.shutdown(context=self.ctx)


@pytest.fixture
def analyses(monkeypatch):
    """Return the list of sensor radii of every analysis the predictor makes."""
    from feeder_sim import part_node
    calls, analyse_at = [], part_node.scene_analysis

    def counted(scene, sensor_radius=0.0, analysis=None):
        calls.append(sensor_radius)
        return analyse_at(scene, sensor_radius, analysis)

    monkeypatch.setattr(part_node, 'scene_analysis', counted)
    return calls


@pytest.fixture
def predictor(analyses):
    p = Predictor(analyses)
    try:
        yield p
    finally:
        p.close()


def shipped_file():
    return yaml.safe_load(CONFIG.read_text())['/**']['ros__parameters']


def test_loading_the_parameter_file_costs_at_most_one_analysis(predictor, analyses):
    assert predictor.configured_analyses == 1
    published = len(predictor.published)
    values = dict(shipped_file(), sensor_radius=0.28, start_edge=1, start_radius=0.13)
    assert len(values) >= 5
    predictor.set_parameters(values)
    assert analyses[predictor.configured_analyses:] == [0.28]
    assert len(predictor.published) == published + 1
    assert predictor.published[-1].sensor_radius == 0.28
    assert predictor.published[-1].scene == 'triangle'
    # The same file again (nothing the analysis depends on changed): no analysis, no message.
    predictor.set_parameters(values)
    assert analyses[predictor.configured_analyses:] == [0.28]
    assert len(predictor.published) == published + 1
    # The shipped file as it is (sensor_radius 0: the analysis's choice) is one more.
    predictor.set_parameters(shipped_file())
    assert analyses[predictor.configured_analyses:] == [0.28, 0.0]
    assert len(predictor.published) == published + 2
    predictor.set_parameters(shipped_file())
    assert analyses[predictor.configured_analyses:] == [0.28, 0.0]
