"""sawdds's message classes (nonrt/python/sawdds/msgs.py) against the IDL the C++ side is generated
from (nonrt/msgs/idl): every IdlStruct class msgs.py defines, and every class its members use, must
have its IDL struct (in pkg/msg/Type.idl) with the same ROS 2 DDS type name, extensibility, member
names in the same order, member types (bounds included), keys and optional members. The IDL structs
sawdds does not use are listed, not failed. The checker is first shown to catch drift: copies of a
class with one thing changed each must be reported.

usage: idl_matches_python.py   (the tools venv's python; exit 0 when everything agrees)
"""
import inspect
import sys
import typing
import unittest
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
IDL_ROOT = ROOT / "nonrt" / "msgs" / "idl"
sys.path.insert(0, str(ROOT / "nonrt" / "python"))  # the source tree's sawdds, not an installed one

import cyclonedds.idl.types as t  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.annotations import appendable, final, key  # noqa: E402

import idl_subset  # noqa: E402
from idl_subset import IdlError, Member  # noqa: E402
from sawdds import msgs  # noqa: E402

# cyclonedds's primitive annotations (cyclonedds.idl.types) by canonical name; `byte` is IDL octet.
PY_PRIMITIVES = {
    "int8": "int8", "uint8": "uint8", "int16": "int16", "uint16": "uint16", "int32": "int32",
    "uint32": "uint32", "int64": "int64", "uint64": "uint64", "byte": "octet", "char": "char",
    "wchar": "wchar", "float32": "float32", "float64": "float64",
}
# Plain Python types as cyclonedds serializes them.
PY_BUILTINS = ((bool, "boolean"), (int, "int64"), (float, "float64"), (str, "string"))


def dds_name(idl_name):
    """fastddsgen -typeros2's name for IDL pkg::msg::Type, as ROS 2 names it: pkg::msg::dds_::Type_."""
    *modules, name = idl_name.split("::")
    return "::".join(modules + ["dds_", name + "_"])


def idl_name(typename):
    """The IDL struct a ROS 2 DDS type name stands for, or None if it is not such a name."""
    parts = typename.split("::")
    if len(parts) < 3 or parts[-2] != "dds_" or not parts[-1].endswith("_") or len(parts[-1]) < 2:
        return None
    return "::".join(parts[:-2] + [parts[-1][:-1]])


class Unsupported(Exception):
    pass


def py_type(hint, nested):
    """The canonical string (as idl_subset's) of a member's type hint; struct classes go to `nested`."""
    for builtin, name in PY_BUILTINS:
        if hint is builtin:
            return name
    if inspect.isclass(hint) and issubclass(hint, IdlStruct):
        nested.append(hint)
        return f"struct {idl_name(hint.__idl_typename__) or hint.__idl_typename__}"
    if typing.get_origin(hint) is typing.Annotated:
        meta = hint.__metadata__[0]
        if isinstance(meta, str) and meta in PY_PRIMITIVES:
            return PY_PRIMITIVES[meta]
        if isinstance(meta, t.sequence):
            elem = py_type(meta.subtype, nested)
            return f"sequence<{elem}>" if meta.max_length is None else f"sequence<{elem},{meta.max_length}>"
        if isinstance(meta, t.array):
            return f"array<{py_type(meta.subtype, nested)},{meta.length}>"
        if isinstance(meta, t.bounded_str):
            return f"string<{meta.max_length}>"
        if isinstance(meta, t.typedef):
            return py_type(meta.subtype, nested)
    if typing.get_origin(hint) is list:
        return f"sequence<{py_type(typing.get_args(hint)[0], nested)}>"
    raise Unsupported(f"{hint!r} is outside the subset this test compares")


def py_members(cls, nested):
    """cls's members as cyclonedds serializes them: its own annotations, in order, as Members."""
    hints = typing.get_type_hints(cls, include_extras=True)
    field_annotations = cls.__idl_field_annotations__
    keylist = set(cls.__idl_annotations__.get("keylist", ()))
    members = []
    for name in cls.__annotations__:
        if name.startswith("__"):
            continue  # cyclonedds skips these too
        hint, flags = hints[name], {}
        args = typing.get_args(hint)
        if typing.get_origin(hint) is typing.Union and type(None) in args and len(args) == 2:
            hint, flags["optional"] = next(a for a in args if a is not type(None)), ""
        own = field_annotations.get(name, {})
        if own.get("key") or name in keylist:
            flags["key"] = ""
        # member_name() is how cyclonedds spells an IDL member that is a Python keyword.
        members.append(Member(own.get("name", name), py_type(hint, nested), flags))
    return members


