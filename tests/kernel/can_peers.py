"""Our SocketCAN backend against independent peers on a vcan, inside the PREEMPT_RT guest.

Our side is saw-kernel-can-side (tests/kernel/can_side.cpp, the public saw/can/bus.hpp API
only); the peers are can-utils (cansend, candump) and python-can's `socketcan` interface, both
written apart from our code. Each check writes RESULTS/can.<check>.result (`pass`, or `fail: why`)
and its log to RESULTS/can.<check>.log:

- classic:     our classic frames (11- and 29-bit, a remote request) reach candump and python-can
               intact, and theirs reach us intact and in order;
- fd:          the same with CAN FD frames (64 and 12 bytes, bit-rate switch), the vcan at MTU 72;
- filters:     a receive filter of ours (100:700) passes exactly the matching peers' frames;
- error_frame: error frames from the peers (controller warning, then passive) move our bus state
               and are counted, never handed over as data;
- bus_down:    `ip link set IF down` in the middle of a 1 kHz cycle shows as state `down` and
               refused frames within a second, with no call that blocks or spins (each call short,
               the process's CPU time a fraction of the run); back up, frames go out again.

Needs root in a kernel with vcan (the guest). Usage: can_peers.py SIDE IFNAME RESULTS
"""

import os
import queue
import re
import select
import subprocess
import sys
import threading
import time
import traceback

import can

SIDE, IFNAME, RESULTS = sys.argv[1:4]


class CheckFailed(Exception):
    pass


def check(cond, why):
    if not cond:
        raise CheckFailed(why)


def parse(text):
    """A frame in cansend's / candump -L's form as (id, extended, remote, fd, brs, data)."""
    m = re.fullmatch(r"([0-9A-Fa-f]{3}|[0-9A-Fa-f]{8})(##([0-9A-Fa-f])|#)(R\d?|[0-9A-Fa-f.]*)", text.strip())
    check(m is not None, f"not a frame: {text!r}")
    ident, ext = int(m.group(1), 16), len(m.group(1)) == 8
    fd = m.group(2).startswith("##")
    brs = fd and (int(m.group(3), 16) & 1) != 0
    remote = m.group(4).startswith("R")
    data = b"" if remote else bytes.fromhex(m.group(4).replace(".", ""))
    return (ident, ext, remote, fd, brs, data)


def from_message(msg):
    return (msg.arbitration_id, msg.is_extended_id, msg.is_remote_frame, msg.is_fd,
            bool(msg.is_fd and msg.bitrate_switch), b"" if msg.is_remote_frame else bytes(msg.data))


def log_frames(lines):
    """Frames of candump -L lines: `(time) ifname frame`."""
    return [parse(line.split()[2]) for line in lines if len(line.split()) == 3]


class Side:
    """saw-kernel-can-side running; its "open" line read before any peer sends."""

    def __init__(self, args, log):
        self.log = log
        self.proc = subprocess.Popen([SIDE, f"socketcan:{IFNAME}", *args], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
        line = self.proc.stderr.readline()
        if not line.startswith("open "):  # (the rest of stderr only then: reading it waits for the exit)
            raise CheckFailed(f"saw-kernel-can-side did not open the bus: {line}{self.proc.stderr.read()}")

    def finish(self, timeout=20):
        out, err = self.proc.communicate(timeout=timeout)
        self.log.append(f"saw-kernel-can-side exit {self.proc.returncode}\n{out}{err}")
        end = re.search(r"^end state=(\S+) error_frames=(\d+) received=(\d+) sent=(\d+) refused=(\d+)$", out, re.M)
        check(end is not None, "saw-kernel-can-side printed no end line")
        return self.proc.returncode, out, dict(zip(("state", "error_frames", "received", "sent", "refused"),
                                                   end.groups()))


class Candump:
    """candump -L on the interface, ready once it has printed a probe frame sent after it started."""

    PROBE = "7FF#5A"

    def __init__(self, log):
        self.log = log
        self.proc = subprocess.Popen(["candump", "-L", IFNAME], stdout=subprocess.PIPE, text=True)
        self.lines = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()
        deadline = time.monotonic() + 10
        while True:
            check(time.monotonic() < deadline, "candump never printed a probe frame")
            subprocess.run(["cansend", IFNAME, self.PROBE], check=True)
            try:
                line = self.lines.get(timeout=0.2)
                if line.split()[2:] == [self.PROBE]:
                    break
            except queue.Empty:
                pass
        # Probes sent before candump printed the first may still be on their way: drain them.
        while True:
            try:
                line = self.lines.get(timeout=0.3)
            except queue.Empty:
                break
            check(line.split()[2:] == [self.PROBE], f"unexpected frame while draining probes: {line}")

    def _read(self):
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))

    def take(self, n, timeout=5):
        got, deadline = [], time.monotonic() + timeout
        while len(got) < n and time.monotonic() < deadline:
            try:
                got.append(self.lines.get(timeout=max(0.0, deadline - time.monotonic())))
            except queue.Empty:
                break
        self.log.append("candump:\n" + "\n".join(got))
        return log_frames(got)

    def close(self):
        self.proc.terminate()
        self.proc.wait(timeout=10)


