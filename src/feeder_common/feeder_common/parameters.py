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
The one parameter gate of a feeder node: declare, coerce, validate on set, apply after set.

Every node declares its table of :class:`feeder_common.params.ParamSpec` through a
:class:`ParameterGate`. It

* builds each descriptor (type, range, read-only, description, constraints);
* takes the value given at start-up (``-p``, ``--params-file``, a launch file) and coerces it:
  an integer for a double becomes that double (ROS users write ``1`` for ``1.0``), any other
  type mismatch or a bad value raises :class:`ParameterError` with one line naming it (the run
  helper prints it and exits with status 2);
* coerces run-time sets the same way (a pre-set callback: ``ros2 param set node x 1`` on a
  double), validates them in an on-set callback that only validates (types, ranges, then the
  node's own ``validate(changes, current)`` for rules across parameters or against the
  scene), and applies accepted ones in a post-set callback (``apply(changes)``).
"""

import math

from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                ParameterType, SetParametersResult)
from rclpy.exceptions import InvalidParameterValueException
from rclpy.parameter import Parameter

from .params import by_name, RENAMED

_TYPES = {'bool': ParameterType.PARAMETER_BOOL, 'integer': ParameterType.PARAMETER_INTEGER,
          'double': ParameterType.PARAMETER_DOUBLE, 'string': ParameterType.PARAMETER_STRING}
# Declared by rclpy itself on every node.
_RCLPY_PARAMETERS = {'use_sim_time', 'start_type_description_service'}


class ParameterError(Exception):
    """A start-up parameter is invalid; the text names it and the fix (one line)."""


def descriptor(spec):
    """Build the ParameterDescriptor of a ParamSpec (rclpy enforces its type and range)."""
    constraints = spec.constraints
    if spec.choices:
        constraints = (constraints + '; ' if constraints else '') + 'one of ' + \
            ', '.join(str(c) for c in spec.choices)
    if spec.max_length is not None:
        constraints = (constraints + '; ' if constraints else '') + \
            f'at most {spec.max_length} characters'
    desc = ParameterDescriptor(name=spec.name, type=_TYPES[spec.kind],
                               description=spec.description, read_only=spec.read_only,
                               additional_constraints=constraints)
    if spec.kind == 'integer':
        lo = int(spec.minimum) if spec.minimum is not None else -(2 ** 63)
        hi = int(spec.maximum) if spec.maximum is not None else 2 ** 63 - 1
        desc.integer_range = [IntegerRange(from_value=lo, to_value=hi, step=0)]
    elif spec.kind == 'double':
        lo = float(spec.minimum) if spec.minimum is not None else -math.inf
        hi = float(spec.maximum) if spec.maximum is not None else math.inf
        desc.floating_point_range = [FloatingPointRange(from_value=lo, to_value=hi, step=0.0)]
    return desc


class ParameterGate:
    """
    Declare a node's parameters from its spec table and gate every later change.

    ``validate(changes, current)`` returns the reason to reject ``changes`` (name -> new value,
    already of the right type and in range) given ``current`` (name -> value of every declared
    parameter), or None; it must not change the node. ``apply(changes)`` runs after an
    accepted set (not during declaration). :attr:`values` always holds the current values.
    """

    def __init__(self, node, specs, validate=None, apply=None):
        self._node = node
        self.specs = by_name(specs)
        self.values = {}
        self._validate = validate
        self._apply = apply
        self._declaring = False
        self._last_reason = None
        node.add_pre_set_parameters_callback(self._pre_set)
        node.add_on_set_parameters_callback(self._on_set)
        node.add_post_set_parameters_callback(self._post_set)

    def given(self, name):
        """Return the value given at start-up for ``name`` (command line, file, launch) or None."""
        # rclpy keeps the node's start-up values here and declare_parameter reads them from it;
        # they are read before declaring so that an integer for a double can be coerced.
        overrides = getattr(self._node, '_parameter_overrides', {})
        override = overrides.get(name)
        if override is None:
            # An old name (feeder_common.params.RENAMED) still sets its one name, with a word.
            old = next((o for o, n in RENAMED.items() if n == name and o in overrides), None)
            if old is not None:
                override = overrides[old]
                self._node.get_logger().warning(
                    f'parameter {old} is now called {name} (one name in every node); '
                    f'took {old}:={override.value}, give {name} instead')
        return None if override is None else override.value

    def declare(self, name, default=None):
        """
        Declare ``name`` with its start-up value (or ``default``, else the table's default).

        Returns the value. Raises ParameterError with one line if the value is unusable.
        """
        spec = self.specs[name]
        value = self.given(name)
        if value is None:
            value = spec.default if default is None else default
        value, reason = spec.validate(value)
        if reason:
            raise ParameterError(reason)
        self._declaring = True
        self._last_reason = None
        try:
            self._node.declare_parameter(name, value, descriptor(spec), ignore_override=True)
        except InvalidParameterValueException as exc:
            raise ParameterError(self._last_reason or str(exc)) from None
        finally:
            self._declaring = False
        self.values[name] = value
        return value

    def declare_all(self, defaults=None, names=None):
        """Declare ``names`` (default: the whole table, in order); returns :attr:`values`."""
        defaults = defaults or {}
        for name in names or self.specs:
            if name not in self.values:
                self.declare(name, defaults.get(name))
        return self.values

    def check_startup(self):
        """Run ``validate`` over every declared value at once (rules across parameters)."""
        if self._validate is not None:
            reason = self._validate(dict(self.values), dict(self.values))
            if reason:
                raise ParameterError(reason)

    def unknown_given(self):
        """Names given at start-up that this node does not declare (typos, other nodes')."""
        given = getattr(self._node, '_parameter_overrides', {})
        return sorted(n for n in given if n not in self.specs and n not in _RCLPY_PARAMETERS
                      and not n.startswith('qos_overrides.')
                      and RENAMED.get(n) not in self.specs)

    # ---- callbacks -----------------------------------------------------------------------

    def _pre_set(self, parameters):
        out = []
        for p in parameters:
            spec = self.specs.get(p.name)
            if spec is not None and spec.kind == 'double' and \
                    p.type_ == Parameter.Type.INTEGER:
                p = Parameter(p.name, Parameter.Type.DOUBLE, float(p.value))
            out.append(p)
        return out

    def _on_set(self, parameters):
        changes = {p.name: p.value for p in parameters if p.name in self.specs}
        reason = None
        for name, value in changes.items():
            value, reason = self.specs[name].validate(value)
            if reason:
                break
        if reason is None and self._validate is not None and changes:
            current = dict(self.values)
            reason = self._validate(changes, current)
        self._last_reason = reason
        return SetParametersResult(successful=reason is None, reason=reason or '')

    def _post_set(self, parameters):
        changes = {p.name: p.value for p in parameters if p.name in self.specs}
        self.values.update(changes)
        if self._apply is not None and changes and not self._declaring:
            self._apply(changes)
