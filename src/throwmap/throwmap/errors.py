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

"""The library's documented errors; everything it raises on purpose derives from ThrowmapError."""


class ThrowmapError(ValueError):
    """Base class of every error the library raises on purpose."""


class InputError(ThrowmapError):
    """A bad part, parameter or scene value; the message names the field and the fix."""

    def __init__(self, field, problem, fix):
        self.field = field
        self.problem = problem
        self.fix = fix
        super().__init__(f'{field}: {problem}; {fix}')


class DomainError(ThrowmapError):
    """
    The throw map f(i, R) is not defined at this state (paper section III.C).

    ``condition`` names the failed condition (``stable_edge``, ``grasp_bound_1`` ..
    ``grasp_bound_4``, ``toe_stub``, ``edge_index``), ``margin`` says by how much it fails
    (metres for radius bounds, nan when it is not a distance).
    """

    def __init__(self, condition, message, margin=float('nan')):
        self.condition = condition
        self.margin = margin
        super().__init__(message)


class NumericalError(ThrowmapError):
    """A computation did not finish within its documented iteration cap."""


class PartLost(ThrowmapError):
    """
    The part left the arm (effect finite_arm): an outcome that ends an orbit, not a failure.

    ``after``: throws done before the one that lost it, when an orbit lost it.
    """

    def __init__(self, message, after=None):
        self.after = after
        super().__init__(message)
