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
Slow, independent reference simulator of one throw and catch (Lynch, Northrop, Pan).

Written from sections II and III of the paper only; nothing is taken from throwmap's kernel or
model, so that the two can check each other.

Method:
* Part frames (section II): edge E^i runs from V^i to V^{i+1} of the counterclockwise hull;
  resting on E^i the edge lies on the arm line y = h with V^i on the left and the centre of
  mass (CM) above it. The body pose is (CM position, angle phi) with world = CM + Rot(phi) b
  for a body vector b (vertex minus CM in the input frame).
* Flight (eqs 5-6, closed form): the heights over the arm of all vertices are sampled on a
  fixed grid (dt = t_upper / FLIGHT_SAMPLES, t_upper a proven upper bound of the flight time;
  smaller for long flights so that the part turns at most MAX_STEP_ANGLE per step; a second
  pass over [0, 1.001 T] when the contact at T comes early, so dt <= T / FLIGHT_SAMPLES);
  the first sign change + -> - of any vertex is refined by bisection. Between samples a vertex
  could dip below the arm and come back (a graze); every sampled local minimum lower than the
  largest such dip (|F''|max dt^2) is refined by bounded minimisation, and a negative minimum
  counts as a contact too.
* Impacts are sticking (eqs 7-9), solved as a 3x3 linear system: the contact vertex stops and
  the impulse passes through it (so angular momentum about it is conserved).