def pycan_bus():
    return can.Bus(interface="socketcan", channel=IFNAME, fd=True, receive_own_messages=False)


def pycan_take(bus, n, log, timeout=5):
    got, deadline = [], time.monotonic() + timeout
    while len(got) < n and time.monotonic() < deadline:
        msg = bus.recv(timeout=max(0.0, deadline - time.monotonic()))
        if msg is None:
            break
        if msg.is_error_frame or msg.arbitration_id == 0x7FF:
            continue
        got.append(from_message(msg))
    log.append("python-can: " + repr(got))
    return got


def both_ways(log, ours, theirs_cansend, theirs_pycan, fd):
    """Our frames out to candump and python-can; the peers' frames in to us, in order."""
    pc = pycan_bus()
    dump = Candump(log)
    try:
        side = Side((["--fd"] if fd else []) + ["receive", "--count", "0", *sum((["--send", f] for f in ours), [])],
                    log)
        rc, _, end = side.finish()
        check(rc == 0 and end["sent"] == str(len(ours)), f"we did not send our {len(ours)} frames: {end}")
        want = [parse(f) for f in ours]
        got = dump.take(len(ours))
        check(got == want, f"candump saw {got}, we sent {want}")
        got = pycan_take(pc, len(ours), log)
        check(got == want, f"python-can saw {got}, we sent {want}")

        n = len(theirs_cansend) + len(theirs_pycan)
        side = Side((["--fd"] if fd else []) + ["receive", "--count", str(n), "--timeout", "10"], log)
        for f in theirs_cansend:
            subprocess.run(["cansend", IFNAME, f], check=True)
        for msg in theirs_pycan:
            pc.send(msg)
        rc, out, end = side.finish()
        got = log_frames(out.splitlines())
        want = [parse(f) for f in theirs_cansend] + [from_message(m) for m in theirs_pycan]
        check(rc == 0 and got == want, f"we received {got} (exit {rc}), the peers sent {want}")
    finally:
        dump.close()
        pc.shutdown()


def check_classic(log):
    both_ways(log, ["123#11223344", "1ABCDEF0#0102", "321#R"], ["456#DEADBEEF", "0000ABCD#01"],
              [can.Message(arbitration_id=0x7A, data=[1, 2, 3], is_extended_id=False),
               can.Message(arbitration_id=0x1234567, data=[], is_extended_id=True)], fd=False)


def check_fd(log):
    payload64 = "".join(f"{i:02X}" for i in range(64))
    both_ways(log, ["123##1" + payload64, "12345678##0" + "A5" * 12], ["456##1" + payload64[:48]],
              [can.Message(arbitration_id=0x1F00F, data=bytes(range(32)), is_extended_id=True, is_fd=True,
                           bitrate_switch=True)], fd=True)


def check_filters(log):
    pc = pycan_bus()
    try:
        side = Side(["--filter", "100:700", "receive", "--count", "2", "--timeout", "10"], log)
        subprocess.run(["cansend", IFNAME, "223#01"], check=True)  # 0x223 & 0x700 = 0x200: filtered
        subprocess.run(["cansend", IFNAME, "123#02"], check=True)
        pc.send(can.Message(arbitration_id=0x523, data=[4], is_extended_id=False))  # filtered
        pc.send(can.Message(arbitration_id=0x1AB, data=[3], is_extended_id=False))
        rc, out, _ = side.finish()
        got = log_frames(out.splitlines())
        want = [parse("123#02"), parse("1AB#03")]
        check(rc == 0 and got == want, f"through filter 100:700 we received {got} (exit {rc}), want {want}")
    finally:
        pc.shutdown()


