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
The library's structure: layers without cycles, no hidden imports, a core that names no effect.

Every module of src/throwmap/throwmap is parsed (imports inside functions included). A module
may import only modules of lower layers (LAYERS, lowest first; docs/physics.md has the
picture); an effect module only its own package's helpers (_common) and lower layers. Imports
inside functions are refused except for the optional heavy plotting (matplotlib), so no cycle
can hide in one.
"""

import ast
import inspect
import pathlib
import re

from throwmap import event_sim, load_scene, pipeline
from throwmap.effects import EVENT_SLOTS, MODULES, SLOT_TABLE, SLOTS
from throwmap.internal import composed_source
from throwmap_testing import SCENES

PKG = pathlib.Path(__file__).resolve().parents[1] / 'throwmap'
LAYERS = [
    ('errors', 'jit'),
    ('status', 'bracket'),
    ('part', 'accuracy', 'sensor', 'rk8', 'picard'),
    ('grasp', 'trajectory'),
    ('ballistic',),
    ('catch',),
    ('event_sim',),
    ('pipeline',),
    ('effects',),
    ('compose',),
    ('model',),
    ('orbits',),
    ('basins',),
    ('stochastic',),
    ('analysis_cache',),
    ('analysis',),
    ('scene',),
    ('part_on_arm',),
    ('design',),
    ('robustness',),
    ('funnel_bound',),
    ('search', 'funnel'),
    ('internal', 'plots'),
    ('cli',),
    ('__init__',),
]
LAYER = {name: k for k, names in enumerate(LAYERS) for name in names}
LAZY_OK = {'throwmap.plots', 'matplotlib', 'matplotlib.pyplot',   # heavy, optional
           'distributed'}
# The simulator core and the models: they run effects through hooks, never by name.
CORE = ('ballistic', 'catch', 'event_sim', 'pipeline', 'compose', 'model', 'scene', 'orbits',
        'basins', 'sensor', 'analysis_cache', 'analysis', 'part_on_arm', 'design', 'robustness')


def modules():
    """Yield (dotted name, path) of every module of the package (not the generated ones)."""
    for path in sorted(PKG.rglob('*.py')):
        if '__pycache__' in path.parts:
            continue
        rel = path.relative_to(PKG.parent).with_suffix('')
        parts = rel.parts[:-1] if rel.parts[-1] == '__init__' else rel.parts
        yield '.'.join(parts), path


def layer_of(dotted):
    parts = dotted.split('.')
    return LAYER['__init__'] if len(parts) == 1 else LAYER[parts[1]]


def imports(dotted, path):
    """Return [(imported module, line, inside a function)] of one module (relative resolved)."""
    tree = ast.parse(path.read_text(encoding='utf-8'))
    package = dotted.split('.') if path.name == '__init__.py' else dotted.split('.')[:-1]
    found = []

    def visit(node, in_function):
        for child in ast.iter_child_nodes(node):
            inside = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef,
                                                       ast.Lambda))
            if isinstance(child, ast.Import):
                found.extend((a.name, child.lineno, inside) for a in child.names)
            elif isinstance(child, ast.ImportFrom):
                base = package[:len(package) - child.level + 1] if child.level else []
                mod = '.'.join(base + ([child.module] if child.module else []))
                # `from . import a`: the names are modules; `from .m import a`: module m.
                names = [f'{mod}.{a.name}' for a in child.names] if not child.module else [mod]
                found.extend((name, child.lineno, inside) for name in names)
            visit(child, inside)

    visit(tree, False)
    return found


def own(module):
    """Return the throwmap module an import refers to (a name in a module: that module)."""
    parts = module.split('.')
    if parts[0] != 'throwmap':
        return None
    if len(parts) >= 3 and parts[1] == 'effects':
        return '.'.join(parts[:3])
    return '.'.join(parts[:2])


def violations(dotted, path):
    """Return what is wrong with one module's imports (empty: nothing)."""
    bad = []
    here = layer_of(dotted)
    for module, line, inside in imports(dotted, path):
        where = f'{path.name}:{line}'
        if inside and module not in LAZY_OK:
            bad.append(f'{where} imports {module} inside a function')
        target = own(module)
        if target is None or target == dotted or dotted == 'throwmap':
            continue
        if target == 'throwmap.effects._common' and dotted.startswith('throwmap.effects'):
            continue
        if dotted == 'throwmap.effects' and target.startswith('throwmap.effects.'):
            continue        # the registry and its helpers
        if dotted == 'throwmap.cli' and target == 'throwmap.plots' and inside:
            continue        # matplotlib only when plotting
        if layer_of(target) >= here:
            bad.append(f'{where} imports {target} (layer {layer_of(target)} >= {here})')
    return bad


