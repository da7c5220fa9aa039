"""Cyclone DDS message classes made from IDL files: the IDL is the one source of every type.

Reads the subset of OMG IDL 4 that sawrt's messages use (modules; @final structs; primitive types;
strings, bounded or not; sequences, bounded or not; arrays; @default values; scoped type names)
and makes, for each struct, an ``IdlStruct`` dataclass with the ROS 2 DDS type name
(``pkg::msg::dds_::Type_``, as ``fastddsgen -typeros2`` names it on the C++ side). Anything
outside that subset is an error naming the file and line, never skipped: a construct read wrongly
would be a type that silently disagrees with the gateway.

(Cyclone's own ``idlc -l py`` is not used: the idlc executable in the cyclonedds 11.0.1 wheel
crashes in the dynamic loader on load, and Debian's idlc 0.10 cannot load that wheel's plugin.)
"""
import re
import types
from dataclasses import dataclass, field
from pathlib import Path

import cyclonedds.idl.types as t
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import final

# IDL spelling -> (Cyclone type, default value).
PRIMITIVES = {
    "boolean": (bool, False), "octet": (t.byte, 0), "char": (t.char, "\0"),
    "int8": (t.int8, 0), "uint8": (t.uint8, 0), "int16": (t.int16, 0), "uint16": (t.uint16, 0),
    "int32": (t.int32, 0), "uint32": (t.uint32, 0), "int64": (t.int64, 0), "uint64": (t.uint64, 0),
    "short": (t.int16, 0), "unsigned short": (t.uint16, 0), "long": (t.int32, 0),
    "unsigned long": (t.uint32, 0), "long long": (t.int64, 0), "unsigned long long": (t.uint64, 0),
    "float": (t.float32, 0.0), "double": (t.float64, 0.0),
}
# Include guards and includes only: every file is read and names resolve across all of them, so
# includes need not be followed; anything conditional could hide or duplicate a type.
DIRECTIVES = ("include", "ifndef", "define", "endif")
TOKEN = re.compile(r"""
    (?P<space>\s+)
  | (?P<comment>//[^\n]*|/\*.*?\*/)
  | (?P<directive>\#[^\n]*)
  | (?P<number>[+-]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?)
  | (?P<scope>::)
  | (?P<ident>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<sym>[{}()<>;,\[\]@=])
""", re.VERBOSE | re.DOTALL)


class IdlError(Exception):
    """A construct outside the subset, or a name that does not resolve: says file:line."""


@dataclass
class Member:
    name: str
    type: tuple  # ("prim", name) | ("string", bound) | ("seq", type, bound) | ("array", type, n) | ("ref", name)
    default: object
    where: str


@dataclass
class Struct:
    name: str  # fully qualified: pkg::msg::Type
    members: list = field(default_factory=list)
    where: str = ""


def _tokens(text, where):
    line, pos = 1, 0
    while pos < len(text):
        m = TOKEN.match(text, pos)
        if not m:
            raise IdlError(f"{where}:{line}: unexpected {text[pos]!r}")
        kind, value = m.lastgroup, m.group()
        if kind == "directive":
            word = value[1:].split()[0] if value[1:].split() else ""
            if word not in DIRECTIVES:
                raise IdlError(f"{where}:{line}: preprocessor directive #{word} is not supported")
        elif kind not in ("space", "comment"):
            yield kind, value, line
        line += value.count("\n")
        pos = m.end()


class _Parser:
    def __init__(self, text, where):
        self.tokens = list(_tokens(text, where))
        self.at = 0
        self.where = where
        self.structs = []

    def _peek(self, ahead=0):
        i = self.at + ahead
        return self.tokens[i] if i < len(self.tokens) else ("end", "", self.tokens[-1][2] if self.tokens else 1)

    def _error(self, message):
        raise IdlError(f"{self.where}:{self._peek()[2]}: {message}")

    def _take(self, expected=None):
        kind, value, _ = self._peek()
        if kind == "end" or (expected is not None and value != expected):
            self._error(f"expected {expected or 'more'}, found {value or 'the end of the file'!r}")
        self.at += 1
        return value

    def _ident(self):
        if self._peek()[0] != "ident":
            self._error(f"expected a name, found {self._peek()[1]!r}")
        name = self._take()
        # An escaped identifier (``_string``, a keyword as a name) is the name without its underscore.
        return name[1:] if name.startswith("_") else name

    def parse(self):
        self._definitions([])
        if self._peek()[0] != "end":
            self._error(f"unexpected {self._peek()[1]!r}")
        return self.structs

    def _definitions(self, scope):
        while self._peek()[0] != "end" and self._peek()[1] != "}":
            annotations = self._annotations()
            word = self._ident()
            if word == "module" and not annotations:
                name = self._ident()
                self._take("{")
                self._definitions(scope + [name])
                self._take("}")
            elif word == "struct":
                if annotations != {"final": None}:
                    self._error("a struct must be @final (XCDR1, as ROS 2 and Fast DDS 2.9 send it), "
                                f"and nothing else; found {sorted(annotations) or 'no annotation'}")
                self._struct(scope)
            else:
                self._error(f"{word!r} is not supported (modules and @final structs only)")
            self._take(";")

    def _annotations(self):
        found = {}
        while self._peek()[1] == "@":
            self._take("@")
            name = self._ident()
            value = None
            if self._peek()[1] == "(":
                self._take("(")
                if name != "default":
                    self._error(f"annotation @{name}(...) is not supported")
                if self._peek(1)[1] == "=":
                    if self._ident() != "value":
                        self._error("@default takes value=")
                    self._take("=")
                value = self._literal()
                self._take(")")
            found[name] = value
        return found

    def _literal(self):
        kind, text, _ = self._peek()
        self.at += 1
        if kind == "number":
            return float(text) if re.search(r"[.eE]", text) else int(text)
        if text in ("TRUE", "FALSE"):
            return text == "TRUE"
        self._error(f"expected a number or TRUE/FALSE, found {text!r}")

    def _struct(self, scope):
        line = self._peek()[2]
        struct = Struct("::".join(scope + [self._ident()]), where=f"{self.where}:{line}")
        self._take("{")
        while self._peek()[1] != "}":
            annotations = self._annotations()
            unknown = set(annotations) - {"default"}
            if unknown:
                self._error(f"member annotation @{sorted(unknown)[0]} is not supported")
            line = self._peek()[2]
            kind = self._type()
            name = self._ident()
            while self._peek()[1] == "[":
                self._take("[")
                n = self._literal()
                self._take("]")
                kind = ("array", kind, n)
            self._take(";")
            struct.members.append(Member(name, kind, annotations.get("default"), f"{self.where}:{line}"))
        self._take("}")
        if not struct.members:
            self._error(f"struct {struct.name} has no member")
        self.structs.append(struct)

    def _type(self):
        word = self._ident()
        if word in ("unsigned", "long") and self._peek()[1] in ("short", "long"):
            word += " " + self._take()
            if word == "unsigned long" and self._peek()[1] == "long":
                word += " " + self._take()
        if word in PRIMITIVES:
            return ("prim", word)
        if word in ("string", "sequence"):
            element, bound = None, None
            if self._peek()[1] == "<":
                self._take("<")
                if word == "sequence":
                    element = self._type()
                    if self._peek()[1] == ",":
                        self._take(",")
                        bound = self._literal()
                else:
                    bound = self._literal()
                self._take(">")
            elif word == "sequence":
                self._error("a sequence needs its element type")
            return ("string", bound) if word == "string" else ("seq", element, bound)
        name = word
        while self._peek()[1] == "::":
            self._take("::")
            name += "::" + self._ident()
        return ("ref", name)


