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
The throw map f(i, R) -> (i', R') of a scene: part, arm offset, release speed, gravity, effects.

One model class for every scene, over the one compiled kernel (throwmap.pipeline, composed per
effect set by throwmap.compose; the paper's base model is the empty set).
"""

import copy
from dataclasses import dataclass, field
import math
import types
import warnings

import numpy as np

from . import compose, status
from .accuracy import Accuracy, compiled_knobs, SETTLE_RULES, SimulatorAccuracy
from .catch import is_jog, records_min_normal, throw_kind
from .effects import EffectSet, event_simulated, EVENT_SLOTS, knob_defaults
from .errors import DomainError, InputError, ThrowmapError
from .event_sim import STICKING_CONTACT
from .grasp import edge_grasp, grasp_table
from .jit import entry_point
from .pipeline import Context, grasp_radii
from .sensor import read_sensor
from .status import EVENT_NAMES, LOST, OFF_DOMAIN, OK, REC_COLS
from .trajectory import throw_trajectory

REC_ROWS = 2048     # one throw's record buffer: a longer catch runs again with room for all


@dataclass(frozen=True)
class Impact:
    """One event of a catch. Energies are per unit mass (J/kg) over the arm surface."""

    kind: str               # 'flight' | 'landing' | 'flat_landing' | 'tip_from_rest' | ...
    vertex: int             # the vertex that hits the arm (or the pivot for tip_from_rest)
    edge: int               # the edge that lands (-1 for the first, corner-first impact)
    x: float                # arm coordinate of the contact vertex, m
    omega_before: float     # rad/s, CCW positive
    omega_after: float
    energy_before: float
    energy_after: float


def impacts_from_records(rows):
    """Return the Impact of every event row (status.REC_* columns)."""
    return tuple(Impact(EVENT_NAMES.get(int(row[0]), 'event'), int(row[1]), int(row[2]),
                        float(row[3]), float(row[4]), float(row[5]), float(row[6]),
                        float(row[7])) for row in rows)


@dataclass(frozen=True)
class ThrowResult:
    """Outcome of one throw and catch from (edge0, R0)."""

    edge0: int
    R0: float
    edge: int
    R: float
    kind: str               # 'jog', 'flip', or 'lost' (off the arm: edge -1, R nan)
    flight_time: float      # s
    net_rotation: float     # rad, flight plus rolling, CCW positive
    first_contact_vertex: int
    impacts: tuple
    release_energy: float   # J/kg over the arm surface, right after release
    trajectory: object = field(default=None, compare=False)
    # The smallest normal force per unit mass (m/s^2) the arm exerts on the pivot while the
    # part rolls (catch.records_min_normal): negative, the roll needs the arm to pull, which a
    # real arm cannot (the part hops; effect liftoff). inf: no roll; nan: not computed (the
    # event simulator's catch, which checks the sign itself where its contact law lifts off).
    min_normal_force: float = math.nan
    release_speed: float = math.nan     # the throw's own w (release_noise perturbs it)
    offset: float = math.nan            # the throw's own h
    lost_reason: str = ''               # lost, or at rest outside f's domain: where and why

    @property
    def in_domain(self):
        """Whether a next throw is defined: the part rests on the arm inside f's domain."""
        return self.edge >= 0 and not self.lost_reason

    @property
    def needs_pull(self):
        """Tell whether a roll of this throw needs the arm to pull the part (N < 0)."""
        return self.min_normal_force < 0.0

    def as_dict(self):
        return {'edge0': self.edge0, 'R0': self.R0, 'edge': self.edge, 'R': self.R,
                'kind': self.kind, 'flight_time': self.flight_time,
                'net_rotation': self.net_rotation,
                'first_contact_vertex': self.first_contact_vertex,
                'impacts': [vars(i) for i in self.impacts],
                'min_normal_force': (self.min_normal_force
                                     if math.isfinite(self.min_normal_force) else None),
                'release_speed': self.release_speed, 'offset': self.offset,
                'lost_reason': self.lost_reason, 'in_domain': self.in_domain}


def _state_arrays(edges, radii):
    """
    Edges and radii as contiguous int64 / float64 arrays; InputError for anything else.

    A non-integer edge (1.5, 'a', True) is refused rather than truncated by the conversion.
    """
    try:
        e = np.asarray(edges)
        r = np.asarray(radii, dtype=float).ravel()
    except (TypeError, ValueError) as exc:
        raise InputError('states', f'edges and radii must be numbers ({exc})',
                         'give integer edge numbers and radii in metres') from None
    integral = e.dtype.kind in 'iu' or (e.dtype.kind == 'f' and bool(np.all(np.isfinite(e)))
                                        and bool(np.all(e == np.round(e))))
    if e.size and not integral:
        raise InputError('states', f'edges must be integers, got {e.ravel()[:4].tolist()}'
                         f'{" ..." if e.size > 4 else ""}', 'give edge numbers as integers')
    return (np.ascontiguousarray(e.astype(np.int64).ravel()), np.ascontiguousarray(r))


def batch_buffers(edges, radii):
    """
    Validate a batch of states and allocate f_batch's outputs.

    Returns (edges, radii, (edge', R', status, flight time, net rotation, catch events, first
    contact vertex) output arrays).
    """
    edges, radii = _state_arrays(edges, radii)
    if edges.shape != radii.shape:
        raise InputError('states', f'{edges.size} edges but {radii.size} radii',
                         'give one edge per radius')
    m = edges.size
    return edges, radii, (np.empty(m, dtype=np.int64), np.empty(m),
                          np.empty(m, dtype=np.int64), np.empty(m), np.empty(m),
                          np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64))


