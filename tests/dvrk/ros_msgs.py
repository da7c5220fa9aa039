"""ROS 2 messages for the simulated dVRK arm, field for field, as this directory's own Cyclone DDS
dataclasses (rosidl's DDS names pkg::msg::dds_::Type_, XCDR1), and the dVRK bridge's QoS
(docs/design/dvrk-arms.md A1, A4). Written from the ROS message definitions, not from sawdds.msgs:
a mistake shared with the repository's IDL cannot pass unnoticed."""
import os
from dataclasses import dataclass, field

# Loopback only, before cyclonedds is imported (it reads CYCLONEDDS_URI once): a test's arm must
# not be seen by, or see, another host. The same configuration as nonrt/python/sawdds/client.py.
LOOPBACK_URI = (
    "<CycloneDDS><Domain Id='any'><General><Interfaces><NetworkInterface name='lo'/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>31</MaxAutoParticipantIndex>"
    "<Peers><Peer address='127.0.0.1'/></Peers></Discovery></Domain></CycloneDDS>"
)
os.environ.setdefault("CYCLONEDDS_URI", LOOPBACK_URI)

from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl import types as t  # noqa: E402
from cyclonedds.util import duration  # noqa: E402


# --- ROS 2 messages, field for field (rosidl's DDS names: pkg::msg::dds_::Type_; @final, unkeyed) ---

@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32 = 0
    nanosec: t.uint32 = 0


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class Empty(IdlStruct, typename="std_msgs::msg::dds_::Empty_"):
    # ROS 2 gives an empty message one byte, as IDL has no empty struct.
    structure_needs_at_least_one_member: t.uint8 = 0


@dataclass
class Bool(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
    data: bool = False


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str = ""


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    w: float = 1.0


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass
class TwistStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TwistStamped_"):
    header: Header = field(default_factory=Header)
    twist: Twist = field(default_factory=Twist)


@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    force: Vector3 = field(default_factory=Vector3)
    torque: Vector3 = field(default_factory=Vector3)


@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    header: Header = field(default_factory=Header)
    wrench: Wrench = field(default_factory=Wrench)


@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header = field(default_factory=Header)
    name: t.sequence[str] = field(default_factory=list)
    position: t.sequence[float] = field(default_factory=list)
    velocity: t.sequence[float] = field(default_factory=list)
    effort: t.sequence[float] = field(default_factory=list)


@dataclass
class Joy(IdlStruct, typename="sensor_msgs::msg::dds_::Joy_"):
    header: Header = field(default_factory=Header)
    axes: t.sequence[t.float32] = field(default_factory=list)
    buttons: t.sequence[t.int32] = field(default_factory=list)


@dataclass
class OperatingState(IdlStruct, typename="crtk_msgs::msg::dds_::OperatingState_"):
    header: Header = field(default_factory=Header)
    state: str = ""
    is_homed: bool = False
    is_busy: bool = False


@dataclass
class StringStamped(IdlStruct, typename="crtk_msgs::msg::dds_::StringStamped_"):
    header: Header = field(default_factory=Header)
    # The ROS field is named "string"; IDL escapes the keyword as `_string`, which names "string".
    string: str = ""


# --- QoS (A4) ---

XCDR1 = Policy.DataRepresentation(use_cdrv0_representation=True)  # what ROS 2 sends (A1, C7)
_RELIABLE = Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100))
COMMAND_QOS = Qos(_RELIABLE, Policy.Durability.Volatile, Policy.History.KeepLast(1), XCDR1)
STATE_QOS = Qos(_RELIABLE, Policy.Durability.Volatile, Policy.History.KeepLast(100), XCDR1)
EVENT_QOS = Qos(_RELIABLE, Policy.Durability.TransientLocal, Policy.History.KeepLast(100), XCDR1)


def stamp_of(seconds):
    ns = int(seconds * 1e9)
    return Time(sec=ns // 10**9, nanosec=ns % 10**9)
