"""sawdds.values, which the generated views stand on: a message's numbers by name, command forms'
fields and their checks, and qualified reads' bytes."""
import struct

import pytest

from sawdds import msgs, values


def test_numbers_name_every_leaf_but_header_and_orientation():
    p = msgs.PoseStamped()
    p.pose.position.x = 0.25
    assert values.numbers(p) == {"pose.position.x": 0.25, "pose.position.y": 0.0, "pose.position.z": 0.0}
    js = msgs.JointState(name=["yaw", "pitch"], position=[1.0, 2.0])
    assert values.numbers(js) == {"position[yaw]": 1.0, "position[pitch]": 2.0}
    assert values.numbers(msgs.Bool(data=True)) == {"data": 1.0}


def test_forms_build_messages_and_refuse_bad_numbers():
    fields = [n for n, _ in values.form_fields(msgs.WrenchStamped)]
    assert fields == ["wrench.force.x", "wrench.force.y", "wrench.force.z",
                      "wrench.torque.x", "wrench.torque.y", "wrench.torque.z"]
    w = values.build(msgs.WrenchStamped, {n: "0" for n in fields} | {"wrench.force.z": "1.5"})
    assert w.wrench.force.z == 1.5
    for bad, why in (("nan", "not finite"), ("inf", "not finite"), ("x", "not a number")):
        with pytest.raises(values.Invalid, match=why):
            values.build(msgs.WrenchStamped, {n: "0" for n in fields} | {"wrench.force.x": bad})
    with pytest.raises(values.Invalid, match="outside"):
        values.parse_number("gain", "20000", float, (0, 1e4))
    assert values.build(msgs.StringStamped, {"string": "enable"}, "state").string == "enable"
    with pytest.raises(values.Invalid, match="not a state command"):
        values.build(msgs.StringStamped, {"string": "explode"}, "state")


def test_qualified_read_bytes_round_trip():
    assert values.pack("float64", "2.5") == struct.pack("<d", 2.5)
    assert values.pack("array<float64,3>", "1, 2 3") == struct.pack("<3d", 1, 2, 3)
    assert values.unpack("array<float64,3>", struct.pack("<3d", 1, 2, 3)) == "1 2 3"
    assert values.unpack("int64", struct.pack("<q", -7)) == "-7"
    assert values.unpack("saw::SdoReply", b"\x01\x02") == "01 02"  # not simple: shown as hex
    with pytest.raises(values.Invalid, match="3 value"):
        values.pack("array<float64,3>", "1 2")
    with pytest.raises(values.Invalid, match="cannot be typed"):
        values.pack("saw::SdoRequest", "1")
