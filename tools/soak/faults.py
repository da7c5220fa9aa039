"""The faults the soak injects, each with the faults it may cause and how recovery is judged.

Every injector returns (recovered, note). A fault it may cause is declared before it acts, on the
deployment's FaultLog, for as long as the injection and its recovery last (plus a margin); any
other FAULT the RT processes log is unexpected."""
import os
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
MARGIN = 3.0  # s after recovery in which a fault the injection caused may still be logged


def gateway_kill(s, d, rng):
    """kill -9 of the deployment's gateway, then a new one: the RT process runs on, and state flows
    again through the new gateway to the soak's readers (untouched)."""
    d.gw.kill()
    d.gw.wait()
    time.sleep(rng.uniform(0.1, 2.0))
    s.drain(d)
    d.start_gateway()
    return s.wait_state(d, 20), f"gateway {d.gw_starts} up"


def peer_crash(s, d, rng):
    """A DDS peer (another process) commands the teleoperation and, on the CANopen arm, asks its
    SDO qualified read in a loop; it is killed -9 mid-stream. The gateway and the RT process run on."""
    arm = [d.p + "slave"] if d.kind == "canopen" else []
    peer = subprocess.Popen([sys.executable, os.path.join(HERE, "peer.py"), "chatter", str(s.domain), d.teleop] + arm,
                            stdout=subprocess.DEVNULL, stderr=open(os.path.join(s.dir, "peer.err"), "a"))
    time.sleep(rng.uniform(1.0, 3.0))
    peer.kill()
    peer.wait()
    s.drain(d)
    ok = d.gw.poll() is None and s.wait_state(d, 10)
    return ok, "gateway alive, state flowing" if ok else f"gateway exit {d.gw.poll()}"


def bad_commands(s, d, rng):
    """A DDS peer sends a NaN force, an unknown state command and an out-of-range scale: each is
    refused with an error event, none reaches a device, nothing faults."""
    arm = d.p + ("slave" if d.kind == "canopen" else "master")
    r = subprocess.run([sys.executable, os.path.join(HERE, "peer.py"), "bad", str(s.domain), d.teleop, arm],
                       capture_output=True, text=True, timeout=60)
    note = (r.stdout.strip().splitlines() or [r.stderr.strip()[-200:]])[-1]
    # A FAULT these commands caused would be one no injection explains (unexpected, reported); a
    # late loop meanwhile is counted as such. Either way the teleoperation is enabled again.
    s.poll_faults()
    s.recover_timing()
    return r.returncode == 0 and s.ensure_enabled(d), note


def segment_scribble(s, d, rng):
    """Random bytes at random places of an exported component's segment, past its header page
    (what a stray or hostile process with the file can do): the RT process runs on; the gateway
    copes or is replaced, and state flows again."""
    comp = rng.choice(d.exports)
    path = f"/dev/shm/saw.{comp}"
    size = os.path.getsize(path)
    n = rng.randint(1, 64)
    with open(path, "r+b") as f:
        for _ in range(n):
            f.seek(rng.randrange(4096, size))
            f.write(bytes(rng.randrange(256) for _ in range(rng.randint(1, 16))))
    time.sleep(1.0)
    note = f"{n} writes to {path}"
    s.drain(d)
    if d.gw.poll() is not None or not s.wait_state(d, 5):
        note += f"; gateway replaced (it {'exited ' + str(d.gw.poll()) if d.gw.poll() is not None else 'delivered nothing'})"
        if d.gw.poll() is None:
            d.gw.kill()
            d.gw.wait()
        d.start_gateway()
    return s.wait_state(d, 20) and s.ensure_enabled(d), note


def drive_reboot(s, d, rng):
    """The CAN drives' process killed and started again (the drives reboot: boot-up, their
    configuration gone): the arm faults saying so and the teleoperation with it; an operator's
    enable, through DDS, configures the drives again and teleoperates."""
    d.faults.allow(rf"^{d.p}slave$", r"heartbeat|stale|reboot|lost|EMCY|drive|bus|node", time.monotonic() + 60, "drive_reboot")
    d.faults.allow(rf"^{d.p}teleop$", r"slave device in FAULT", time.monotonic() + 60, "drive_reboot")
    d.drives.send_signal(signal.SIGKILL)
    d.drives.wait()
    time.sleep(rng.uniform(0.2, 1.0))
    d.start_drives()
    time.sleep(0.5)
    return s.ensure_enabled(d, timeout=30), f"drives started {d.drive_starts} times"


INJECTORS = {
    "gateway_kill": (gateway_kill, ("sim", "canopen", "bilateral")),
    "peer_crash": (peer_crash, ("sim", "canopen", "bilateral")),
    "bad_commands": (bad_commands, ("sim", "canopen", "bilateral")),
    "segment_scribble": (segment_scribble, ("sim", "canopen", "bilateral")),
    "drive_reboot": (drive_reboot, ("canopen",)),
}
