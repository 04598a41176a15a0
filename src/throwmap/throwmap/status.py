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
The compiled code's vocabulary: status codes with their messages, records, event codes.

Every compiled path (the composed pipeline, event_sim, the effects' hooks) answers with a named
record (Outcome, ThrowRecord) holding one of these status codes, and writes events in the
record layout below; :func:`error_for` turns a status into the exception the Python API
raises, with a message that names the problem and the fix. A new status is one line in CODES
and one in TEMPLATES or, if its message needs more than a template, one builder.
"""

from collections import namedtuple
import functools
import math
import numbers

from .errors import DomainError, NumericalError, PartLost, ThrowmapError

# ------------------------------------------------------------------------------ status codes
OK = 0
ERR_EDGE_INDEX = 1          # no such edge
ERR_UNSTABLE_EDGE = 2       # f is defined on stable edges only
ERR_GRASP = 3               # R below R_grasp: no dynamic grasp (bounds (1)-(4))
ERR_TOE_STUB = 4            # the left vertex does not start right of the pivot
ERR_FLIGHT_CAP = 5          # no contact within accuracy.max_flight_steps advancement steps
ERR_SETTLE_CAP = 6          # no rest within accuracy.max_impacts impacts
ERR_NONFINITE = 7           # a non-finite state (a flight that never lands, ...)
ERR_PAINLEVE = 9            # sliding contact with no consistent normal force (event_sim)
ERR_SIM_CAP = 10            # more than accuracy.max_sim_steps integrator steps (event_sim)
LOST = 20                   # finite_arm: the part left the arm (an outcome, not an error)
ERR_CARRY_GRASP = 21        # finite_carry: no dynamic grasp somewhere along the carry
ERR_ARM_STRIKE = 22         # finite_carry: the returning arm meets the part
ERR_RELEASE = 24            # a perturbed release speed <= 0
# A throw whose part came to rest outside the domain of f (below R_min: a slip under liftoff's
# finite friction): one throw's outcome only (pipeline.throw_one, with the rest state); batches
# and orbits report it as LOST, since no later throw is defined (issue 21 item 3).
OFF_DOMAIN = 25

CODES = {OK: 'ok', ERR_EDGE_INDEX: 'edge_index', ERR_UNSTABLE_EDGE: 'stable_edge',
         ERR_GRASP: 'grasp', ERR_TOE_STUB: 'toe_stub', ERR_FLIGHT_CAP: 'flight_cap',
         ERR_SETTLE_CAP: 'settle_cap', ERR_NONFINITE: 'nonfinite', ERR_PAINLEVE: 'painleve',
         ERR_SIM_CAP: 'sim_cap', LOST: 'lost', ERR_CARRY_GRASP: 'carry_grasp',
         ERR_ARM_STRIKE: 'arm_strike', ERR_RELEASE: 'release_speed', OFF_DOMAIN: 'off_domain'}

# ------------------------------------------------------------------------------ records
# What a throw's flight and catch gave (a motion hook's answer, throwmap.pipeline): status,
# resting edge and R, first contact time and vertex, net rotation, impacts, catch records
# written, lowest and highest arm coordinate a vertex touched.
Outcome = namedtuple('Outcome', ['status', 'edge', 'R', 't', 'rot', 'impacts', 'vertex',
                                 'records', 'x_lo', 'x_hi'])
# One throw: the compiled kernel's answer (throwmap.pipeline.build), the one record every
# caller reads by name. status, edge, R, t (release to first contact), rot, impacts, vertex
# and records as in Outcome; w and h the throw's own release speed and arm offset; energy per
# unit mass at release over the arm surface (J/kg). A failed throw has edge -1 and R nan.
ThrowRecord = namedtuple('ThrowRecord', ['status', 'edge', 'R', 't', 'rot', 'impacts',
                                         'vertex', 'records', 'w', 'h', 'energy'])

# ------------------------------------------------------------------------------ events
EV_FLIGHT_IMPACT = 0      # a vertex hits the arm at the end of flight
EV_LANDING = 1            # rolling brings an edge down; impact at its other vertex
EV_FLAT_LANDING = 2       # an edge lands flat from flight (two-point impact)
EV_TIP_FROM_REST = 3      # stopped on an unstable edge, the part tips over from rest
EV_BOUNCE = 4             # an impact that sends the part back into flight (event_sim)
EV_LIFTOFF = 5            # the normal force at the pivot reached zero: back into flight
EV_SETTLE_SNAP = 6        # rocking energy below settle_energy: laid flat about the pivot
EV_HELD = 7               # a resisting torque held the part on a corner: released from its edge

EVENT_NAMES = {EV_FLIGHT_IMPACT: 'flight', EV_LANDING: 'landing',
               EV_FLAT_LANDING: 'flat_landing', EV_TIP_FROM_REST: 'tip_from_rest',
               EV_BOUNCE: 'bounce', EV_LIFTOFF: 'liftoff', EV_SETTLE_SNAP: 'settle_snap',
               EV_HELD: 'held_on_corner'}

# Columns of a record row (one row per event). The rolling columns (pivot, alpha0, omega0,
# alpha1, pivot x) describe the roll that ended in a landing (closed-form catch only; nan
# elsewhere): throwmap.trajectory replays them.
REC_KIND, REC_VERTEX, REC_EDGE, REC_X, REC_W_BEFORE, REC_W_AFTER, REC_E_BEFORE, REC_E_AFTER, \
    REC_PIVOT, REC_ALPHA0, REC_OMEGA0, REC_ALPHA1, REC_PIVOT_X = range(13)
REC_COLS = 13

_BOUND_NAMES = {1: 'line of force passes left of the left vertex',
                2: 'force outside the right edge of the friction cone',
                3: 'line of force passes right of the right vertex',
                4: 'force outside the left edge of the friction cone'}


def bound_name(bound, impulse=True):
    """Words for constraint (1)..(4) of the dynamic grasp (impulse or force cone)."""
    text = _BOUND_NAMES[bound]
    return text.replace('force outside', 'impulse outside') if impulse else text


# ------------------------------------------------------------------------------ messages
def _domain(model, status, edge, R):
    err = model.domain_error(edge, R)
    if err is not None:
        return err
    if status in (ERR_GRASP, ERR_CARRY_GRASP):
        # In the domain of the nominal map, yet this throw's perturbed release (effect
        # release_noise) had no grasp.
        return DomainError('grasp_noise', f'no dynamic grasp at ({edge}, {R:.6g} m) with this '
                           "throw's sampled release speed and offset (release_noise); throw from "
                           'further out')
    return DomainError('unknown', f'status {status} ({CODES.get(status, "?")}) at ({edge}, '
                       f'{R})')


def _arm_strike(model, status, edge, R):
    carry = model.effects.get('finite_carry')
    return DomainError('arm_strike', f'from ({edge}, {R:.6g} m) the returning arm meets the part '
                       f'within throw.carry.return_time = {carry.return_time:g} s; return the '
                       'arm faster (smaller return_time) or throw higher')


def _lost(model, status, edge, R):
    # Where and why, as the noise-free throw from (edge, R) loses the part; a noisy throw
    # that the nominal one does not lose gets the general sentence.
    try:
        reason = model.nominal().throw(edge, R).lost_reason
    except ThrowmapError:
        reason = ''
    return PartLost(f'lost: from ({edge}, {R:.6g} m) '
                    + (reason or 'the part left the arm or came to rest outside the domain of f'))


# Messages that are templates: status -> (exception of a message, template). A template
# quotes the throw's ``edge`` and ``R`` and what ``model`` knows (str.format fields).
TEMPLATES = {
    ERR_FLIGHT_CAP: (NumericalError,
                     'flight from ({edge}, {R:.6g} m): no contact found within '
                     'accuracy.max_flight_steps = {model.accuracy.max_flight_steps} steps; '
                     'raise it or contact_time_tol'),
    ERR_SETTLE_CAP: (NumericalError,
                     'catch after ({edge}, {R:.6g} m) did not settle within '
                     'accuracy.max_impacts = {model.accuracy.max_impacts} impacts; raise it'),
    ERR_NONFINITE: (NumericalError,
                    'throw from ({edge}, {R:.6g} m) produced a non-finite state'),
    ERR_PAINLEVE: (NumericalError,
                   'catch after ({edge}, {R:.6g} m): sliding contact with no consistent '
                   'normal force (Painleve paradox); lower contact.mu'),
    ERR_SIM_CAP: (NumericalError,
                  'throw from ({edge}, {R:.6g} m) did not settle within '
                  'accuracy.max_sim_steps = {model.knobs.max_sim_steps} integrator '
                  'steps; raise it, or integrator_step / roll_step'),
    ERR_RELEASE: (functools.partial(DomainError, 'release_speed'),
                  'from ({edge}, {R:.6g} m) the sampled release speed is '
                  '<= 0; noise.release_speed_sd is too large for the release speed'),
}

# Messages that need more than a template: status -> builder(model, status, edge, R).
BUILDERS = {ERR_EDGE_INDEX: _domain, ERR_UNSTABLE_EDGE: _domain, ERR_GRASP: _domain,
            ERR_TOE_STUB: _domain, ERR_CARRY_GRASP: _domain, ERR_ARM_STRIKE: _arm_strike,
            LOST: _lost}


def error_for(model, status, edge, R, after=None):
    """
    Return the exception for a status of a throw from (edge, R).

    ``model`` answers domain_error(edge, R) and has what the messages quote (accuracy, knobs,
    and the parameters of the effect that gave the status, ``model.effects.get(name)``).
    ``after``: the orbit's throws before the failing one; the message then says so.
    """
    try:
        R = float(R)
    except (TypeError, ValueError):
        R = math.nan
    if isinstance(edge, numbers.Integral) and not isinstance(edge, bool):
        edge = int(edge)
    if int(status) in TEMPLATES:
        exception, template = TEMPLATES[int(status)]
        err = exception(template.format(model=model, edge=edge, R=R))
    else:
        err = BUILDERS.get(int(status), _domain)(model, int(status), edge, R)
    if after is not None:
        if isinstance(err, PartLost):
            err.after = after
        else:
            err.args = (f'after {after} throws the orbit left the domain of f: {err}',)
    return err


def message(model, status, edge, R):
    """Return the message of :func:`error_for` as text."""
    return str(error_for(model, status, edge, R))
