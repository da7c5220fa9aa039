"""The gateway's samples as bytes: where a message's numbers lie in its CDR (XCDR1, @final) encoding,
so that a batch of samples of one layout decodes in one numpy call instead of one Python object
per sample; and each message's ROS 2 definition (.msg text), for an MCAP file's schemas.

A layout is taken from one sample (a string's or a sequence's length fixes where what follows
lies); a batch is decoded with it only if every sample has the same length and the same length
fields, else the caller decodes those samples one by one."""
import dataclasses
import typing

import numpy as np

from cyclonedds.idl import types as t

# Primitive CDR names -> (numpy little-endian type, size)
PRIMITIVES = {"float64": ("<f8", 8), "float32": ("<f4", 4), "int64": ("<i8", 8), "uint64": ("<u8", 8),
              "int32": ("<i4", 4), "uint32": ("<u4", 4), "int16": ("<i2", 2), "uint16": ("<u2", 2),
              "int8": ("i1", 1), "uint8": ("u1", 1), "byte": ("u1", 1), "char": ("u1", 1), "bool": ("u1", 1)}
HEADER = 4  # the encapsulation header before the payload (alignment counts from after it)
SKIPPED = ("header", "orientation", "structure_needs_at_least_one_member")  # as values.numbers


def _kind(hint):
    """('prim', name) | ('str',) | ('seq', element hint) | ('struct', class) for a field's type hint."""
    if hint is str:
        return ("str",)
    if hint is bool:
        return ("prim", "bool")
    if hint is float:
        return ("prim", "float64")
    if hint is int:
        return ("prim", "int64")
    if dataclasses.is_dataclass(hint):
        return ("struct", hint)
    if typing.get_origin(hint) is typing.Annotated:
        base, meta = typing.get_args(hint)[:2]
        if isinstance(meta, str) and meta in PRIMITIVES:
            return ("prim", meta)
        if isinstance(meta, (t.sequence, t.array)):
            if isinstance(meta, t.sequence):
                return ("seq", meta.subtype, meta.max_length)
            return ("arr", meta.subtype, meta.length)
        return _kind(base)
    if isinstance(hint, str) and hint in PRIMITIVES:
        return ("prim", hint)
    raise TypeError(f"no CDR layout for {hint!r}")


def _hints(cls):
    return typing.get_type_hints(cls, include_extras=True)


class Layout:
    """Where the numeric leaves of one message lie (offsets from the sample's first byte), as found
    in `data` (one sample); `names` in the order values.numbers() gives them."""

    def __init__(self, cls, data: bytes, names: list):
        self.size = len(data)
        self.leaves = []  # (offset, numpy type)
        self.lengths = []  # offsets of the uint32 length fields (strings, sequences)
        self.stamp = None  # offset of header.stamp (int32 sec, uint32 nanosec), if any
        self._data = data
        self._walk(cls, HEADER, numeric=True, prefix="")
        del self._data
        if len(self.leaves) != len(names):
            raise ValueError(f"{cls.__name__}: {len(self.leaves)} leaves in the bytes, {len(names)} numbers")
        self.names = list(names)
        self._lengths_of_first = self._u32(np.frombuffer(data, dtype="u1")[None, :], self.lengths)

    @staticmethod
    def _align(pos, size):
        rel = pos - HEADER
        return pos + (-rel) % size

    def _u32_at(self, pos):
        return int.from_bytes(self._data[pos:pos + 4], "little")

    def _walk(self, cls, pos, numeric, prefix):
        for f in dataclasses.fields(cls):
            keep = numeric and f.name not in SKIPPED
            pos = self._field(_kind(_hints(cls)[f.name]), pos, keep, prefix + f.name)
        return pos

    def _field(self, kind, pos, keep, name):
        if kind[0] == "prim":
            dtype, size = PRIMITIVES[kind[1]]
            pos = self._align(pos, size)
            if keep:
                self.leaves.append((pos, dtype))
            return pos + size
        if kind[0] == "str":
            pos = self._align(pos, 4)
            self.lengths.append(pos)
            return pos + 4 + self._u32_at(pos)
        if kind[0] == "struct":
            if name == "header" and self.stamp is None:
                self.stamp = self._align(pos, 4)
            return self._walk(kind[1], pos, keep, name + ".")
        count = kind[2] if kind[0] == "arr" else 0
        if kind[0] == "seq":
            pos = self._align(pos, 4)
            self.lengths.append(pos)
            count = self._u32_at(pos)
            pos += 4
        sub = _kind(kind[1])
        for _ in range(count):
            pos = self._field(sub, pos, keep and sub[0] == "prim", name)
        return pos

    @staticmethod
    def _u32(rows, offsets):
        if not offsets:
            return np.zeros((rows.shape[0], 0), dtype="<u4")
        idx = np.asarray(offsets)[:, None] + np.arange(4)[None, :]
        return rows[:, idx].copy().view("<u4").reshape(rows.shape[0], len(offsets))

    def decode(self, datas: list):
        """(values[n, leaves] as float64, stamps[n] in s or None) of samples of this layout, or None
        when one of them is laid out otherwise (a string or a sequence of another length)."""
        if any(len(d) != self.size for d in datas):
            return None
        rows = np.frombuffer(b"".join(datas), dtype="u1").reshape(len(datas), self.size)
        if self.lengths and not np.array_equal(self._u32(rows, self.lengths),
                                               np.broadcast_to(self._lengths_of_first,
                                                               (len(datas), len(self.lengths)))):
            return None
        out = np.empty((len(datas), len(self.leaves)))
        for j, (off, dtype) in enumerate(self.leaves):
            size = np.dtype(dtype).itemsize
            out[:, j] = rows[:, off:off + size].copy().view(dtype)[:, 0]
        stamps = None
        if self.stamp is not None:
            sec = rows[:, self.stamp:self.stamp + 4].copy().view("<i4")[:, 0]
            nsec = rows[:, self.stamp + 4:self.stamp + 8].copy().view("<u4")[:, 0]
            stamps = sec + nsec * 1e-9
        return out, stamps


# ---- ROS 2 message definitions (for MCAP's "ros2msg" schemas) ----

def ros_name(cls) -> str:
    """'geometry_msgs/msg/PoseStamped' for 'geometry_msgs::msg::dds_::PoseStamped_'."""
    pkg, msg, _, name = cls.__idl_typename__.split("::")
    return f"{pkg}/{msg}/{name.rstrip('_')}"


def _short(cls):
    pkg, _, name = ros_name(cls).split("/")
    return f"{pkg}/{name}"


def _ros_type(kind, deps):
    if kind[0] == "prim":
        return {"char": "uint8"}.get(kind[1], kind[1])
    if kind[0] == "str":
        return "string"
    if kind[0] == "struct":
        deps.append(kind[1])
        return _short(kind[1])
    element = _ros_type(_kind(kind[1]), deps)
    if kind[0] == "arr":
        return f"{element}[{kind[2]}]"
    return f"{element}[<={kind[2]}]" if kind[2] else f"{element}[]"


def _definition(cls, deps):
    return "\n".join(f"{_ros_type(_kind(_hints(cls)[f.name]), deps)} {f.name}" for f in dataclasses.fields(cls))


def ros2msg(cls) -> str:
    """The message's .msg text with every type it uses after it, as ROS 2 bags (MCAP) store it."""
    deps = []
    text = _definition(cls, deps)
    done = set()
    while deps:
        d = deps.pop(0)
        if d in done:
            continue
        done.add(d)
        text += "\n" + "=" * 80 + f"\nMSG: {_short(d)}\n" + _definition(d, deps)
    return text + "\n"
