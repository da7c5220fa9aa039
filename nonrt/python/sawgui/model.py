"""What the GUI shows, without Qt: which topics its views read (the headless mode and the scale
benchmark subscribe to the same), the teleoperation's settings and their limits, and the
words a person reads for a state."""
from sawdds import values



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


def teleop_components(live) -> list:
    """Components that look like a teleoperation (a scale setting and a tracking error)."""
    out = []
    for name, c in sorted(live.components().items()):
        names = {e.name for e in c["endpoints"]}
        if {"set_scale", "tracking_error"} <= names:
            out.append(name)
    return out


def endpoint(live, component: str, name: str, kinds=("read", "write", "void", "write_event", "void_event")):
    for e in live.endpoints(component):
        if e.name == name and e.kind in kinds:
            return e
    return None


def teleop_sides(live, teleop: str):
    """(master, slave) component names of a teleoperation: the arms of the same gateway, by name."""
    comps = live.components()
    gw = comps.get(teleop, {}).get("gateway")
    arms = [n for n, c in sorted(comps.items()) if c["gateway"] == gw and n != teleop and
            any(e.name == "measured_cp" for e in c["endpoints"])]
    master = next((a for a in arms if "master" in a), arms[0] if arms else None)
    slave = next((a for a in arms if "slave" in a), arms[-1] if arms else None)
    return master, slave


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
