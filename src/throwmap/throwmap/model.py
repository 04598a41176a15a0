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

"""The throw map f(i, R) -> (i', R') for one part, arm offset, release speed and gravity."""

from dataclasses import dataclass, field
import math
import warnings

import numpy as np

from . import base_map, status
from .accuracy import Accuracy, compiled_knobs, SETTLE_RULES
from .catch import is_jog, records_min_normal, throw_kind
from .errors import DomainError, InputError
from .grasp import edge_grasp, grasp_table
from .jit import entry_point
from .sensor import read_sensor
from .status import EVENT_NAMES, OK, REC_COLS
from .trajectory import throw_trajectory


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
    kind: str               # 'jog' or 'flip'
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
                                     if math.isfinite(self.min_normal_force) else None)}


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
    f(i, R) for a part on an arm with offset h, release speed w and gravity g (< 0).

    Units are SI: metres, seconds, radians. ``g`` follows the paper: the acceleration along y,
    negative (e.g. -9.66 for the paper's inclined plate). ``mu``, when given, adds the friction
    bounds (2) and (4) to the grasp domain; without it only the geometric bounds (1) and (3)
    apply and the required mu_min is reported instead.
    """

    stochastic = False
    seed = None
    arm_length = math.inf       # the paper's arm has no end (effect finite_arm gives it one)

    def __init__(self, part, offset, release_speed, gravity, mu=None, settle_rule='full',
                 accuracy=None, field_prefix=''):
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
        self._knobs = compiled_knobs(self.accuracy, None, settle_rule)
        self._no_record = np.empty((0, REC_COLS))
        self._f = None

    @staticmethod
    def _number(value, name, what):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
            raise InputError(name, f'must be a number, got {value!r}', f'give {what}')
        value = float(value)
        if not math.isfinite(value):
            raise InputError(name, f'must be finite, got {value!r}', f'give {what}')
        return value

    def _base_args(self):
        return (self.w, self.g, self.h, self.r_grasp, self.part.arrays, self._knobs)

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
        return [(max(float(self.r_grasp[edge]), float(-self.part.u_l[edge])), math.inf)]

    def domain_note(self):
        """Return a line on the domain beyond the impulse-cone grasp table, or None."""
        return None

    def domain_error(self, edge, R):
        """Return the DomainError f would raise at (edge, R), or None inside the domain."""
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

    def check(self, edge, R):
        """Raise the DomainError of (edge, R), if it is outside the domain of f."""
        err = self.domain_error(edge, R)
        if err is not None:
            raise err

    # ----------------------------------------------------------------------------- the map
    def _state(self, edge, R):
        """
        (edge, R) as the kernel's types (int, float), or raise the DomainError.

        The compiled kernel only takes an integer edge and a real R: anything else (a string,
        None, a bool, a float edge, an integer beyond 64 bits) would fail to compile with a
        numba TypingError, and an infinite R would fly forever; those are outside the domain.
        """
        if (isinstance(edge, (int, np.integer)) and not isinstance(edge, bool)
                and isinstance(R, (int, float, np.integer, np.floating))
                and not isinstance(R, bool) and math.isfinite(R) and 0 <= edge < self.part.n):
            return int(edge), float(R)
        err = self.domain_error(edge, R)
        raise err if err is not None else DomainError(
            'radius', f'R must be a finite number of metres, got {R!r}')

    def _throw_one(self, edge, R, rec):
        # The compiled throw, called directly (its argument types never change; jit.entry_point).
        if self._f is None:
            self._f = entry_point(base_map.throw_one, edge, R, *self._base_args(), rec, math.inf)
        return self._f(edge, R, *self._base_args(), rec, math.inf)      # the base model: no end

    def f(self, edge, R):
        """(edge', R', kind) of one throw; raises DomainError outside the domain."""
        edge, R = self._state(edge, R)
        out = self._throw_one(edge, R, self._no_record)
        if out[0] != OK:
            self._raise(out[0], edge, R)
        return out[1], out[2], throw_kind(edge, out[1], out[4])

    def throw(self, edge, R, trajectory=False, samples=60):
        """Full ThrowResult; with ``trajectory`` the sampled poses (throwmap.trajectory)."""
        edge, R = self._state(edge, R)
        rec = np.empty((64, REC_COLS))
        st, j, r1, t, rot, nimp, k0, nrec = self._throw_one(edge, R, rec)
        if st != OK:
            self._raise(st, edge, R)
        if nrec > rec.shape[0]:     # rare long rolls: run again with room for every event
            rec = np.empty((nrec, REC_COLS))
            self._throw_one(edge, R, rec)
        hd = self.h + self.part.d[edge]
        e0 = 0.5 * self.w ** 2 * (hd * hd + R * R + self.part.rho2) - self.g * self.part.d[edge]
        traj = None
        if trajectory:
            traj = throw_trajectory(self, edge, R, t, rec[:nrec], samples)
        return ThrowResult(int(edge), float(R), int(j), float(r1), throw_kind(edge, j, rot),
                           float(t), float(rot), int(k0), impacts_from_records(rec[:nrec]),
                           float(e0), traj, self._min_normal(rec, nrec))

    def _min_normal(self, rec, nrec):
        # Outside f: the hot path stays as fast as before (bench/throwmap_speed.py).
        part = self.part.arrays
        return float(records_min_normal(rec, nrec, part.vrad, part.rho2, -self.g))

    def f_batch(self, edges, radii):
        """
        Evaluate f over many states at once.

        Returns a dict of arrays: edge, R, kind ('jog'/'flip'/''), status, flight_time,
        net_rotation, events (the number of catch events ``throw`` would list),
        first_contact_vertex. States outside the domain get status != 0 and NaN R;
        ``error_message(status, edge, R)`` gives the text.
        """
        edges, radii, out = batch_buffers(edges, radii)
        base_map.throw_many(edges, radii, *self._base_args(), self._no_record, *out)
        return batch_result(edges, out)

    def orbit_arrays(self, edge, R, throws):
        """Iterate f: arrays of edges, radii and net rotations (index 0 is the start)."""
        self.check(edge, R)
        out_edge = np.empty(throws + 1, dtype=np.int64)
        out_r = np.empty(throws + 1)
        out_rot = np.empty(throws + 1)
        st, done = base_map.orbit(edge, float(R), throws, *self._base_args(), self._no_record,
                                  out_edge, out_r, out_rot)
        if st != OK:
            self._raise(st, int(out_edge[done]), float(out_r[done]), after=done)
        return out_edge, out_r, out_rot

    def orbits(self, edges, radii, throws):
        """Iterate many orbits at once: arrays (starts, throws + 1), status, throws done."""
        edges, radii, out = orbit_buffers(edges, radii, throws)
        base_map.orbit_many(edges, radii, throws, *self._base_args(), self._no_record, *out)
        return out

    # ----------------------------------------------------------------------------- noise
    def nominal(self):
        """Return the model without its random effects: this one, which has none."""
        return self

    def reseed(self, seed):
        """Restart the random sequences: nothing to do without random effects."""

    def read_sensor(self, edge, R, x, footprint=0.0):
        """Return the sensor's bits at x for parts resting at (edge, R); edge -1 reads 0."""
        return read_sensor(self.part, edge, R, x, footprint)

    # ----------------------------------------------------------------------------- errors
    def error_message(self, status_code, edge, R):
        """Return the message of a kernel status at (edge, R) (f_batch, orbits)."""
        return status.message(self, status_code, edge, R)

    def _raise(self, status_code, edge, R, after=None):
        raise status.error_for(self, status_code, edge, R, after)
