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
Planar part: convex hull, mass properties and the per-edge frame quantities of section II.

Conventions (paper section II): vertices V^0..V^{n-1} counterclockwise; edge E^i runs from V^i to
V^{i+1}. Resting on E^i, V^i is the left vertex and V^{i+1} the right one. The frame F^i sits at
the centre of mass with u^i along E^i and v^i pointing away from the edge (up when resting).
"""

from collections import namedtuple
import math

import numpy as np

from .errors import InputError

# Relative tolerance (of the part's size) under which a vertex counts as lying on a hull edge.
_COLLINEAR_REL = 1e-12

# Limits no real part reaches, checked before any work: the feeder's parts have a handful of
# corners and are centimetres across. The per-edge tables the contact finder reads (U, V) grow
# as vertices^2 (64 MiB at the limit: the hard cases include a 1024-gon); everything else in
# Part is linear in the vertex count.
MAX_VERTICES = 2048
MAX_COORDINATE = 1000.0         # metres from the outline's origin
MIN_SIZE = 1e-9                 # metres across


def check_vertex_count(count, field):
    """Refuse an outline of more than MAX_VERTICES points (before anything reads them)."""
    if count > MAX_VERTICES:
        raise InputError(f'{field}.vertices', f'has {count} points; the limit is {MAX_VERTICES} '
                         '(a part for this feeder has a handful of corners)',
                         f'simplify the outline to at most {MAX_VERTICES} points (only its '
                         'convex hull touches the arm)')


def _crossing_edges(pts):
    """
    Return (i, j), two outline edges that cross or touch (edge k runs from point k to k+1).

    None for a simple outline. Linear for a convex outline (all turns one way, turning once
    around); otherwise every pair of edges is tested, vectorised per edge.
    """
    n = len(pts)
    a = pts
    b = np.roll(pts, -1, axis=0)
    ein = b - a
    eout = np.roll(ein, -1, axis=0)     # edge k+1
    turn = ein[:, 0] * eout[:, 1] - ein[:, 1] * eout[:, 0]
    folds = np.flatnonzero((turn == 0) & ((ein * eout).sum(axis=1) < 0))
    if folds.size:
        k = int(folds[0])
        return k, (k + 1) % n
    turning = np.arctan2(turn, (ein * eout).sum(axis=1)).sum()
    if (np.all(turn > 0) or np.all(turn < 0)) and abs(abs(turning) - 2 * math.pi) < 1e-6:
        return None

    def orient(p, q, r):
        return np.sign((q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1])
                       - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0]))

    def within(p, q, r):
        """Whether r (collinear with p-q) lies within the segment's bounding box."""
        return ((np.minimum(p[..., 0], q[..., 0]) <= r[..., 0])
                & (r[..., 0] <= np.maximum(p[..., 0], q[..., 0]))
                & (np.minimum(p[..., 1], q[..., 1]) <= r[..., 1])
                & (r[..., 1] <= np.maximum(p[..., 1], q[..., 1])))

    idx = np.arange(n)
    for start in range(0, n, 64):              # 64 edges against all: O(n) memory per block
        i = idx[start:start + 64, None]
        p, q = a[i], b[i]                      # (rows, 1, 2) against (n, 2)
        o1, o2 = orient(p, q, a), orient(p, q, b)
        o3, o4 = orient(a, b, p), orient(a, b, q)
        hit = (o1 * o2 < 0) & (o3 * o4 < 0)
        hit |= (o1 == 0) & within(p, q, a)
        hit |= (o2 == 0) & within(p, q, b)
        hit |= (o3 == 0) & within(a, b, p)
        hit |= (o4 == 0) & within(a, b, q)
        # Only edges that share no point with edge i: j >= i + 2, and not the closing pair.
        hit &= (idx[None, :] >= i + 2) & ~((i == 0) & (idx[None, :] == n - 1))
        if hit.any():
            row, col = np.argwhere(hit)[0]
            return int(i[row, 0]), int(col)
    return None


