"""Read the tensors of a TensorFlow 1 checkpoint (``NAME.index`` + ``NAME.data-*``) without TensorFlow.

The format is TensorFlow's "tensor bundle":

- ``NAME.index`` is a LevelDB-style sorted string table (SSTable): data blocks of prefix-compressed
  key/value entries, an index block pointing at them, and a 48-byte footer ending with the magic number
  ``0xdb4775248b80fb57``. Each key is a tensor name; each value is a serialised ``BundleEntryProto``
  (dtype, shape, shard id, byte offset and size in the data file, crc32c). The entry with the empty key is
  the ``BundleHeaderProto`` (number of shards, endianness).
- ``NAME.data-SSSSS-of-NNNNN`` holds the raw little-endian tensor bytes.

Only what the published Aud2Repr2Pose demo checkpoint needs is supported: uncompressed blocks, whole
(unsliced) tensors of the numeric dtypes below. Anything else raises :class:`CheckpointError` naming the
file and what was found.
"""
from __future__ import annotations

import pathlib

import numpy as np

from evalsuite.errors import InputError

__all__ = ["CheckpointError", "read_tf1_checkpoint", "resolve_checkpoint_prefix"]

_MAGIC = 0xDB4775248B80FB57
# TensorFlow DataType enum -> numpy dtype (types.proto); little-endian on disk.
_DTYPES = {1: "<f4", 2: "<f8", 3: "<i4", 4: "u1", 5: "<i2", 6: "i1", 9: "<i8", 10: "?", 19: "<f2"}


class CheckpointError(InputError):
    """A TensorFlow 1 checkpoint that cannot be read (missing file, corrupt table, unsupported tensor)."""


