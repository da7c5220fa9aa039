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


# What a CANopen arm whose drives or bus went away may say (its own FAULT), and its teleoperation's.
ARM_GONE = r"heartbeat|stale|reboot|lost|EMCY|drive|bus|node|send|CAN|deadline"


def allow_device_faults(d, device, text, seconds, injection):
    """The FAULTs an injection may cause on `device` (a component suffix: slave, master) and the
    teleoperation's that follows it, expected for `seconds`."""
    until = time.monotonic() + seconds
    d.faults.allow(rf"^{d.p}{device}$", text, until, injection)
    d.faults.allow(rf"^{d.p}teleop$", rf"{device} device in FAULT", until, injection)


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
    allow_device_faults(d, "slave", ARM_GONE, 60, "drive_reboot")
    d.drives.send_signal(signal.SIGKILL)
    d.drives.wait()
    time.sleep(rng.uniform(0.2, 1.0))
    d.start_drives()
    time.sleep(0.5)
    return s.ensure_enabled(d, timeout=30), f"drives started {d.drive_starts} times"


def can_bus_down(s, d, rng):
    """The CAN interface taken down for 0.2–1 s and up again (a cable pulled, a bus-off): the arm
    faults saying so — its frames refused, the drives' heartbeats and PDOs gone, or the drives
    stopping on their own RPDO deadline — and the teleoperation with it; an operator's enable
    starts the drives again and teleoperates."""
    ifname = d.bus.split(":", 1)[1]
    allow_device_faults(d, "slave", ARM_GONE, 60, "can_bus_down")
    subprocess.run(["ip", "link", "set", ifname, "down"], check=True)
    down = rng.uniform(0.2, 1.0)
    try:
        time.sleep(down)
    finally:
        subprocess.run(["ip", "link", "set", ifname, "up"], check=True)
    time.sleep(0.5)
    return s.ensure_enabled(d, timeout=30), f"{ifname} down for {down:.2f} s"


UDC = "/sys/kernel/config/usb_gadget/sawfalcon/UDC"


def falcon_replug(s, d, rng):
    """The Falcon unplugged (its USB gadget unbound from the controller) for 0.5–2 s and plugged in
    again: the Falcon faults saying it is gone, with zero force, and the teleoperation with it; the
    driver's I/O thread finds it again and loads its firmware (an enable before then is refused,
    saying it is not connected); an operator's enable homes it and teleoperates. Recovered when the
    Falcon is ENABLED, homed and no longer busy, and the teleoperation ENABLED."""
    s.device_reader(d, "master")  # before the unplug: it sees every state from here
    allow_device_faults(d, "master", r"unplugged|not connected|lost|usb|USB", 60, "falcon_replug")
    with open(UDC) as f:
        udc = f.read().strip()
    with open(UDC, "w") as f:
        f.write("\n")
    out = rng.uniform(0.5, 2.0)
    try:
        time.sleep(out)
    finally:
        with open(UDC, "w") as f:
            f.write(udc + "\n")
    time.sleep(1.0)
    if not s.ensure_enabled(d, timeout=30):
        return False, f"unplugged for {out:.2f} s; the teleoperation not ENABLED again"
    ready, seen = s.device_ready(d, "master", 30)
    return ready, f"unplugged for {out:.2f} s" + ("" if ready else f"; the Falcon last seen {seen}")


INJECTORS = {
    "gateway_kill": (gateway_kill, ("sim", "canopen", "bilateral", "falcon")),
    "peer_crash": (peer_crash, ("sim", "canopen", "bilateral", "falcon")),
    "bad_commands": (bad_commands, ("sim", "canopen", "bilateral")),
    "segment_scribble": (segment_scribble, ("sim", "canopen", "bilateral")),
    "drive_reboot": (drive_reboot, ("canopen",)),
    "can_bus_down": (can_bus_down, ("canopen",)),
    "falcon_replug": (falcon_replug, ("falcon",)),
}
# Kinds that need a real kernel interface (the PREEMPT_RT guest's vcan0 and USB gadget).
STRUCTURAL = {"can_bus_down": lambda d: d.bus.startswith("socketcan:")}


def applies(kind, d):
    """Whether fault `kind` can be injected on deployment `d`."""
    return d.kind in INJECTORS[kind][1] and STRUCTURAL.get(kind, lambda _: True)(d)
