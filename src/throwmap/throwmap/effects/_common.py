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
Helpers shared by the effect modules.

The scene's values, number parsing with clear errors, the frictional impact law (Routh with
Stronge's restitution) that impact_restitution and liftoff both use, and the holding zone of a
torque that resists a roll (backplate_friction's static hold).
"""

from dataclasses import dataclass
import math
from typing import Optional

from ..errors import InputError
from ..jit import njit


@dataclass(frozen=True)
class SceneValues:
    """
    What an effect's ``parse`` reads: the raw scene mapping and the values the scene parsed.

    data: the scene's mapping as loaded; plate: the parsed plate section (g0, inclination_deg,
    g_normal = g0 cos(inclination), mu) or None; mu: contact.mu or None; arm_length: arm.length
    in m or None.
    """

    data: dict
    plate: Optional[dict] = None
    mu: Optional[float] = None
    arm_length: Optional[float] = None

    def section(self, name):
        """Return the scene's section ``name`` (an empty mapping when absent)."""
        value = self.data.get(name)
        return value if isinstance(value, dict) else {}


def number(data, key, where, what, lo=None, hi=None, lo_open=False, default=None,
           scale_keys=None):
    """
    Return a finite number from ``data`` in SI, from ``key`` or one of its unit spellings.

    scale_keys: [(spelled_key, factor), ...]; the first present wins and two present is an
    error. Bounds are checked on the SI value; the error names the key as written.
    """
    spellings = scale_keys or [(key, 1.0)]
    present = [(k, f) for k, f in spellings if k in data]
    if len(present) > 1:
        raise InputError(f'{where}.{present[0][0]}',
                         f'given twice ({" and ".join(k for k, _ in present)})',
                         'give only one of them')
    if not present:
        if default is None:
            return None
        return default
    spelled, factor = present[0]
    value = data[spelled]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f'{where}.{spelled}', f'must be a number, got {value!r}', f'give {what}')
    if not math.isfinite(value):
        raise InputError(f'{where}.{spelled}', f'must be finite, got {value!r}', f'give {what}')
    si = float(value) * factor
    if lo is not None and (si < lo or (lo_open and si == lo)):
        raise InputError(f'{where}.{spelled}', f'must be {">" if lo_open else ">="} '
                         f'{lo / factor:g}, got {value!r}', f'give {what}')
    if hi is not None and si > hi:
        raise InputError(f'{where}.{spelled}', f'must be <= {hi / factor:g}, got {value!r}',
                         f'give {what}')
    return si


def check_keys(data, allowed, where):
    if not isinstance(data, dict):
        raise InputError(where, f'must be a mapping, got {type(data).__name__}',
                         'write it as key: value pairs')
    for key in data:
        if key not in allowed:
            raise InputError(f'{where}.{key}', 'unknown key',
                             f'allowed here: {", ".join(sorted(allowed))}')


@njit
def routh_stronge_impact(rx, ry, vx, vy, om, rho2, e, mu):
    """
    Frictional impact at a contact point r = (rx, ry) from the CM on the arm (normal +y).

    Routh's method with Stronge's energetic restitution (effect impact_restitution's
    docstring; effect liftoff uses it at e = 0). mu = inf is the
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
def hold_turn(phi, om, bu_p, bv_p, reach):
    """
    Return (held, turn) for a part at rest on pivot p that a resisting torque holds.

    Held while the CM lies within ``reach`` of the pivot's vertical (there the resistance
    outweighs gravity's torque). ``turn``: the rotation about p that brings the CM just past
    the holding zone on the side it leans to (on om's side when straight above), where the
    feeder's vibration lets it fall from rest.
    """
    c = math.cos(phi)
    s = math.sin(phi)
    cx = -(c * bu_p - s * bv_p)
    cy = -(s * bu_p + c * bv_p)
    if abs(cx) > reach:
        return False, 0.0
    lc = math.sqrt(cx * cx + cy * cy)
    side = cx if cx != 0.0 else -om
    target = math.copysign(min(1.01 * reach, lc), side)
    alpha = math.atan2(cy, cx)
    alpha_new = math.acos(target / lc)
    return True, alpha_new - alpha
