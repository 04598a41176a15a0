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
rosbag2 MCAP bags as ``ros2 bag record`` writes them (ROS-free: the recorder feeds CDR bytes).

A bag is a directory with ``metadata.yaml`` (rosbag2 format version 9, ``ros_distro:
kilted``) and one ``.mcap`` file laid out as rosbag2_storage_mcap writes it: profile ``ros2``,
one ``ros2msg`` schema per type (the full definition with its dependencies, from the rosbags
Kilted type store, into which a type it lacks, such as feeder_interfaces/msg/Verdict, is read
from its package's installed ``.msg`` file: ``installed_types``), one ``cdr`` channel per
topic whose metadata carries ``offered_qos_profiles`` (so a latched topic is replayed latched)
and ``topic_type_hash`` (the RIHS01 hash of the type), messages with ``log_time`` = receive
time and ``publish_time`` = send time, and a ``rosbag2`` metadata record holding the
serialized bag metadata.

A bag survives its writer being killed (SIGKILL, a crash): messages are held in memory for at
most one flush period (``BagWriter.flush``, the recorder calls it on a timer), and every flush
appends the finished chunk with its message indexes, then a provisional end (DataEnd and a
footer without a summary, which MCAP readers and rosbags accept by scanning the file), in one
write, then rewrites ``metadata.yaml``. The next flush writes over the provisional end. So at
any moment the directory is a readable bag holding all but the last flush period's messages.
``close`` writes the real end: the ``rosbag2`` metadata record, the summary (schemas, channels,
statistics, chunk and metadata indexes) and the footer. ``reindex`` (``bag_reindex BAG``, like
``ros2 bag reindex``) rebuilds ``metadata.yaml`` from the ``.mcap`` and gives an ``.mcap``
without a summary (a killed writer's, or one cut off mid-record) a summary and footer.
"""

from collections import defaultdict
import io
import os
import pathlib
import struct
import sys
import zlib

from mcap.data_stream import ReadDataStream, RecordBuilder
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import (Channel, Chunk, ChunkIndex, DataEnd, Footer, Header, MessageIndex,
                          Metadata, MetadataIndex, Schema, Statistics, SummaryOffset)
from rosbags.interfaces import (Nodetype, Qos, QosDurability, QosHistory, QosLiveliness,
                                QosReliability, QosTime)
from rosbags.rosbag2.metadata import dump_qos_v9
from rosbags.typesys import get_types_from_msg, get_typestore, Stores, TypesysError
import yaml

VERSION = 9
ROS_DISTRO = 'kilted'
LIBRARY = 'feeder bag_recorder (rosbag2_storage_mcap layout)'
MAGIC = b'\x89MCAP0\r\n'
# A chunk is written when a flush comes or when it holds this much (rosbag2's default size).
CHUNK_BYTES = 1 << 20
# Message record head: opcode, record length, channel, sequence, log time, publish time.
_MESSAGE = struct.Struct('<BQHIQQ')
_RECORD_HEAD = struct.Struct('<BQ')
_DUMPER = getattr(yaml, 'CSafeDumper', yaml.SafeDumper)


def qos_time(nanoseconds):
    """Convert a duration in ns to QosTime (rosbag2: infinite = 9223372036 s 854775807 ns)."""
    sec, nsec = divmod(int(nanoseconds), 1_000_000_000)
    return QosTime(sec, nsec)


def qos(history, depth, reliability, durability, deadline_ns=0, lifespan_ns=0, liveliness=0,
        lease_ns=0, avoid_ros_namespace_conventions=False):
    """Build a rosbags Qos from rmw enum values (the same integers rclpy's policies use)."""
    return Qos(QosHistory(int(history)), int(depth), QosReliability(int(reliability)),
               QosDurability(int(durability)), qos_time(deadline_ns), qos_time(lifespan_ns),
               QosLiveliness(int(liveliness)), qos_time(lease_ns),
               bool(avoid_ros_namespace_conventions))


def _yaml(data):
    return yaml.dump(data, Dumper=_DUMPER, default_flow_style=False, sort_keys=False)


def _record(rec):
    """Return the bytes of one MCAP record (the mcap library's encoding)."""
    builder = RecordBuilder()
    rec.write(builder)
    return builder.end()


def _provisional_end():
    """Return a DataEnd and a footer without summary (readers scan the data section)."""
    return (_record(DataEnd(data_section_crc=0))
            + _record(Footer(summary_start=0, summary_offset_start=0, summary_crc=0)) + MAGIC)


def installed_msg_file(msgtype):
    """
    Return the installed ``.msg`` file of 'pkg/msg/Type' (share/pkg/msg/Type.msg), or None.

    Looked up in the ament index (AMENT_PREFIX_PATH: the colcon install, the venv, /opt/ros),
    where rosidl_generate_interfaces installs every message's source text.
    """
    parts = msgtype.split('/')
    if len(parts) != 3 or parts[1] != 'msg' or not all(parts):
        return None
    from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
    try:
        share = pathlib.Path(get_package_share_directory(parts[0]))
    except (PackageNotFoundError, LookupError, OSError, ValueError):
        return None
    path = share / 'msg' / f'{parts[2]}.msg'
    return path if path.is_file() else None


def _named_types(fielddesc):
    """Yield the message types a rosbags field description refers to (nested in arrays)."""
    kind, rest = fielddesc
    if kind == Nodetype.NAME:
        yield rest
    elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        yield from _named_types(rest[0])


def installed_types(typestore, msgtype):
    """
    Add ``msgtype`` and the types it uses to ``typestore`` from their installed ``.msg`` files.

    Only types the store lacks are read. Returns True if ``msgtype`` is in the store afterwards,
    False if it or a type it uses has no installed definition (or one that does not parse).
    """
    found = {}
    todo = [msgtype]
    while todo:
        name = todo.pop()
        if name in typestore.fielddefs or name in found:
            continue
        path = installed_msg_file(name)
        if path is None:
            return False
        try:
            types = get_types_from_msg(path.read_text(), name)
        except TypesysError:
            return False
        found.update(types)
        for _, fields in types.values():
            todo.extend(t for _, desc in fields for t in _named_types(desc))
    typestore.register(found)
    return msgtype in typestore.fielddefs


class BagError(Exception):
    """A bag that cannot be read or repaired; the text says what and where."""


class McapLog:
    """
    An MCAP file that is a readable MCAP after every ``flush``.

    The data section holds schema and channel records (outside chunks, so a channel is on disk
    before its first chunk) and unindexed-compression chunks, each followed by its message
    indexes. ``data_end`` is where the provisional end starts (the next write goes there).
    """

    def __init__(self, stream, data_end):
        self._stream = stream
        self.data_end = data_end
        self.schemas = {}
        self.channels = {}
        self.stats = {}                 # channel id -> [count, first log time, last log time]
        self.chunk_indexes = []         # ChunkIndex records, encoded once written (bytes)
        self.metadata_indexes = []
        self.metadata_names = set()
        self._pending = bytearray()     # schema/channel records for the next write
        self._chunk = bytearray()
        self._index = defaultdict(list)
        self._chunk_times = None        # [start, end] of the chunk in memory
        self._last_entries = {}         # message index entries of the last chunk read

    @classmethod
    def create(cls, path, profile, library):
        stream = open(path, 'xb', buffering=0)
        head = MAGIC + _record(Header(profile=profile, library=library))
        log = cls(stream, len(head))
        log._write_at(0, head + _provisional_end())
        return log

    def _write_at(self, offset, data):
        self._stream.seek(offset)
        view = memoryview(data)
        while view:
            view = view[self._stream.write(view):]

    def add_schema(self, name, encoding, data):
        schema_id = len(self.schemas) + 1
        self.schemas[schema_id] = Schema(id=schema_id, name=name, encoding=encoding, data=data)
        self._pending += _record(self.schemas[schema_id])
        return schema_id

    def add_channel(self, topic, schema_id, message_encoding, metadata):
        channel_id = len(self.channels) + 1
        self.channels[channel_id] = Channel(id=channel_id, topic=topic, schema_id=schema_id,
                                            message_encoding=message_encoding,
                                            metadata=metadata)
        self.stats[channel_id] = [0, None, None]
        self._pending += _record(self.channels[channel_id])
        return channel_id

    def add_message(self, channel_id, log_time, data, publish_time, sequence):
        """Append one message to the chunk in memory (the hot path: no record objects)."""
        chunk = self._chunk
        self._index[channel_id].append((log_time, len(chunk)))
        chunk += _MESSAGE.pack(Opcode.MESSAGE, 22 + len(data), channel_id, sequence, log_time,
                               publish_time)
        chunk += data
        st = self.stats[channel_id]
        if st[0]:
            if log_time < st[1]:
                st[1] = log_time
            elif log_time > st[2]:
                st[2] = log_time
        else:
            st[1] = st[2] = log_time
        st[0] += 1
        times = self._chunk_times
        if times is None:
            self._chunk_times = [log_time, log_time]
        elif log_time < times[0]:
            times[0] = log_time
        elif log_time > times[1]:
            times[1] = log_time
        if len(chunk) >= CHUNK_BYTES:
            self.flush()

    def _take_chunk(self, out):
        """Append the chunk in memory and its message indexes to ``out``; return its index."""
        data = bytes(self._chunk)
        start, end = self._chunk_times
        chunk_start = self.data_end + len(out)
        rec = _record(Chunk(compression='', data=data, message_start_time=start,
                            message_end_time=end, uncompressed_crc=zlib.crc32(data),
                            uncompressed_size=len(data)))
        out += rec
        index_start = self.data_end + len(out)
        offsets = {}
        for channel_id, entries in sorted(self._index.items()):
            offsets[channel_id] = self.data_end + len(out)
            out += _record(MessageIndex(channel_id=channel_id, records=entries))
        self._chunk = bytearray()
        self._index = defaultdict(list)
        self._chunk_times = None
        return ChunkIndex(message_start_time=start, message_end_time=end,
                          chunk_start_offset=chunk_start, chunk_length=len(rec),
                          message_index_offsets=offsets,
                          message_index_length=self.data_end + len(out) - index_start,
                          compression='', compressed_size=len(data),
                          uncompressed_size=len(data))

    def flush(self):
        """Put everything held in memory on disk, then a provisional end; False if none."""
        out = self._pending
        self._pending = bytearray()
        if self._chunk:
            # Kept encoded until the summary: a ChunkIndex object costs about 4 times its
            # bytes, and a recorder holds one per flush for the whole bag.
            self.chunk_indexes.append(_record(self._take_chunk(out)))
        if not out:
            return False
        # One write: a kill leaves either the old provisional end or the new one intact
        # (or, mid-write, a cut record that reindex drops).
        self._write_at(self.data_end, out + _provisional_end())
        self.data_end += len(out)
        return True

    @property
    def message_count(self):
        return sum(st[0] for st in self.stats.values())

    def finish(self, metadata=()):
        """Write the metadata records, DataEnd, the summary and the footer; close the file."""
        self.flush()
        out = bytearray()
        for name, values in metadata:
            rec = _record(Metadata(name=name, metadata=values))
            self.metadata_indexes.append(MetadataIndex(offset=self.data_end + len(out),
                                                       length=len(rec), name=name))
            self.metadata_names.add(name)
            out += rec
        out += _record(DataEnd(data_section_crc=0))
        summary_start = self.data_end + len(out)
        summary = bytearray()
        offsets = []
        counted = [st for st in self.stats.values() if st[0]]
        stats = Statistics(
            message_count=self.message_count, schema_count=len(self.schemas),
            channel_count=len(self.channels), attachment_count=0,
            metadata_count=len(self.metadata_indexes), chunk_count=len(self.chunk_indexes),
            message_start_time=min((st[1] for st in counted), default=0),
            message_end_time=max((st[2] for st in counted), default=0),
            channel_message_counts={c: st[0] for c, st in self.stats.items()})
        for opcode, records in ((Opcode.SCHEMA, self.schemas.values()),
                                (Opcode.CHANNEL, self.channels.values()),
                                (Opcode.STATISTICS, [stats]),
                                (Opcode.CHUNK_INDEX, self.chunk_indexes),
                                (Opcode.METADATA_INDEX, self.metadata_indexes)):
            group = b''.join(r if isinstance(r, bytes) else _record(r) for r in records)
            if group:
                offsets.append(SummaryOffset(group_opcode=opcode,
                                             group_start=summary_start + len(summary),
                                             group_length=len(group)))
                summary += group
        summary_offset_start = summary_start + len(summary)
        for offset in offsets:
            summary += _record(offset)
        crc = zlib.crc32(summary)
        crc = zlib.crc32(_RECORD_HEAD.pack(Opcode.FOOTER, 20)
                         + struct.pack('<QQ', summary_start, summary_offset_start), crc)
        out += summary + _record(Footer(summary_start=summary_start,
                                        summary_offset_start=summary_offset_start,
                                        summary_crc=crc)) + MAGIC
        self._write_at(self.data_end, out)
        self._stream.truncate(self.data_end + len(out))
        self._stream.close()

    def close(self):
        """Close the file as it stands (flushed data and the provisional end stay readable)."""
        self._stream.close()

    @classmethod
    def recover(cls, path):
        """
        Read an MCAP file's data section record by record.

        Returns (log, complete, dropped): a McapLog positioned to write the end after the last
        whole record, whether the file already has its summary and footer, and how many bytes
        after the last whole record are unusable (a record cut off by a kill).
        """
        with open(path, 'rb') as reader:
            log, complete, dropped = cls._scan(reader, os.fstat(reader.fileno()).st_size)
        # A killed writer leaves at most one flush's write cut off; more is damage, not that.
        if dropped > 2 * CHUNK_BYTES + (1 << 20):
            raise BagError(f'cannot be read after byte {log.data_end} ({dropped} bytes follow, '
                           'more than a killed writer leaves); not repaired')
        log._stream = open(path, 'r+b', buffering=0)
        return log, complete, dropped

    @classmethod
    def _scan(cls, reader, size):
        if reader.read(8) != MAGIC:
            raise BagError('does not start with the MCAP magic bytes (not an MCAP file)')
        head = reader.read(9)
        if len(head) < 9 or head[0] != Opcode.HEADER or 17 + _RECORD_HEAD.unpack(head)[1] > size:
            raise BagError('ends inside its header record: it holds no messages to recover')
        reader.read(_RECORD_HEAD.unpack(head)[1])
        pos = 17 + _RECORD_HEAD.unpack(head)[1]
        log = cls(None, pos)
        last_chunk = None
        data_end = None
        while True:
            head = reader.read(9)
            if len(head) < 9:
                break
            opcode, length = _RECORD_HEAD.unpack(head)
            if pos + 9 + length > size:
                break
            body = reader.read(length)
            if opcode == Opcode.DATA_END or opcode == Opcode.FOOTER:
                data_end = pos
                break
            try:
                last_chunk = log._scan_record(opcode, head, body, pos, last_chunk)
            except (struct.error, UnicodeDecodeError, ValueError, McapError):
                break           # a record cut off by a kill, its length field intact
            pos += 9 + length
        log.data_end = pos if data_end is None else data_end
        if data_end is None and last_chunk is not None:
            log._reindex_last_chunk(last_chunk)
        complete = False
        if data_end is not None and size >= 8 + 37:
            reader.seek(size - 37)
            tail = reader.read(37)
            footer = Footer.read(ReadDataStream(io.BytesIO(tail[9:29])))
            complete = tail[:1] == bytes([Opcode.FOOTER]) and tail[-8:] == MAGIC and \
                footer.summary_start != 0
        return log, complete, 0 if data_end is not None else size - pos

    def _scan_record(self, opcode, head, body, pos, last_chunk):
        """Take in one data-section record; return the chunk its message indexes belong to."""
        if opcode == Opcode.CHUNK:
            chunk = Chunk.read(ReadDataStream(io.BytesIO(body)))
            if chunk.compression:
                raise BagError(f'has a {chunk.compression} compressed chunk at byte {pos}; '
                               'reindex reads uncompressed bags (what bag_recorder writes)')
            if chunk.uncompressed_crc and zlib.crc32(chunk.data) != chunk.uncompressed_crc:
                raise ValueError(f'damaged chunk at byte {pos}')
            self._last_entries = self._scan_records(chunk.data)
            index = ChunkIndex(
                message_start_time=chunk.message_start_time,
                message_end_time=chunk.message_end_time, chunk_start_offset=pos,
                chunk_length=9 + len(body), message_index_offsets={}, message_index_length=0,
                compression='', compressed_size=len(chunk.data),
                uncompressed_size=chunk.uncompressed_size)
            self.chunk_indexes.append(index)
            return index
        if opcode == Opcode.MESSAGE_INDEX and last_chunk is not None:
            channel_id = struct.unpack_from('<H', body)[0]
            last_chunk.message_index_offsets[channel_id] = pos
            last_chunk.message_index_length += 9 + len(body)
            return last_chunk
        if opcode == Opcode.METADATA:
            name = Metadata.read(ReadDataStream(io.BytesIO(body))).name
            self.metadata_indexes.append(MetadataIndex(offset=pos, length=9 + len(body),
                                                       name=name))
            self.metadata_names.add(name)
        else:
            self._scan_records(head + body)
        return None

    def _reindex_last_chunk(self, index):
        """Give the last chunk all its message indexes again if the cut took some of them."""
        if set(index.message_index_offsets) == set(self._last_entries):
            return
        self.data_end = index.chunk_start_offset + index.chunk_length
        self._pending = bytearray()
        index.message_index_offsets = {}
        for channel_id, entries in sorted(self._last_entries.items()):
            index.message_index_offsets[channel_id] = self.data_end + len(self._pending)
            self._pending += _record(MessageIndex(channel_id=channel_id, records=entries))
        index.message_index_length = len(self._pending)

    def _scan_records(self, data):
        """
        Count the schema, channel and message records in ``data`` (a chunk's or one).

        Returns the message index entries {channel: [(log time, offset)]} of ``data``.
        """
        entries = defaultdict(list)
        view = memoryview(data)
        pos = 0
        while pos + 9 <= len(view):
            opcode, length = _RECORD_HEAD.unpack_from(view, pos)
            body = view[pos + 9:pos + 9 + length]
            if opcode == Opcode.MESSAGE:
                channel_id, _, log_time = struct.unpack_from('<HIQ', body)
                entries[channel_id].append((log_time, pos))
                st = self.stats.setdefault(channel_id, [0, None, None])
                st[1] = log_time if st[0] == 0 else min(st[1], log_time)
                st[2] = log_time if st[0] == 0 else max(st[2], log_time)
                st[0] += 1
            elif opcode == Opcode.SCHEMA:
                schema = Schema.read(ReadDataStream(io.BytesIO(body)))
                self.schemas[schema.id] = schema
            elif opcode == Opcode.CHANNEL:
                channel = Channel.read(ReadDataStream(io.BytesIO(body)))
                self.channels[channel.id] = channel
                self.stats.setdefault(channel.id, [0, None, None])
            pos += 9 + length
        return entries


def bag_metadata(log, file_name, qos_cache=None):
    """Return the ``rosbag2_bagfile_information`` (version 9) of what ``log`` holds."""
    qos_cache = {} if qos_cache is None else qos_cache
    topics = []
    times = []
    for channel_id, channel in log.channels.items():
        count, first, last = log.stats.get(channel_id, (0, None, None))
        if count:
            times.append((first, last))
        if channel_id not in qos_cache:
            qos_cache[channel_id] = yaml.safe_load(
                channel.metadata.get('offered_qos_profiles', '')) or []
        schema = log.schemas.get(channel.schema_id)
        topics.append({'topic_metadata': {
            'name': channel.topic, 'type': schema.name if schema else '',
            'serialization_format': channel.message_encoding,
            'offered_qos_profiles': qos_cache[channel_id],
            'type_description_hash': channel.metadata.get('topic_type_hash', '')},
            'message_count': count})
    start = min(a for a, _ in times) if times else 0
    duration = max(b for _, b in times) - start if times else 0
    count = sum(t['message_count'] for t in topics)
    return {
        'version': VERSION,
        'storage_identifier': 'mcap',
        'duration': {'nanoseconds': duration},
        'starting_time': {'nanoseconds_since_epoch': start},
        'message_count': count,
        'topics_with_message_count': topics,
        'compression_format': '',
        'compression_mode': '',
        'relative_file_paths': [file_name],
        'files': [{'path': file_name,
                   'starting_time': {'nanoseconds_since_epoch': start},
                   'duration': {'nanoseconds': duration},
                   'message_count': count}],
        'custom_data': {},
        'ros_distro': ROS_DISTRO,
    }


def _write_metadata_yaml(bag_dir, info):
    """Replace metadata.yaml atomically (a reader never sees half a file)."""
    tmp = bag_dir / 'metadata.yaml.tmp'
    tmp.write_text(_yaml({'rosbag2_bagfile_information': info}))
    os.replace(tmp, bag_dir / 'metadata.yaml')


class BagWriter:
    """A rosbag2 MCAP directory being written: topics, then serialized CDR messages."""

    def __init__(self, path):
        self.path = pathlib.Path(path)
        if self.path.exists():
            raise FileExistsError(f'{self.path} exists; give a new directory for the bag')
        self.path.mkdir(parents=True)
        self.typestore = get_typestore(Stores.ROS2_KILTED)
        self.file_name = f'{self.path.name}.mcap'
        # rosbag2's defaults: chunked, no compression.
        self._log = McapLog.create(self.path / self.file_name, 'ros2', LIBRARY)
        self._schemas = {}
        self._channels = {}
        self._qos_cache = {}
        self._last_log_time = 0
        self.closed = False
        _write_metadata_yaml(self.path, self.metadata())

    def knows(self, msgtype):
        """
        Whether ``msgtype`` (e.g. 'std_msgs/msg/Bool') can be recorded with its definition.

        That is: the Kilted type store has it, or its package is installed (then it is read
        into the store from its ``.msg`` file, with the types it uses).
        """
        return msgtype in self.typestore.fielddefs or installed_types(self.typestore, msgtype)

    def type_hash(self, msgtype):
        """RIHS01 hash of ``msgtype`` from the type store (what the type's .json file says)."""
        return self.typestore.hash_rihs01(msgtype)

    def add_topic(self, topic, msgtype, offered_qos=(), type_hash=None):
        """
        Add a topic with its publishers' QoS profiles (rosbags Qos) and type hash.

        ``type_hash`` is the hash the publishers announced (rosbag2 records that one); None:
        the type store's.
        """
        if topic in self._channels:
            raise ValueError(f'{topic} is already in the bag')
        if not self.knows(msgtype):
            raise ValueError(f'{msgtype} is neither in the Kilted type store nor an installed '
                             'message (share/<pkg>/msg/<Type>.msg on AMENT_PREFIX_PATH): build '
                             'and source the package that defines it')
        if msgtype not in self._schemas:
            msgdef, _ = self.typestore.generate_msgdef(msgtype, ros_version=2)
            self._schemas[msgtype] = self._log.add_schema(msgtype, 'ros2msg', msgdef.encode())
        profiles = dump_qos_v9(list(offered_qos))
        channel_id = self._log.add_channel(
            topic, self._schemas[msgtype], 'cdr',
            {'offered_qos_profiles': _yaml(profiles).strip(),
             'topic_type_hash': type_hash or self.type_hash(msgtype)})
        self._qos_cache[channel_id] = profiles
        self._channels[topic] = channel_id

    def write(self, topic, log_time_ns, data, publish_time_ns=None, sequence=0):
        """
        Write one serialized message (times: received, sent; int ns).

        The log time never goes back (a message received before the previous one but handed
        over after it is logged at the previous one's time): a killed writer's .mcap has no
        index, and readers of unindexed MCAP (rosbags) require log-time order.
        """
        log_time_ns = max(int(log_time_ns), self._last_log_time)
        self._last_log_time = log_time_ns
        self._log.add_message(self._channels[topic], log_time_ns, data,
                              log_time_ns if publish_time_ns is None else int(publish_time_ns),
                              int(sequence) & 0xFFFFFFFF)

    def flush(self):
        """Put the messages held in memory on disk and bring metadata.yaml up to date."""
        if not self.closed and self._log.flush():
            _write_metadata_yaml(self.path, self.metadata())

    @property
    def counts(self):
        return {topic: self._log.stats[c][0] for topic, c in self._channels.items()}

    @property
    def total(self):
        return self._log.message_count

    def metadata(self):
        """Return the ``rosbag2_bagfile_information`` of the bag so far (version 9)."""
        return bag_metadata(self._log, self.file_name, self._qos_cache)

    def close(self):
        """Finish the MCAP file (summary, metadata record) and write metadata.yaml."""
        if self.closed:
            return
        self.closed = True
        info = self.metadata()
        self._log.finish([('rosbag2', {'serialized_metadata': _yaml(info)})])
        _write_metadata_yaml(self.path, info)


def reindex(bag_dir):
    """
    Rebuild a bag's metadata.yaml from its .mcap, finishing an .mcap that has no summary.

    Like ``ros2 bag reindex``. An .mcap left by a killed writer (a provisional end, or a record
    cut off mid-write) gets the ``rosbag2`` metadata record, a summary and a footer after its
    last whole record; a finished one is only read. Returns a one-line report.
    """
    bag_dir = pathlib.Path(bag_dir)
    if not bag_dir.is_dir():
        raise BagError(f'{bag_dir}: not a bag directory')
    files = sorted(bag_dir.glob('*.mcap'))
    if len(files) != 1:
        raise BagError(f'{bag_dir}: expected one .mcap file, found {len(files)}')
    path = files[0]
    try:
        log, complete, dropped = McapLog.recover(path)
    except BagError as exc:
        raise BagError(f'{path}: {exc}') from None
    except OSError as exc:
        raise BagError(f'{path}: cannot be read ({exc.strerror})') from None
    info = bag_metadata(log, path.name)
    if complete:
        log.close()
        what = 'complete'
    else:
        extra = [] if 'rosbag2' in log.metadata_names else [
            ('rosbag2', {'serialized_metadata': _yaml(info)})]
        log.finish(extra)
        what = 'had no summary (writer killed?): summary and footer written' + (
            f', {dropped} bytes of a record cut off at its end dropped' if dropped else '')
    _write_metadata_yaml(bag_dir, info)
    return (f'{bag_dir}: {info["message_count"]} messages on '
            f'{len(info["topics_with_message_count"])} topics; {path.name} {what}; '
            'metadata.yaml rebuilt')


def reindex_main(argv=None):
    """``bag_reindex BAG_DIR ...``: rebuild metadata.yaml (and a killed writer's .mcap end)."""
    import argparse
    p = argparse.ArgumentParser(
        prog='bag_reindex', description='Rebuild metadata.yaml of rosbag2 MCAP bags from their '
        '.mcap files (like ros2 bag reindex); an .mcap without summary (its writer was killed) '
        'is finished after its last whole record.')
    p.add_argument('bags', nargs='+', metavar='BAG_DIR')
    args = p.parse_args(sys.argv[1:] if argv is None else argv)
    status = 0
    for bag in args.bags:
        try:
            print(f'bag_reindex: {reindex(bag)}', flush=True)
        except BagError as exc:
            print(f'bag_reindex: {exc}', file=sys.stderr, flush=True)
            status = 2
    return status