* Rolling about the contact vertex V^p is integrated numerically (scipy solve_ivp, DOP853,
  rtol 1e-12) with the pendulum equation (rho^2 + l_p^2) phi'' = g (x_CM - x_pivot). On a
  convex polygon only the neighbours V^{p+1} and V^{p-1} can reach the arm, exactly when the
  body angle reaches the pose with E^p, respectively E^{p-1}, flat: these two angles are
  terminal events, and so are turning points (phi' = 0), so that a part that only just reaches
  an edge is not stepped past (see _roll). Each new contact is again a sticking impact.
* Conventions shared with throwmap (its documented model choices, not physics of the paper):
  an edge within FLAT_TOL rad of the arm when the flight ends lands flat and the part stops on
  it; while rolling, if the post-impact rotation about the new contact would turn the part back
  into the arm, the part stops flat on the edge that just landed. A part stopped on an unstable
  edge tips over, from rest, about the vertex its CM lies beyond. The part has settled when it
  lies flat on a stable edge and its kinetic energy is below both tip-over barriers
  g_abs (l_k - d_j) of that edge's vertices (energy never increases, so it cannot leave).

Energies are per unit mass, J/kg, with the potential measured from the arm surface.
"""

from dataclasses import dataclass, field
import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

FLIGHT_SAMPLES = 40000     # fixed time steps over the flight-time bound (at least)
MAX_STEP_ANGLE = 0.002     # rad: long flights get more steps, so the part turns less per step
MAX_FLIGHT_SAMPLES = 4000000
FLAT_TOL = 1e-9            # rad: an edge this close to the arm at the end of flight lands flat
ROLL_RTOL = 1e-12
ROLL_ATOL_REL = 1e-14      # times the part size (angle) / natural rate (angular velocity)
MAX_IMPACTS = 20000
TWO_PI = 2.0 * math.pi


def polygon_mass_properties(vertices):
    """(area, centroid, rho^2) of a uniform lamina bounded by a CCW polygon (shoelace sums)."""
    p = np.asarray(vertices, dtype=float)
    q = np.roll(p, -1, axis=0)
    cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    area = 0.5 * cross.sum()
    cx = ((p[:, 0] + q[:, 0]) * cross).sum() / (6.0 * area)
    cy = ((p[:, 1] + q[:, 1]) * cross).sum() / (6.0 * area)
    # Second moments about the origin, then the parallel-axis theorem.
    ixx = ((p[:, 1] ** 2 + p[:, 1] * q[:, 1] + q[:, 1] ** 2) * cross).sum() / 12.0
    iyy = ((p[:, 0] ** 2 + p[:, 0] * q[:, 0] + q[:, 0] ** 2) * cross).sum() / 12.0
    polar = ixx + iyy - area * (cx * cx + cy * cy)
    return float(area), np.array([cx, cy]), float(polar / area)


def _rot(phi, b):
    """Rotate the body vector b = (bx, by) by phi (counterclockwise)."""
    c, s = math.cos(phi), math.sin(phi)
    return c * b[0] - s * b[1], s * b[0] + c * b[1]


def _wrap(a):
    """Angle in (-pi, pi]."""
    a = math.fmod(a, TWO_PI)
    if a <= -math.pi:
        a += TWO_PI
    elif a > math.pi:
        a -= TWO_PI
    return a


def sticking_impact(r, vel, omega, rho2):
    """
    Post-impact (xdot, ydot, phidot) of eqs 7-9 for a vertex at r (from the CM) that sticks.

    Unknowns (x+, y+, w+):  x+ - r_y w+ = 0;  y+ + r_x w+ = 0;
    r_x (y+ - y-) - r_y (x+ - x-) - rho^2 (w+ - w-) = 0.
    """
    rx, ry = r
    a = np.array([[1.0, 0.0, -ry],
                  [0.0, 1.0, rx],
                  [-ry, rx, -rho2]])
    b = np.array([0.0, 0.0, rx * vel[1] - ry * vel[0] - rho2 * omega])
    return np.linalg.solve(a, b)


@dataclass
class RefImpact:
    """One event of the reference catch (energies per unit mass over the arm)."""

    kind: str           # 'flight' | 'landing' | 'flat_landing' | 'tip_from_rest'
    vertex: int         # vertex that hits the arm (the pivot for tip_from_rest)
    edge: int           # edge that ends up on the arm (-1 for a corner-first flight impact)
    x: float            # arm coordinate of that vertex, m
    omega_before: float
    omega_after: float
    energy_before: float
    energy_after: float


@dataclass
class RefResult:
    """Outcome of one reference throw from (edge0, R0)."""

    edge0: int
    R0: float
    edge: int
    R: float
    kind: str                   # 'jog' | 'flip'
    flight_time: float
    net_rotation: float
    first_contact_vertex: int
    impacts: list = field(default_factory=list)
    release_energy: float = 0.0
    flight_energy_drift: float = 0.0    # |E(contact) - E(release)| / energy scale
    roll_energy_drift: float = 0.0      # max over rolling segments, relative to energy scale
    roll_segments: int = 0
    contact_speed: float = 0.0          # m/s, downward speed of the contact vertex at impact


class ReferencePart:
    """Frames F^i and mass data of a convex part, computed from the paper's definitions."""

    def __init__(self, vertices, cm, rho2):
        self.v = np.asarray(vertices, dtype=float)
        self.cm = np.asarray(cm, dtype=float)
        self.rho2 = float(rho2)
        n = len(self.v)
        self.n = n
        self.b = self.v - self.cm                    # body vectors of the vertices
        self.dist = np.hypot(self.b[:, 0], self.b[:, 1])
        self.size = float(self.dist.max())
        self.theta = np.empty(n)                     # body angle that lays E^i flat on the arm
        self.d = np.empty(n)
        self.u_l = np.empty(n)
        self.u_r = np.empty(n)
        self.length = np.empty(n)
        for i in range(n):
            e = self.v[(i + 1) % n] - self.v[i]
            self.length[i] = math.hypot(e[0], e[1])
            self.theta[i] = -math.atan2(e[1], e[0])
            # In the resting pose F^i: u along the edge, v up. Resting CM height d = -v(V^i).
            ul, vl = _rot(self.theta[i], self.b[i])
            ur, vr = _rot(self.theta[i], self.b[(i + 1) % n])
            self.u_l[i], self.u_r[i] = ul, ur
            self.d[i] = -0.5 * (vl + vr)
        if np.any(self.d <= 0.0):
            raise ValueError('the CM must lie strictly inside the convex polygon')
        self.stable = (self.u_l < 0.0) & (self.u_r > 0.0)

    def uv(self, i):
        """(u, v) of every vertex in F^i (eq 6's coordinates)."""
        c, s = math.cos(self.theta[i]), math.sin(self.theta[i])
        return c * self.b[:, 0] - s * self.b[:, 1], s * self.b[:, 0] + c * self.b[:, 1]


class ReferenceSimulator:
    """f(i, R) by dense time stepping of the flight and numerical integration of rolling."""

    def __init__(self, vertices, cm, rho2, h, w, g, flight_samples=FLIGHT_SAMPLES,
                 flat_tol=FLAT_TOL, rtol=ROLL_RTOL):
        if not g < 0 or not w > 0:
            raise ValueError('need g < 0 and w > 0')
        self.part = ReferencePart(vertices, cm, rho2)
        self.h = float(h)
        self.w = float(w)
        self.g = float(g)
        self.g_abs = -self.g
        self.samples = int(flight_samples)
        self.flat_tol = float(flat_tol)
        self.rtol = float(rtol)
        self.last_contact_from_graze = False

    # ------------------------------------------------------------------ flight (eqs 5-6)
    def _vertex_in_frame(self, i, k):
        """
        (c0, u, v) of V^k in F^i, c0 = d^i + v its resting height over the arm.

        c0 is exactly 0 for the two vertices of the resting edge (they lie on the arm by
        definition), which keeps their heights right in the first instants of the flight.
        """
        u, v = self.part.uv(i)
        c0 = 0.0 if k in (i, (i + 1) % self.part.n) else self.part.d[i] + v[k]
        return c0, u[k], v[k]

    def _flight_heights(self, i, R, t, vertex):
        """
        Height over the arm at times t of a vertex (c0, u, v) of F^i (eqs 5 and 6).

        d + R w t + g t^2 / 2 + u sin(w t) + v cos(w t), summed as c0 + (R + u) w t
        + u (sin(w t) - w t) - 2 v sin^2(w t / 2) + g t^2 / 2 so that no term cancels another
        near t = 0 (a part thrown from just right of the pivot hops for only ~1e-7 s).
        """
        c0, u, v = vertex
        wt = self.w * t
        return (c0 + (R + u) * wt + u * (np.sin(wt) - wt) - 2.0 * v * np.sin(0.5 * wt) ** 2
                + 0.5 * self.g * t * t)

    def _flight_time_bound(self, i, R):
        """
        Time by which the part has certainly touched the arm.

        The lowest point of a convex part is at least min_j d^j below its CM in every
        orientation, so a contact has happened once the CM is only that high over the arm.
        """
        drop = self.part.d[i] - float(self.part.d.min())
        vy = R * self.w
        return (vy + math.sqrt(vy * vy + 2.0 * self.g_abs * drop)) / self.g_abs

    def _first_root(self, i, R, vertex, ts, hs, bound_dd):
        """
        First time the vertex (c0, u, v) reaches the arm, from samples hs at ts.

        Returns (time, whether it was found as a dip between two samples).
        """
        def height(t):
            return float(self._flight_heights(i, R, np.array([t]), vertex)[0])

        def bisect(lo, hi):
            # height(lo) > 0 >= height(hi)
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if mid <= lo or mid >= hi:
                    break
                if height(mid) > 0.0:
                    lo = mid
                else:
                    hi = mid
            return hi

        best, graze = math.inf, False
        below = np.flatnonzero(hs[1:] <= 0.0)
        if below.size:
            j = int(below[0]) + 1
            best = bisect(ts[j - 1], ts[j])
        # Grazes: a dip below the arm between two samples shows as a low sampled minimum.
        dt = ts[1] - ts[0]
        limit = bound_dd * dt * dt
        last = min(len(hs) - 2, (int(below[0]) if below.size else len(hs) - 2))
        inner = hs[1:last + 1]
        cand = np.flatnonzero((inner > 0.0) & (inner <= limit)
                              & (inner <= hs[0:last]) & (inner <= hs[2:last + 2])) + 1
        for j in cand:
            if ts[j - 1] >= best:
                break
            res = minimize_scalar(height, bounds=(ts[j - 1], ts[j + 1]), method='bounded',
                                  options={'xatol': dt * 1e-12})
            if res.fun <= 0.0:
                t = bisect(ts[j - 1], float(res.x))
                if t < best:
                    best, graze = t, True
                break
        return best, graze

    def _scan(self, i, R, t_end):
        """(T, k, graze): first contact in [0, t_end] on a fixed grid of time steps."""
        part = self.part
        turns = math.ceil(self.w * t_end / MAX_STEP_ANGLE)
        steps = max(self.samples, min(MAX_FLIGHT_SAMPLES, turns))
        ts = np.linspace(0.0, t_end, steps + 1)
        best_t, best_k, best_graze = math.inf, -1, False
        for k in range(part.n):
            vertex = self._vertex_in_frame(i, k)
            hs = self._flight_heights(i, R, ts, vertex)
            bound_dd = self.g_abs + self.w * self.w * part.dist[k]     # >= |F''|
            t, graze = self._first_root(i, R, vertex, ts, hs, bound_dd)
            if t < best_t:
                best_t, best_k, best_graze = t, k, graze
        return best_t, best_k, best_graze

    def flight_contact(self, i, R):
        """
        (T, k): flight time and first contact vertex, by dense sampling plus bisection.

        The first pass covers [0, t_up]; when the contact comes much earlier than t_up, a
        second pass samples [0, 1.001 T] again so that dt <= T / samples holds for the flight
        that actually happens; the earlier contact of the two passes is taken.
        """
        t_up = self._flight_time_bound(i, R) * (1.0 + 1e-9) + 1e-15
        t, k, graze = self._scan(i, R, t_up)
        if not math.isfinite(t):
            raise RuntimeError(f'no contact found before the flight-time bound {t_up} s')
        if t < 0.5 * t_up:
            # Both passes evaluate the same heights: a contact either finds is a contact (they
            # can differ only at a graze of rounding depth).
            t2, k2, graze2 = self._scan(i, R, min(t_up, 1.001 * t))
            if t2 < t:
                t, k, graze = t2, k2, graze2
        self.last_contact_from_graze = graze
        return t, k

    # ------------------------------------------------------------------ rolling
    def _cm_rel(self, p, phi):
        """CM minus pivot V^p, world frame, body angle phi."""
        bx, by = _rot(phi, self.part.b[p])
        return -bx, -by

    def _roll_energy(self, p, phi, omega):
        lp = self.part.dist[p]
        return 0.5 * (self.part.rho2 + lp * lp) * omega * omega + \
            self.g_abs * self._cm_rel(p, phi)[1]

    def _roll_window(self, p, phi):
        """
        Body angles [A, B] of rolling about V^p: E^p flat at A, E^{p-1} flat at B.

        Rotating about V^p clockwise (phi falling) brings V^{p+1} down onto the arm, which
        happens exactly when E^p is flat; counterclockwise brings V^{p-1} down, E^{p-1} flat.
        B - A is the exterior angle of the polygon at V^p.
        """
        part = self.part
        ext = (part.theta[(p - 1) % part.n] - part.theta[p]) % TWO_PI
        a = part.theta[p] + TWO_PI * round((phi - part.theta[p] - 0.5 * ext) / TWO_PI)
        return a, a + ext

    def _roll(self, p, phi, omega, start_edge=-1):
        """
        Integrate rolling about V^p until a neighbour vertex reaches the arm.

        ``start_edge`` is the edge through V^p lying flat at the start (-1 if none). The state
        is (psi, omega) with psi = phi - phi_start, so that angles near the start keep full
        precision. Returns (q, phi, omega, time, relative energy drift).

        Landing events are sign changes of the angular distance to the two ends A and B of
        the range. A part that only just reaches an end overshoots it (in the unconstrained
        pendulum) by a dip that one integration step could jump over, so turning points
        (omega = 0) are events too: psi is monotonic between turning points, and a turning
        point beyond an end means that end was crossed, found by root-finding on the dense
        output since the last turn.
        """
        part = self.part
        n = part.n
        bp = part.b[p]
        inertia = part.rho2 + part.dist[p] ** 2
        g = self.g
        a, b = self._roll_window(p, phi)
        if not a - 1e-9 <= phi <= b + 1e-9:
            raise RuntimeError('rolling starts outside the range of its pivot')
        if start_edge == p:
            phi = a
        elif start_edge == (p - 1) % n:
            phi = b
        elif start_edge != -1:
            raise ValueError(f'edge {start_edge} does not end at vertex {p}')
        lo, hi = a - phi, b - phi

        def accel(psi):
            ang = phi + psi
            return g * -(math.cos(ang) * bp[0] - math.sin(ang) * bp[1]) / inertia

        def rhs(_, y):
            return [y[1], accel(y[0])]

        # Distance in angle to the landing of V^{p+1} (at A, phi falling) and of V^{p-1} (at B,
        # phi rising). A start exactly on an end (the edge that just landed) is divided by t,
        # so that coming straight back to it is still a sign change and t = 0 is not a root.
        start_rate = omega if omega != 0.0 else accel(0.0)

        def ev_lo(t, y):
            if lo == 0.0:
                return start_rate if t == 0.0 else y[0] / t
            return y[0] - lo

        def ev_hi(t, y):
            if hi == 0.0:
                return -start_rate if t == 0.0 else -y[0] / t
            return hi - y[0]

        ev_lo.terminal = ev_hi.terminal = True
        ev_lo.direction = ev_hi.direction = -1.0
        nbrs = ((p + 1) % n, (p - 1) % n)
        rate = math.sqrt(self.g_abs * part.dist[p] / inertia)      # natural angular rate
        chunk = 50.0 / rate
        atol = [ROLL_ATOL_REL, ROLL_ATOL_REL * max(rate, abs(omega))]
        e0 = self._roll_energy(p, phi, omega)
        scale = self.g_abs * part.size + 0.5 * inertia * omega * omega

        def landing(k, t1, psi1, om1):
            phi1 = phi + psi1
            drift = abs(self._roll_energy(p, phi1, om1) - e0) / scale
            return nbrs[k], float(phi1), float(om1), float(t1), drift

        t_s, y_s = 0.0, [0.0, omega]
        for _ in range(40):
            if y_s[1] == 0.0:
                # From rest (or a turning point): omega ~ accel * (t - t_s) at first.
                acc_s, t_turn0 = accel(y_s[0]), t_s

                def ev_turn(t, y):
                    return acc_s if t == t_turn0 else y[1] / (t - t_turn0)
            else:
                def ev_turn(t, y):
                    return y[1]
            ev_turn.terminal = True
            sol = solve_ivp(rhs, (t_s, t_s + chunk), y_s, method='DOP853', rtol=self.rtol,
                            atol=atol, events=[ev_lo, ev_hi, ev_turn], dense_output=True)
            if sol.status < 0:
                raise RuntimeError(f'rolling integration failed: {sol.message}')
            hit = [k for k in range(3) if sol.t_events[k].size]
            if not hit:
                t_s, y_s = float(sol.t[-1]), [float(sol.y[0, -1]), float(sol.y[1, -1])]
                continue
            k = min(hit, key=lambda m: sol.t_events[m][0])
            t1 = float(sol.t_events[k][0])
            psi1, om1 = (float(x) for x in sol.y_events[k][0])
            if k < 2:
                return landing(k, t1, psi1, om1)
            # A turning point. Beyond an end: that end was crossed since t_s (psi monotonic).
            for m, bound in ((0, lo), (1, hi)):
                if (psi1 < bound) if m == 0 else (psi1 > bound):
                    tc = brentq(lambda t: sol.sol(t)[0] - bound, t_s, t1, xtol=1e-15,
                                rtol=4 * np.finfo(float).eps)
                    return landing(m, tc, bound, float(sol.sol(tc)[1]))
            t_s, y_s = t1, [psi1, 0.0]
        raise RuntimeError('rolling did not reach an edge (balanced on a vertex?)')

    def _flat_angle(self, j, phi):
        """theta_j + 2 pi m closest to phi: the body angle at which E^j lies flat."""
        th = self.part.theta[j]
        return th + TWO_PI * round((phi - th) / TWO_PI)

    def _landing_pivot_x(self, p, xp, q, phi):
        bx, _ = _rot(phi, self.part.b[q] - self.part.b[p])
        return xp + bx

    def _settle(self, p, xp, phi, omega, res, start_edge=-1):
        """
        Roll and impact from pivot V^p at arm x = xp until settled; fills res.

        ``start_edge``: the edge through V^p that lies flat at the start, or -1.
        """
        part = self.part
        n = part.n
        g_abs = self.g_abs
        while True:
            if len(res.impacts) > MAX_IMPACTS:
                raise RuntimeError('catch did not settle')
            q, phi_e, om_e, _, drift = self._roll(p, phi, omega, start_edge)
            res.roll_segments += 1
            res.roll_energy_drift = max(res.roll_energy_drift, drift)
            # q = p + 1 lands when rolling clockwise (E^p flat), q = p - 1 counterclockwise.
            if q == (p + 1) % n:
                j, s = p, -1.0
            else:
                j, s = q, 1.0
            phi = self._flat_angle(j, phi_e)
            if abs(phi - phi_e) > 1e-6:
                raise RuntimeError('landing event away from the flat pose')
            xq = self._landing_pivot_x(p, xp, q, phi)
            cm = self._cm_rel(p, phi)
            vel = (-om_e * cm[1], om_e * cm[0])
            r_q = _rot(phi, part.b[q])
            lq = part.dist[q]
            _, _, om_new = sticking_impact(r_q, vel, om_e, part.rho2)
            e_before = 0.5 * (part.rho2 + part.dist[p] ** 2) * om_e ** 2 + g_abs * part.d[j]
            continues = om_new * s > 0.0
            ke = 0.5 * (part.rho2 + lq * lq) * om_new * om_new if continues else 0.0
            res.impacts.append(RefImpact('landing', q, j, xq, om_e, om_new if continues else 0.0,
                                         e_before, ke + g_abs * part.d[j]))
            if continues and part.stable[j]:
                barrier_p = g_abs * (part.dist[p] - part.d[j])
                barrier_q = g_abs * (lq - part.d[j])
                if ke <= barrier_p and ke <= barrier_q:
                    continues = False
            start_edge = j
            if continues:
                p, xp, omega = q, xq, om_new
                continue
            if part.stable[j]:
                return self._finish(j, q, xq, phi, res)
            p, xp = self._tip_from_rest(j, q, xq, phi, res)
            omega = 0.0

    def _tip_from_rest(self, j, q, xq, phi, res):
        """Tip over from rest off unstable E^j (V^q at xq), about the vertex the CM is beyond."""
        part = self.part
        n = part.n
        left = j
        right = (j + 1) % n
        x_left = xq if q == left else xq - part.length[j]
        if part.u_r[j] <= 0.0:
            p, xp = right, x_left + part.length[j]
        else:
            p, xp = left, x_left
        e_rest = self.g_abs * part.d[j]
        res.impacts.append(RefImpact('tip_from_rest', p, j, xp, 0.0, 0.0, e_rest, e_rest))
        return p, xp

    def _finish(self, j, q, xq, phi, res):
        bx, _ = _rot(phi, self.part.b[q])
        res.edge = int(j)
        res.R = float(xq - bx)
        res.net_rotation = float(phi - self.part.theta[res.edge0])
        same = res.edge == res.edge0 and abs(res.net_rotation) < math.pi
        res.kind = 'jog' if same else 'flip'
        return res

    # ------------------------------------------------------------------ the map
    def throw(self, i, R):
        """One throw and catch from (edge i, radius R); returns a RefResult."""
        part = self.part
        if not part.stable[i]:
            raise ValueError(f'edge {i} is not stable')
        w, g, h = self.w, self.g, self.h
        hd = h + part.d[i]
        phi0 = float(part.theta[i])
        res = RefResult(int(i), float(R), -1, math.nan, '', math.nan, math.nan, -1)
        # Release: the arm's rotation w about the pivot, imparted to the part (impulsive throw).
        vel0 = np.array([-hd * w, R * w])
        res.release_energy = 0.5 * (vel0 @ vel0 + part.rho2 * w * w) + self.g_abs * part.d[i]
        T, k = self.flight_contact(i, R)
        res.flight_time = float(T)
        res.first_contact_vertex = int(k)
        # Pose and velocity at contact (eq 5).
        phi = phi0 + w * T
        cm = np.array([R - hd * w * T, hd + R * w * T + 0.5 * g * T * T])
        vel = np.array([-hd * w, R * w + g * T])
        e_flight = 0.5 * (vel @ vel + part.rho2 * w * w) + self.g_abs * (cm[1] - h)
        res.flight_energy_drift = abs(e_flight - res.release_energy) / res.release_energy
        r_k = _rot(phi, part.b[k])
        xk = cm[0] + r_k[0]
        res.contact_speed = float(-(vel[1] + w * r_k[0]))
        n = part.n
        # Tilt of the two edges at V^k: E^k flat when its direction is +x (V^{k+1} above V^k
        # means a positive angle); E^{k-1} flat when its direction is +x (negative when above).
        tilt_next = _wrap(phi + math.atan2(*(part.b[(k + 1) % n] - part.b[k])[::-1]))
        tilt_prev = _wrap(phi + math.atan2(*(part.b[k] - part.b[(k - 1) % n])[::-1]))
        flat = None
        if tilt_next <= self.flat_tol:
            flat = (k, k)
        elif -tilt_prev <= self.flat_tol:
            flat = ((k - 1) % n, k)
        if flat is not None:
            j, q = flat
            phi = self._flat_angle(j, phi)
            e_rest = self.g_abs * part.d[j]
            res.impacts.append(RefImpact('flat_landing', k, j, xk, w, 0.0, e_flight, e_rest))
            if part.stable[j]:
                return self._finish(j, q, xk, phi, res)
            p, xp = self._tip_from_rest(j, q, xk, phi, res)
            return self._settle(p, xp, phi, 0.0, res, start_edge=j)
        _, _, omega = sticking_impact(r_k, vel, w, part.rho2)
        lk = part.dist[k]
        e_after = 0.5 * (part.rho2 + lk * lk) * omega * omega + self.g_abs * (-r_k[1])
        res.impacts.append(RefImpact('flight', k, -1, xk, w, omega, e_flight, e_after))
        return self._settle(k, xk, phi, omega, res)


def reference_throw(vertices, cm, rho2, h, w, g, edge, R, **kw):
    """Run one reference throw (see ReferenceSimulator)."""
    return ReferenceSimulator(vertices, cm, rho2, h, w, g, **kw).throw(edge, R)
