"""What the views stand on, without a window: sawdds.cdr's batch decoding gives the numbers the
message objects give, for every message type; its ROS 2 schemas decode our CDR in an independent
reader (mcap_ros2, from the schema text alone); a window's series breaks where the samples
stopped (a NaN row: the plot draws a gap, not a line); a form starts from the value the component
publishes, and from nothing else."""
import math
import types

import numpy as np
from mcap.records import Schema
from mcap_ros2.decoder import DecoderFactory

from sawdds import cdr, msgs, values
from sawdds.live import Series
from sawgui import model


def filled(cls):
    """A sample of `cls` with a distinct value in every leaf (strings and sequences not empty)."""
    s = cls()
    counter = iter(range(1, 1000))

    def fill(obj):
        for f in obj.__dataclass_fields__:
            v = getattr(obj, f)
            if hasattr(v, "__dataclass_fields__"):
                fill(v)
            elif isinstance(v, bool):
                setattr(obj, f, True)
            elif isinstance(v, int):
                setattr(obj, f, next(counter))
            elif isinstance(v, float):
                setattr(obj, f, next(counter) + 0.25)
            elif isinstance(v, str):
                setattr(obj, f, "x" * next(counter))
    fill(s)
    if cls is msgs.JointState:
        s.name, s.position, s.velocity, s.effort = ["a", "bc"], [1.5, 2.5], [3.5, 4.5], [5.5, 6.5]
    if cls is msgs.Joy:
        s.axes, s.buttons = [0.5, -0.5], [1, 0, 1]
    return s


def test_a_batch_decodes_to_the_numbers_of_every_message_type():
    for cls in msgs.BY_DDS_NAME.values():
        if cls in (msgs.Manifest,):
            continue
        s = filled(cls)
        data, names = s.serialize(), list(values.numbers(s))
        layout = cdr.Layout(cls, data, names)
        got, _ = layout.decode([data, data])
        assert list(got[1]) == list(values.numbers(s).values()), cls.__name__
    # A sample laid out otherwise (a longer string) is not decoded with the first's layout.
    a, b = msgs.OperatingState(state="ENABLED"), msgs.OperatingState(state="DISABLED")
    layout = cdr.Layout(msgs.OperatingState, a.serialize(), list(values.numbers(a)))
    assert layout.decode([a.serialize(), b.serialize()]) is None


def test_the_ros2_schemas_decode_our_cdr_in_an_independent_reader():
    factory = DecoderFactory()
    for i, cls in enumerate(msgs.BY_DDS_NAME.values()):
        s = filled(cls)
        schema = Schema(id=i + 1, name=cdr.ros_name(cls), encoding="ros2msg", data=cdr.ros2msg(cls).encode())
        decoded = factory.decoder_for("cdr", schema)(s.serialize())
        for name, x in values.numbers(s).items():
            v = decoded
            for part in name.replace("]", "").replace("[", ".").split("."):
                v = v[int(part)] if part.isdigit() else (getattr(v, part) if not isinstance(v, list) else
                                                        v[s.name.index(part)])
            assert math.isclose(float(v), x), (cls.__name__, name, v, x)


def test_a_gap_in_the_samples_is_a_break_in_the_series():
    e = types.SimpleNamespace(dds_type="std_msgs::msg::dds_::Float64_", kind="read", component_name="c")
    s = Series(e, window=10.0)
    before = [(msgs.Float64(data=1.0).serialize(), 100 + i * 0.001) for i in range(500)]
    after = [(msgs.Float64(data=2.0).serialize(), 101 + i * 0.001) for i in range(500)]  # 0.5 s without one
    s.add_raw(before)
    s.add_raw(after)
    t, rows = s.window_arrays(2000)
    nan = np.nonzero(np.isnan(rows[:, 0]))[0]
    assert len(nan) == 1 and t[nan[0] - 1] < 100.5 < t[nan[0] + 1], (nan, t[nan[0] - 1:nan[0] + 2])
    assert s.count == 1000 and s.stats[0] == 1000 and s.stats[1][0] == 1.0 and s.stats[2][0] == 2.0


class FakeLive:
    def __init__(self, endpoints, latest):
        self._endpoints, self._latest = endpoints, latest

    def endpoints(self, component):
        return self._endpoints

    def latest(self, topic):
        return self._latest.get(topic, (None, None))


def endpoint(name, kind, dds_type, topic):
    return types.SimpleNamespace(name=name, kind=kind, dds_type=dds_type, topic=topic, limited=False)


