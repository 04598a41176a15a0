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
Effect impact_restitution: restitution e and finite friction mu at impacts.

Physics: at an impact of vertex r (from the CM) with the arm (normal +y), K is the 2x2 matrix
mapping an impulse per unit mass to the change of the contact point's velocity u. The impact is
followed in terms of the normal impulse p (Routh's method): while the point slips, the
tangential impulse grows as -mu sign(u_t) dp; while it is stuck, by whatever keeps u_t = 0 if
that lies inside the friction cone, else slip starts. Compression ends when u_n = 0;
restitution goes on until the normal impulse has given back e^2 of the work it absorbed in
compression (Stronge's energetic coefficient). Friction work is never positive and the net
normal work is (1 - e^2) times the compression work, so kinetic energy never increases (tested
over random impacts). The Chatterjee-Ruina algebraic law was the first candidate; with the
clip to the friction cone it created energy in about 6 % of random impacts of these parts
(strong coupling of normal and tangential motion), so it was not used. A rebound slower than
``contact.bounce_threshold`` (m/s) is plastic: the event simulator removes it with a further
normal impulse, which only dissipates. A flat landing of an edge is a two-point plastic impact
whose tangential impulse is clipped to mu times the normal one; the part then slides flat with
Coulomb friction mu until it stops (or tips, when one corner's share of the load turns
negative).

``contact.pivot`` says what a vertex does after a plastic impact:
* 'hinge' (default, the paper's rolling model): the foam grips it; the part turns about it
  without slipping or lifting off (a vertex still slipping after the clipped impact is caught
  by a further sticking impulse, which only dissipates). mu then acts in impacts and in flat
  sliding.
* 'unilateral': full Coulomb contact: the vertex slides when the friction force needed to hold
  it exceeds mu N, and lifts off (the part flies again) when N would turn negative.

Hooks: ``impact`` (the law above, and whether the part bounces off) and the contact law (mu,
the pivot model, and whether the law is the sticking one, for the event simulator's settling
rule). Limit: e = 0 with mu = inf is the sticking model wherever eqs 7-9 give a normal impulse
>= 0; where they would need a pulling one, a contact cannot pull and Routh's limit (tested
against brute-force Routh with mu = 1e3) differs from them. On the throws of the shipped parts
the throw map then equals the base model's (tested). mu is contact.mu, the same
coefficient the grasp bounds (2) and (4) use; without it the arm's friction is unbounded.

Scene: contact: {restitution: 0.3, mu: 0.8, bounce_threshold: 0.01, pivot: hinge};
effects: [impact_restitution].
"""

from collections import namedtuple
from dataclasses import dataclass
import math

from ._common import number
from ..errors import InputError
from ..event_sim import ContactLaw
from ..jit import njit

NAME = 'impact_restitution'
SCHEMA = {'contact': ('restitution', 'bounce_threshold', 'pivot')}
KNOBS = {}
PIVOTS = ('hinge', 'unilateral')

RestitutionParams = namedtuple('RestitutionParams', ['e', 'mu', 'bounce_threshold'])


@dataclass(frozen=True)
class ImpactRestitution:
    """Parameters: restitution e, the arm's friction mu, the bounce threshold, the pivot."""

    restitution: float
    mu: float               # inf when the scene gives no contact.mu
    bounce_threshold: float
    unilateral: bool


def parse(scene):
    """From the scene's contact section."""
    contact = scene.section('contact')
    if 'restitution' not in contact:
        raise InputError('contact.restitution', 'missing (effect impact_restitution needs it)',
                         'give the coefficient of restitution e in [0, 1], e.g. 0.3')
    e = number(contact, 'restitution', 'contact', 'e in [0, 1]', lo=0.0, hi=1.0)
    vb = number(contact, 'bounce_threshold', 'contact', 'a speed in m/s, e.g. 0.01', lo=0.0,
                default=0.01)
    pivot = contact.get('pivot', 'hinge')
    if pivot not in PIVOTS:
        raise InputError('contact.pivot', f'unknown pivot model {pivot!r}',
                         f'use one of {", ".join(PIVOTS)}')
    mu = scene.mu
    return ImpactRestitution(e, math.inf if mu is None else float(mu), vb,
                             pivot == 'unilateral')


def slots(params):
    """Fill impact: the impact law."""
    return ('impact',)


def bundle(params, part, knobs):
    """Return the compiled parameters of the impact law."""
    return RestitutionParams(float(params.restitution), float(params.mu),
                             float(params.bounce_threshold))


def contact_law(params):
    """Friction and pivot model of the contact phases; sticking when e = 0 and mu = inf."""
    return ContactLaw(float(params.mu), bool(params.unilateral),
                      params.restitution == 0.0 and math.isinf(params.mu))


@njit
def routh_stronge_impact(rx, ry, vx, vy, om, rho2, e, mu):
    """
    Frictional impact at a contact point r = (rx, ry) from the CM on the arm (normal +y).

    Routh's method with Stronge's energetic restitution (module docstring). mu = inf is the
    limit mu -> inf: slip stops at zero normal impulse unless the approach stops first (then
    the contact leaves at u_n = e |u_n0|, or at the u_n where the slip stops if lower); with
    e = 0 the result is the sticking impact of eqs 7-9 wherever that impulse pushes (>= 0).
    Returns (vx, vy, om).
    """
    ut = vx - om * ry
    un = vy + om * rx
    if un >= 0.0:
        return vx, vy, om    # separating or resting: no impact
    inv = 1.0 / rho2
    ktt = 1.0 + ry * ry * inv
    knn = 1.0 + rx * rx * inv
    ktn = -rx * ry * inv
    pt = 0.0
    pn = 0.0
    eps = 1e-13 * (abs(ut) + abs(un))
    if math.isinf(mu) and ut != 0.0:
        # Unbounded friction (Routh as mu -> inf): a tangential impulse at zero normal impulse
        # until the slip stops, u_n = u_n0 + ktn p_t on the way. If the approach stops first,
        # compression and restitution both happen within this slip: their works are
        # int u_n dp_t / mu, in the same ratio for every large mu, so Stronge's restitution
        # (e^2 of the compression work given back, u_n linear in p_t) ends at u_n = e |u_n0|,
        # or where the slip stops if that comes first. (Stopping at u_n = 0 was the e = 0
        # answer for every e: not the limit of large mu.)
        d_pt = -ut / ktt
        un_stop = un + ktn * d_pt
        if un_stop >= 0.0:
            d_pt = (min(-e * un, un_stop) - un) / ktn
            return vx + d_pt, vy, om - ry * d_pt * inv
        pt += d_pt
        ut = 0.0
        un += ktn * d_pt
    work = 0.0
    compressing = True
    target = 0.0
    for _ in range(16):
        if abs(ut) > eps:
            sigma = 1.0 if ut > 0.0 else -1.0
            rate_t = -mu * sigma
            stuck = False
        else:
            ut = 0.0
            lam = -ktn / ktt
            if abs(lam) <= mu:
                rate_t = lam
                stuck = True
            else:
                rate_t = mu if lam > 0.0 else -mu
                stuck = False
        dut = ktt * rate_t + ktn
        dun = ktn * rate_t + knn
        step = math.inf
        ends_slip = False
        if not stuck and ut != 0.0 and dut * ut < 0.0:
            step = -ut / dut
            ends_slip = True
        if compressing:
            if dun > 0.0:
                s_c = -un / dun
                if s_c <= step:
                    step = s_c
                    ends_slip = False
            elif not ends_slip:
                # No normal impulse stops the approach and the slip never ends: cannot happen
                # for a rigid lamina (a jam's slip dies out, below), kept as a guard: stick.
                det = ktt * knn - ktn * ktn
                pt -= (knn * ut - ktn * un) / det
                pn -= (-ktn * ut + ktt * un) / det
                return vx + pt, vy + pn, om + (rx * pn - ry * pt) * inv
            # Else a jam (Painleve): while slipping the approach speeds up, but the slip dies
            # out first; the contact then sticks (|ktn| / ktt < knn / |ktn| <= mu) and
            # compression ends with the point at rest; restitution follows as always.
        else:
            # W(p + s) = work + un s + dun s^2 / 2 reaches the target
            rem = target - work
            if dun > 0.0:
                s_r = (-un + math.sqrt(un * un + 2.0 * dun * rem)) / dun
            else:
                s_r = rem / un if un > 0.0 else 0.0
            if s_r <= step:
                step = s_r
                ends_slip = False
        work += un * step + 0.5 * dun * step * step
        pn += step
        pt += rate_t * step
        ut = 0.0 if ends_slip else ut + dut * step
        un = un + dun * step
        if ends_slip:
            continue
        if compressing:
            compressing = False
            un = 0.0
            target = work * (1.0 - e * e)
            if e == 0.0:
                break
        elif not ends_slip:
            break
    return vx + pt, vy + pn, om + (rx * pn - ry * pt) * inv


@njit
def impact(rx, ry, vx, vy, om, rho2, prm):
    """Apply the impact law; the part bounces when it rebounds faster than the threshold (hook)."""
    vx1, vy1, om1 = routh_stronge_impact(rx, ry, vx, vy, om, rho2, prm.e, prm.mu)
    bounces = prm.e > 0.0 and vy1 + om1 * rx > prm.bounce_threshold
    return vx1, vy1, om1, bounces
