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
Shared helpers of the throwmap tests.

A module of its own: every package's tests have a conftest.py, so `from conftest import ...`
would be ambiguous when all suites run together.
"""

import copy
import math
import pathlib

import numpy as np
from throwmap import Part, Scene
import yaml

REPO = pathlib.Path(__file__).resolve().parents[3]
SCENES = REPO / 'scenes'
TRIANGLE_VERTICES = [[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]]
PAPER_W = math.radians(320.0)
# The paper's triangle as scene data, and the effects' settings the simulator tests share: the
# experiment's back plate, a 20 g part in air, and the event simulator's reference knobs.
TRIANGLE_SCENE = {'name': 't', 'part': {'vertices': TRIANGLE_VERTICES},
                  'arm': {'offset': -0.005}, 'throw': {'release_speed': PAPER_W}}
PLATE = {'inclination_deg': 80, 'g0': 9.81, 'mu': 0.1}
AIR = {'density': 1.2, 'drag_coefficient': 1.2, 'frontal_area_cm2': 4.0, 'mass_g': 20.0}
REFERENCE_KNOBS = {'integrator_step': 5e-5, 'roll_step': 5e-5, 'contact_root_tol': 1e-13,
                   'roll_method': 'rk4', 'flight_method': 'rk4'}
# The body-force effect sets the simulator tests throw the triangle with.
FORCE_SETS = {
    'plate': {'plate': PLATE, 'effects': ['backplate_friction']},
    'air': {'gravity': -9.66, 'air': AIR, 'effects': ['air_drag']},
    'plate and air': {'plate': PLATE, 'air': AIR, 'effects': ['backplate_friction', 'air_drag']},
}


def force_scene(effects, plate=None, **accuracy):
    """Return the triangle with the FORCE_SETS entry ``effects``, a plate and accuracy knobs."""
    data = copy.deepcopy(TRIANGLE_SCENE)
    data.update(copy.deepcopy(FORCE_SETS[effects]))
    if plate is not None:
        data['plate'] = plate
    if accuracy:
        data['accuracy'] = accuracy
    return Scene(data)


def hard_part_on_the_plate(name, **accuracy):
    """Return scenes/hard/NAME.yaml with the back plate (and its drag) instead of gravity."""
    from throwmap.scene import read_yaml
    data = read_yaml(SCENES / 'hard' / f'{name}.yaml')
    data.pop('gravity', None)
    data['plate'] = dict(PLATE)
    data['effects'] = ['backplate_friction']
    if accuracy:
        data['accuracy'] = dict(data.get('accuracy') or {}, **accuracy)
    return Scene(data)


def worst(got, ref):
    """Return (edges that differ, max abs dR over the rest) of two f_batch results."""
    assert np.all(got['status'] == 0) and np.all(ref['status'] == 0)
    same = got['edge'] == ref['edge']
    return int(np.sum(~same)), float(np.max(np.abs(got['R'] - ref['R'])[same]))


def random_convex_vertices(rng, n_max=8, scale=0.05):
    """Return a random convex polygon (CCW) of 3..n_max corners around the origin."""
    while True:
        n = int(rng.integers(3, n_max + 1))
        angles = np.sort(rng.uniform(0, 2 * np.pi, n))
        radii = scale * rng.uniform(0.4, 1.0, n)
        pts = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
        try:
            part = Part(pts)
        except ValueError:
            continue
        if part.n >= 3 and part.d_min > 0.02 * scale:
            return part.vertices


def random_state(model, rng, spread=3.0):
    """Return a random (edge, R) inside the domain of f."""
    part = model.part
    edge = int(rng.choice(part.stable_edges))
    lo = model.r_min(edge) * 1.0001 + 1e-9
    R = lo + rng.uniform(0, spread) * max(lo, part.r)
    return edge, float(R)


def shipped_scene(name, endless=False, **sections):
    """
    Return the shipped scene ``scenes/<name>.yaml`` with sections replaced (None: removed).

    ``endless``, or an ``effects`` list without finite_arm: the scene's arm is taken as endless
    (its length removed), as before the paper's scenes stated the 40 cm arm (issue 21): what a
    test of other physics compares against the base model.
    """
    with open(SCENES / f'{name}.yaml', encoding='utf-8') as fh:
        data = yaml.safe_load(fh)
    for key, value in sections.items():
        if value is None:
            data.pop(key, None)
        else:
            data[key] = copy.deepcopy(value)
    effects = data.get('effects') or []
    if endless or 'finite_arm' not in effects:
        for key in ('length', 'length_cm'):
            data.get('arm', {}).pop(key, None)
        data['effects'] = [e for e in effects if e != 'finite_arm']
        if not data['effects']:
            data.pop('effects')
    return Scene(data)
