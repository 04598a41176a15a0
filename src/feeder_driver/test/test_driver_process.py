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

"""driver_node as a process: start-up parameter errors, params file, lifecycle, SIGINT."""

import os
import pathlib
import signal
import subprocess
import sys
import time

from feeder_testing import dds_env, EmulatorThread
from lifecycle_msgs.msg import State, Transition
from lifecycle_msgs.srv import ChangeState, GetState
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from std_srvs.srv import Trigger

PKG = pathlib.Path(__file__).resolve().parents[1]


def driver_cmd(*ros_args):
    return [sys.executable, '-m', 'feeder_driver.driver_node', '--ros-args',
            '-r', '__ns:=/feeder', *ros_args]


def env_for(domain_id):
    env = dds_env(domain_id)
    env['PYTHONPATH'] = os.pathsep.join([str(PKG), str(PKG.parent / 'feeder_common'),
                                         env.get('PYTHONPATH', '')])
    env['PYTHONUNBUFFERED'] = '1'
    return env


@pytest.mark.parametrize('arg, text', [
    ('cycle_period:=-1.0', 'cycle_period = -1.0 is outside [0.005, 3600.0]'),
    ('cycle_period:=abc', "cycle_period must be a double, got string 'abc'"),
    ('reconnect_initial_s:=20.0', 'must not exceed reconnect_max_s'),
    ('baud_rate:=1234', 'baud_rate = 1234 is not one of the allowed values'),
])
def test_bad_startup_parameter_exits_2_with_the_reason(domain_id, arg, text):
    res = subprocess.run(driver_cmd('-p', arg), env=env_for(domain_id), capture_output=True,
                         text=True, timeout=60)
    assert res.returncode == 2, res.stderr
    assert text in res.stderr and 'Traceback' not in res.stderr


class Probe:
    def __init__(self, domain_id):
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=domain_id)
        self.node = rclpy.create_node('probe', context=self.ctx)
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)

    def call(self, srv_type, name, request, timeout=10.0):
        # Right after discovery a first request can go unanswered (the response path is not
        # matched yet), so retry with a short per-attempt timeout.
        cl = self.node.create_client(srv_type, name)
        assert cl.wait_for_service(timeout_sec=timeout), f'{name} did not appear'
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            fut = cl.call_async(request)
            self.executor.spin_until_future_complete(fut, timeout_sec=1.0)
            if fut.done():
                return fut.result()
            cl.remove_pending_request(fut)
        raise AssertionError(f'{name} did not answer within {timeout} s')

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.ctx)


@pytest.fixture
def probe(domain_id):
    pr = Probe(domain_id)
    yield pr
    pr.close()


def test_params_file_lifecycle_and_sigint(domain_id, probe, scene_path, sensor_radius,
                                          link_path):
    config = str(PKG / 'config' / 'driver.yaml')
    with EmulatorThread(scene_path, link_path, sensor_radius=sensor_radius, cycle_time=0.3,
                        heartbeat=0.2) as emu:
        proc = subprocess.Popen(driver_cmd('--params-file', config, '-p', f'port:={link_path}',
                                           '-p', 'autostart:=false'),
                                env=env_for(domain_id), stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
        try:
            base = '/feeder/feeder_driver'
            st = probe.call(GetState, f'{base}/get_state', GetState.Request())
            assert st.current_state.id == State.PRIMARY_STATE_UNCONFIGURED
            res = probe.call(Trigger, f'{base}/trigger_cycle', Trigger.Request())
            assert not res.success and 'unconfigured' in res.message
            for tid in (Transition.TRANSITION_CONFIGURE, Transition.TRANSITION_ACTIVATE):
                req = ChangeState.Request()
                req.transition.id = tid
                assert probe.call(ChangeState, f'{base}/change_state', req).success
            deadline = time.monotonic() + 5
            while True:
                res = probe.call(Trigger, f'{base}/trigger_cycle', Trigger.Request())
                if res.success or time.monotonic() > deadline:
                    break
                time.sleep(0.05)
            assert res.success and 'seq 1' in res.message, res.message
            time.sleep(0.1)        # the cycle is in flight (0.3 s): SIGINT must STOP it
            proc.send_signal(signal.SIGINT)
            out, _ = proc.communicate(timeout=10)
            assert proc.returncode == 0, out
            assert 'Traceback' not in out
            end = time.monotonic() + 2
            while not emu.records and time.monotonic() < end:
                time.sleep(0.02)
            assert emu.records[0]['outcome'] == 'aborted'   # the controller got STOP
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
