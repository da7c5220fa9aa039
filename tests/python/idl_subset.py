"""A parser for the subset of OMG IDL 4 that nonrt/msgs/idl uses: modules, @final/@appendable/
@mutable structs, primitive types, bounded and unbounded strings and sequences, arrays, typedefs
and constants. Anything else (enums, unions, inheritance, maps, wide strings, conditional
preprocessing) is an error, not skipped: a type this parser cannot read is a type nothing checks.

Every type is rendered as one canonical string (``int32``, ``string<8>``, ``sequence<float64>``,
``array<array<float64,4>,3>``, ``struct std_msgs::msg::Header``) so that the Python side can be
rendered the same way and compared with ``==``.
"""
import ast
import re
from dataclasses import dataclass, field
from pathlib import Path

# IDL spellings of the primitive types, by their canonical (IDL 4 fixed-width) name.
PRIMITIVES = {
    "boolean": "boolean", "octet": "octet", "char": "char", "wchar": "wchar",
    "int8": "int8", "uint8": "uint8", "int16": "int16", "uint16": "uint16",
    "int32": "int32", "uint32": "uint32", "int64": "int64", "uint64": "uint64",
    "short": "int16", "unsigned short": "uint16", "long": "int32", "unsigned long": "uint32",
    "long long": "int64", "unsigned long long": "uint64", "float": "float32", "double": "float64",
}
EXTENSIBILITIES = ("final", "appendable", "mutable")
# Include guards and includes only: every file is parsed and names are resolved across all of
# them, so includes need not be followed; anything conditional could hide or duplicate a type.
DIRECTIVES = ("include", "ifndef", "define", "endif", "pragma")

TOKEN = re.compile(r"""
    (?P<space>\s+)
  | (?P<comment>//[^\n]*|/\*.*?\*/)
  | (?P<string>"(?:[^"\\\n]|\\.)*")
  | (?P<number>0[xX][0-9a-fA-F]+|(?:\d+\.\d*|\.\d+)(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+|\d+)
  | (?P<scope>::)
  | (?P<ident>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<sym>[{}()<>;,\[\]@=:+\-])
""", re.VERBOSE | re.DOTALL)


class IdlError(Exception):
    pass


@dataclass
class Member:
    name: str
    type: str
    annotations: dict


@dataclass
class Struct:
    name: str  # fully qualified: pkg::msg::Type
    members: list
    annotations: dict
    where: str  # file:line

    @property
    def extensibility(self):
        """The explicit extensibility, or None: implementations disagree on the default."""
        found = [a for a in self.annotations if a in EXTENSIBILITIES]
        if "extensibility" in self.annotations:
            found.append(self.annotations["extensibility"].strip().lower())
        if len(found) > 1:
            raise IdlError(f"{self.where}: {self.name} has two extensibilities: {found}")
        return found[0] if found else None


@dataclass
class Const:
    name: str
    type: str
    value: object
    where: str


@dataclass
class Idl:
    structs: dict = field(default_factory=dict)  # by fully qualified name
    consts: dict = field(default_factory=dict)
    typedefs: dict = field(default_factory=dict)  # fully qualified name -> parsed type
    files: dict = field(default_factory=dict)  # path -> names of the structs it defines


@dataclass
class _Token:
    kind: str
    text: str
    line: int


def _tokens(text, where):
    lines = []
    for number, raw in enumerate(text.splitlines(), 1):
        if raw.strip().startswith("#"):
            directive = (raw.strip()[1:].split() or [""])[0]
            if directive not in DIRECTIVES:
                raise IdlError(f"{where}:{number}: unsupported preprocessor directive #{directive}")
            raw = ""  # kept as an empty line so that line numbers stay right
        lines.append(raw)
    text = "\n".join(lines)
    out, pos, line = [], 0, 1
    while pos < len(text):
        m = TOKEN.match(text, pos)
        if not m:
            raise IdlError(f"{where}:{line}: unexpected character {text[pos]!r}")
        kind = m.lastgroup
        if kind not in ("space", "comment"):
            out.append(_Token(kind, m.group(), line))
        line += m.group().count("\n")
        pos = m.end()
    out.append(_Token("eof", "", line))
    return out


def _number(text):
    if re.fullmatch(r"0[xX][0-9a-fA-F]+", text):
        return int(text, 16)
    if re.fullmatch(r"0[0-7]+", text):
        return int(text, 8)
    if re.fullmatch(r"\d+", text):
        return int(text)
    return float(text)


def _unescape(name):
    # IDL 4 §7.2.3.1: a leading underscore escapes a keyword ("_string" is the member "string").
    return name[1:] if name.startswith("_") else name