def _signed_area_and_centroid(pts):
    x, y = pts[:, 0], pts[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = cross.sum() / 2.0
    if area == 0.0:
        return 0.0, np.zeros(2), 0.0
    cx = ((x + xn) * cross).sum() / (6.0 * area)
    cy = ((y + yn) * cross).sum() / (6.0 * area)
    # Polar second moment about the origin, then shifted to the centroid.
    jo = ((x * x + x * xn + xn * xn + y * y + y * yn + yn * yn) * cross).sum() / 12.0
    j_cm = jo - area * (cx * cx + cy * cy)
    return area, np.array([cx, cy]), j_cm


def _hull_indices(pts):
    """Return indices of strict convex-hull vertices (collinear points dropped), CCW."""
    order = sorted(range(len(pts)), key=lambda k: (pts[k, 0], pts[k, 1]))
    scale = float(np.ptp(pts, axis=0).max())
    eps = _COLLINEAR_REL * scale * scale

    def cross(o, a, b):
        return ((pts[a, 0] - pts[o, 0]) * (pts[b, 1] - pts[o, 1])
                - (pts[a, 1] - pts[o, 1]) * (pts[b, 0] - pts[o, 0]))

    lower, upper = [], []
    for k in order:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], k) <= eps:
            lower.pop()
        lower.append(k)
    for k in reversed(order):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], k) <= eps:
            upper.pop()
        upper.append(k)
    return lower[:-1] + upper[:-1]


# The part as compiled code takes it (throwmap.part.Part.arrays): one bundle, not 15 arguments.
# Per edge i: d (CM height over E^i), u_l, u_r, stable, edge_len; per vertex k: vrad (distance from
# the CM), acw / accw (angle of CM - V^k from the arm at the two ends of its rolling range),
# kcw / kccw (omega ratio of a landing at the next vertex clockwise / counterclockwise);
# U[i, k], V[i, k]: vertex k in frame F^i; rest_angle[i]: rotation of the resting pose on E^i;
# OU[i, j], OV[i, j]: outline point j in frame F^i (the hull's vertices for a convex part; where
# a distributed force has its kinks, throwmap.picard).
PartArrays = namedtuple('PartArrays', ['n', 'rho2', 'd', 'u_l', 'u_r', 'stable', 'edge_len',
                                       'vrad', 'acw', 'accw', 'kcw', 'kccw', 'U', 'V',
                                       'rest_angle', 'OU', 'OV'])


def triangulate(outline):
    """Ear-clipping triangulation of a simple counterclockwise polygon: list of index triples."""
    pts = [tuple(p) for p in np.asarray(outline, dtype=float)]
    idx = list(range(len(pts)))
    tris = []

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def inside(p, a, b, c):
        return cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0

    guard = 0
    while len(idx) > 3 and guard < 10_000:
        guard += 1
        for m in range(len(idx)):
            i0, i1, i2 = idx[m - 1], idx[m], idx[(m + 1) % len(idx)]
            a, b, c = pts[i0], pts[i1], pts[i2]
            if cross(a, b, c) <= 0:
                continue
            if any(inside(pts[k], a, b, c) for k in idx if k not in (i0, i1, i2)):
                continue
            tris.append((i0, i1, i2))
            idx.pop(m)
            break
        else:   # pragma: no cover - degenerate outline; fall back to a fan
            break
    if len(idx) >= 3:
        for m in range(1, len(idx) - 1):
            tris.append((idx[0], idx[m], idx[m + 1]))
    return tris


