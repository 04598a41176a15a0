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
Where a scene's throws spend their time, by compiled function: perf samples named.

perf sees numba's machine code as anonymous [JIT] addresses. This script compiles the scene's
throw kernel into a fresh numba cache (so that every linked library still holds its object
code), writes the address and size of each compiled function, attaches ``perf record`` to the
throws alone (not the compilation) and counts the samples per function and per libm routine.

    python bench/jit_profile.py rectangle [--batches 400] [--states 2000]
    python bench/jit_profile.py experiment --knobs '{"flight_method": "picard"}'

Needs Linux perf (``apt install linux-perf``). Session 38 used it to find that the
rectangle's flights spent a third of its time in the contact finder, and that two rewrites
faster in isolation were slower in the kernel (docs/accuracy.md).
"""

import argparse
import bisect
import collections
import copy
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def demangled(symbol):
    """Return 'module.function' of numba's mangled _ZN<len><part>...<len><function>B..."""
    parts, i = [], 3
    while i < len(symbol) and symbol[i].isdigit():
        j = i
        while symbol[j].isdigit():
            j += 1
        n = int(symbol[i:j])
        parts.append(symbol[j:j + n])
        i = j + n
    parts = [p for p in parts if p not in ('build', '_3clocals_3e')]
    return '.'.join(parts[-2:])


def function_table(library):
    """Return [(address, size, name)] of every compiled function ``library`` links."""
    rows, seen = [], set()

    def walk(lib):
        if id(lib) in seen:
            return
        seen.add(id(lib))
        try:
            ser = lib.serialize_using_object_code()
        except Exception:   # noqa: B902 - the runtime's library holds no object code
            ser = None
        if ser is not None:
            obj = ser[2][0] if isinstance(ser[2], tuple) else ser[2]
            with tempfile.NamedTemporaryFile(suffix='.o') as f:
                f.write(obj)
                f.flush()
                out = subprocess.run(['nm', '-S', '--defined-only', f.name],
                                     capture_output=True, text=True).stdout
            for line in out.splitlines():
                parts = line.split()
                if len(parts) == 4 and parts[2] in 'tT' and parts[3].startswith('_ZN'):
                    try:
                        address = lib.get_pointer_to_function(parts[3])
                    except Exception:   # noqa: B902 - not a function of this library
                        continue
                    rows.append((address, int(parts[1], 16), demangled(parts[3])))
        for sub in getattr(lib, '_linking_libraries', ()):
            walk(sub)

    walk(library)
    return sorted(set(rows))


def child(scene, batches, states, table_path, knobs):
    """Compile the scene's kernel, write its function table, say 'ready', run the throws."""
    sys.path.insert(0, HERE)
    from accuracy_vs_time import CONTACT_SCENES, load, PLATE_SCENES, random_states
    name, changes, (seed, r_hi), _ = {**PLATE_SCENES, **CONTACT_SCENES}.get(
        scene, (scene, {}, (0, 0.3), None))
    changes = copy.deepcopy(changes)
    if knobs:
        changes['accuracy'] = json.loads(knobs)
    model = load(name, **changes).model
    edges, radii = random_states(model, states, seed, r_hi)
    model.f_batch(edges[:2], radii[:2])
    kernel = list(model.composed.throw_many.overloads.values())[0]
    with open(table_path, 'w') as f:
        for address, size, fn in function_table(kernel.library):
            f.write(f'{address:x} {size} {fn}\n')
    print('ready', flush=True)
    t0 = time.perf_counter()
    for _ in range(batches):
        model.f_batch(edges, radii)
    print(f'{(time.perf_counter() - t0) / batches / states * 1e6:.2f} us per throw', flush=True)


def main():
    """Run the child under perf; print the samples per compiled function and libm routine."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('scene', help="a scene of scenes/ or a bench name ('rectangle', ...)")
    parser.add_argument('--batches', type=int, default=400)
    parser.add_argument('--states', type=int, default=2000)
    parser.add_argument('--knobs', default='', help="the scene's accuracy knobs, as JSON")
    parser.add_argument('--child', metavar='TABLE', help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        return child(args.scene, args.batches, args.states, args.child, args.knobs)
    with tempfile.TemporaryDirectory() as tmp:
        table, data = os.path.join(tmp, 'functions.txt'), os.path.join(tmp, 'perf.data')
        env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(tmp, 'numba'))
        proc = subprocess.Popen([sys.executable, __file__, args.scene, '--batches',
                                 str(args.batches), '--states', str(args.states),
                                 '--knobs', args.knobs, '--child', table],
                                env=env, stdout=subprocess.PIPE, text=True)
        if proc.stdout.readline().strip() != 'ready':
            sys.exit('jit_profile: the kernel did not compile')
        subprocess.run(['perf', 'record', '-q', '-F', '2000', '-p', str(proc.pid), '-o', data],
                       check=True, stderr=subprocess.DEVNULL)
        print(proc.stdout.read().strip())
        proc.wait()
        rows = [line.split() for line in open(table)]
        starts = [int(r[0], 16) for r in rows]
        out = subprocess.run(['perf', 'script', '-i', data, '-F', 'ip,sym,dso'],
                             capture_output=True, text=True).stdout
    counts, total = collections.Counter(), 0
    for line in out.splitlines():
        parts = line.split()
        if not parts:
            continue
        total += 1
        ip = int(parts[0], 16)
        i = bisect.bisect_right(starts, ip) - 1
        if i >= 0 and ip < starts[i] + int(rows[i][1]):
            counts[rows[i][2]] += 1
        else:
            counts[' '.join(parts[1:2]) or '?'] += 1
    print(f'{total} samples at 2 kHz')
    for fn, n in counts.most_common(20):
        print(f'{n:7d} {100 * n / total:5.1f} %  {fn}')


if __name__ == '__main__':
    main()
