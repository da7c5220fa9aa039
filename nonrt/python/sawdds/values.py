"""What a sample holds, generically: its numbers by dotted name (for plots, statistics and CSV),
its text, and building a message from numbers (for command forms). No per-type code beyond the
few names a person expects (a pose's orientation is not plotted)."""
import dataclasses
import math
import struct

from . import msgs

# Leaves not worth a curve: a stamped message's header, a pose's orientation (a quaternion).
SKIPPED = ("header", "orientation", "structure_needs_at_least_one_member")
STATE_COMMANDS = ("enable", "disable", "pause", "resume", "home")


def numbers(sample, prefix: str = "") -> dict:
    """The sample's numeric leaves by dotted name ("pose.position.x", "position[1]", "data")."""
    out = {}
    for f in dataclasses.fields(sample):
        if f.name in SKIPPED:
            continue
        v = getattr(sample, f.name)
        name = prefix + f.name
        if dataclasses.is_dataclass(v):
            out.update(numbers(v, name + "."))
        elif isinstance(v, bool):
            out[name] = 1.0 if v else 0.0
        elif isinstance(v, (int, float)):
            out[name] = float(v)
        elif isinstance(v, list) and v and isinstance(v[0], (int, float)):
            names = getattr(sample, "name", None) if f.name in ("position", "velocity", "effort") else None
            for i, x in enumerate(v):
                label = names[i] if isinstance(names, list) and i < len(names) else str(i)
                out[f"{name}[{label}]"] = float(x)
    return out


def text(sample) -> str:
    """One line for a log: an operating state, a string, or the numbers."""
    if isinstance(sample, msgs.OperatingState):
        return sample.state + (" (homed)" if sample.is_homed else "") + (" (busy)" if sample.is_busy else "")
    if isinstance(sample, msgs.StringStamped):
        return sample.string
    if isinstance(sample, msgs.Joy):
        return "pressed" if sample.buttons and sample.buttons[0] else "released"
    return ", ".join(f"{k} {v:.6g}" for k, v in numbers(sample).items())


def form_fields(cls) -> list:
    """The leaves a command form asks for: (dotted name, python type), header and orientation left out
    (a pose command keeps its identity orientation)."""
    out = []

    def walk(c, prefix):
        for f in dataclasses.fields(c):
            if f.name in SKIPPED:
                continue
            default = getattr(c(), f.name)
            if dataclasses.is_dataclass(default):
                walk(type(default), prefix + f.name + ".")
            elif isinstance(default, (bool, int, float, str)):
                out.append((prefix + f.name, type(default)))
            elif isinstance(default, list):
                out.append((prefix + f.name, list))
    walk(cls, "")
    return out


class Invalid(ValueError):
    """A command value the form refuses, with the reason a person reads."""


def parse_number(name: str, text_value: str, kind=float, limits=None) -> float:
    """A form's number, refused if it is not one, not finite or outside `limits` (min, max)."""
    try:
        x = kind(float(text_value)) if kind is int else float(text_value)
    except ValueError:
        raise Invalid(f"{name}: {text_value!r} is not a number") from None
    if isinstance(x, float) and not math.isfinite(x):
        raise Invalid(f"{name}: {text_value!r} is not finite")
    if limits is not None and not (limits[0] <= x <= limits[1]):
        raise Invalid(f"{name}: {x:g} is outside [{limits[0]:g}, {limits[1]:g}]")
    return x


def build(cls, values: dict, limits=None):
    """A message of class `cls` from {dotted name: text} (form_fields' names); Invalid if a value is bad."""
    sample = cls()
    for name, kind in form_fields(cls):
        raw = values.get(name, "")
        *path, leaf = name.split(".")
        target = sample
        for p in path:
            target = getattr(target, p)
        if kind is str:
            if cls is msgs.StringStamped and name == "string" and raw not in STATE_COMMANDS and limits == "state":
                raise Invalid(f"{raw!r} is not a state command ({', '.join(STATE_COMMANDS)})")
            setattr(target, leaf, raw)
        elif kind is bool:
            setattr(target, leaf, str(raw).lower() in ("1", "true", "yes", "on"))
        elif kind is list:
            items = [w for w in str(raw).replace(",", " ").split() if w]
            setattr(target, leaf, [parse_number(name, w, float, limits if isinstance(limits, tuple) else None)
                                   for w in items])
        else:
            setattr(target, leaf, parse_number(name, str(raw), kind, limits if isinstance(limits, tuple) else None))
    return sample


# Qualified reads carry the rt type's bytes: the simple ones are packed here.
_PACK = {"float64": "d", "float32": "f", "int64": "q", "uint64": "Q", "int32": "i", "uint32": "I", "bool": "?"}


def pack(saw_type: str, text_value: str) -> bytes:
    """The bytes of a qualifier of rt type `saw_type` (a number, bool or array<T,N>) from text."""
    words = [w for w in text_value.replace(",", " ").split() if w]
    if saw_type.startswith("array<") and saw_type.endswith(">"):
        elem, _, n = saw_type[6:-1].partition(",")
        code, count = _PACK.get(elem.strip()), int(n)
    else:
        code, count = _PACK.get(saw_type), 1
    if code is None:
        raise Invalid(f"a {saw_type} qualifier cannot be typed here")
    if len(words) != count:
        raise Invalid(f"{count} value(s) expected, got {len(words)}")
    kind = int if code in "qQiI" else float
    vals = [w.lower() in ("1", "true") if code == "?" else parse_number("qualifier", w, kind) for w in words]
    return struct.pack("<" + code * count, *vals)


def unpack(saw_type: str, data: bytes) -> str:
    """A qualified read's result as text (numbers when the type is simple, hex otherwise)."""
    if saw_type.startswith("array<") and saw_type.endswith(">"):
        elem, _, n = saw_type[6:-1].partition(",")
        code, count = _PACK.get(elem.strip()), int(n)
    else:
        code, count = _PACK.get(saw_type), 1
    if code is None or struct.calcsize("<" + code * count) != len(data):
        return data.hex(" ")
    return " ".join(f"{v:.6g}" if isinstance(v, float) else str(v) for v in struct.unpack("<" + code * count, data))
