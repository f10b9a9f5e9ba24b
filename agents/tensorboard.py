"""TensorBoard event files without the tensorboard package.

stable-baselines3 writes TensorBoard logs through ``torch.utils.tensorboard``, which
needs the ``tensorboard`` package (and its protobuf, grpc and web-server
dependencies) just to *write* a file. An event file is simple: a sequence of
TFRecord frames, each holding one protobuf ``Event``. This module writes scalar
events by hand, so training logs open in any TensorBoard without the project
depending on it.

Formats, from their public specifications:

- TFRecord frame: ``uint64 length``, ``uint32 masked_crc32c(length)``, the data,
  ``uint32 masked_crc32c(data)``, little-endian; ``masked(c) = ((c >> 15 | c << 17)
  + 0xa282ead8) mod 2³²``.
- ``Event``: ``wall_time`` (field 1, double), ``step`` (2, int64), ``file_version``
  (3, string) or ``summary`` (5, message); ``Summary.value`` (1, repeated);
  ``Value.tag`` (1, string), ``Value.simple_value`` (2, float).
"""

from __future__ import annotations

import socket
import struct
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.logger import KVWriter

__all__ = ["EventFileWriter", "TensorBoardOutput", "crc32c", "read_scalars"]


def _crc32c_table() -> list[int]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0x82F63B78 if crc & 1 else crc >> 1
        table.append(crc)
    return table


_TABLE = _crc32c_table()


def crc32c(data: bytes) -> int:
    """CRC-32C (Castagnoli), as TFRecord frames use."""
    crc = 0xFFFFFFFF
    for byte in data:
        crc = _TABLE[(crc ^ byte) & 0xFF] ^ (crc >> 8)
    return crc ^ 0xFFFFFFFF


def _masked(crc: int) -> int:
    return (((crc >> 15) | (crc << 17)) + 0xA282EAD8) & 0xFFFFFFFF


def _varint(value: int) -> bytes:
    out = bytearray()
    value &= (1 << 64) - 1
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def _field(number: int, wire: int) -> bytes:
    return _varint(number << 3 | wire)


def _length_delimited(number: int, payload: bytes) -> bytes:
    return _field(number, 2) + _varint(len(payload)) + payload


def _event(wall_time: float, step: int, body: bytes) -> bytes:
    return _field(1, 1) + struct.pack("<d", wall_time) + _field(2, 0) + _varint(step) + body


def _scalar_summary(values: Mapping[str, float]) -> bytes:
    summary = b"".join(
        _length_delimited(
            1, _length_delimited(1, tag.encode()) + _field(2, 5) + struct.pack("<f", value)
        )
        for tag, value in values.items()
    )
    return _length_delimited(5, summary)


class EventFileWriter:
    """Appends scalar events to ``events.out.tfevents.<time>.<host>`` in ``folder``."""

    def __init__(self, folder: str | Path) -> None:
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        now = time.time()
        self.path = folder / f"events.out.tfevents.{int(now)}.{socket.gethostname()}"
        self._file = self.path.open("ab")
        self._record(_event(now, 0, _length_delimited(3, b"brain.Event:2")))

    def _record(self, data: bytes) -> None:
        header = struct.pack("<Q", len(data))
        self._file.write(header + struct.pack("<I", _masked(crc32c(header))))
        self._file.write(data + struct.pack("<I", _masked(crc32c(data))))

    def scalars(self, values: Mapping[str, float], step: int) -> None:
        if values:
            self._record(_event(time.time(), step, _scalar_summary(values)))
            self._file.flush()

    def close(self) -> None:
        self._file.close()


class TensorBoardOutput(KVWriter):
    """stable-baselines3 logger output writing every numeric value as a scalar."""

    def __init__(self, folder: str | Path) -> None:
        self.writer = EventFileWriter(folder)

    def write(
        self,
        key_values: dict[str, Any],
        key_excluded: dict[str, tuple[str, ...]],
        step: int = 0,
    ) -> None:
        scalars = {
            key: float(value)
            for key, value in key_values.items()
            if isinstance(value, int | float | np.number)
            and not isinstance(value, bool)
            and "tensorboard" not in (key_excluded.get(key) or ())
        }
        self.writer.scalars(scalars, step)

    def close(self) -> None:
        self.writer.close()


def _read_varint(data: bytes, pos: int) -> tuple[int, int]:
    shift = value = 0
    while True:
        byte = data[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if not byte & 0x80:
            return value, pos


def _fields(data: bytes) -> list[tuple[int, int, Any]]:
    fields, pos = [], 0
    while pos < len(data):
        key, pos = _read_varint(data, pos)
        number, wire = key >> 3, key & 7
        value: Any
        if wire == 0:
            value, pos = _read_varint(data, pos)
        elif wire == 1:
            value, pos = data[pos : pos + 8], pos + 8
        elif wire == 5:
            value, pos = data[pos : pos + 4], pos + 4
        elif wire == 2:
            size, pos = _read_varint(data, pos)
            value, pos = data[pos : pos + size], pos + size
        else:
            raise ValueError(f"unsupported protobuf wire type {wire}")
        fields.append((number, wire, value))
    return fields


def read_scalars(path: str | Path) -> dict[str, list[tuple[int, float]]]:
    """Every scalar in an event file, tag → [(step, value)], checking each frame's
    checksums (``ValueError`` on a corrupt file)."""
    data = Path(path).read_bytes()
    out: dict[str, list[tuple[int, float]]] = {}
    pos = 0
    while pos < len(data):
        header = data[pos : pos + 8]
        (length,) = struct.unpack("<Q", header)
        (header_crc,) = struct.unpack("<I", data[pos + 8 : pos + 12])
        record = data[pos + 12 : pos + 12 + length]
        (record_crc,) = struct.unpack("<I", data[pos + 12 + length : pos + 16 + length])
        if header_crc != _masked(crc32c(header)) or record_crc != _masked(crc32c(record)):
            raise ValueError(f"{path}: corrupt record at byte {pos}")
        pos += 16 + length
        event = {number: value for number, _, value in _fields(record)}
        if 5 not in event:
            continue
        for number, _, value in _fields(event[5]):
            if number != 1:
                continue
            parts = {n: v for n, _, v in _fields(value)}
            tag = parts[1].decode()
            out.setdefault(tag, []).append((int(event[2]), struct.unpack("<f", parts[2])[0]))
    return out
