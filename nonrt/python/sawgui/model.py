"""What the GUI shows, without Qt: which topics its views read (the headless mode and the scale
benchmark subscribe to the same), the teleoperation's settings and their limits, and the
words a person reads for a state."""
import math

from sawdds import msgs, values



def limits(endpoint):
    """(min, max) a write command's component declares (the registry carries them), or None."""
    return (endpoint.limit_min, endpoint.limit_max) if endpoint is not None and endpoint.limited else None


def read_back(live, component: str, command) -> object:
    """The read endpoint that publishes the current value of write command `command` (same
    message type): `set_X` is read back as `X`, a CRTK `servo_Y` / `move_Y` as `setpoint_Y`;
    None when the component publishes none (a form then starts empty, never from a guess)."""
    if command is None:
        return None
    name = command.name
    wanted = [name[4:]] if name.startswith("set_") else (
        ["setpoint_" + name.split("_", 1)[1]] if name.startswith(("servo_", "move_")) else [])
    for e in live.endpoints(component):
        if e.kind == "read" and e.name in wanted and e.dds_type == command.dds_type and e.topic:
            return e
    return None


def form_texts(sample, fields) -> dict:
    """{field name: text} of a form's fields (values.form_fields) from a sample of the same type."""
    out = {}
    for name, kind in fields:
        v = sample
        for part in name.split("."):
            v = getattr(v, part, None)
        if v is None:
            continue
        if kind is list:
            out[name] = " ".join(f"{x:.6g}" for x in v)
        elif kind in (int, float):
            out[name] = f"{v:.6g}"
        elif kind is bool:
            out[name] = "true" if v else "false"
        else:
            out[name] = str(v)
    return out


def placeholder(lim) -> str:
    """What an empty numeric field says it wants."""
    return f"within [{lim[0]:g}, {lim[1]:g}]" if lim else "a number"
STATE_COLORS = {"ENABLED": "#1f9d3a", "DISABLED": "#6b6b6b", "PAUSED": "#c98a00", "FAULT": "#d01010",
                "GONE": "#404040", "": "#909090"}


TELEOPERATION = "teleoperation"


def teleop_components(live) -> list:
    """Components that say they are a teleoperation: the kind in their description (the read
    `description`, saw_msgs/ComponentDescription), whatever their commands are named."""
    out = []
    for name, c in sorted(live.components().items()):
        d = live.description(name)
        if d is not None and d.kind == TELEOPERATION and c.get("gone_at") is None:
            out.append(name)
    return out


def role_servers(live, component: str) -> dict:
    """{role: component name} of the roles a component declares, from the servers its
    description names ("component.interface"); a role not connected has None."""
    d = live.description(component)
    if d is None:
        return {}
    return {role: (server.rsplit(".", 1)[0] or None) if server else None for role, server in zip(d.roles, d.servers)}


def endpoint(live, component: str, name: str, kinds=("read", "write", "void", "write_event", "void_event")):
    for e in live.endpoints(component):
        if e.name == name and e.kind in kinds:
            return e
    return None


def teleop_sides(live, teleop: str):
    """(master, slave) component names of a teleoperation: the components its description says
    play the roles "master" and "slave"."""
    roles = role_servers(live, teleop)
    return roles.get("master"), roles.get("slave")


class DeclaredSetting:
    """One setting a component declares (its description): name, unit, bounds, how many numbers,
    whether it is a command; with its read-back endpoint `name` and its write endpoint
    `set_<name>` (None when the gateway does not serve or map them) and the message class of each."""

    def __init__(self, declared, read, write):
        self.name, self.unit, self.count, self.command = declared.name, declared.unit, declared.count, declared.command
        self.bounds = (declared.min, declared.max)
        self.read = read if read is not None and read.topic and read.dds_type in msgs.BY_DDS_NAME else None
        self.write = write if write is not None and write.topic and write.dds_type in msgs.BY_DDS_NAME else None
        source = self.write or self.read
        self.cls = msgs.BY_DDS_NAME[source.dds_type] if source is not None else None
        self.fields = values.form_fields(self.cls) if self.cls is not None else []

    @property
    def finite_bounds(self):
        """The bounds when both are finite (the form checks them), else None."""
        return self.bounds if all(math.isfinite(b) for b in self.bounds) else None

    def label(self) -> str:
        unit = f" ({self.unit})" if self.unit else ""
        flag = bool(self.fields) and all(kind is bool for _, kind in self.fields)
        lim = None if flag else self.finite_bounds  # a flag's [0, 1] says nothing
        return f"{self.name}{unit}" + (f"  [{lim[0]:g}, {lim[1]:g}]" if lim else "")


def declared_settings(live, component: str) -> list:
    """The settings a component declares, in its declaration order (DeclaredSetting each); empty
    before its description arrives."""
    d = live.description(component)
    if d is None:
        return []
    return [DeclaredSetting(s, endpoint(live, component, s.name, kinds=("read",)),
                            endpoint(live, component, "set_" + s.name, kinds=("write",)) if s.command else None)
            for s in d.settings]


def teleop_topics(live, teleop: str) -> list:
    """What the teleoperation panel reads."""
    master, slave = teleop_sides(live, teleop)
    # What it draws and says; not the forces (1 kHz it would decode and never show).
    wanted = [(teleop, "tracking_error"), (teleop, "fault"), (slave, "measured_cp"), (master, "measured_cp"),
              (master, "clutch")]
    return [e.topic for c, n in wanted if c for e in [endpoint(live, c, n)] if e is not None and e.topic]


def component_topics(live, component: str) -> list:
    """What a component view reads: every mapped read command and event."""
    return sorted({e.topic for e in live.endpoints(component)
                   if e.topic and e.kind in ("read", "write_event", "void_event")})


def task_topics(live) -> list:
    """Every mapped period_statistics read (a task's cycles, overruns and wake-up latencies)."""
    return [e.topic for c in live.components() for e in live.endpoints(c)
            if e.name == "period_statistics" and e.kind == "read" and e.topic]


def default_topics(live) -> list:
    """What the window reads when it opens: the system view (operating states and refusals, which
    Live reads anyway), the teleoperation panel and the task health."""
    out = []
    for t in teleop_components(live):
        out += teleop_topics(live, t)
    return out + task_topics(live)


def shown_state(component: dict) -> str:
    """The state a person reads: a FAULT stays said once the component has gone ("FAULT (gone)")."""
    state = component.get("state") or ""
    if component.get("gone_at"):
        return "FAULT (gone)" if state == "FAULT" else "GONE"
    return state


def state_color(state: str) -> str:
    return STATE_COLORS.get(state.split(" ")[0] if state else "", "#909090")


__all__ = ["values"]
