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
``contact.bounce_threshold`` (m/s) is plastic: a further normal impulse removes it, which only
dissipates. A flat landing of an edge is a two-point plastic impact whose tangential impulse
is clipped to mu times the normal one; the part then slides flat with Coulomb friction mu until
it stops (or tips, when one corner's share of the load turns negative).

``contact.pivot`` says what a vertex does after a plastic impact:
* 'hinge' (default, the paper's rolling model): the foam grips it; the part turns about it
  without slipping or lifting off (a vertex still slipping after the clipped impact is caught
  by a further sticking impulse, which only dissipates). mu then acts in impacts and in flat
  sliding.
* 'unilateral': full Coulomb contact: the vertex slides when the friction force needed to hold
  it exceeds mu N, and lifts off (the part flies again) when N would turn negative.

Limit: e = 0 with mu = inf (or large enough that no impulse reaches the cone) is the sticking
model; the throw map then equals the base model's (tested). mu is contact.mu, the same
coefficient the grasp bounds (2) and (4) use; without it the arm's friction is unbounded.

Scene: contact: {restitution: 0.3, mu: 0.8, bounce_threshold: 0.01, pivot: hinge};
effects: [impact_restitution].
"""

from dataclasses import dataclass
import math

from ._common import number
from ..errors import InputError

NAME = 'impact_restitution'
PIVOTS = ('hinge', 'unilateral')


@dataclass(frozen=True)
class ImpactRestitution:
    restitution: float
    mu: float               # inf when the scene gives no contact.mu
    bounce_threshold: float
    unilateral: bool


def parse(contact):
    contact = contact or {}
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
    mu = contact.get('mu')
    return ImpactRestitution(e, math.inf if mu is None else float(mu), vb,
                             pivot == 'unilateral')
