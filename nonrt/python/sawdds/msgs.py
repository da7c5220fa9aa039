"""The ROS 2 / CRTK messages sawrt's gateway uses, for Cyclone DDS (field for field as nonrt/msgs/idl).

Type names are the ROS 2 DDS names (``pkg::msg::dds_::Type_``); all are @final and travel as
XCDR1, the representation Fast DDS 2.9 and ROS 2 use.
"""
from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import final
import cyclonedds.idl.types as t


@final
@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32 = 0
    nanosec: t.uint32 = 0


@final
@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@final
@dataclass
class Float64(IdlStruct, typename="std_msgs::msg::dds_::Float64_"):
    data: t.float64 = 0.0


@final
@dataclass
class Int64(IdlStruct, typename="std_msgs::msg::dds_::Int64_"):
    data: t.int64 = 0


@final
@dataclass
class Bool(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
    data: bool = False


@final
@dataclass
class Empty(IdlStruct, typename="std_msgs::msg::dds_::Empty_"):
    structure_needs_at_least_one_member: t.uint8 = 0


@final
@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@final
@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@final
@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0
    w: t.float64 = 1.0


@final
@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@final
@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@final
@dataclass
class Vector3Stamped(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3Stamped_"):
    header: Header = field(default_factory=Header)
    vector: Vector3 = field(default_factory=Vector3)


@final
@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@final
@dataclass
class TwistStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TwistStamped_"):
    header: Header = field(default_factory=Header)
    twist: Twist = field(default_factory=Twist)


@final
@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    force: Vector3 = field(default_factory=Vector3)
    torque: Vector3 = field(default_factory=Vector3)


@final
@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    header: Header = field(default_factory=Header)
    wrench: Wrench = field(default_factory=Wrench)


@final
@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header = field(default_factory=Header)
    name: t.sequence[str] = field(default_factory=list)
    position: t.sequence[t.float64] = field(default_factory=list)
    velocity: t.sequence[t.float64] = field(default_factory=list)
    effort: t.sequence[t.float64] = field(default_factory=list)


@final
@dataclass
class Joy(IdlStruct, typename="sensor_msgs::msg::dds_::Joy_"):
    header: Header = field(default_factory=Header)
    axes: t.sequence[t.float32] = field(default_factory=list)
    buttons: t.sequence[t.int32] = field(default_factory=list)


@final
@dataclass
class OperatingState(IdlStruct, typename="crtk_msgs::msg::dds_::OperatingState_"):
    header: Header = field(default_factory=Header)
    state: str = ""
    is_homed: bool = False
    is_busy: bool = False


@final
@dataclass
class StringStamped(IdlStruct, typename="crtk_msgs::msg::dds_::StringStamped_"):
    header: Header = field(default_factory=Header)
    string: str = ""


@final
@dataclass
class Endpoint(IdlStruct, typename="saw_msgs::msg::dds_::Endpoint_"):
    component_name: str = ""
    interface_name: str = ""
    name: str = ""
    kind: str = ""
    saw_type: str = ""
    saw_size: t.uint32 = 0
    saw_version: t.uint32 = 0
    dds_type: str = ""
    topic: str = ""
    result_type: str = ""
    result_size: t.uint32 = 0
    result_version: t.uint32 = 0
    limited: bool = False
    limit_min: t.float64 = 0.0
    limit_max: t.float64 = 0.0


@final
@dataclass
class MasterSlave(IdlStruct, typename="saw_msgs::msg::dds_::MasterSlave_"):
    header: Header = field(default_factory=Header)
    master: t.float64 = 0.0
    slave: t.float64 = 0.0


@final
@dataclass
class TaskStatistics(IdlStruct, typename="saw_msgs::msg::dds_::TaskStatistics_"):
    header: Header = field(default_factory=Header)
    cycles: t.uint64 = 0
    overruns: t.uint64 = 0
    missed_periods: t.uint64 = 0
    period: t.int64 = 0
    last_wakeup_latency: t.int64 = 0
    max_wakeup_latency: t.int64 = 0
    last_compute: t.int64 = 0
    max_compute: t.int64 = 0
    mean_compute: t.float64 = 0.0


@final
@dataclass
class Manifest(IdlStruct, typename="saw_msgs::msg::dds_::Manifest_"):
    header: Header = field(default_factory=Header)
    host: str = ""
    pid: t.int32 = 0
    gateway: str = ""
    state: str = ""
    endpoints: t.sequence[Endpoint] = field(default_factory=list)


@final
@dataclass
class Query(IdlStruct, typename="saw_msgs::msg::dds_::Query_"):
    client: t.uint64 = 0
    number: t.uint64 = 0
    data: t.sequence[t.byte, 256] = field(default_factory=list)


@final
@dataclass
class QueryReply(IdlStruct, typename="saw_msgs::msg::dds_::QueryReply_"):
    client: t.uint64 = 0
    number: t.uint64 = 0
    status: t.int32 = 0
    data: t.sequence[t.byte, 256] = field(default_factory=list)


BY_DDS_NAME = {cls.__idl_typename__: cls for cls in (
    Float64, Int64, Bool, Empty, PoseStamped, Vector3Stamped, TwistStamped, WrenchStamped, JointState, Joy,
    OperatingState, StringStamped, MasterSlave, TaskStatistics, Manifest, Query, QueryReply)}
