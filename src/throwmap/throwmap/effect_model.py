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
The throw map of a scene with effects: the ThrowModel interface over a composed pipeline.

The named effects' hooks are composed into one compiled module (throwmap.compose); this class
validates states, draws the random numbers, and turns statuses into results and errors, as
ThrowModel does for the base model. It names no effect: what an effect changes at the Python
level (the domain's intervals, the sensor's readings, why a part was lost) comes from the
effect module's optional functions (throwmap.effects). A scene without effects never gets
here: its model is the base ThrowModel.
"""

import copy
from dataclasses import dataclass
import math
import types

import numpy as np

from . import compose
from .accuracy import compiled_knobs, SimulatorAccuracy
from .catch import throw_kind
from .effects import EffectSet, event_simulated, EVENT_SLOTS, knob_defaults
from .errors import ThrowmapError
from .event_sim import STICKING_CONTACT
from .jit import entry_point
from .model import (batch_buffers, batch_result, impacts_from_records, orbit_buffers,
                    ThrowModel, ThrowResult)
from .pipeline import Context
from .sensor import read_sensor
from .status import LOST, OFF_DOMAIN, OK, REC_COLS

REC_ROWS = 2048


@dataclass(frozen=True)
class EffectThrowResult(ThrowResult):
    """ThrowResult of a scene with effects: ``kind`` may be 'lost' (edge -1, R nan)."""

    release_speed: float = math.nan     # the throw's own w (release_noise)
    offset: float = math.nan            # the throw's own h
    lost_reason: str = ''

    def as_dict(self):
        d = super().as_dict()
        d.update({'release_speed': self.release_speed, 'offset': self.offset,
                  'lost_reason': self.lost_reason})
        return d


class EffectModel(ThrowModel):
    """
    ThrowModel over the effects of an EffectSet.

    Same interface as ThrowModel: f, throw, f_batch, orbit_arrays, orbits, domain_error,
    error_message, r_min, read_sensor, nominal, reseed.

    With random effects the model owns a seeded numpy Generator (``rng``): every f, f_batch and
    orbit call draws from it, so results depend on the seed and on the order of calls;
    ``reseed(seed)`` starts the sequence again. ``knobs``: the simulator's and the effects'
    accuracy knobs; ``arm_length``: the scene's (inf without one). f and throw reuse one record
    buffer: one model per thread.
    """

    def __init__(self, part, offset, release_speed, gravity, mu=None, settle_rule='full',
                 accuracy=None, effects=None, simulator=None, knobs=None, seed=0,
                 arm_length=None, field_prefix=''):
        super().__init__(part, offset, release_speed, gravity, mu=mu, settle_rule=settle_rule,
                         accuracy=accuracy, field_prefix=field_prefix)
        if arm_length is not None:
            self.arm_length = float(arm_length)     # the scene's arm.length
        self.effects = effects or EffectSet()
        self.simulator = simulator or SimulatorAccuracy()
        values = dict(vars(self.simulator))
        values.update(knob_defaults())
        values.update(knobs or {})
        self.knobs = types.SimpleNamespace(**values)
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.stochastic = self.effects.stochastic
        modules = self.effects.modules()
        laws = [(n, m.contact_law(p)) for n, m, p in modules if hasattr(m, 'contact_law')]
        if len(laws) > 1:
            raise ThrowmapError(f'effects {" and ".join(n for n, _ in laws)} both set the '
                                'contact law; a scene can name only one of them')
        self.slots = self.effects.slots()
        self.composed = compose.load(self.slots)
        self.prm = self.composed.EffectParams(*[
            m.bundle(p, part, self.knobs) for n, m, p in modules if n in self.slots])
        self.ctx = Context(self.w, self.h, self.g, math.inf if self.mu is None else self.mu,
                           part.arrays, compiled_knobs(self.accuracy, self.simulator,
                                                       settle_rule),
                           laws[0][1] if laws else STICKING_CONTACT)
        filled = {s for slots in self.slots.values() for s in slots}
        self._event_motion = event_simulated(filled)    # compose: the event simulator
        self._draws = 'perturb' in filled
        self._sensor_models = [(m.read_sensor, p) for _, m, p in modules
                               if hasattr(m, 'read_sensor')]
        # Throws are the base model's own (same release, flight and catch): trajectories apply.
        self._base_motion = (not filled & {'perturb', 'release', *EVENT_SLOTS} and not laws
                             and self.simulator.contact_method == 'advancement')
        self._rec = np.empty((REC_ROWS, REC_COLS))
        self._one = None
        self._domain_effect = next(((n, m, p) for n, m, p in modules if hasattr(m, 'domain')),
                                   None)
        self._domain = None
        if self._domain_effect is not None:
            _, module, params = self._domain_effect
            self._domain = module.domain(self, params)
            self.r_grasp = np.array([self._domain[i][0][0] if self._domain.get(i) else math.inf
                                     for i in range(part.n)])

    # ------------------------------------------------------------------------- randomness
    def reseed(self, seed):
        """Restart the random sequences from ``seed``."""
        self.seed = seed
        self.rng = np.random.default_rng(seed)

    def nominal(self):
        """
        Return the same model without its random effects (the same compiled code).

        Its throws draw zeros (w + sd 0 = w exactly) and its sensor reads exactly.
        """
        if not self.stochastic:
            return self
        model = copy.copy(self)
        model.effects = self.effects.without_noise()
        model.stochastic = False
        model._draws = False
        model._sensor_models = []
        model._rec = np.empty((REC_ROWS, REC_COLS))
        return model

    def _normals(self, shape):
        if not self._draws:
            return np.zeros(shape + (2,))
        return self.rng.standard_normal(shape + (2,))

    def read_sensor(self, edge, R, x, footprint=0.0):
        """One reading of the sensor at x: geometry, then the effects' sensor models."""
        return read_sensor(self.part, edge, R, x, footprint, self._sensor_models, self.rng)

    # ------------------------------------------------------------------------- domain
    def domain_intervals(self, edge):
        if self._domain is None:
            return ThrowModel.domain_intervals(self, edge)
        return list(self._domain.get(int(edge), []))

    def domain_error(self, edge, R):
        err = ThrowModel.domain_error(self, edge, R)
        if self._domain_effect is None or (err is not None and err.condition in (
                'edge_index', 'stable_edge', 'radius')):
            return err
        _, module, params = self._domain_effect
        return module.domain_error(self, params, edge, R)

    def domain_note(self):
        if self._domain_effect is None:
            return None
        _, module, params = self._domain_effect
        return module.domain_note(self, params) if hasattr(module, 'domain_note') else None

    def nominal_status(self, edges, radii):
        """Statuses of noise-free throws from many states (domain scans)."""
        edges, radii, out = batch_buffers(edges, radii)
        self.composed.throw_many(edges, radii, np.zeros((edges.size, 2)), self.ctx, self.prm,
                                 self._no_record, *out)
        return out[2]

    # ------------------------------------------------------------------------- the map
    def _state(self, edge, R):
        # Type, edge and radius errors before any random draw, as the base model refuses them.
        err = ThrowModel.domain_error(self, edge, R)
        if err is not None and err.condition in ('edge_index', 'stable_edge', 'radius'):
            raise err
        return int(edge), float(R)

    def _throw(self, edge, R, z, rec):
        if self._one is None:
            self._one = entry_point(self.composed.throw_one, edge, R, 0.0, 0.0, self.ctx,
                                    self.prm, rec)
        return self._one(edge, R, float(z[0]), float(z[1]), self.ctx, self.prm, rec)

    def f(self, edge, R):
        """
        (edge', R', kind); kind 'lost' (edge -1, R nan) when the part leaves the arm.

        Also 'lost' when the part comes to rest outside the domain of f (below R_min), where no
        later throw is defined: :meth:`throw` says where it rests and why.
        """
        edge, R = self._state(edge, R)
        out = self._throw(edge, R, self._normals((1,))[0], self._rec)
        st = out[0]
        if st == LOST or st == OFF_DOMAIN:
            return -1, math.nan, 'lost'
        if st != OK:
            self._raise(st, edge, R)
        return out[1], out[2], throw_kind(edge, out[1], out[4])

    def throw(self, edge, R, trajectory=False, samples=60):
        """
        Return the full result of one throw.

        ``trajectory`` is filled only where the throw is the base model's own (effects that
        only check or lose it, sensor noise), else None: the event simulator keeps no poses.
        """
        edge, R = self._state(edge, R)
        z = self._normals((1,))[0]
        rec = self._rec
        st, j, r1, t, rot, _, k0, nrec, w, h, e0 = self._throw(edge, R, z, rec)
        if st not in (OK, LOST, OFF_DOMAIN):
            self._raise(st, edge, R)
        if nrec > rec.shape[0]:     # a long catch: again, with room for every event
            rec = np.empty((nrec, REC_COLS))
            self._throw(edge, R, z, rec)
        rows = rec[:nrec]
        reason = ''
        if st == OFF_DOMAIN:
            kind = 'lost'
            reason = self._off_domain_reason(int(j), float(r1))
            j, r1 = -1, math.nan
        elif st == LOST:
            kind = 'lost'
            for _, module, params in self.effects.modules():
                if hasattr(module, 'lost_reason'):
                    reason = module.lost_reason(rows, r1, params)
        else:
            kind = throw_kind(edge, j, rot)
        traj = None
        if trajectory and st == OK and self._base_motion:
            traj = ThrowModel.throw(self, edge, R, trajectory=True, samples=samples).trajectory
        low = math.nan if self._event_motion else self._min_normal(rec, nrec)
        return EffectThrowResult(int(edge), float(R), int(j), float(r1), kind, float(t),
                                 float(rot), int(k0), impacts_from_records(rows), float(e0),
                                 traj, min_normal_force=low, release_speed=float(w),
                                 offset=float(h), lost_reason=reason)

    def _off_domain_reason(self, edge, R):
        err = self.domain_error(edge, R)
        why = str(err) if err is not None else 'the nominal release does not grasp it there'
        return (f'the part came to rest on edge {edge} at R = {R:.6g} m, outside the domain of '
                f'f ({why}); no later throw is defined')

    def f_batch(self, edges, radii):
        edges, radii, out = batch_buffers(edges, radii)
        z = np.ascontiguousarray(self._normals((edges.size,)))
        self.composed.throw_many(edges, radii, z, self.ctx, self.prm, self._no_record, *out)
        return batch_result(edges, out)

    def orbits(self, edges, radii, throws):
        edges, radii, out = orbit_buffers(edges, radii, throws)
        z = np.ascontiguousarray(self._normals((edges.size, throws)))
        self.composed.orbit_many(edges, radii, throws, z, self.ctx, self.prm, self._no_record,
                                 *out)
        return out

    def orbit_arrays(self, edge, R, throws):
        """Like ThrowModel.orbit_arrays; a lost throw ends the arrays with edge -1, R nan."""
        self.check(edge, R)
        e, r, rot, st, done = self.orbits([edge], [R], throws)
        st, done = int(st[0]), int(done[0])
        if st == LOST:
            return e[0, :done + 2], r[0, :done + 2], rot[0, :done + 2]
        if st != OK:
            self._raise(st, int(e[0, done]), float(r[0, done]), after=done)
        return e[0], r[0], rot[0]
