"""sawdds's message classes are made from the IDL the C++ side is generated from (nonrt/msgs/idl):
every struct of every IDL file is a class under its ROS 2 DDS name, field for field, @final, and a
value survives the trip through its bytes; the reader refuses what it does not understand with the
file and line rather than making a class that disagrees with the gateway.

usage: idl_classes.py   (the tools venv's python)
"""
import dataclasses
import re
import sys
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
IDL_ROOT = ROOT / "nonrt" / "msgs" / "idl"
sys.path.insert(0, str(ROOT / "nonrt" / "python"))
from sawdds import idl, msgs  # noqa: E402


def idl_members(path):
    """(struct name, [member names]) of one IDL file, read with a regex: an independent look at it."""
    text = re.sub(r"//[^\n]*", "", path.read_text(encoding="utf-8"))
    found = []
    for name, body in re.findall(r"struct\s+(\w+)\s*\{(.*?)\};", text, re.S):
        members = [m.lstrip("_") for m in re.findall(r"(\w+)\s*(?:\[\s*\d+\s*\])?\s*;", body)]
        found.append((name, members))
    return found


class EveryIdlStructIsAClass(unittest.TestCase):
    def test_each_file_struct_and_member(self):
        files = sorted(IDL_ROOT.rglob("*.idl"))
        self.assertGreater(len(files), 20)
        for f in files:
            package = f.relative_to(IDL_ROOT).parts[0]
            for name, members in idl_members(f):
                with self.subTest(file=str(f.relative_to(ROOT)), struct=name):
                    cls = msgs.BY_DDS_NAME.get(f"{package}::msg::dds_::{name}_")
                    self.assertIsNotNone(cls, f"no class for {package}/{name}")
                    self.assertIs(getattr(msgs, name), cls)
                    self.assertEqual([x.name for x in dataclasses.fields(cls)], members)
                    self.assertEqual(cls.__idl_annotations__.get("extensibility"), "final")

    def test_values_survive_their_bytes(self):
        samples = [
            msgs.PoseStamped(header=msgs.Header(stamp=msgs.Time(sec=3, nanosec=7), frame_id="base"),
                             pose=msgs.Pose(position=msgs.Point(x=0.1, y=-0.2, z=0.3))),
            msgs.JointState(name=["a", "b"], position=[1.0, 2.0], velocity=[0.5], effort=[]),
            msgs.Joy(axes=[0.25], buttons=[1, 0]),
            msgs.StringStamped(string="hello"),
            msgs.Manifest(host="h", pid=4, endpoints=[msgs.Endpoint(name="servo_cp", limited=True, limit_max=2.0)]),
            msgs.Query(client=9, number=2, data=list(range(256))),
        ]
        for value in samples:
            with self.subTest(type=type(value).__name__):
                self.assertEqual(type(value).deserialize(value.serialize()), value)

    def test_ros2_defaults(self):
        # ROS 2's geometry_msgs/Quaternion: w defaults to 1, so a pose made with defaults is the identity.
        self.assertEqual(msgs.Pose().orientation.w, 1.0)
        self.assertEqual(msgs.Quaternion().x, 0.0)

    def test_a_bounded_sequence_is_bounded(self):
        with self.assertRaises(Exception):
            msgs.Query(data=[0] * 257).serialize()


class TheReaderRefusesWhatItDoesNotKnow(unittest.TestCase):
    def refused(self, text, where):
        with self.assertRaises(idl.IdlError) as caught:
            idl.classes(idl.parse(text, "x/msg/T.idl"))
        self.assertIn(f"x/msg/T.idl:{where}", str(caught.exception))
        return str(caught.exception)

    def test_constructs_outside_the_subset(self):
        self.refused("module x {\n enum E { A, B };\n};\n", "2")
        self.assertIn("@final", self.refused("module x {\n@appendable\nstruct T { long a; };\n};\n", "3"))
        self.refused("#ifdef FOO\nmodule x { };\n#endif\n", "1")
        self.refused("module x {\n@final\nstruct T {\n  map<long, long> m;\n};\n};\n", "4")
        self.refused("module x {\n@final\nstruct T {\n  @key long a;\n};\n};\n", "4")

    def test_an_undefined_type_names_the_member(self):
        message = self.refused("module x {\n@final\nstruct T {\n  x::Nope n;\n};\n};\n", "4")
        self.assertIn("T.n", message)

    def test_what_it_reads(self):
        classes = idl.classes(idl.parse(
            "module x { module msg {\n@final struct A { @default(value=2.5) double d; string<4> s; long n[3]; };\n"
            "@final struct B { A a; sequence<A, 2> many; unsigned long long u; boolean _string; };\n}; };\n"))
        a, b = classes["x::msg::A"], classes["x::msg::B"]
        self.assertEqual(a.__idl_typename__, "x::msg::dds_::A_")
        self.assertEqual((a().d, a().n), (2.5, [0, 0, 0]))
        value = b(a=a(s="abcd"), many=[a(d=1.0)], u=2**64 - 1, string=True)
        self.assertEqual(b.deserialize(value.serialize()), value)
        with self.assertRaises(Exception):
            a(s="abcde").serialize()


if __name__ == "__main__":
    unittest.main(verbosity=2)
