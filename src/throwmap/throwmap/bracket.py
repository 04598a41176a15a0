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
The one root bracketing of the event simulator and its flights.

A crossing comes in two kinds. A discrete event (a vertex found at or below the arm, the event
a contact step ends in) has no value to interpolate: it is bisected (:func:`make_first_event`).
A continuous function with a sign change (a vertex's height, the side of an edge's line the
instantaneous centre is on) is located by the Illinois variant of regula falsi
(:func:`make_crossing`), which converges superlinearly and keeps the crossing bracketed.

Each is made over the function it brackets, as the rest of the simulator is made over its
hooks: numba caches no function that takes another as an argument. The functions take their
constants as one tuple, ``fn(tau, args)``, so that both inline into their callers.

A walk toward a crossing steps as far as a lower bound proves safe (:func:`parabola_exit`).
"""

import math

from .jit import njit

NO_EVENT = 0


@njit(inline=True)
def parabola_exit(f, d, bound):
    """
    Return how far in h > 0 the parabola f + d h - bound h^2 / 2 stays >= 0 (0: it falls at once).

    A value f >= 0 with slope d whose second derivative stays above -``bound`` lies above that
    parabola, so it cannot turn negative sooner: the safe step of a walk that must not step over
    a crossing. Each sign of d has its own form, free of the cancellation the other one has
    (f tiny against d^2 / bound loses the step to rounding in the other).
    """
    if f < 0.0:
        return 0.0
    root = math.sqrt(d * d + 2.0 * bound * f)
    if d > 0.0:
        return (d + root) / bound if bound > 0.0 else math.inf
    den = root - d
    if den > 0.0:
        return 2.0 * f / den
    return math.inf if f > 0.0 else 0.0     # d = 0 and f bound = 0: a constant


def make_first_event(event_at):
    """
    Return ``first_event(lo, hi, tol, code, info, args)``: bisect to the first event.

    No event at lo; the event (``code``, ``info``) at hi. ``event_at(tau, args)`` returns the
    event at tau as (code, info), code 0 for none. Returns (hi, code, info) of the first
    event once hi - lo <= tol.
    """

    @njit(cache=False, inline=True)
    def first_event(lo, hi, tol, code, info, args):
        while hi - lo > tol:
            mid = 0.5 * (lo + hi)
            c, i = event_at(mid, args)
            if c != NO_EVENT:
                hi = mid
                code = c
                info = i
            else:
                lo = mid
        return hi, code, info

    return first_event


def make_crossing(value_at):
    """
    Return ``crossing(a, b, fa, fb, tol, max_iter, args)``: where ``value_at`` turns <= 0.

    ``value_at(tau, args)`` is fa > 0 at a and fb <= 0 at b. Returns a time within ``tol``
    after the crossing (the bracket's right end), by Illinois regula falsi: the end that
    stays is halved in weight, so the bracket shrinks from both sides.
    """

    @njit(cache=False, inline=True)
    def crossing(a, b, fa, fb, tol, max_iter, args):
        side = 0
        for _ in range(max_iter):
            if b - a <= tol:
                return b
            m = b - fb * (b - a) / (fb - fa)
            if not (a < m < b):
                m = 0.5 * (a + b)
            fm = value_at(m, args)
            if fm > 0.0:
                a = m
                fa = fm
                if side == -1:
                    fb *= 0.5
                side = -1
            else:
                b = m
                fb = fm
                if side == 1:
                    fa *= 0.5
                side = 1
            if fm == 0.0 or (side == 1 and b - a > 0.0 and abs(fm) < 1e-300):
                return b
        return b

    return crossing
