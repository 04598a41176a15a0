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
The hardware stand-in's truth log (ROS-free): one JSON line per fired cycle.

The real feeder cannot say where the part lies; the hardware stand-in (standin_node) can.
Its ROS interface stays exactly the driver's, so the true state goes to a file (parameter
``truth_log``, off by default) for a run to count false readies against: a header line, then
per cycle its ``seq``, the state before and after the throw (``edge0``, ``R0``, ``edge``,
``R``; edge -1 and R null: no part on the arm), the release-speed ``setpoint`` (null: the
scene's own) and the throw's ``release_speed`` (noise included), the throw's ``kind``, the
reported sensor bit ``detected`` and the geometric ``seen`` (differs from ``detected`` only
with sensor_noise), or ``error`` for a throw that failed. The same fields as the controller
emulator's ``--truth-log`` where both have them.
"""

import json
import math


class TruthLogError(Exception):
    """The truth log cannot be opened; the text names the file and the fix."""


def _number(x):
    return None if x is None or not math.isfinite(x) else float(x)


class TruthLog:
    """Append-only JSON lines, flushed per record (a reader may follow it while the node runs)."""

    def __init__(self, path, header):
        try:
            self._file = open(path, 'w', encoding='utf-8')
        except OSError as exc:
            raise TruthLogError(f'truth_log {path!r}: cannot open it for writing '
                                f"({exc.strerror}); give a writable path, or '' for no log"
                                ) from None
        self.path = path
        self._write(dict({'type': 'header'}, **header))

    def cycle(self, seq, stamp_ns, throw=None, seen=None, error=None, setpoint=None):
        """
        Record one fired cycle: its throw (throwmap.part_on_arm.Throw) or its error text.

        ``setpoint``: the release speed it was fired at (rad/s; None: the scene's own);
        ``release_speed`` the speed the throw had (release noise included).
        """
        rec = {'type': 'cycle', 'seq': int(seq), 'stamp_ns': int(stamp_ns),
               'setpoint': _number(setpoint)}
        if throw is not None:
            rec.update(edge0=throw.edge0, R0=_number(throw.R0), edge=throw.edge,
                       R=_number(throw.R), kind=throw.kind, detected=bool(throw.detected),
                       seen=bool(seen), release_speed=_number(throw.release_speed))
        if error is not None:
            rec['error'] = str(error)
        self._write(rec)

    def _write(self, rec):
        if self._file is not None:
            self._file.write(json.dumps(rec) + '\n')
            self._file.flush()

    def close(self):
        if self._file is not None:
            self._file.close()
            self._file = None


def read_truth_log(path):
    """Return (header, {seq: cycle record}) of a truth log; a later record of a seq wins."""
    header, cycles = None, {}
    with open(path, encoding='utf-8') as f:
        for line in f:
            if not line.strip():
                continue
            rec = json.loads(line)
            if rec['type'] == 'header':
                header = rec
            else:
                cycles[rec['seq']] = rec
    return header, cycles