def idl_flags(member):
    return {a: "" for a in ("key", "optional")
            if a in member.annotations and member.annotations[a].strip().upper() != "FALSE"}


def compare(idl, cls, checked=None):
    """What differs between class `cls` (and the classes its members use) and the IDL: a list of lines."""
    checked = set() if checked is None else checked
    if cls in checked:
        return []
    checked.add(cls)
    label = f"{cls.__qualname__} ({cls.__idl_typename__})"
    name = idl_name(cls.__idl_typename__)
    if name is None:
        return [f"{label}: not a ROS 2 DDS type name (pkg::msg::dds_::Type_), as fastddsgen -typeros2 makes"]
    struct = idl.structs.get(name)
    if struct is None:
        return [f"{label}: no struct {name} in nonrt/msgs/idl"]
    problems = []
    expected_file = "/".join(name.split("::")) + ".idl"
    if not struct.where.startswith(expected_file + ":"):
        problems.append(f"{label}: {name} is defined at {struct.where}, not in {expected_file}")
    py_ext = cls.__idl_annotations__.get("extensibility")
    if py_ext != struct.extensibility:
        problems.append(f"{label}: extensibility {py_ext} in Python, {struct.extensibility} in the IDL "
                        f"({struct.where})")
    nested = []
    try:
        members = py_members(cls, nested)
    except Unsupported as e:
        return problems + [f"{label}: {e}"]
    py_names, idl_names = [m.name for m in members], [m.name for m in struct.members]
    if py_names != idl_names:
        problems.append(f"{label}: members {py_names} in Python, {idl_names} in the IDL ({struct.where})")
    by_name = {m.name: m for m in struct.members}
    for m in members:
        other = by_name.get(m.name)
        if other is None:
            continue
        if m.type != other.type:
            problems.append(f"{label}: {m.name} is {m.type} in Python, {other.type} in the IDL ({struct.where})")
        if m.annotations != idl_flags(other):
            problems.append(f"{label}: {m.name} is {sorted(m.annotations) or 'plain'} in Python, "
                            f"{sorted(idl_flags(other)) or 'plain'} in the IDL ({struct.where})")
    for n in nested:
        problems += compare(idl, n, checked)
    return problems


def claimed_classes():
    """Every IdlStruct class msgs.py defines: each claims to be its IDL struct, field for field."""
    return [c for c in vars(msgs).values()
            if inspect.isclass(c) and issubclass(c, IdlStruct) and c.__module__ == msgs.__name__]