class _Parser:
    def __init__(self, text, where, idl):
        self.toks = _tokens(text, where)
        self.i = 0
        self.where = where
        self.idl = idl
        self.defined = []

    # --- tokens
    def peek(self, k=0):
        return self.toks[self.i + k]

    def next(self):
        t = self.toks[self.i]
        self.i += 1
        return t

    def error(self, msg, tok=None):
        tok = tok or self.peek()
        return IdlError(f"{self.where}:{tok.line}: {msg} (at {tok.text!r})")

    def expect(self, text):
        t = self.next()
        if t.text != text:
            raise self.error(f"expected {text!r}", t)
        return t

    def ident(self):
        t = self.next()
        if t.kind != "ident":
            raise self.error("expected an identifier", t)
        return _unescape(t.text)

    def accept(self, text):
        if self.peek().text == text:
            self.i += 1
            return True
        return False

    # --- grammar
    def parse(self):
        self.definitions([])
        if self.peek().kind != "eof":
            raise self.error("unexpected '}'")
        return self.defined

    def definitions(self, scope):
        while self.peek().kind != "eof" and self.peek().text != "}":
            annotations = self.annotations()
            t = self.next()
            if t.text == "module":
                if annotations:
                    raise self.error("annotations on a module", t)
                name = self.ident()
                self.expect("{")
                self.definitions(scope + [name])
                self.expect("}")
                self.expect(";")
            elif t.text == "struct":
                self.struct(scope, annotations, t)
            elif t.text == "const":
                self.const(scope, t)
            elif t.text == "typedef":
                self.typedef(scope, t)
            else:
                raise self.error("unsupported definition", t)

    def annotations(self):
        found = {}
        while self.accept("@"):
            name = self.ident()
            args = ""
            if self.accept("("):
                depth, parts = 1, []
                while True:
                    t = self.next()
                    if t.kind == "eof":
                        raise self.error("unterminated annotation", t)
                    depth += {"(": 1, ")": -1}.get(t.text, 0)
                    if depth == 0:
                        break
                    parts.append(t.text)
                args = " ".join(parts)
            found[name] = args
        return found

    def struct(self, scope, annotations, tok):
        name = self.ident()
        if self.accept(";"):
            return  # a forward declaration
        if self.peek().text == ":":
            raise self.error("unsupported: struct inheritance")
        fq = "::".join(scope + [name])
        where = f"{self.where}:{tok.line}"
        self.expect("{")
        members = []
        while not self.accept("}"):
            member_annotations = self.annotations()
            base = self.type_spec(scope)
            while True:
                mname = self.ident()
                dims = []
                while self.accept("["):
                    dims.append(self.const_expr(scope))
                    self.expect("]")
                mtype = base
                for d in reversed(dims):
                    mtype = ("array", mtype, d)
                members.append(Member(mname, mtype, dict(member_annotations)))
                if not self.accept(","):
                    break
            self.expect(";")
        self.expect(";")
        if fq in self.idl.structs:
            other = self.idl.structs[fq]
            raise IdlError(f"{where}: struct {fq} is also defined at {other.where}")
        if len({m.name for m in members}) != len(members):
            raise IdlError(f"{where}: struct {fq} names a member twice")
        self.idl.structs[fq] = Struct(fq, members, annotations, where)
        self.defined.append(fq)

    def const(self, scope, tok):
        ctype = self.type_spec(scope)
        name = self.ident()
        self.expect("=")
        negative = self.accept("-")
        t = self.next()
        if t.kind == "number":
            value = -_number(t.text) if negative else _number(t.text)
        elif t.kind == "string" and not negative:
            value = ast.literal_eval(t.text)  # C's escapes, as far as IDL strings use them
        elif t.text in ("TRUE", "FALSE") and not negative:
            value = t.text == "TRUE"
        elif t.kind == "ident" and not negative:
            self.i -= 1
            value = ("ref", scope, self.scoped_name())
        else:
            raise self.error("unsupported constant expression (a literal or another constant only)", t)
        self.expect(";")
        fq = "::".join(scope + [name])
        if fq in self.idl.consts:
            raise IdlError(f"{self.where}:{tok.line}: constant {fq} is defined twice")
        self.idl.consts[fq] = Const(fq, ctype, value, f"{self.where}:{tok.line}")

    def typedef(self, scope, tok):
        base = self.type_spec(scope)
        while True:
            name = self.ident()
            dims = []
            while self.accept("["):
                dims.append(self.const_expr(scope))
                self.expect("]")
            t = base
            for d in reversed(dims):
                t = ("array", t, d)
            fq = "::".join(scope + [name])
            if fq in self.idl.typedefs:
                raise IdlError(f"{self.where}:{tok.line}: typedef {fq} is defined twice")
            self.idl.typedefs[fq] = t
            if not self.accept(","):
                break
        self.expect(";")

    def const_expr(self, scope):
        """A positive bound: a literal or a constant's name (resolved once every file is read)."""
        t = self.peek()
        if t.kind == "number" and re.fullmatch(r"\d+", t.text):
            self.i += 1
            return int(t.text)
        if t.kind in ("ident", "scope"):
            return ("ref", scope, self.scoped_name())
        raise self.error("unsupported bound (a positive integer or a constant only)")

    def scoped_name(self):
        parts = [""] if self.accept("::") else []
        parts.append(self.ident())
        while self.accept("::"):
            parts.append(self.ident())
        return "::".join(parts)

    def type_spec(self, scope):
        t = self.peek()
        if t.text == "sequence":
            self.next()
            self.expect("<")
            elem = self.type_spec(scope)
            bound = self.const_expr(scope) if self.accept(",") else None
            self.expect(">")
            return ("sequence", elem, bound)
        if t.text == "string":
            self.next()
            bound = None
            if self.accept("<"):
                bound = self.const_expr(scope)
                self.expect(">")
            return ("string", bound)
        if t.text in ("wstring", "map", "any", "fixed", "Object", "ValueBase"):
            raise self.error("unsupported type")
        words = []
        if t.text == "unsigned":
            words.append(self.next().text)
            if self.peek().text not in ("short", "long"):
                raise self.error("expected short or long after unsigned")
        if self.peek().text == "long":
            words.append(self.next().text)
            if self.peek().text == "long":
                words.append(self.next().text)
            elif self.peek().text == "double":
                raise self.error("unsupported type: long double")
            return ("prim", PRIMITIVES[" ".join(words)])
        if self.peek().text in PRIMITIVES:
            words.append(self.next().text)
            return ("prim", PRIMITIVES[" ".join(words)])
        if words:
            raise self.error("expected short or long after unsigned")
        if self.peek().kind not in ("ident", "scope"):
            raise self.error("expected a type")
        return ("named", scope, self.scoped_name())