def test_a_form_starts_from_the_published_value_and_nothing_else():
    ms = "saw_msgs::msg::dds_::MasterSlave_"
    gains = endpoint("set_gains", "write", ms, "rt/t/set_gains")
    limits = endpoint("set_force_limits", "write", ms, "rt/t/set_force_limits")
    back = endpoint("gains", "read", ms, "rt/t/gains")
    live = FakeLive([gains, limits, back], {"rt/t/gains": (msgs.MasterSlave(master=300, slave=250), 0)})
    assert model.read_back(live, "t", gains) is back
    assert model.read_back(live, "t", limits) is None  # not published: the form starts empty
    sample, _ = live.latest(back.topic)
    assert model.form_texts(sample, values.form_fields(msgs.MasterSlave)) == {"master": "300", "slave": "250"}
    cp = endpoint("servo_cp", "write", "geometry_msgs::msg::dds_::PoseStamped_", "rt/a/servo_cp")
    setpoint = endpoint("setpoint_cp", "read", "geometry_msgs::msg::dds_::PoseStamped_", "rt/a/setpoint_cp")
    assert model.read_back(FakeLive([cp, setpoint], {}), "a", cp) is setpoint
    assert model.placeholder((0, 10000)) == "within [0, 10000]"


def test_a_batch_becomes_one_message_not_one_per_sample(monkeypatch):
    """What keeps the reader thread off the interpreter lock: a batch of 1 kHz samples is decoded
    by numpy, and only its newest sample becomes a Python message."""
    e = types.SimpleNamespace(dds_type="geometry_msgs::msg::dds_::PoseStamped_", kind="read", component_name="c")
    s = Series(e, window=10.0)
    made = []
    real = msgs.PoseStamped.deserialize.__func__
    monkeypatch.setattr(msgs.PoseStamped, "deserialize",
                        classmethod(lambda cls, data, **kw: made.append(1) or real(cls, data, **kw)))
    p = msgs.PoseStamped()
    batch = []
    for i in range(1000):
        p.pose.position.x = i * 1e-3
        batch.append((p.serialize(), 100 + i * 1e-3))
    s.add_raw(batch[:500])
    s.add_raw(batch[500:])
    assert len(made) == 3, len(made)  # the layout's first sample, then each batch's newest
    assert s.count == 1000 and s.last.pose.position.x == 0.999
    names, _, rows = s.names, *s.window_arrays(10**6)
    assert names[0] == "pose.position.x" and rows[-1][0] == 0.999 and len(rows) == 1000


class DescribedLive:
    """Components with endpoints and (some) descriptions, as Live has them."""

    def __init__(self, components, descriptions):
        self._components, self._descriptions = components, descriptions

    def components(self):
        return {n: {"endpoints": eps, "gone_at": None} for n, eps in self._components.items()}

    def endpoints(self, component):
        return self._components.get(component, [])

    def description(self, component):
        return self._descriptions.get(component)


def test_a_teleoperation_is_what_its_description_says_not_what_its_commands_are_named():
    f64 = "std_msgs::msg::dds_::Float64_"
    # A component with a teleoperation's command names but no description, and one named like
    # nothing in particular that says it is a teleoperation, its master the arm named "zz".
    lookalike = [endpoint("set_scale", "write", f64, "rt/l/set_scale"),
                 endpoint("tracking_error", "read", f64, "rt/l/tracking_error")]
    ops = [endpoint("set_stiffness", "write", f64, "rt/ops/set_stiffness"),
           endpoint("stiffness", "read", f64, "rt/ops/stiffness")]
    declared = [msgs.DeclaredSetting(name="stiffness", unit="N/m", min=0.0, max=1e4, count=1, command=True),
                msgs.DeclaredSetting(name="mirror", unit="", min=-math.inf, max=math.inf, count=3, command=False)]
    d = msgs.ComponentDescription(kind="teleoperation", variant="position_position", roles=["master", "slave"],
                                  servers=["zz.arm", "aa_master.arm"], settings=declared)
    live = DescribedLive({"lookalike": lookalike, "ops": ops, "zz": [], "aa_master": []}, {"ops": d})
    assert model.teleop_components(live) == ["ops"]
    assert model.teleop_sides(live, "ops") == ("zz", "aa_master")
    settings = model.declared_settings(live, "ops")
    assert [s.name for s in settings] == ["stiffness", "mirror"]
    assert settings[0].label() == "stiffness (N/m)  [0, 10000]"
    assert settings[0].fields == [("data", float)] and settings[0].write.topic == "rt/ops/set_stiffness"
    assert settings[1].label() == "mirror" and settings[1].finite_bounds is None
    assert settings[1].read is None and settings[1].write is None  # not served: the row says so
