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

"""Effect impact_restitution: restitution e and finite friction mu at impacts.

Physics: at an impact of vertex r (from the CM) with the arm (normal +y), let K be the 2x2
matrix mapping an impulse per unit mass to the change of the contact point's velocity u, and
P_I = -K^-1 u the impulse that stops the point (plastic sticking, eqs 7-9). The
Chatterjee-Ruina algebraic law applies P = ((1 + e) P_I,n, P_I,t) (normal restitution e,
tangential restitution 0) and, if that leaves the friction cone |P_t| <= mu P_n, clips P_t to
the cone. Kinetic energy never increases (tested over random impacts). A rebound slower than
contact.bounce_threshold (m/s) is plastic: a further normal impulse removes it, which only
dissipates. After a plastic impact the vertex rolls (sticking) or slides with Coulomb friction;
a flat landing of an edge is a two-point plastic impact with its tangential impulse clipped to
mu times the normal one.

contact.pivot: 'hinge' (default) keeps a vertex that stopped on the foam on the arm while
the part turns about it, as the paper's rolling model does; 'unilateral' lets it lift off when
the normal force would turn negative (the part then flies again).

Limit: e = 0 with mu = inf (or large enough that no impulse reaches the cone) is the sticking
model; the throw map then equals the base model's (tested). mu is contact.mu, the same
coefficient the grasp bounds (2) and (4) use; without it the arm's friction is unbounded.

Scene: contact: {restitution: 0.3, mu: 0.8, bounce_threshold: 0.01, pivot: hinge};
effects: [impact_restitution].
"""

from dataclasses import dataclass
import math

from ..errors import InputError
from ._common import number

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
