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
The internal API: compiled pieces that tests check one by one against physics.

Not for applications (they use the public API in ``throwmap``); listed here so that a test
names what it reaches into, and a refactor sees it.

* :func:`sticking_impact` (throwmap.catch): eqs 7-9.
* :func:`routh_stronge_impact` (effect impact_restitution): the frictional impact law.
* :func:`plate_drag` (effect backplate_friction): the plate's drag at one state, with the
  quadrature of ``Part.area_quadrature``; :func:`plate_drag_exact`: the same in closed form;
  :func:`crossing_log_coefficient`: its ln|d| part where the instantaneous centre crosses an edge.
* :func:`carry_release_state`, :func:`carry_margin`, :func:`carry_holds`,
  :func:`carry_interval` (effect finite_carry): the state at release, the wrench-cone margin
  along the carry, the release hook's grasp test (tables instead of trigonometry) and the
  radii that keep the grasp.
* :func:`composed_source` (throwmap.compose): the text of the module an effect set compiles.
"""

from .catch import sticking_impact
from .compose import source as composed_source
from .effects.backplate_friction import (crossing_log_coefficient, plate_drag, plate_drag_exact,
                                         plate_moments)
from .effects.finite_carry import (carry_holds, carry_interval, carry_margin,
                                   release_state as carry_release_state)
from .effects.impact_restitution import routh_stronge_impact

__all__ = ['carry_holds', 'carry_interval', 'carry_margin', 'carry_release_state',
           'composed_source', 'crossing_log_coefficient', 'plate_drag', 'plate_drag_exact',
           'plate_moments', 'routh_stronge_impact', 'sticking_impact']