def check_error_frame(log):
    pc = pycan_bus()
    try:
        side = Side(["receive", "--count", "1", "--timeout", "10"], log)
        # CAN_ERR_FLAG | CAN_ERR_CRTL; data[1] = CAN_ERR_CRTL_TX_WARNING (linux/can/error.h).
        subprocess.run(["cansend", IFNAME, "20000004#0008000000000000"], check=True)
        # Then CAN_ERR_CRTL_TX_PASSIVE from python-can, then a data frame.
        pc.send(can.Message(arbitration_id=0x4, data=[0, 0x20, 0, 0, 0, 0, 0, 0], is_error_frame=True,
                            is_extended_id=False))
        pc.send(can.Message(arbitration_id=0x42, data=[1], is_extended_id=False))
        rc, out, end = side.finish()
        got = log_frames(out.splitlines())
        check(rc == 0 and got == [parse("042#01")], f"we received {got} (exit {rc}): only the data frame is data")
        check(end["error_frames"] == "2", f"error frames counted: {end['error_frames']}, want 2")
        check(end["state"] == "error-passive" or end["state"] == "error_passive",
              f"bus state after a warning then a passive error frame: {end['state']}")
    finally:
        pc.shutdown()


def check_bus_down(log):
    seconds = 4.0
    side = Side(["cycle", "--seconds", str(seconds)], log)
    changes = []
    lines = []

    def read():
        for line in side.proc.stdout:
            lines.append(line)
            m = re.match(r"state (\S+) at (\d+) ms", line)
            if m:
                changes.append((m.group(1), time.monotonic()))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        time.sleep(1.0)  # mid-run: the cycle has been sending for a second
        subprocess.run(["ip", "link", "set", IFNAME, "down"], check=True)
        went_down = time.monotonic()
        while not any(s == "down" for s, _ in changes) and time.monotonic() < went_down + 2:
            time.sleep(0.01)
        time.sleep(0.5)
    finally:
        subprocess.run(["ip", "link", "set", IFNAME, "up"], check=True)
    came_up = time.monotonic()
    _, ru = os.wait4(side.proc.pid, 0)[1:]
    reader.join(timeout=10)
    out = "".join(lines)
    err = side.proc.stderr.read()
    log.append(out + err)
    cpu = ru.ru_utime + ru.ru_stime
    log.append(f"cpu time {cpu:.3f} s over {seconds} s")
    downs = [t for s, t in changes if s == "down"]
    check(downs, "the bus never reported `down` after ip link set down")
    check(downs[0] - went_down < 1.0, f"`down` reported {downs[0] - went_down:.3f} s after the link went down")
    check(any(s != "down" and t > came_up - 0.05 for s, t in changes),
          "the bus did not come back from `down` once the link was up (no frame went out)")
    m = re.search(r"cycles=(\d+) refused_in_cycle=(\d+) longest_call_us=(\d+)", out)
    check(m is not None, "no cycle summary")
    cycles, refused, longest = map(int, m.groups())
    check(refused > 0, "no frame was refused while the link was down")
    check(longest < 50_000, f"a receive()/send() call took {longest} us: it blocked")
    check(re.search(r"^end state=error-active|^end state=error_active", out, re.M) is not None,
          "the bus did not end error-active after the link came back")
    log.append(f"cycles {cycles}, refused {refused}, longest call {longest} us")


def main():
    failed = 0
    for name, fn in (("classic", check_classic), ("fd", check_fd), ("filters", check_filters),
                     ("error_frame", check_error_frame), ("bus_down", check_bus_down)):
        log = []
        try:
            fn(log)
            result = "pass"
        except Exception as e:  # a check's failure, or a peer that broke: either fails the check
            result = f"fail: {e}" if isinstance(e, CheckFailed) else f"fail: {traceback.format_exc()}"
            failed += 1
            # What the kernel says about the interface and its receivers, for the log.
            log.append(subprocess.run(["ip", "-details", "-statistics", "link", "show", IFNAME],
                                      capture_output=True, text=True).stdout)
            with open("/proc/net/can/rcvlist_all") as f:
                log.append(f.read())
            log.append(subprocess.run(["ps", "-ef"], capture_output=True, text=True).stdout)
        with open(os.path.join(RESULTS, f"can.{name}.log"), "w") as f:
            f.write("\n".join(log) + "\n")
        with open(os.path.join(RESULTS, f"can.{name}.result"), "w") as f:
            f.write(result + "\n")
        print(f"can.{name}: {result}", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