def test_every_module_has_a_layer():
    missing = [d for d, _ in modules() if '.' in d and d.split('.')[1] not in LAYER]
    assert not missing, f'place these modules in LAYERS (test_structure.py): {missing}'


def test_imports_go_down_the_layers_and_none_hides_in_a_function():
    bad = [v for dotted, path in modules() for v in violations(dotted, path)]
    assert not bad, '\n'.join(bad)


def test_the_check_sees_an_upward_import_and_a_hidden_one(tmp_path):
    path = tmp_path / 'ballistic.py'
    path.write_text('from .status import OK\n\n\ndef f():\n    from .scene import Scene\n'
                    '    return Scene\n\n\nfrom .model import ThrowModel\n')
    bad = violations('throwmap.ballistic', path)
    assert len(bad) == 3 and 'inside a function' in bad[0] and 'throwmap.scene' in bad[1]
    assert 'throwmap.model' in bad[2]


def registry_names():
    tree = ast.parse((PKG / 'effects' / '__init__.py').read_text(encoding='utf-8'))
    for node in tree.body:
        if isinstance(node, ast.Assign) and node.targets[0].id == 'REGISTRY':
            return [e.value for e in node.value.elts]
    raise AssertionError('no REGISTRY in throwmap/effects/__init__.py')


def code_words(path):
    """Return the identifiers and string constants of a module, docstrings left out."""
    tree = ast.parse(path.read_text(encoding='utf-8'))
    docstrings = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.ClassDef)) and node.body and \
                isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value,
                                                                  ast.Constant):
            docstrings.add(id(node.body[0].value))
    words = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            words.add(node.id)
        elif isinstance(node, ast.Attribute):
            words.add(node.attr)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and \
                id(node) not in docstrings:
            words.update(re.findall(r'[A-Za-z_]+', node.value))
    return words


def test_the_core_names_no_effect():
    names = set(registry_names())
    bad = {m: sorted(names & code_words(PKG / f'{m}.py')) for m in CORE}
    assert not any(bad.values()), f'effects named in the core: {bad}'


def test_a_scene_compiles_only_the_effects_it_names():
    text = composed_source({'finite_arm': ('check',)})
    others = [n for n in registry_names() if n != 'finite_arm' and n in text]
    assert not others and 'fx_finite_arm.check' in text and 'event_sim.build' not in text
    model = load_scene(str(SCENES / 'experiment.yaml')).model
    loaded = sorted(k for k in vars(model.composed) if k.startswith('fx_'))
    assert loaded == ['fx_backplate_friction', 'fx_finite_arm']


def _parameters(fn):
    return ', '.join(inspect.signature(getattr(fn, 'py_func', fn)).parameters)


def test_the_slot_table_is_the_one_place_a_hook_is_declared():
    # Every hook an effect fills, and every default, takes the arguments its slot declares;
    # the event slots are event_sim.build's parameters, in order.
    assert SLOTS == tuple(SLOT_TABLE)
    assert tuple(inspect.signature(event_sim.build).parameters) == EVENT_SLOTS
    homes = {'pipeline': pipeline, 'event_sim': event_sim}
    for name, slot in SLOT_TABLE.items():
        home, attr = slot.default.split('.')
        assert _parameters(getattr(homes[home], attr)) == slot.signature, name
        for module in MODULES.values():
            if hasattr(module, name):
                assert _parameters(getattr(module, name)) == slot.signature, (module, name)
    # A hook with another signature is seen.
    assert _parameters(lambda w, h, z0, prm: None) != SLOT_TABLE['perturb'].signature