class ParsesTheIdlSubset(unittest.TestCase):
    def test_reads_every_construct_of_the_subset(self):
        idl = idl_subset.resolve(idl_subset.parse_text("""
            #ifndef X
            #define X
            #include "other.idl"
            module a { module b {
            const uint32 N = 8;
            const string GREETING = "hi";
            typedef sequence<double, N> Bounded;
            struct Forward;
            @appendable
            struct Inner { @key unsigned long long id; };
            @final
            struct Outer {
              Inner rel;            // a relative name
              ::a::b::Inner abs;    // an absolute one
              string<N> s; string u;
              sequence<octet, 256> bytes;
              Bounded typed;
              double m[3][4], v[2];
              long l; unsigned short us; short sh; long long ll; float f; boolean ok; char c;
              @optional int8 maybe;
              string _string;       // escaped keyword
            };
            }; };
            #endif
            """, "inline.idl"))
        outer = idl.structs["a::b::Outer"]
        self.assertEqual([(m.name, m.type) for m in outer.members], [
            ("rel", "struct a::b::Inner"), ("abs", "struct a::b::Inner"), ("s", "string<8>"), ("u", "string"),
            ("bytes", "sequence<octet,256>"), ("typed", "sequence<float64,8>"),
            ("m", "array<array<float64,4>,3>"), ("v", "array<float64,2>"), ("l", "int32"), ("us", "uint16"),
            ("sh", "int16"), ("ll", "int64"), ("f", "float32"), ("ok", "boolean"), ("c", "char"),
            ("maybe", "int8"), ("string", "string")])
        self.assertEqual(outer.extensibility, "final")
        inner = idl.structs["a::b::Inner"]
        self.assertEqual((inner.extensibility, inner.members[0].type, idl_flags(inner.members[0])),
                         ("appendable", "uint64", {"key": ""}))
        self.assertEqual(idl_flags(outer.members[15]), {"optional": ""})
        self.assertEqual({n: c.value for n, c in idl.consts.items()}, {"a::b::N": 8, "a::b::GREETING": "hi"})

    def test_rejects_what_it_cannot_read(self):
        for text in ("module m { enum E { A, B }; };",
                     "module m { union U switch (long) { case 1: long a; }; };",
                     "module m { struct A { long a; }; struct B : A { long b; }; };",
                     "module m { struct A { wstring w; }; };",
                     "module m { struct A { Unknown u; }; };",
                     "module m { struct A { sequence<long, M> s; }; };",
                     "#ifdef FOO\nmodule m { struct A { long a; }; };\n#endif",
                     "module m { struct A { long a; }; }; module m { struct A { long a; }; };"):
            with self.subTest(text=text), self.assertRaises(IdlError):
                idl_subset.resolve(idl_subset.parse_text(text))