def _lookup(table, scope, name):
    """An IDL scoped name resolved as IDL does: from the innermost enclosing scope outwards."""
    if name.startswith("::"):
        candidates = [name[2:]]
    else:
        candidates = ["::".join(scope[:n] + [name]) for n in range(len(scope), -1, -1)]
    for c in candidates:
        if c in table:
            return c
    return None


def _resolve_value(idl, value, seen=()):
    if isinstance(value, tuple) and value[0] == "ref":
        _, scope, name = value
        fq = _lookup(idl.consts, scope, name)
        if fq is None or fq in seen:
            raise IdlError(f"unknown or circular constant {name}")
        return _resolve_value(idl, idl.consts[fq].value, seen + (fq,))
    return value


def _bound(idl, bound):
    value = _resolve_value(idl, bound)
    if not isinstance(value, int) or isinstance(value, bool) or value <= 0:
        raise IdlError(f"a bound must be a positive integer, not {value!r}")
    return value


def canonical(idl, t, where=""):
    """The canonical string of a parsed type, every name and bound resolved."""
    kind = t[0]
    if kind == "prim":
        return t[1]
    if kind == "string":
        return "string" if t[1] is None else f"string<{_bound(idl, t[1])}>"
    if kind == "sequence":
        elem = canonical(idl, t[1], where)
        return f"sequence<{elem}>" if t[2] is None else f"sequence<{elem},{_bound(idl, t[2])}>"
    if kind == "array":
        return f"array<{canonical(idl, t[1], where)},{_bound(idl, t[2])}>"
    _, scope, name = t
    fq = _lookup(idl.typedefs, scope, name)
    if fq is not None:
        return canonical(idl, idl.typedefs[fq], where)
    fq = _lookup(idl.structs, scope, name)
    if fq is None:
        raise IdlError(f"{where}: unknown type {name}")
    return f"struct {fq}"


def parse_text(text, where="<idl>", idl=None):
    """Parses one IDL text into `idl` (a new Idl if None); types are resolved by `resolve`."""
    idl = idl if idl is not None else Idl()
    idl.files[where] = _Parser(text, where, idl).parse()
    return idl


def resolve(idl):
    """Replaces every member's parsed type by its canonical string, and constants by their values."""
    for s in idl.structs.values():
        for m in s.members:
            if isinstance(m.type, tuple):
                m.type = canonical(idl, m.type, f"{s.where}: {s.name}.{m.name}")
    for c in idl.consts.values():
        if isinstance(c.type, tuple):
            c.type = canonical(idl, c.type, c.where)
        c.value = _resolve_value(idl, c.value)
    return idl


def parse_files(root):
    """Every *.idl under `root`, parsed and resolved; file names relative to `root`."""
    idl = Idl()
    root = Path(root)
    for path in sorted(root.rglob("*.idl")):
        parse_text(path.read_text(encoding="utf-8"), str(path.relative_to(root)), idl)
    return resolve(idl)