def batch_result(edges, outputs):
    """Return f_batch's dict from the filled outputs (kind '' on failure, 'lost' if lost)."""
    out_edge, out_r, out_status, out_t, out_rot, out_events, out_vertex = outputs
    ok = out_status == OK
    kind = np.where(~ok, '', np.where(is_jog(edges, out_edge, out_rot), 'jog', 'flip'))
    kind = np.where(out_status == status.LOST, 'lost', kind)
    return {'edge': out_edge, 'R': out_r, 'status': out_status, 'kind': kind,
            'flight_time': out_t, 'net_rotation': out_rot, 'events': out_events,
            'first_contact_vertex': out_vertex}


def orbit_buffers(edges, radii, throws):
    """
    Validate the starts of many orbits and allocate their outputs.

    Returns (edges, radii, (edges, radii, rotations) of shape (starts, throws + 1), status,
    throws done).
    """
    edges, radii = _state_arrays(edges, radii)
    if edges.shape != radii.shape:
        raise InputError('states', f'{edges.size} edges but {radii.size} radii',
                         'give one edge per radius')
    m = edges.size
    return edges, radii, (np.full((m, throws + 1), -1, dtype=np.int64),
                          np.full((m, throws + 1), np.nan), np.zeros((m, throws + 1)),
                          np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64))