class TheCheckerCatchesDrift(unittest.TestCase):
    """Copies of JointState (sequences, a nested struct) and Header, each wrong in one way."""

    @classmethod
    def setUpClass(cls):
        cls.idl = idl_subset.parse_files(IDL_ROOT)

    def assertDrift(self, klass, *expected):
        problems = compare(self.idl, klass)
        self.assertTrue(problems, f"{klass.__qualname__} was not caught")
        for e in expected:
            self.assertTrue(any(e in p for p in problems), f"no problem mentions {e!r}: {problems}")

    def test_a_faithful_copy_passes(self):
        # The control: each copy below differs from this one in one thing only.
        @final
        @dataclass
        class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
            header: msgs.Header = field(default_factory=msgs.Header)
            name: t.sequence[str] = field(default_factory=list)
            position: t.sequence[t.float64] = field(default_factory=list)
            velocity: t.sequence[t.float64] = field(default_factory=list)
            effort: t.sequence[t.float64] = field(default_factory=list)
        self.assertEqual(compare(self.idl, JointState), [])

    def test_a_renamed_member(self):
        @final
        @dataclass
        class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
            header: msgs.Header = field(default_factory=msgs.Header)
            names: t.sequence[str] = field(default_factory=list)
            position: t.sequence[t.float64] = field(default_factory=list)
            velocity: t.sequence[t.float64] = field(default_factory=list)
            effort: t.sequence[t.float64] = field(default_factory=list)
        self.assertDrift(JointState, "'names'")

    def test_a_member_of_another_type(self):
        @final
        @dataclass
        class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
            header: msgs.Header = field(default_factory=msgs.Header)
            name: t.sequence[str] = field(default_factory=list)
            position: t.sequence[t.float32] = field(default_factory=list)
            velocity: t.sequence[t.float64] = field(default_factory=list)
            effort: t.sequence[t.float64] = field(default_factory=list)
        self.assertDrift(JointState, "position is sequence<float32> in Python, sequence<float64> in the IDL")

    def test_a_bound_the_idl_does_not_have(self):
        @final
        @dataclass
        class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
            header: msgs.Header = field(default_factory=msgs.Header)
            name: t.sequence[str] = field(default_factory=list)
            position: t.sequence[t.float64, 10] = field(default_factory=list)
            velocity: t.sequence[t.float64] = field(default_factory=list)
            effort: t.sequence[t.float64] = field(default_factory=list)
        self.assertDrift(JointState, "sequence<float64,10>")

    def test_members_in_another_order(self):
        @final
        @dataclass
        class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
            header: msgs.Header = field(default_factory=msgs.Header)
            name: t.sequence[str] = field(default_factory=list)
            velocity: t.sequence[t.float64] = field(default_factory=list)
            position: t.sequence[t.float64] = field(default_factory=list)
            effort: t.sequence[t.float64] = field(default_factory=list)
        self.assertDrift(JointState, "members")

    def test_a_missing_and_an_extra_member(self):
        @final
        @dataclass
        class Missing(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
            header: msgs.Header = field(default_factory=msgs.Header)
            name: t.sequence[str] = field(default_factory=list)
            position: t.sequence[t.float64] = field(default_factory=list)
            velocity: t.sequence[t.float64] = field(default_factory=list)

        @final
        @dataclass
        class Extra(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
            x: t.float64 = 0.0
            y: t.float64 = 0.0
            z: t.float64 = 0.0
            w: t.float64 = 0.0
        self.assertDrift(Missing, "members")
        self.assertDrift(Extra, "'w'")

    def test_a_wrong_type_name(self):
        @final
        @dataclass
        class Misspelt(IdlStruct, typename="sensor_msgs::msg::dds_::JointStates_"):
            data: t.float64 = 0.0

        @final
        @dataclass
        class NotRos2(IdlStruct, typename="sensor_msgs::msg::JointState"):
            data: t.float64 = 0.0
        self.assertDrift(Misspelt, "no struct sensor_msgs::msg::JointStates")
        self.assertDrift(NotRos2, "not a ROS 2 DDS type name")

    def test_another_extensibility_or_a_key(self):
        @appendable
        @dataclass
        class Appendable(IdlStruct, typename="std_msgs::msg::dds_::Float64_"):
            data: t.float64 = 0.0

        @final
        @dataclass
        class Keyed(IdlStruct, typename="std_msgs::msg::dds_::Float64_"):
            data: t.float64 = 0.0
            key("data")
        self.assertDrift(Appendable, "extensibility appendable in Python, final in the IDL")
        self.assertDrift(Keyed, "data is ['key'] in Python")

    def test_drift_in_a_nested_struct(self):
        @final
        @dataclass
        class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
            stamp: msgs.Time = field(default_factory=msgs.Time)
            frame: str = ""

        @final
        @dataclass
        class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
            header: Header = field(default_factory=Header)
            name: t.sequence[str] = field(default_factory=list)
            position: t.sequence[t.float64] = field(default_factory=list)
            velocity: t.sequence[t.float64] = field(default_factory=list)
            effort: t.sequence[t.float64] = field(default_factory=list)
        self.assertDrift(JointState, "Header (std_msgs::msg::dds_::Header_): members")


class SawddsMatchesTheIdl(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.idl = idl_subset.parse_files(IDL_ROOT)
        cls.classes = claimed_classes()

    def test_every_message_class_matches_its_idl_struct(self):
        self.assertTrue(self.classes, "no IdlStruct classes found in sawdds.msgs")
        checked, problems = set(), []
        for cls in self.classes:
            problems += compare(self.idl, cls, checked)
        print(f"\nchecked {len(checked)} classes against {len(self.idl.files)} IDL files: "
              + ", ".join(sorted(c.__idl_typename__ for c in checked)))
        used = {idl_name(c.__idl_typename__) for c in checked}
        unused = sorted(set(self.idl.structs) - used)
        print("IDL structs sawdds has no class for (not checked): " + (", ".join(unused) or "none"))
        if self.idl.consts:
            print("IDL constants: " + ", ".join(f"{n} = {c.value!r}" for n, c in sorted(self.idl.consts.items())))
        if problems:
            self.fail("sawdds.msgs and nonrt/msgs/idl differ:\n" + "\n".join(problems))

    def test_the_topic_type_table_names_each_class_by_its_type_name(self):
        for typename, cls in msgs.BY_DDS_NAME.items():
            with self.subTest(typename=typename):
                self.assertEqual(typename, cls.__idl_typename__)
                self.assertIn(cls, self.classes)

    def test_python_constants_named_as_idl_constants_have_their_values(self):
        for name, const in self.idl.consts.items():
            short = name.split("::")[-1]
            if hasattr(msgs, short):
                with self.subTest(constant=name):
                    self.assertEqual(getattr(msgs, short), const.value)


if __name__ == "__main__":
    unittest.main(verbosity=2)
