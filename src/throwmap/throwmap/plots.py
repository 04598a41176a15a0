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

"""Figures in the manner of the paper's Figures 5, 6 and 7 (PNG, matplotlib Agg)."""

import os

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

EDGE_COLORS = ['tab:blue', 'tab:orange', 'tab:green', 'tab:red', 'tab:purple', 'tab:brown',
               'tab:pink', 'tab:gray', 'tab:olive', 'tab:cyan']


def edge_color(e):
    return EDGE_COLORS[int(e) % len(EDGE_COLORS)]


def plot_orbit(scene, orb, path, sensor=None):
    """Figure 5: R against throw number, coloured by edge."""
    fig, ax = plt.subplots(figsize=(9, 4))
    k = np.arange(len(orb.edges))
    ax.plot(k, orb.radii * 100, color='0.8', lw=0.8, zorder=1)
    for e in sorted({int(x) for x in orb.edges}):
        sel = orb.edges == e
        ax.scatter(k[sel], orb.radii[sel] * 100, s=10, color=edge_color(e), label=f'edge {e}',
                   zorder=2)
    if sensor is not None:
        ax.axhline(sensor.guarantee_radius * 100, color='k', ls='--', lw=0.8,
                   label=f'sensor guarantee {sensor.guarantee_radius * 100:.1f} cm (x)')
    ax.set_xlabel('throw number')
    ax.set_ylabel('throwing radius R (cm)')
    ax.set_title(f'{scene.name}: orbit from ({orb.edges[0]}, {orb.radii[0] * 100:.1f} cm)')
    ax.legend(loc='upper right', fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_cycle(scene, orb, ls, path):
    """Figure 6: the part's resting poses (and flights) through one cycle of the limit set."""
    model = scene.model
    part = scene.part
    edges, radii = orb.edges, orb.radii
    key = ls.pattern[0] if ls.pattern else int(edges[-1])
    # One cycle: from a flip onto `key` to the next one, taken from the orbit's tail.
    flips = [k for k in range(len(edges) // 2, len(edges))
             if k > 0 and edges[k] == key and edges[k - 1] != key]
    per_cycle = max(1, sum(1 for e in ls.pattern if e == key))
    if len(flips) > per_cycle:
        a, b = flips[0], flips[per_cycle]
    else:
        a, b = len(edges) - 12, len(edges) - 1
    states = list(range(a, b + 1))
    ncol = min(6, len(states))
    nrow = (len(states) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(2.6 * ncol, 1.9 * nrow), squeeze=False)
    x_hi = max(radii[states]) + 1.5 * part.r
    for ax, k in zip(axes.flat, states):
        e, R = int(edges[k]), float(radii[k])
        ax.plot([0, x_hi * 100], [model.h * 100] * 2, color='k', lw=2)
        if k + 1 < len(edges) and k < b:
            res = model.throw(e, R, trajectory=True, samples=12)
            tr = res.trajectory
            if tr is not None:   # scenes with effects may have no sampled poses
                for s in range(0, len(tr.t), max(1, len(tr.t) // 6)):
                    v = tr.vertices_at(s) * 100
                    ax.fill(v[:, 0], v[:, 1], facecolor='none', edgecolor='0.7', lw=0.6)
                ax.plot(tr.x * 100, tr.y * 100, color='0.6', lw=0.6)
            title = f'{k - a}: E{e}, {R * 100:.1f} cm -> {res.kind}'
        else:
            title = f'{k - a}: E{e}, {R * 100:.1f} cm'
        v = part.pose_vertices(e, R, model.h) * 100
        ax.fill(v[:, 0], v[:, 1], facecolor=edge_color(e), alpha=0.7, edgecolor='k', lw=0.8)
        ax.set_title(title, fontsize=8)
        ax.set_aspect('equal')
        ax.set_xlim(0, x_hi * 100)
        ax.tick_params(labelsize=6)
    for ax in list(axes.flat)[len(states):]:
        ax.axis('off')
    fig.suptitle(f'{scene.name}: one cycle of the limit set (cm)', fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_basin(scene, bas, ls, path):
    """Figure 7: orbits from a grid of starts (diamonds) converging to the limit set."""
    fig, ax = plt.subplots(figsize=(9, 4.5))
    throws = bas.edges.shape[1]
    k = np.arange(throws)
    for s in range(bas.edges.shape[0]):
        e, r = bas.edges[s], bas.radii[s]
        ok = e >= 0
        ax.plot(k[ok], r[ok] * 100, color='0.85', lw=0.4, zorder=1)
    for e in sorted({int(x) for x in np.unique(bas.edges) if x >= 0}):
        sel = bas.edges == e
        ax.scatter(np.broadcast_to(k, bas.edges.shape)[sel], bas.radii[sel] * 100, s=2,
                   color=edge_color(e), zorder=2, label=f'edge {e}')
    for e in sorted({int(x) for x in bas.start_edges}):
        sel = bas.start_edges == e
        ax.scatter(np.zeros(sel.sum()), bas.start_radii[sel] * 100, marker='D', s=18,
                   facecolor='none', edgecolor=edge_color(e), zorder=3)
    for e, (lo, hi) in sorted(ls.bands.items()):
        ax.axhspan(lo * 100, hi * 100, xmin=0.97, xmax=1.0, color=edge_color(e), alpha=0.4)
    summary = ', '.join(f'{n} -> {s}' for s, n in sorted(bas.summary().items()))
    ax.set_title(f'{scene.name}: {bas.edges.shape[0]} starts, {throws - 1} throws each '
                 f'({summary})', fontsize=9)
    ax.set_xlabel('throw number')
    ax.set_ylabel('R (cm)')
    ax.legend(loc='upper right', fontsize=8, markerscale=4)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_all(scene, out_dir, orb, ls, bas, sensor=None):
    os.makedirs(out_dir, exist_ok=True)
    return [plot_orbit(scene, orb, os.path.join(out_dir, f'{scene.name}_orbit.png'), sensor),
            plot_cycle(scene, orb, ls, os.path.join(out_dir, f'{scene.name}_cycle.png')),
            plot_basin(scene, bas, ls, os.path.join(out_dir, f'{scene.name}_basin.png'))]
