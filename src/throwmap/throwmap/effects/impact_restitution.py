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
  sliding. A bounce that would not come back by itself (a roll about the vertex needs a pull)
  is held by the hinge: plastic, so e -> 0 tends to the e = 0 hinge model (event_sim).
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

from ._common import number, routh_stronge_impact
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
def impact(rx, ry, vx, vy, om, rho2, prm):
    """Apply the impact law; the part bounces when it rebounds faster than the threshold (hook)."""
    vx1, vy1, om1 = routh_stronge_impact(rx, ry, vx, vy, om, rho2, prm.e, prm.mu)
    bounces = prm.e > 0.0 and vy1 + om1 * rx > prm.bounce_threshold
    return vx1, vy1, om1, bounces