class Part:
    """
    A rigid planar part treated as its convex hull (paper section II).

    Parameters
    ----------
    vertices : (n, 2) array-like, metres, counterclockwise, in the paper's numbering.
        A non-convex outline is allowed: mass properties come from the outline (uniform lamina),
        contact geometry from its convex hull. Hull vertices keep the input's order; V^0 is the
        first input vertex that lies on the hull.
    cm : optional (2,) centre of mass in the same frame (default: centroid of the outline).
    radius_of_gyration : optional rho > 0 about the centre of mass, metres (default: lamina).
    field : name used in error messages (e.g. ``part``).

    """

    def __init__(self, vertices, cm=None, radius_of_gyration=None, field='part'):
        self.field = field
        pts = self._validate_points(vertices, field)
        scale = float(np.ptp(pts, axis=0).max())
        if scale < MIN_SIZE:
            raise InputError(f'{field}.vertices', f'the outline is {scale:.3g} m across; the '
                             f'smallest part allowed is {MIN_SIZE:g} m', 'give the vertices in '
                             'metres (a part for this feeder is centimetres across)')
        far = pts[np.argmax(((pts - pts[0]) ** 2).sum(axis=1))] - pts[0]
        off_line = np.abs(far[0] * (pts[:, 1] - pts[0, 1]) - far[1] * (pts[:, 0] - pts[0, 0]))
        if off_line.max() <= 1e-12 * scale * scale:
            raise InputError(f'{field}.vertices', 'the outline has zero area (all points on one '
                             'line)', 'give at least 3 points that are not collinear')
        crossing = _crossing_edges(pts)
        if crossing is not None:
            i, j = crossing
            n = len(pts)
            raise InputError(f'{field}.vertices', f'the outline crosses itself: its edge from '
                             f'point {i} to {(i + 1) % n} meets its edge from point {j} to '
                             f'{(j + 1) % n}', 'list the points in order around the part, '
                             'counterclockwise, so that no two edges cross or touch')
        area, centroid, j_cm = _signed_area_and_centroid(pts)
        if abs(area) <= 1e-12 * scale * scale:
            raise InputError(f'{field}.vertices', 'the outline has zero area (all points on one '
                             'line)', 'give at least 3 points that are not collinear')
        if area < 0:
            raise InputError(f'{field}.vertices', 'the outline is listed clockwise',
                             'list the vertices counterclockwise (paper numbering), e.g. '
                             f'reversed: {pts[::-1].tolist()}')
        hull = _hull_indices(pts)
        if len(hull) < 3:
            raise InputError(f'{field}.vertices', 'the convex hull has fewer than 3 corners',
                             'give at least 3 points that are not collinear')
        # Keep the caller's numbering: hull vertices in input order, starting at the first one.
        hull_set = set(hull)
        self.outline = pts
        self.hull_input_index = np.array([k for k in range(len(pts)) if k in hull_set])
        self.vertices = pts[self.hull_input_index].copy()
        if cm is None:
            cm_arr = centroid
        else:
            cm_arr = np.asarray(cm, dtype=float)
            if cm_arr.shape != (2,) or not np.all(np.isfinite(cm_arr)):
                raise InputError(f'{field}.cm', f'must be two finite numbers, got {cm!r}',
                                 'give the centre of mass as [x, y] in metres')
        if radius_of_gyration is None:
            rho2 = j_cm / area
        else:
            rho = radius_of_gyration
            if (not isinstance(rho, (int, float)) or isinstance(rho, bool)
                    or not math.isfinite(rho) or rho <= 0):
                raise InputError(f'{field}.radius_of_gyration', f'must be > 0, got {rho!r}',
                                 'give rho = sqrt(I_cm / m) in metres, or omit it for a '
                                 'uniform lamina')
            rho2 = float(rho) ** 2
        self.cm = cm_arr
        self.rho2 = float(rho2)
        self.area = float(area)
        self._arrays = None
        self._compute_edge_frames(scale)

    @staticmethod
    def _validate_points(vertices, field):
        if hasattr(vertices, '__len__') and not isinstance(vertices, (str, bytes)):
            check_vertex_count(len(vertices), field)
        try:
            pts = np.asarray(vertices, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f'{field}.vertices', f'not a list of [x, y] pairs: {vertices!r}',
                             'give vertices as [[x0, y0], [x1, y1], ...] in metres') from None
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise InputError(f'{field}.vertices', f'expected [[x, y], ...], got shape {pts.shape}',
                             'give vertices as [[x0, y0], [x1, y1], ...] in metres')
        if not np.all(np.isfinite(pts)):
            raise InputError(f'{field}.vertices', 'contains NaN or infinity',
                             'give finite coordinates in metres')
        check_vertex_count(len(pts), field)
        far = np.abs(pts).max()
        if far > MAX_COORDINATE:
            k = int(np.argmax(np.abs(pts).max(axis=1)))
            raise InputError(f'{field}.vertices', f'point {k} {pts[k].tolist()} is out of range: '
                             f'coordinates are limited to +-{MAX_COORDINATE:g} m',
                             'give the vertices in metres (a part for this feeder is '
                             'centimetres across)')
        distinct = {tuple(p) for p in pts.tolist()}
        if len(distinct) < 3:
            raise InputError(f'{field}.vertices',
                             f'fewer than 3 distinct points ({len(distinct)})',
                             'give at least 3 distinct points, counterclockwise')
        if len(distinct) != len(pts):
            raise InputError(f'{field}.vertices', 'repeats a point',
                             'list each corner once (the outline closes by itself)')
        return pts

    def _compute_edge_frames(self, scale):
        verts = self.vertices
        n = len(verts)
        rel = verts - self.cm
        nxt = np.roll(verts, -1, axis=0)
        edge_vec = nxt - verts
        length = np.hypot(edge_vec[:, 0], edge_vec[:, 1])
        e = edge_vec / length[:, None]
        normal = np.stack([-e[:, 1], e[:, 0]], axis=1)        # points into the part
        # u, v of every vertex k in every edge frame i: U[i, k], V[i, k].
        self.U = e @ rel.T
        self.V = normal @ rel.T
        d = -(normal * rel).sum(axis=1)                         # CM height over E^i
        if np.any(d <= _COLLINEAR_REL * scale):
            worst = int(np.argmin(d))
            raise InputError(f'{self.field}.cm', f'the centre of mass {self.cm.tolist()} is not '
                             f'strictly inside the convex hull (distance {d[worst]:.3g} m to '
                             f'edge E{worst})', 'move the centre of mass inside the part, or omit '
                             'it to use the centroid')
        self.n = n
        self.d = d
        self.edge_length = length
        self.u_l = self.U[np.arange(n), np.arange(n)]
        self.u_r = self.U[np.arange(n), (np.arange(n) + 1) % n]
        self.v_l = -d
        self.v_r = -d
        self.stable = (self.u_l < 0) & (self.u_r > 0)
        # Rotation that takes the body frame to the resting pose on E^i (edge along +x).
        self.rest_angle = -np.arctan2(e[:, 1], e[:, 0])
        self.vertex_radius = np.hypot(rel[:, 0], rel[:, 1])
        self.r = float(self.vertex_radius.max())
        if not self.stable.any():
            raise InputError(f'{self.field}', 'no edge is stable',
                             'a convex part always has a stable edge; check the centre of mass')
        self.d_min = float(d[self.stable].min())
        self.stable_edges = [int(i) for i in np.flatnonzero(self.stable)]
        # Angle of (CM - V^p) from the arm when E^p (p is its left vertex) or E^{p-1}
        # (p is its right vertex) lies flat: the two ends of the rolling range about V^p.
        # Both from V^p's own offset (d^{p-1} comes from V^{p-1}'s; the same number in exact
        # arithmetic, but with a CM very close to V^p its rounding, ~1e-16 of the edge, would
        # be a large angle, and the ends would not differ by exactly the exterior angle).
        idx = np.arange(n)
        self.alpha_cw_end = np.arctan2(-self.V[idx, idx], -self.U[idx, idx])
        self.alpha_ccw_end = np.arctan2(-self.V[idx - 1, idx], -self.U[idx - 1, idx])
        # Impulse ratio omega+/omega- for a sticking impact at the next vertex while rolling
        # about V^p (from conservation of angular momentum about the new contact).
        rel_nxt, rel_prv = np.roll(rel, -1, axis=0), np.roll(rel, 1, axis=0)
        self.k_cw = ((self.rho2 + (rel * rel_nxt).sum(axis=1))
                     / (self.rho2 + (rel_nxt * rel_nxt).sum(axis=1)))
        self.k_ccw = ((self.rho2 + (rel * rel_prv).sum(axis=1))
                      / (self.rho2 + (rel_prv * rel_prv).sum(axis=1)))

    @property
    def arrays(self):
        """Return the part's per-edge and per-vertex arrays as one bundle for compiled code."""
        if self._arrays is None:
            ou, ov, _, _ = self.outline_frames()
            self._arrays = PartArrays(self.n, self.rho2, self.d, self.u_l, self.u_r, self.stable,
                                      self.edge_length, self.vertex_radius, self.alpha_cw_end,
                                      self.alpha_ccw_end, self.k_cw, self.k_ccw, self.U, self.V,
                                      self.rest_angle, ou, ov)
        return self._arrays

    def area_quadrature(self, level):
        """
        Return a quadrature of the part's area (its outline, a uniform lamina).

        Every triangle of the outline is split into level^2 similar ones, each weighted by its
        area at its centroid. Returns QU, QV (the points in every edge frame F^i, shape (n,
        points)) and the weights QW (sum 1).
        """
        pts = self.outline
        qx, qy, qw = [], [], []
        for i0, i1, i2 in triangulate(pts):
            a, b, c = pts[i0], pts[i1], pts[i2]
            ab = (b - a) / level
            ac = (c - a) / level
            area = 0.5 * abs(ab[0] * ac[1] - ab[1] * ac[0])
            for r in range(level):
                for s in range(level - r):
                    p0 = a + r * ab + s * ac
                    subs = [(p0, p0 + ab, p0 + ac)]
                    if r + s < level - 1:
                        subs.append((p0 + ab, p0 + ab + ac, p0 + ac))
                    for t0, t1, t2 in subs:
                        cen = (t0 + t1 + t2) / 3.0
                        qx.append(cen[0])
                        qy.append(cen[1])
                        qw.append(area)
        qw = np.array(qw)
        qw /= qw.sum()
        rel = np.stack([np.array(qx) - self.cm[0], np.array(qy) - self.cm[1]], axis=1)
        verts = self.vertices
        e = np.roll(verts, -1, axis=0) - verts
        e /= np.hypot(e[:, 0], e[:, 1])[:, None]
        normal = np.stack([-e[:, 1], e[:, 0]], axis=1)
        return (np.ascontiguousarray(e @ rel.T), np.ascontiguousarray(normal @ rel.T),
                np.ascontiguousarray(qw))

    def outline_frames(self):
        """
        Return the outline in every edge frame F^i, from the CM, and the centroid's offset.

        Returns OU, OV (shape (n, outline points)) and CU, CV (shape (n,)): what the exact
        plate drag (backplate_friction) integrates over.
        """
        verts = self.vertices
        e = np.roll(verts, -1, axis=0) - verts
        e /= np.hypot(e[:, 0], e[:, 1])[:, None]
        normal = np.stack([-e[:, 1], e[:, 0]], axis=1)
        rel = np.asarray(self.outline, dtype=float) - self.cm
        x, y = self.outline[:, 0], self.outline[:, 1]
        xn, yn = np.roll(x, -1), np.roll(y, -1)
        cross = x * yn - xn * y
        centroid = np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (
            3.0 * cross.sum()) - self.cm
        return (np.ascontiguousarray(e @ rel.T), np.ascontiguousarray(normal @ rel.T),
                np.ascontiguousarray(e @ centroid), np.ascontiguousarray(normal @ centroid))

    def shadow(self, edge):
        """(u_min, u_max): the part's extent along the arm, relative to R, resting on ``edge``."""
        return float(self.U[edge].min()), float(self.U[edge].max())

    def pose_vertices(self, edge, R, h):
        """Return world coordinates (frame F) of the hull resting on ``edge`` at radius R."""
        return np.stack([R + self.U[edge], h + self.d[edge] + self.V[edge]], axis=1)

    def describe(self):
        rows = []
        for i in range(self.n):
            rows.append({'edge': i, 'u_l': float(self.u_l[i]), 'v_l': float(self.v_l[i]),
                         'u_r': float(self.u_r[i]), 'v_r': float(self.v_r[i]),
                         'd': float(self.d[i]), 'length': float(self.edge_length[i]),
                         'stable': bool(self.stable[i])})
        return rows