def _varint(buf: bytes, pos: int) -> tuple[int, int]:
    value, shift = 0, 0
    while True:
        if pos >= len(buf):
            raise ValueError("truncated varint")
        byte = buf[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return value, pos
        shift += 7
        if shift > 63:
            raise ValueError("varint longer than 64 bits")


def _proto_fields(buf: bytes) -> list[tuple[int, int | bytes]]:
    """Decode one protobuf message into (field number, value) pairs (varints, fixed and length-delimited)."""
    fields: list[tuple[int, int | bytes]] = []
    pos = 0
    while pos < len(buf):
        key, pos = _varint(buf, pos)
        number, wire = key >> 3, key & 7
        if wire == 0:
            value, pos = _varint(buf, pos)
            fields.append((number, value))
        elif wire == 1:
            fields.append((number, int.from_bytes(buf[pos:pos + 8], "little")))
            pos += 8
        elif wire == 2:
            length, pos = _varint(buf, pos)
            fields.append((number, buf[pos:pos + length]))
            pos += length
        elif wire == 5:
            fields.append((number, int.from_bytes(buf[pos:pos + 4], "little")))
            pos += 4
        else:
            raise ValueError(f"unsupported protobuf wire type {wire}")
    if pos != len(buf):
        raise ValueError("protobuf message overruns its length")
    return fields


def _block_entries(data: bytes, offset: int, size: int) -> list[tuple[bytes, bytes]]:
    """Key/value pairs of one SSTable block (prefix-compressed keys; restart array at the end)."""
    if offset + size + 5 > len(data):
        raise ValueError("block runs past the end of the file")
    if data[offset + size] != 0:
        raise ValueError(f"compressed block (type {data[offset + size]}) is not supported")
    block = data[offset:offset + size]
    n_restarts = int.from_bytes(block[-4:], "little")
    end = len(block) - 4 - 4 * n_restarts
    if end < 0:
        raise ValueError("block restart array is larger than the block")
    entries, pos, key = [], 0, b""
    while pos < end:
        shared, pos = _varint(block, pos)
        unshared, pos = _varint(block, pos)
        value_len, pos = _varint(block, pos)
        if shared > len(key):
            raise ValueError("key shares more bytes than the previous key has")
        key = key[:shared] + block[pos:pos + unshared]
        pos += unshared
        entries.append((key, block[pos:pos + value_len]))
        pos += value_len
    return entries


def _entry(value: bytes) -> dict:
    """BundleEntryProto -> dict(dtype, shape, shard, offset, size, has_slices)."""
    out: dict = {"dtype": 0, "shape": (), "shard": 0, "offset": 0, "size": 0, "has_slices": False}
    for number, val in _proto_fields(value):
        if number == 1:
            out["dtype"] = val
        elif number == 2:
            assert isinstance(val, bytes)
            dims = []
            for dn, dv in _proto_fields(val):
                if dn == 2:  # TensorShapeProto.dim
                    assert isinstance(dv, bytes)
                    size = dict(_proto_fields(dv)).get(1, 0)
                    dims.append(int(size))
                elif dn == 3 and dv:  # unknown_rank
                    raise ValueError("tensor of unknown rank")
            out["shape"] = tuple(dims)
        elif number == 3:
            out["shard"] = val
        elif number == 4:
            out["offset"] = val
        elif number == 5:
            out["size"] = val
        elif number == 7:
            out["has_slices"] = True
    return out


def resolve_checkpoint_prefix(path: str | pathlib.Path) -> pathlib.Path:
    """The checkpoint prefix (``.../chkpt-final``) from a prefix, its ``.index`` file or its folder.

    A folder is resolved through its ``checkpoint`` state file's file name (its absolute path is the
    training machine's and is ignored) or, failing that, its only ``*.index`` file.
    """
    p = pathlib.Path(path)
    if p.suffix == ".index":
        return p.with_suffix("")
    if p.is_dir():
        state = p / "checkpoint"
        if state.is_file():
            for line in state.read_text(errors="replace").splitlines():
                if line.startswith("model_checkpoint_path:"):
                    name = line.split(":", 1)[1].strip().strip('"').replace("\\", "/").rsplit("/", 1)[-1]
                    if (p / f"{name}.index").is_file():
                        return p / name
        indexes = sorted(p.glob("*.index"))
        if len(indexes) == 1:
            return indexes[0].with_suffix("")
        raise CheckpointError(f"{p}: expected one TensorFlow checkpoint (NAME.index + NAME.data-*) "
                              f"in this folder, found {len(indexes)} .index files")
    return p


def read_tf1_checkpoint(path: str | pathlib.Path) -> dict[str, np.ndarray]:
    """All tensors of a TensorFlow 1 checkpoint, by variable name, as numpy arrays.

    ``path`` is the checkpoint prefix, its ``.index`` file or the folder holding it.
    """
    prefix = resolve_checkpoint_prefix(path)
    index = prefix.parent / f"{prefix.name}.index"
    if not index.is_file():
        raise CheckpointError(f"{index}: checkpoint index file not found")
    data = index.read_bytes()
    try:
        if len(data) < 48 or int.from_bytes(data[-8:], "little") != _MAGIC:
            raise ValueError("no SSTable footer (bad magic number): not a TensorFlow checkpoint index")
        footer = data[-48:]
        _, pos = _varint(footer, 0)          # metaindex handle (unused)
        _, pos = _varint(footer, pos)
        idx_off, pos = _varint(footer, pos)  # index block handle
        idx_size, pos = _varint(footer, pos)
        entries: dict[bytes, bytes] = {}
        for _, handle in _block_entries(data, idx_off, idx_size):
            off, hp = _varint(handle, 0)
            size, _ = _varint(handle, hp)
            entries.update(_block_entries(data, off, size))
    except ValueError as exc:
        raise CheckpointError(f"{index}: corrupt checkpoint index: {exc}") from None
    header = dict(_proto_fields(entries.pop(b"", b"")))
    n_shards = int(header.get(1, 1) or 1)
    if header.get(2, 0) not in (0,):  # BundleHeaderProto.endianness: 0 = little
        raise CheckpointError(f"{index}: big-endian checkpoints are not supported")
    shards: dict[int, bytes] = {}
    tensors: dict[str, np.ndarray] = {}
    for key, value in sorted(entries.items()):
        name = key.decode("utf-8", "replace")
        try:
            entry = _entry(value)
        except ValueError as exc:
            raise CheckpointError(f"{index}: tensor {name!r}: corrupt entry: {exc}") from None
        if entry["has_slices"]:
            raise CheckpointError(f"{index}: tensor {name!r} is saved in slices, which is not supported")
        dtype = _DTYPES.get(int(entry["dtype"]))
        if dtype is None:
            raise CheckpointError(f"{index}: tensor {name!r} has TensorFlow dtype {entry['dtype']}, "
                                  f"expected one of {sorted(_DTYPES)}")
        shard = int(entry["shard"])
        if shard not in shards:
            data_file = prefix.parent / f"{prefix.name}.data-{shard:05d}-of-{n_shards:05d}"
            if not data_file.is_file():
                raise CheckpointError(f"{data_file}: checkpoint data file not found")
            shards[shard] = data_file.read_bytes()
        blob = shards[shard]
        start, size = int(entry["offset"]), int(entry["size"])
        expected = int(np.prod(entry["shape"], dtype=np.int64)) * np.dtype(dtype).itemsize
        if size != expected or start + size > len(blob):
            raise CheckpointError(f"{index}: tensor {name!r}: {size} bytes at offset {start} do not hold "
                                  f"shape {entry['shape']} of {np.dtype(dtype)} in a {len(blob)}-byte data file")
        tensors[name] = np.frombuffer(blob, dtype=dtype, count=size // np.dtype(dtype).itemsize,
                                      offset=start).reshape(entry["shape"]).copy()
    return tensors