def parse(text, where="<idl>"):
    """The structs of one IDL text."""
    return _Parser(text, where).parse()


def dds_name(name):
    """``pkg::msg::Type`` -> ``pkg::msg::dds_::Type_``, the name ROS 2 and fastddsgen -typeros2 use."""
    *scope, leaf = name.split("::")
    return "::".join(scope + ["dds_", leaf + "_"])


class _Builder:
    def __init__(self, structs):
        self.structs = {}
        for s in structs:
            if s.name in self.structs:
                raise IdlError(f"{s.where}: {s.name} is also defined at {self.structs[s.name].where}")
            self.structs[s.name] = s
        self.classes = {}

    def cls(self, name, stack=()):
        if name in self.classes:
            return self.classes[name]
        s = self.structs[name]
        if name in stack:
            raise IdlError(f"{s.where}: {name} contains itself")
        annotations, namespace = {}, {}
        for m in s.members:
            annotations[m.name], default = self._field(s, m, stack + (name,))
            namespace[m.name] = default
        body = {"__annotations__": annotations, **namespace, "__module__": "sawdds.msgs"}
        cls = types.new_class(name.split("::")[-1], (IdlStruct,), {"typename": dds_name(name)},
                              lambda ns: ns.update(body))
        cls = final(dataclass(cls))
        self.classes[name] = cls
        return cls

    def _resolve(self, struct, member, name):
        scope = struct.name.split("::")[:-1]
        for i in range(len(scope), -1, -1):  # innermost scope first, as IDL resolves a name
            full = "::".join(scope[:i] + [name])
            if full in self.structs:
                return full
        raise IdlError(f"{member.where}: type {name} of {struct.name}.{member.name} is not defined")

    def _field(self, struct, m, stack):
        kind = m.type
        if m.default is not None and kind[0] != "prim":
            raise IdlError(f"{m.where}: @default on {struct.name}.{m.name}, which is not a primitive")
        if kind[0] == "prim":
            py, zero = PRIMITIVES[kind[1]]
            return py, zero if m.default is None else type(zero)(m.default)
        if kind[0] == "string":
            return (str if kind[1] is None else t.bounded_str[kind[1]]), ""
        if kind[0] == "ref":
            nested = self.cls(self._resolve(struct, m, kind[1]), stack)
            return nested, field(default_factory=nested)
        if kind[0] == "seq":
            element = self._element(struct, m, kind[1], stack)
            py = t.sequence[element] if kind[2] is None else t.sequence[element, kind[2]]
            return py, field(default_factory=list)
        element = self._element(struct, m, kind[1], stack)
        zero = self._zero(struct, m, kind[1], stack)
        return t.array[element, kind[2]], field(default_factory=lambda: [zero() for _ in range(kind[2])])

    def _element(self, struct, m, kind, stack):
        return self._field(struct, Member(m.name, kind, None, m.where), stack)[0]

    def _zero(self, struct, m, kind, stack):
        default = self._field(struct, Member(m.name, kind, None, m.where), stack)[1]
        if hasattr(default, "default_factory"):
            return default.default_factory
        return lambda: default


def classes(structs):
    """An ``IdlStruct`` class per struct, by fully qualified IDL name."""
    builder = _Builder(structs)
    return {name: builder.cls(name) for name in builder.structs}


def load(*roots):
    """The classes of every ``*.idl`` file under each of ``roots`` (``<pkg>/msg/<Type>.idl``), by IDL
    name; names resolve across all of them (a lab's IDL including std_msgs/Header)."""
    structs = []
    for root in map(Path, roots):
        files = sorted(root.rglob("*.idl"))
        if not files:
            raise IdlError(f"{root}: no IDL file")
        for f in files:
            structs += parse(f.read_text(encoding="utf-8"), str(f.relative_to(root)) if len(roots) == 1 else str(f))
    return classes(structs)