class ThrowModel:
    """
    f(i, R) for a part on an arm with offset h, release speed w, gravity g (< 0) and effects.

    Units are SI: metres, seconds, radians. ``g`` follows the paper: the acceleration along y,
    negative (e.g. -9.66 for the paper's inclined plate). ``mu``, when given, adds the friction
    bounds (2) and (4) to the grasp domain; without it only the geometric bounds (1) and (3)
    apply and the required mu_min is reported instead.

    ``effects`` (an EffectSet; none: the paper's base model) are composed into the one compiled
    kernel (throwmap.compose). What an effect changes at the Python level (the domain's
    intervals, the sensor's readings, why a part was lost) comes from its module's optional
    functions (throwmap.effects). With random effects the model owns a seeded numpy Generator
    (``rng``): every f, f_batch and orbit call draws from it, so results depend on the seed and
    on the order of calls; ``reseed(seed)`` starts the sequence again. ``simulator``, ``knobs``:
    the event simulator's and the effects' accuracy knobs; ``arm_length``: the scene's (inf
    without one). f and throw reuse one record buffer: one model per thread.
    """

    arm_length = math.inf       # the paper's arm has no end (effect finite_arm gives it one)

    def __init__(self, part, offset, release_speed, gravity, mu=None, settle_rule='full',
                 accuracy=None, effects=None, simulator=None, knobs=None, seed=0,
                 arm_length=None, field_prefix=''):
        self.part = part
        self.h = self._number(offset, f'{field_prefix}arm.offset', 'the arm offset h in metres')
        self.w = self._number(release_speed, f'{field_prefix}throw.release_speed',
                              'the release speed in rad/s')
        self.g = self._number(gravity, f'{field_prefix}gravity', 'g in m/s^2')
        if self.w <= 0:
            raise InputError(f'{field_prefix}throw.release_speed',
                             f'must be > 0 rad/s, got {release_speed!r}',
                             'give the arm speed at release, e.g. 5.5851 (320 deg/s)')
        if self.g >= 0:
            raise InputError(f'{field_prefix}gravity', f"must be < 0 (the paper's sign: y up, "
                             f'gravity down), got {gravity!r}', 'use e.g. -9.81 or -9.66')
        if mu is not None:
            mu = self._number(mu, f'{field_prefix}contact.mu', 'the friction coefficient')
            if mu <= 0:
                raise InputError(f'{field_prefix}contact.mu', f'must be > 0, got {mu!r}',
                                 'give the part-arm Coulomb friction coefficient, or omit it')
        self.mu = mu
        if settle_rule not in SETTLE_RULES:
            raise InputError(f'{field_prefix}settle_rule', f'unknown rule {settle_rule!r}',
                             f'use one of {", ".join(SETTLE_RULES)}')
        self.settle_rule = settle_rule
        self.accuracy = accuracy or Accuracy()
        if not -part.d_min < self.h < 0:
            warnings.warn(f'{field_prefix}arm.offset h = {self.h:g} m is outside Proposition '
                          f"IV.4's range 0 > h > -d_min = {-part.d_min:g} m: the limit-set "
                          'guarantee does not apply (f is still computed)', stacklevel=2)
        self.grasp = [edge_grasp(part, i, self.h, mu) for i in range(part.n)]
        self.r_grasp = np.array([gr.R_grasp for gr in self.grasp])
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
        mu_c = math.inf if mu is None else mu
        self.ctx = Context(self.w, self.h, self.g, mu_c, part.arrays,
                           compiled_knobs(self.accuracy, self.simulator, settle_rule),
                           laws[0][1] if laws else STICKING_CONTACT,
                           grasp_radii(part.arrays, self.h, mu_c))
        filled = {s for slots in self.slots.values() for s in slots}
        self._event_motion = event_simulated(filled)    # compose: the event simulator
        self._draws = 'perturb' in filled
        self._sensor_models = [(m.read_sensor, p) for _, m, p in modules
                               if hasattr(m, 'read_sensor')]
        # Throws are the base model's own (same release, flight and catch): trajectories apply.
        self._base_motion = (not filled & {'perturb', 'release', *EVENT_SLOTS} and not laws
                             and self.simulator.contact_method == 'advancement')
        self._rec = np.empty((REC_ROWS, REC_COLS))
        self._no_record = np.empty((0, REC_COLS))
        self._no_draws = np.zeros((0, 2))
        self._one = None
        self._f = None
        self._domain_effect = next(((n, m, p) for n, m, p in modules if hasattr(m, 'domain')),
                                   None)
        self._domain = None
        if self._domain_effect is not None:
            _, module, params = self._domain_effect
            self._domain = module.domain(self, params)
            self.r_grasp = np.array([self._domain[i][0][0] if self._domain.get(i) else math.inf
                                     for i in range(part.n)])

    def at(self, offset, release_speed):
        """
        Return this scene's model at another design: arm offset h and release speed w (SI).

        The same part, effects, knobs, seed and arm; what depends on h and w (the grasp table,
        an effect's domain) is computed again.
        """
        return ThrowModel(self.part, offset, release_speed, self.g, mu=self.mu,
                          settle_rule=self.settle_rule, accuracy=self.accuracy,
                          effects=self.effects, simulator=self.simulator,
                          knobs=dict(vars(self.knobs)), seed=self.seed,
                          arm_length=self.arm_length if math.isfinite(self.arm_length) else None)

    @staticmethod
    def _number(value, name, what):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
            raise InputError(name, f'must be a number, got {value!r}', f'give {what}')
        value = float(value)
        if not math.isfinite(value):
            raise InputError(name, f'must be finite, got {value!r}', f'give {what}')
        return value

    # ----------------------------------------------------------------------------- grasp
    def grasp_table(self):
        return grasp_table(self.part, self.h, self.mu)

    def r_min(self, edge):
        """
        Return the lower end of the domain of f on a stable edge (inf: no domain there).

        R_grasp, or the toe-stub bound -u_l (the left vertex must start right of the pivot)
        when that is larger; an effect may move it (:meth:`domain_intervals`).
        """
        spans = self.domain_intervals(edge)
        return spans[0][0] if spans else math.inf

    def r_max(self, edge):
        """Return the upper end of the domain of f on a stable edge (inf: unbounded)."""
        spans = self.domain_intervals(edge)
        return spans[-1][1] if spans else -math.inf

    def start_radius(self, edge):
        """Return a radius well inside the domain: 1.5 R_min, or mid-interval if that is less."""
        lo, hi = self.r_min(edge), self.r_max(edge)
        return min(1.5 * lo, 0.5 * (lo + hi))

    def domain_intervals(self, edge):
        """
        Return the domain of f on a stable edge as intervals of R, [(lo, hi), ...].

        The base model's is one half-line [max(R_grasp, -u_l), inf); an effect may bound it
        above or split it (finite_carry). Empty: no R on this edge can be thrown.
        """
        if self._domain is not None:
            return list(self._domain.get(int(edge), []))
        return [(max(float(self.r_grasp[edge]), float(-self.part.u_l[edge])), math.inf)]

    def domain_note(self):
        """Return a line on the domain beyond the impulse-cone grasp table, or None."""
        if self._domain_effect is None:
            return None
        _, module, params = self._domain_effect
        return module.domain_note(self, params) if hasattr(module, 'domain_note') else None

    def _base_domain_error(self, edge, R):
        # The paper's domain: a stable edge, a finite R, the impulse-cone grasp, no toe stub.
        part = self.part
        if isinstance(edge, bool) or not isinstance(edge, (int, np.integer)):
            return DomainError('edge_index', f'edge must be an integer, got {edge!r}')
        if not 0 <= edge < part.n:
            return DomainError('edge_index', f'edge {edge} does not exist: the part has edges '
                               f'0..{part.n - 1}')
        if not part.stable[edge]:
            return DomainError('stable_edge', f'edge {edge} is not stable (u_l = '
                               f'{part.u_l[edge]:.4g} m, u_r = {part.u_r[edge]:.4g} m; stable '
                               f'needs u_l < 0 < u_r): f is defined only on stable edges '
                               f'{part.stable_edges}')
        if (isinstance(R, bool) or not isinstance(R, (int, float, np.integer, np.floating))
                or not math.isfinite(R)):
            return DomainError('radius', f'R must be a finite number of metres, got {R!r}')
        gr = self.grasp[edge]
        if R < gr.R_grasp:
            return DomainError(f'grasp_bound_{gr.binding}',
                               f'no dynamic grasp on edge {edge} at R = {R:.6g} m: bound '
                               f'({gr.binding}) ({status.bound_name(gr.binding)}) needs R >= '
                               f'{gr.R_grasp:.6g} m (short by {gr.R_grasp - R:.3g} m); throw '
                               f'from R >= R_grasp', margin=gr.R_grasp - R)
        if not R + part.u_l[edge] > 0:
            need = -part.u_l[edge]
            return DomainError('toe_stub', f'at R = {R:.6g} m the left vertex of edge {edge} '
                               f'sits at x = {R - need:.3g} m, not right of the pivot: it would '
                               f'stub its toe (move down) at release; need R > {need:.6g} m',
                               margin=need - R)
        return None

    def domain_error(self, edge, R):
        """Return the DomainError f would raise at (edge, R), or None inside the domain."""
        err = self._base_domain_error(edge, R)
        if self._domain_effect is None or (err is not None and err.condition in (
                'edge_index', 'stable_edge', 'radius')):
            return err
        _, module, params = self._domain_effect
        return module.domain_error(self, params, edge, R)

    def check(self, edge, R):
        """Raise the DomainError of (edge, R), if it is outside the domain of f."""
        err = self.domain_error(edge, R)
        if err is not None:
            raise err

    def nominal_status(self, edges, radii):
        """Statuses of noise-free throws from many states (domain scans)."""
        edges, radii, out = batch_buffers(edges, radii)
        self.composed.throw_many(edges, radii, self._no_draws, self.ctx, self.prm,
                                 self._no_record, *out)
        return out[2]

    # ----------------------------------------------------------------------------- the map
    def _state(self, edge, R):
        """
        (edge, R) as the kernel's types (int, float), or raise the DomainError.

        The compiled kernel only takes an integer edge and a real R: anything else (a string,
        None, a bool, a float edge, an integer beyond 64 bits) would fail to compile with a
        numba TypingError, and an infinite R would fly forever; those are outside the domain.
        Checked before any random draw; the kernel's status covers the rest of the domain.
        """
        if (isinstance(edge, (int, np.integer)) and not isinstance(edge, bool)
                and isinstance(R, (int, float, np.integer, np.floating))
                and not isinstance(R, bool) and math.isfinite(R) and 0 <= edge < self.part.n):
            return int(edge), float(R)
        err = self._base_domain_error(edge, R)
        raise err if err is not None else DomainError(
            'radius', f'R must be a finite number of metres, got {R!r}')

    def _draw(self):
        # This throw's two standard normal draws (release_noise); none without random effects.
        if not self._draws:
            return 0.0, 0.0
        z = self.rng.standard_normal(2)
        return float(z[0]), float(z[1])

    def _throw(self, edge, R, z, rec):
        # The compiled throw, called directly (its argument types never change; jit.entry_point).
        if self._one is None:
            self._one = entry_point(self.composed.throw_one, edge, R, 0.0, 0.0, self.ctx,
                                    self.prm, rec)
        return self._one(edge, R, z[0], z[1], self.ctx, self.prm, rec)

    def f(self, edge, R):
        """
        (edge', R', kind) of one throw; raises DomainError outside the domain.

        kind 'lost' (edge -1, R nan) when the part leaves the arm (finite_arm), or comes to
        rest outside the domain of f (below R_min), where no later throw is defined:
        :meth:`throw` says where it rests and why.
        """
        edge, R = self._state(edge, R)
        z0, z1 = self._draw() if self._draws else (0.0, 0.0)
        if self._f is None:
            self._f = entry_point(self.composed.throw_f, edge, R, z0, z1, self.ctx, self.prm,
                                  self._no_record)
        st, j, r1, rot = self._f(edge, R, z0, z1, self.ctx, self.prm, self._no_record)
        if st != OK:
            if st == LOST or st == OFF_DOMAIN:
                return -1, math.nan, 'lost'
            self._raise(st, edge, R)
        return j, r1, throw_kind(edge, j, rot)

    def throw(self, edge, R, trajectory=False, samples=60):
        """
        Return the full ThrowResult of one throw.

        kind 'lost' (edge -1, R nan) with ``lost_reason``: the part left the arm. A part that
        came to rest outside the domain of f (below R_min) keeps its physical result (edge, R,
        'jog' or 'flip') with ``in_domain`` false and the reason in ``lost_reason``: no next
        throw is defined (f, f_batch and orbits report it as lost: edge -1, R nan).

        ``trajectory``: the sampled poses (throwmap.trajectory), where the throw is the base
        model's own (effects that only check or lose it, sensor noise); else None: the event
        simulator keeps no poses.
        """
        edge, R = self._state(edge, R)
        z = self._draw()
        rec = self._rec
        t = self._throw(edge, R, z, rec)
        if t.status not in (OK, LOST, OFF_DOMAIN):
            self._raise(t.status, edge, R)
        if t.records > rec.shape[0]:     # a long catch: again, with room for every event
            rec = np.empty((t.records, REC_COLS))
            self._throw(edge, R, z, rec)
        rows = rec[:t.records]
        j, r1, reason = t.edge, t.R, ''
        if t.status == OFF_DOMAIN:
            # The part rests there, on the arm, as the physics says; no next throw is defined.
            kind = throw_kind(edge, j, t.rot)
            reason = self._off_domain_reason(int(j), float(r1))
        elif t.status == LOST:
            kind = 'lost'
            for _, module, params in self.effects.modules():
                if hasattr(module, 'lost_reason'):
                    reason = module.lost_reason(rows, r1, params)
        else:
            kind = throw_kind(edge, j, t.rot)
        traj = None
        if trajectory and t.status == OK and self._base_motion:
            traj = throw_trajectory(self, edge, R, t.t, rows, samples)
        low = math.nan if self._event_motion else self._min_normal(rec, t.records)
        return ThrowResult(int(edge), float(R), int(j), float(r1), kind, float(t.t),
                           float(t.rot), int(t.vertex), impacts_from_records(rows),
                           float(t.energy), traj, low, float(t.w), float(t.h), reason)

    def _min_normal(self, rec, nrec):
        # Outside f: the hot path stays as fast as before (bench/throwmap_speed.py).
        part = self.part.arrays
        return float(records_min_normal(rec, nrec, part.vrad, part.rho2, -self.g))

    def _off_domain_reason(self, edge, R):
        err = self.domain_error(edge, R)
        why = str(err) if err is not None else 'the nominal release does not grasp it there'
        return (f'the part came to rest on edge {edge} at R = {R:.6g} m, outside the domain of '
                f'f ({why}); no later throw is defined')

    def _draws_for(self, shape):
        # Draws for many throws; an array with no rows tells the kernel: no perturbation.
        if not self._draws:
            return self._no_draws.reshape((0,) * len(shape) + (2,))
        return np.ascontiguousarray(self.rng.standard_normal(shape + (2,)))

    def f_batch(self, edges, radii):
        """
        Evaluate f over many states at once.

        Returns a dict of arrays: edge, R, kind ('jog'/'flip'/'lost'/''), status, flight_time,
        net_rotation, events (the number of catch events ``throw`` would list),
        first_contact_vertex. States outside the domain get status != 0 and NaN R;
        ``error_message(status, edge, R)`` gives the text.
        """
        edges, radii, out = batch_buffers(edges, radii)
        self.composed.throw_many(edges, radii, self._draws_for((edges.size,)), self.ctx,
                                 self.prm, self._no_record, *out)
        return batch_result(edges, out)

    def orbits(self, edges, radii, throws):
        """Iterate many orbits at once: arrays (starts, throws + 1), status, throws done."""
        edges, radii, out = orbit_buffers(edges, radii, throws)
        self.composed.orbit_many(edges, radii, throws, self._draws_for((edges.size, throws)),
                                 self.ctx, self.prm, self._no_record, *out)
        return out

    def orbit_arrays(self, edge, R, throws):
        """
        Iterate f: arrays of edges, radii and net rotations (index 0 is the start).

        A lost throw ends the arrays with edge -1, R nan; another failure raises.
        """
        self.check(edge, R)
        e, r, rot, st, done = self.orbits([edge], [R], throws)
        st, done = int(st[0]), int(done[0])
        if st == LOST:
            return e[0, :done + 2], r[0, :done + 2], rot[0, :done + 2]
        if st != OK:
            self._raise(st, int(e[0, done]), float(r[0, done]), after=done)
        return e[0], r[0], rot[0]

    # ----------------------------------------------------------------------------- noise
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

    def read_sensor(self, edge, R, x, footprint=0.0):
        """One reading of the sensor at x: geometry, then the effects' sensor models."""
        return read_sensor(self.part, edge, R, x, footprint, self._sensor_models, self.rng)

    # ----------------------------------------------------------------------------- errors
    def error_message(self, status_code, edge, R):
        """Return the message of a kernel status at (edge, R) (f_batch, orbits)."""
        return status.message(self, status_code, edge, R)

    def _raise(self, status_code, edge, R, after=None):
        raise status.error_for(self, status_code, edge, R, after)
