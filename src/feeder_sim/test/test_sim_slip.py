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
A part that slips to rest below R_min (liftoff, mu 1) on the hardware stand-in (issue 21 item 3).

The real StandInNode runs in-process (own context, own domain) on the triangle with effect
liftoff and no arm length; the part is put just above R_min on the hypotenuse and cycles are
triggered through its ``~/trigger_cycle`` service callback. The throw that strands the part is
a completed cycle that loses it, once, with the reason; the cycles after it are empty throws,
not a DomainError on every cycle (before issue 21 item 3) nor an exception out of the timer (a
lost part on an arm without a length once failed to format its message).
"""

import pathlib

from feeder_common import messages
from feeder_testing import reserve_domain_id
import pytest
import rclpy
from rclpy.context import Context
from rclpy.parameter import Parameter
from std_srvs.srv import Trigger
import yaml

REPO = pathlib.Path(__file__).resolve().parents[3]
NS = '/slip'


@pytest.fixture
def standin(tmp_path):
    from feeder_common.node import autostart
    from feeder_sim.standin_node import StandInNode
    scene = yaml.safe_load((REPO / 'scenes' / 'triangle.yaml').read_text())
    scene.update(name='triangle_slip', effects=['liftoff'], liftoff={'mu': 1.0})
    scene['arm'].pop('length_cm', None)     # no arm length: stranded, not lost off the end
    path = tmp_path / 'slip.yaml'
    path.write_text(yaml.safe_dump(scene))
    ctx = Context()
    rclpy.init(context=ctx, domain_id=reserve_domain_id())
    node = StandInNode(context=ctx, namespace=NS, parameter_overrides=[
        Parameter('scene', value=str(path))])
    try:
        autostart(node)
        yield node
    finally:
        node.destroy_node()
        rclpy.shutdown(context=ctx)


def test_a_part_stranded_below_r_min_is_lost_once_with_its_reason(standin):
    node = standin
    r_min = node._scene.model.r_min(1)
    assert node.set_parameters([Parameter('start_radius', value=r_min + 1e-6)])[0].successful
    statuses = []
    pub = next(p for p in node.publishers if p.topic_name == f'{NS}/cycle_status')
    publish = pub.publish
    pub.publish = lambda msg: (statuses.append(messages.parse_cycle_status(msg)), publish(msg))
    trigger = next(s for s in node.services if s.srv_name == '~/trigger_cycle')
    answers = [trigger.callback(Trigger.Request(), Trigger.Response()) for _ in range(3)]
    assert [a.success for a in answers] == [True] * 3, [a.message for a in answers]
    assert all('failed' not in a.message for a in answers), [a.message for a in answers]
    assert [(s.ok, s.sensor) for s in statuses] == [(True, False)] * 3
    assert node._lost_seq == statuses[0].seq
    assert 'outside the domain of f' in node._lost_reason
    assert 'stub its toe' in node._lost_reason
    assert node._predictor.lost and node._predictor.lost_at == 1
