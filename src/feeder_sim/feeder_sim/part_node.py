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
The lifecycle skeleton of feeder_sim's two nodes: a node that follows a part on the arm.

:class:`PartNode` holds what the hardware stand-in (``standin_node``) and the predictor
(``predictor_node``) share: the scene (loaded once), the parameter gate over the node's own
table (feeder_sim.params), the analysis at the sensor in use (redone only when its input,
``sensor_radius``, changes), the part's state (throwmap.PartOnArm), the lifecycle
transitions, the part lost (off the arm's end, or at rest below R_min), and the ``lifecycle``
and ``prediction`` diagnostics. Each node adds its interface in the hooks
:meth:`_part_options`, :meth:`_configure_own`, :meth:`_create_interface`, :meth:`_apply_own`,
:meth:`_analysis_changed`, :meth:`_part_placed`, :meth:`_place_hint` and :meth:`_release_own`.
"""

import functools
import math

from feeder_common.diagnostics import Updater
from feeder_common.node import FeederLifecycleNode, publish
from feeder_common.parameters import ParameterGate
from rclpy.lifecycle import TransitionCallbackReturn
from throwmap import analyse, load_scene, PartOnArm, scene_analysis, ThrowmapError
from throwmap.part_on_arm import LOST

from .params import check_changes, check_start

HARDWARE_ID = 'sim'


class PartNode(FeederLifecycleNode):
    """
    Lifecycle node that follows one part on the arm, throw by throw.

    Subclasses set :attr:`PROG` (the executable, named in warnings), :attr:`PARAMS` (their
    parameter table) and :attr:`PART` (what a restart restarts: ``part`` or ``prediction``).
    """

    PROG = None
    PARAMS = ()
    PART = 'part'

    def __init__(self, node_name, **kwargs):
        super().__init__(node_name, **kwargs)
        # Scenes by path, loaded once (the parameter checks load them too).
        self._load_scene = functools.lru_cache(maxsize=None)(load_scene)
        self._active = False
        self._base_analysis = None
        self._analysis = None
        self._analysis_radius = None    # the sensor_radius self._analysis was made for
        self._predictor = None          # throwmap.PartOnArm while configured
        self._pubs = {}
        self._last_throw = None
        self._lost_seq = None           # cycle that lost the part (off the arm, or below R_min)
        self._lost_reason = ''
        self._seq = 0
        self._counts = {'completed': 0, 'failed': 0}
        self._rate_mark = (0, self.get_clock().now())
        self._params = ParameterGate(self, self.PARAMS, self._validate, self._apply)
        p = self._params
        p.declare_all(names=('autostart', 'scene'))
        self._scene = self._load_scene(p.values['scene'])
        edge0, r0 = self._scene.default_start()
        p.declare_all(defaults={'start_edge': edge0, 'start_radius': r0})
        for name in p.unknown_given():
            self.get_logger().warning(f'parameter {name} is not a parameter of {self.PROG}; '
                                      'ignored (docs/nodes.md lists them)')
        self._diagnostics = Updater(self, p.values['diagnostic_updater.period'], HARDWARE_ID)
        self._diagnostics.add('lifecycle', self._diag_lifecycle)
        self._diagnostics.add('prediction', self._diag_prediction)

    # ------------------------------------------------------------------ hooks
    def _part_options(self, scene):
        """Return how this node's part throws: PartOnArm's model, noisy_sensor and seed."""
        raise NotImplementedError(f'{type(self).__name__} must define _part_options')

    def _configure_own(self):
        """Open what the node needs beyond its part (configure); the reason it cannot, or None."""
        return None

    def _create_interface(self):
        """Create the node's publishers and subscriptions (configure)."""
        raise NotImplementedError(f'{type(self).__name__} must define _create_interface')

    def _apply_own(self, changes):
        """Apply the node's own accepted parameter changes (post-set)."""

    def _analysis_changed(self):
        """React to a new analysis (another sensor_radius) while configured."""

    def _part_placed(self):
        """React to the part (or the prediction) restarted at the start state."""

    def _release_own(self):
        """Release what the node created beyond its publishers (cleanup, shutdown)."""

    # ------------------------------------------------------------------ parameters
    def _validate(self, changes, current):
        """On-set: the reason to reject ``changes``; never changes the node's state."""
        reason = check_changes(changes, self._load_scene, current)
        if reason:
            return reason
        if ('start_edge' in changes or 'start_radius' in changes) and self._scene is not None:
            edge = changes.get('start_edge', current.get('start_edge'))
            R = changes.get('start_radius', current.get('start_radius'))
            if edge is not None and R is not None:
                return check_start(self._scene.model, edge, R)
        return None

    def _apply(self, changes):
        """Post-set: apply accepted changes."""
        if 'diagnostic_updater.period' in changes:
            self._diagnostics.set_period(changes['diagnostic_updater.period'])
        self._apply_own(changes)
        if self._predictor is None:
            return
        if 'start_edge' in changes or 'start_radius' in changes:
            self._place_part()
        if 'sensor_radius' in changes and self._set_analysis(changes['sensor_radius']):
            self._predictor.sensor_radius = self._analysis.sensor.radius
            self.get_logger().info(f'sensor at {self._analysis.sensor.radius:.4f} m')
            self._analysis_changed()

    def _param(self, name):
        return self._params.values[name]

    def _set_analysis(self, sensor_radius):
        """
        Make the analysis at ``sensor_radius`` (0: the analysis's choice) the one in use.

        Returns whether it changed. The analysis depends on the scene (fixed while configured)
        and ``sensor_radius`` alone, so it is kept by that input: ``ros2 param load`` sets a
        file's parameters one at a time (one post-set callback each), and a file loaded again,
        or one that gives the radius in use, costs no analysis and republishes nothing.
        """
        if self._analysis is not None and sensor_radius == self._analysis_radius:
            return False
        self._analysis = scene_analysis(self._scene, sensor_radius, self._base_analysis)
        self._analysis_radius = sensor_radius
        return True

    def _place_part(self):
        """Restart the part (or the prediction) at (start_edge, start_radius)."""
        edge, R = self._param('start_edge'), self._param('start_radius')
        self._predictor.place(edge, R)
        self._last_throw = None
        self._lost_seq = None
        self.get_logger().info(f'{self.PART} restarted at edge {edge}, R {R:.4f} m')
        self._part_placed()
        return edge, R

    # ------------------------------------------------------------------ lifecycle
    def on_configure(self, state):
        scene = self._scene
        try:
            self._base_analysis = analyse(scene)
            self._set_analysis(self._param('sensor_radius'))
            sensor = self._analysis.sensor
            self._predictor = PartOnArm(
                scene, self._param('start_edge'), self._param('start_radius'), sensor.radius,
                sensor.footprint, **self._part_options(scene))
        except ThrowmapError as exc:
            self.configure_error = f'scene {scene.source}: {exc}'
            self.get_logger().error(f'configure failed: {self.configure_error}')
            return TransitionCallbackReturn.FAILURE
        reason = self._configure_own()
        if reason:
            self.configure_error = reason
            self.get_logger().error(f'configure failed: {reason}')
            return TransitionCallbackReturn.FAILURE
        self._create_interface()
        self.get_logger().info(
            f'{scene.name}: limit set {self._analysis.limit_set.signature}, goal edge '
            f'{sensor.goal_edge}, sensor at {sensor.radius:.4f} m (guarantee '
            f'{sensor.guarantee_radius:.4f} m), start {self._predictor.state}')
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state):
        result = super().on_activate(state)
        self._active = True
        return result

    def on_deactivate(self, state):
        self._active = False
        return super().on_deactivate(state)

    def on_cleanup(self, state):
        self._release()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state):
        self._active = False
        self._release()
        return TransitionCallbackReturn.SUCCESS

    def _send(self, name, msg):
        """Publish ``msg`` on publisher ``name`` (a refusal is logged: node.publish)."""
        return publish(self._pubs[name], msg, self.get_logger())

    def _release(self):
        self._release_own()
        for p in self._pubs.values():
            self.destroy_lifecycle_publisher(p)
        self._pubs = {}
        self._predictor = None
        self._analysis = None
        self._analysis_radius = None

    # ------------------------------------------------------------------ throws
    def _throw_lost(self, seq, throw):
        """Report the part lost if ``throw`` (of cycle ``seq``) is the one that lost it."""
        if throw.kind == LOST and throw.count == self._predictor.lost_at:
            self._lost_seq = seq
            self._lost_reason = throw.lost_reason or "the part left the arm's end"
            arm = self._scene.arm_length
            arm = (f'arm length {arm:g} m' if arm is not None and math.isfinite(arm)
                   else 'arm taken as endless')
            self.get_logger().error(
                f'part lost at cycle {seq} (thrown from edge {throw.edge0} at R '
                f'{throw.R0:.4f} m; {arm}): {self._lost_reason}; set start_edge / '
                f'start_radius{self._place_hint()} when a part is back on the arm')

    def _place_hint(self):
        """Return the other ways to put a part back, for the lost-part message ('' if none)."""
        return ''

    # ------------------------------------------------------------------ diagnostics
    def _rate(self):
        now = self.get_clock().now()
        done, mark_time = self._rate_mark
        total = self._counts['completed'] + self._counts['failed']
        dt = (now - mark_time).nanoseconds * 1e-9
        self._rate_mark = (total, now)
        return (total - done) / dt if dt > 0 else 0.0

    def _diag_lifecycle(self, stat):
        stat.summary('ok' if self._active else 'warn', self.lifecycle_state)
        stat.update({'scene': self._scene.source, 'namespace': self.get_namespace()})

    def _diag_prediction(self, stat):
        pred = self._predictor
        if pred is None:
            stat.summary('warn', f'{self.lifecycle_state}: no prediction')
            return
        edge, R = pred.state
        an = self._analysis
        arm = self._scene.arm_length
        stat.update({
            'edge': edge, 'R': 'none' if pred.lost else f'{R:.6f}', 'throws': pred.count,
            'last_kind': self._last_throw.kind if self._last_throw else 'none',
            'in_limit_set': not pred.lost and an.limit_set.contains(edge, R),
            'goal_edge': an.sensor.goal_edge, 'sensor_radius': f'{an.sensor.radius:.6f}',
            'guarantee_radius': f'{an.sensor.guarantee_radius:.6f}',
            'warmup_throws': an.sensor.warmup_throws, 'noisy_sensor': pred.noisy_sensor,
            'arm_length': f'{arm:.6f}' if arm is not None and math.isfinite(arm)
            else 'unbounded'})
        if pred.lost:
            stat.add('lost_at_seq', self._lost_seq)
            stat.add('lost_reason', self._lost_reason)
            stat.summary('error', f'part lost at cycle {self._lost_seq}')
        else:
            stat.summary('ok', f'edge {edge}, R {100 * R:.2f} cm after {pred.count} throws')
