"""Interop with an independent DDS (Cyclone DDS, Python): a real saw-rt process exports a simulated
arm, a real saw-gateway maps it to DDS on loopback, and this client (sawdds) lists it, reads its
state, sends commands (valid ones run, invalid ones are refused with an error event) and sees FAULT
when the RT process is killed with -9.

usage: cyclone_interop.py SAW_RT SAW_GATEWAY
"""
import os
import signal
import subprocess
import sys
import tempfile
import time


from harness import check, dds_domain, exit_code, wait_for  # noqa: E402
from sawdds import Client, msgs  # noqa: E402
from cyclonedds.internal import InvalidSample  # noqa: E402  (after sawdds: CYCLONEDDS_URI)


def main(saw_rt, saw_gateway):
    name = f"arm{os.getpid()}"
    domain = dds_domain()  # tests running side by side do not see each other
    yaml = f"""deployment:
  name: interop-{name}
components:
  - name: {name}
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80}}
    params:
      model: omni
      hand: {{type: sinusoid, amplitude: [0.03, 0.0, 0.0], frequency: 0.5, stiffness: 200, damping: 2}}
exports:
  - {{component: {name}, provided: arm}}
"""
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        f.write(yaml)
    rt = subprocess.Popen([saw_rt, f.name], stdout=subprocess.DEVNULL)
    gw = subprocess.Popen([saw_gateway, "--attach", name, "--domain", str(domain), "--wait", "10"],
                          stdout=subprocess.PIPE, text=True)
    try:
        c = Client(domain)
        topic = f"rt/{name}/"
        ms = c.manifests(10, until=lambda ms: any(e.component_name == name for m in ms.values() for e in m.endpoints))
        ends = {e.name: e for m in ms.values() for e in m.endpoints if e.component_name == name}
        check(set(ends) >= {"measured_cp", "measured_cv", "servo_cf", "state_command", "operating_state"},
              f"the registry lists {name}'s commands and events: {sorted(ends)}")
        check(ends.get("measured_cp") and ends["measured_cp"].dds_type == "geometry_msgs::msg::dds_::PoseStamped_",
              "measured_cp is a ROS 2 PoseStamped")

        cp = c.reader(topic + "measured_cp")
        first = wait_for(cp, lambda s: True, 5)
        check(first is not None and first.header.frame_id == name, "state arrives, stamped with the component")
        later = wait_for(cp, lambda s: abs(s.pose.position.x - first.pose.position.x) > 1e-4, 5) if first else None
        check(later is not None, "the state changes (the simulated hand moves the arm)")
        js = wait_for(c.reader(topic + "measured_js"), lambda s: True, 5)
        check(js is not None and js.name == ["yaw", "shoulder_pitch", "elbow_pitch"] and len(js.position) == 3,
              f"measured_js names each joint, as ROS tools need: {js.name if js else None}")

        states = c.reader(topic + "operating_state")
        errors = c.error_reader(name)
        check(c.wait_matched(states) and c.wait_matched(errors), "the event and error readers match the gateway")

        c.send(topic + "state_command", msgs.StringStamped(string="disable"))
        s = wait_for(states, lambda s: s.state == "DISABLED", 5)
        check(s is not None, "a state_command sent from Cyclone DDS runs: operating_state DISABLED arrives")

        c.send(topic + "state_command", msgs.StringStamped(string="explode"))
        e = wait_for(errors, lambda e: "state_command" in e.string, 5)
        check(e is not None and "unknown state command" in e.string,
              f"an unknown state command is refused with an error event: {e.string if e else None!r}")
        nan = msgs.WrenchStamped()
        nan.wrench.force.x = float("nan")
        c.send(topic + "servo_cf", nan)
        e = wait_for(errors, lambda e: "servo_cf" in e.string, 5)
        check(e is not None and "not finite" in e.string,
              f"a NaN force is refused before the bridge: {e.string if e else None!r}")

        # kill -9 of the gateway: the RT process runs on; a new gateway re-attaches; this client's
        # readers, untouched, receive again.
        gw.kill()
        gw.wait()
        cp.take(N=64)
        time.sleep(0.2)  # a window with no gateway (a bound, not a race: nothing below depends on it)
        check(rt.poll() is None, "the RT process survives its gateway's kill -9")
        check(not [s for s in cp.take(N=64) if not isinstance(s, InvalidSample)], "no state while no gateway runs")
        gw = subprocess.Popen([saw_gateway, "--attach", name, "--domain", str(domain), "--wait", "10"],
                              stdout=subprocess.PIPE, text=True)
        again = wait_for(cp, lambda s: True, 10)
        check(again is not None, "a restarted gateway re-attaches and the same reader receives again")
        c.send(topic + "state_command", msgs.StringStamped(string="explode"))
        e = wait_for(errors, lambda e: "state_command" in e.string, 5)
        check(e is not None, "commands flow through the new gateway")
        c.send(topic + "state_command", msgs.StringStamped(string="enable"))
        check(wait_for(states, lambda s: s.state == "ENABLED", 5) is not None, "enable runs: ENABLED arrives")

        t0 = time.monotonic()
        rt.send_signal(signal.SIGKILL)
        rt.wait()
        fault = wait_for(states, lambda s: s.state == "FAULT", 5)
        dt = (time.monotonic() - t0) * 1e3
        check(fault is not None, f"kill -9 of the RT process: FAULT published ({dt:.0f} ms after the kill)")
        print(f"figure: FAULT seen by the Cyclone DDS client {dt:.1f} ms after kill -9", flush=True)
        m = c.manifests(3, until=lambda ms: any(x.state == "FAULT" for x in ms.values()))
        check(any(x.state == "FAULT" for x in m.values()), "the manifest says FAULT")
    finally:
        if rt.poll() is None:
            rt.kill()
        gw.send_signal(signal.SIGTERM)
        out, _ = gw.communicate(timeout=10)
        print(out.strip().splitlines()[-1] if out.strip() else "(no gateway output)")
        rejected = [l for l in out.splitlines() if "rejected" in l]
        check(bool(rejected) and " 1 rejected" in rejected[-1], "the new gateway counted its refused command")
        os.unlink(f.name)
        # kill -9 leaves the RT process's segment behind (a new server would take it over).
        if os.path.exists(f"/dev/shm/saw.{name}"):
            os.unlink(f"/dev/shm/saw.{name}")
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
