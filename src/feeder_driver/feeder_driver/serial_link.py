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
Serial transport of the driver: pyserial port plus a reader thread (ROS-free).

The reader thread does blocking reads with a short timeout, feeds the protocol parser and
hands ``(generation, t_monotonic, events)`` to ``on_events``; then it sets
:attr:`SerialLink.read_until` to the time that read began (every byte that arrived before it
has been handed over: the owner judges reply deadlines on it). On a read error it calls
``on_lost(generation, error)`` once and exits. ``generation`` increases with every open,
so the owner can ignore events of a connection it has already closed. Writes happen on the
caller's thread. :meth:`close` stops and joins the reader before it closes the port.
"""

import threading
import time

import serial

from . import protocol

READ_TIMEOUT_S = 0.05
WRITE_TIMEOUT_S = 0.5


class LinkError(Exception):
    """Opening, writing or reading the port failed; the text names the port and the cause."""


class SerialLink:
    """One serial port (any pyserial URL) with a reader thread."""

    def __init__(self, port, baudrate, on_events, on_lost, read_timeout=READ_TIMEOUT_S,
                 write_timeout=WRITE_TIMEOUT_S, clock=time.monotonic):
        self.port = port
        self.baudrate = baudrate
        self._on_events = on_events
        self._on_lost = on_lost
        self._read_timeout = read_timeout
        self._write_timeout = write_timeout
        self._clock = clock
        self.parser = protocol.Parser(protocol.CONTROLLER_MESSAGES)
        self.generation = 0
        self.bytes_written = 0
        self._ser = None
        self._thread = None
        self._stop = threading.Event()
        # Start of the latest completed read (monotonic); None while closed.
        self.read_until = None

    @property
    def is_open(self):
        return self._ser is not None

    def open_port(self):
        """Open the port (exclusive), flush stale input, start the reader thread."""
        if self._ser is not None:
            self.close()
        try:
            ser = serial.serial_for_url(self.port, baudrate=self.baudrate,
                                        timeout=self._read_timeout,
                                        write_timeout=self._write_timeout, exclusive=True)
        except Exception as exc:    # noqa: B902 - any URL handler error: report, retry later
            raise LinkError(f'{self.port}: {exc}') from None
        try:
            ser.reset_input_buffer()
        except (serial.SerialException, OSError) as exc:
            ser.close()
            raise LinkError(f'{self.port}: flushing input failed: {exc}') from None
        self.generation += 1
        self.parser.reset()
        self.read_until = self._clock()     # the input before this instant was flushed
        self._ser = ser
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._reader, args=(ser, self.generation,
                                                                   self._stop),
                                        name=f'feeder-serial-{self.generation}', daemon=True)
        self._thread.start()
        return self.generation

    def write(self, data):
        """Write bytes; raises LinkError when the port is closed or the write fails."""
        ser = self._ser
        if ser is None:
            raise LinkError(f'{self.port}: port is not open')
        try:
            ser.write(data)
            ser.flush()
        except Exception as exc:    # noqa: B902 - SerialException, OSError, timeouts, ...
            raise LinkError(f'{self.port}: write failed: {exc}') from None
        self.bytes_written += len(data)

    def close(self):
        """Stop the reader thread, then close the port (safe to call twice)."""
        ser, thread = self._ser, self._thread
        self._ser = None
        self._thread = None
        if ser is None:
            return
        self._stop.set()
        try:
            ser.cancel_read()
        except (AttributeError, serial.SerialException, OSError):
            pass
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=max(1.0, 4 * self._read_timeout))
        try:
            ser.close()
        except (serial.SerialException, OSError):
            pass

    def _reader(self, ser, generation, stop):
        while not stop.is_set():
            began = self._clock()
            try:
                data = ser.read(ser.in_waiting or 1)
            except Exception as exc:    # noqa: B902 - any read failure means the link is gone
                if not stop.is_set():
                    self._on_lost(generation, f'{self.port}: read failed: {exc}')
                return
            if stop.is_set():
                return
            if data:
                events = self.parser.feed(data)
                self._on_events(generation, self._clock(), events)
            self.read_until = began
