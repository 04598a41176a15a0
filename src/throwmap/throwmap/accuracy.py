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
Accuracy knobs (docs/accuracy.md measures what each one costs), and their compiled bundle.

:class:`Accuracy` holds the base model's knobs, :class:`SimulatorAccuracy` those of the contact
finder's alternative and of the event simulator. Effects add their own knobs (an effect module's
``KNOBS``, e.g. backplate_friction's ``plate_quadrature``); :func:`check_knob` validates them
all alike. Compiled code takes every knob as one :data:`Knobs` bundle.
"""

from collections import namedtuple
from dataclasses import dataclass, fields
import math

from .errors import InputError

SETTLE_RULES = ('full', 'first_stable')
CONTACT_METHODS = ('advancement', 'scan')
METHOD_ADVANCEMENT = 0
METHOD_SCAN = 1
FLIGHT_METHODS = ('rk4', 'rk8', 'picard')
FLIGHT_RK4 = 0
FLIGHT_RK8 = 1
FLIGHT_PICARD = 2
ROLL_METHODS = ('rk4', 'energy')
ROLL_RK4 = 0
ROLL_ENERGY = 1

# The knobs as compiled code takes them, and the settle rule (first_stable: the catch ends on
# the first stable edge that lands, section IV's simplification).
Knobs = namedtuple('Knobs', ['contact_time_tol', 'flat_landing_tol', 'max_flight_steps',
                             'max_impacts', 'first_stable', 'contact_method',
                             'contact_scan_step', 'contact_root_tol', 'integrator_step',
                             'roll_step', 'settle_energy', 'max_sim_steps', 'flight_method',
                             'flight_step', 'roll_method', 'flight_tol', 'flight_grade'])


def check_knob(name, value, default):
    """
    Validate one knob: an integer if its default is an int, else a number > 0.

    An integer knob is >= 1, or >= 0 when its default is 0 (0 selects an exact method:
    plate_quadrature).
    """
    if isinstance(default, int):
        lo = 0 if default == 0 else 1
        if isinstance(value, bool) or not isinstance(value, int) or value < lo:
            raise InputError(f'accuracy.{name}', f'must be an integer >= {lo}, got {value!r}',
                             f'use e.g. the default {default}')
    elif (isinstance(value, bool) or not isinstance(value, (int, float))
          or not math.isfinite(value) or value < 0 or (value == 0 and default != 0)):
        bound = '>= 0' if default == 0 else '> 0'
        raise InputError(f'accuracy.{name}', f'must be a number {bound}, got {value!r}',
                         f'use e.g. the default {default}')
    return value


@dataclass(frozen=True)
class Accuracy:
    """
    Accuracy knobs of the base model.

    contact_time_tol : s. Conservative advancement stops once the next guaranteed-safe step is
        shorter than this; the contact time is then exact to about this much (or to the
        spacing of doubles at that time, about 4.4e-16 t, when that is coarser).
    flat_landing_tol : rad. An edge within this angle of the arm at impact lands flat (two-point
        sticking impact: the part stops) instead of corner first.
    max_flight_steps : cap on advancement steps per vertex (a NumericalError beyond it).
    max_impacts : cap on impacts while settling (a NumericalError beyond it). Settling always
        ends (every impact loses energy), but a near-circular part rolls like a wheel: an
        n-gon loses only ~(2 pi / n)^2 of its energy per impact and needs ~n^2 impacts
        (300,000 for a 1024-gon thrown from R_grasp). An impact costs ~50 ns in f, f_batch
        and orbits; ``throw`` also keeps a record of each one (~350 bytes).
    """

    contact_time_tol: float = 1e-12
    flat_landing_tol: float = 1e-9
    max_flight_steps: int = 100_000
    max_impacts: int = 1_000_000

    def __post_init__(self):
        for name in ('contact_time_tol', 'flat_landing_tol'):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InputError(f'accuracy.{name}', f'must be a number > 0, got {value!r}',
                                 f'use e.g. the default {getattr(Accuracy, name)}')
        for name in ('max_flight_steps', 'max_impacts'):
            value = getattr(self, name)
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= 10):
                raise InputError(f'accuracy.{name}', f'must be an integer >= 10, got {value!r}',
                                 f'use e.g. the default {getattr(Accuracy, name)}')


@dataclass(frozen=True)
class SimulatorAccuracy:
    """
    Knobs of the contact finder's alternative and of the event simulator (throwmap.event_sim).

    contact_method : 'advancement' (conservative advancement: exact, never misses a contact)
        or 'scan' (samples every contact_scan_step, bisects to contact_root_tol; misses any
        graze shorter than a step). Applies to ballistic flight.
    contact_scan_step : s, sample interval of the 'scan' method.
    contact_root_tol : s, location tolerance of every scanned event (scan method, and all
        events of the event simulator: bisection, or regula falsi on the quantity that crossed
        zero); rad for the closed-form roll's liftoff and slip.
    integrator_step : s, RK4 step of flight in the event simulator under a body force;
        contacts are looked for at every step, so this is also its scan resolution.
    roll_step : s, RK4 step of rolling/sliding phases in the event simulator.
    settle_energy : J/kg, rocking energy above the flat pose below which the event simulator
        lays the part flat (only when the impact law is not the sticking one; otherwise the
        exact rule holds).
    max_sim_steps : cap on integrator steps per throw in the event simulator: it bounds the work
        of one throw (500000 steps: 500 s simulated at 1 ms steps).
    flight_method : how the event simulator integrates flight under a body force (without
        one the flight is the base model's closed form whatever this says): 'rk4' (fixed RK4
        steps of integrator_step, contacts bisected on re-integrated sub-steps; the accuracy
        reference) or 'rk8' (fixed steps of flight_step with the order-8 Dormand-Prince
        tableau, contacts looked for on the step's quintic Hermite interpolant no farther apart
        than integrator_step, or farther where a speed bound proves no vertex can reach the
        arm, and the contact state integrated exactly from the step's start), or 'picard' (the
        series about the ballistic flight: pieces of at most flight_step, ended where the
        plate drag has a kink, each solved by Picard sweeps at Gauss-Legendre nodes until a
        sweep moves its end by less than flight_tol; throwmap.picard). A scene whose body
        force declares FLIGHT_KNOBS (backplate_friction: picard, 0.08 s, 1e-10, grade 1.5) takes
        those it does not name when it names neither flight_method nor integrator_step
        (throwmap.scene).
    flight_step : s, the largest step of flight_method 'rk8', the largest piece of 'picard'.
    flight_tol : the error allowed per step of flight_method 'rk8' (DOP853's estimate, in m,
        rad, m/s and rad/s alike); steps shrink and grow to meet it. For 'picard': the last
        sweep's increment at a piece's end (m; velocities times the piece, rad times the
        part's size), the series' remainder.
    flight_grade : 'picard' only; 0 (default): off. Else a piece is at most flight_grade
        times its distance in time from where the plate drag is singular (the instantaneous
        centre on the outline: the drag goes as d^2 ln|d| in the centre's distance d from an
        edge), that distance estimated as the centre's distance from the outline over its
        speed, and a piece is not split at a kink until it is within flight_step / 16 of it
        (graded pieces: the 5 nodes of a piece that reaches the singularity lose their order);
        the piece in which the contact falls is solved again to end at it.
    roll_method : how the event simulator rolls about a sticking pivot: 'energy' (default:
        closed form, the work-energy equation in the roll angle, exact when the body force's
        torque about the pivot is -sign(omega) (a0 + a2 omega^2), as the plate's and the
        air's are; checked numerically for every pivot, otherwise that roll takes rk4 steps;
        about a unilateral pivot liftoff and slip are found in the roll angle, in steps the
        forces' margins prove clear and of at least 10 rad/s times roll_step, where an event
        narrower than that may go unseen) or 'rk4' (steps of roll_step; the default
        before issue 24, kept as the reference). Slides always take rk4 steps.
    """

    contact_method: str = 'advancement'
    contact_scan_step: float = 1e-3
    contact_root_tol: float = 1e-12
    integrator_step: float = 1e-3
    roll_step: float = 1e-3
    settle_energy: float = 1e-8
    max_sim_steps: int = 500_000
    flight_method: str = 'rk4'
    flight_step: float = 0.02
    roll_method: str = 'energy'
    flight_tol: float = 1e-12
    flight_grade: float = 0.0

    def __post_init__(self):
        if self.contact_method not in CONTACT_METHODS:
            raise InputError('accuracy.contact_method', f'unknown method {self.contact_method!r}',
                             f'use one of {", ".join(CONTACT_METHODS)}')
        if self.flight_method not in FLIGHT_METHODS:
            raise InputError('accuracy.flight_method', f'unknown method {self.flight_method!r}',
                             f'use one of {", ".join(FLIGHT_METHODS)}')
        if self.roll_method not in ROLL_METHODS:
            raise InputError('accuracy.roll_method', f'unknown method {self.roll_method!r}',
                             f'use one of {", ".join(ROLL_METHODS)}')
        for f in fields(self):
            if f.name not in ('contact_method', 'flight_method', 'roll_method'):
                check_knob(f.name, getattr(self, f.name), f.default)


BASE_KEYS = tuple(f.name for f in fields(Accuracy))
SIMULATOR_KEYS = tuple(f.name for f in fields(SimulatorAccuracy))


def compiled_knobs(accuracy, simulator=None, settle_rule='full'):
    """Return the :data:`Knobs` bundle of the base and simulator knobs and the settle rule."""
    sim = simulator or SimulatorAccuracy()
    return Knobs(float(accuracy.contact_time_tol), float(accuracy.flat_landing_tol),
                 int(accuracy.max_flight_steps), int(accuracy.max_impacts),
                 settle_rule == 'first_stable',
                 METHOD_SCAN if sim.contact_method == 'scan' else METHOD_ADVANCEMENT,
                 float(sim.contact_scan_step), float(sim.contact_root_tol),
                 float(sim.integrator_step), float(sim.roll_step), float(sim.settle_energy),
                 int(sim.max_sim_steps), FLIGHT_METHODS.index(sim.flight_method),
                 float(sim.flight_step), ROLL_METHODS.index(sim.roll_method),
                 float(sim.flight_tol), float(sim.flight_grade))
