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
Effect backplate_friction: Coulomb drag of the part on the inclined back plate.

Physics (paper section V.B): the back plate is inclined at angle beta from horizontal, so the
in-plane gravity is g = -g0 sin(beta) and the part presses on the plate with m g0 cos(beta),
spread as a uniform pressure over its area. Every area element dA slides on the plate at its own
velocity v(r) = v_cm + omega z x r and feels the Coulomb force -mu_p (m g0 cos(beta) / A)
v / |v| dA. Per unit mass, the drag force is -mu_p g_n <v/|v|> and its torque about the CM is
-mu_p g_n <r x v/|v|>, with g_n = g0 cos(beta) and <.> the area average, evaluated by
quadrature (accuracy.plate_quadrature). |v| -> 0 is regularised as
v / sqrt(|v|^2 + v_reg^2) (accuracy.plate_v_reg, default 1e-4 m/s). While rolling about a
fixed vertex P, v(r) = omega z x (r - P), so the drag is the torque -sign(omega) mu_p g_n
<|r - P|> about P (plus a force, which the pivot takes). For the experiment (beta = 80 deg,
mu_p = 0.1) the drag is 0.1 cot(80 deg) = 1.8 % of the in-plane gravity.

Flight is then no longer ballistic: the general simulator (throwmap.general) integrates it.
mu_p = 0 gives the base model's flight and rolling exactly (tested).

Scene: plate: {inclination_deg: 80, g0: 9.81, mu: 0.1}; effects: [backplate_friction].
"""

from dataclasses import dataclass

from ..errors import InputError

NAME = 'backplate_friction'


@dataclass(frozen=True)
class BackplateFriction:
    mu: float           # Coulomb coefficient of part on plate
    g_normal: float     # g0 cos(beta), m/s^2: the plate's pressure per unit mass

    @property
    def drag(self):
        """mu_p g_n: the largest drag per unit mass (m/s^2)."""
        return self.mu * self.g_normal


def parse(plate):
    """From the scene's plate section (already validated: g0, inclination)."""
    if plate is None:
        raise InputError('effects.backplate_friction', 'needs the back plate',
                         'give plate: {inclination_deg: 80, g0: 9.81, mu: 0.1} instead of '
                         'gravity')
    if plate.get('mu') is None:
        raise InputError('plate.mu', 'missing (effect backplate_friction needs it)',
                         'give the part/plate Coulomb coefficient, e.g. mu: 0.1')
    return BackplateFriction(plate['mu'], plate['g_normal'])
