"""A DDS peer of the soak (Cyclone DDS, through sawdds): a process the soak starts and kills.

  peer.py chatter DOMAIN TELEOP [ARM]   commands the teleoperation (its scale, unchanged) and, with
                                        ARM (a CANopen arm), asks its `sdo` qualified read (the
                                        statusword of node 1) in a loop, until killed: mid-call
  peer.py bad DOMAIN TELEOP ARM         sends commands a gateway must refuse (a NaN force to ARM, an
                                        unknown state command and an out-of-range scale to TELEOP)
                                        and exits 0 when each came back refused on the error topics
"""
import os
import struct
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "nonrt", "python"))
from sawdds import Client, msgs  # noqa: E402
from sawdds.client import XCDR1  # noqa: E402
from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402


def chatter(domain, teleop, arm=None):
    c = Client(domain)
    w, _ = c.writer(f"rt/{teleop}/set_scale")
    if arm:
        qos = Qos(Policy.Reliability.Reliable(10**9), Policy.History.KeepLast(16), XCDR1)
        ask = DataWriter(c.participant, c._topic(f"rq/{arm}/sdoRequest", msgs.Query), qos=qos)
        DataReader(c.participant, c._topic(f"rr/{arm}/sdoReply", msgs.QueryReply), qos=qos)
    # saw::canopen::SdoRequest: tag, index, subindex, node, write, size, data[8] (20 bytes, aligned)
    sdo = list(struct.pack("<IHBBBB8s2x", 1, 0x6041, 0, 1, 0, 0, bytes(8)))
    print("chatter: running", flush=True)
    n = 0
    while True:
        w.write(msgs.Float64(data=1.0))
        if arm:
            n += 1
            ask.write(msgs.Query(client=os.getpid(), number=n, data=sdo))
        time.sleep(0.005)


def bad(domain, teleop, arm):
    c = Client(domain)
    errors = {n: c.error_reader(n) for n in (teleop, arm)}
    for r in errors.values():
        c.wait_matched(r, 10)
    nan = msgs.WrenchStamped()
    nan.wrench.force.x = float("nan")
    c.send(f"rt/{arm}/servo_cf", nan, 10)
    c.send(f"rt/{teleop}/state_command", msgs.StringStamped(string="explode"), 10)
    c.send(f"rt/{teleop}/set_scale", msgs.Float64(data=1e9), 10)
    want = {(arm, "servo_cf"), (teleop, "state_command"), (teleop, "set_scale")}
    seen = set()
    deadline = time.monotonic() + 10
    while want - seen and time.monotonic() < deadline:
        for comp, r in errors.items():
            for e in r.take(N=16):
                for w in want:
                    if w[0] == comp and hasattr(e, "string") and w[1] in e.string:
                        seen.add(w)
        time.sleep(0.01)
    print(f"bad: {len(seen)} of {len(want)} refused; not: {sorted(want - seen)}", flush=True)
    return 0 if seen == want else 1


if __name__ == "__main__":
    mode, domain = sys.argv[1], int(sys.argv[2])
    if mode == "chatter":
        chatter(domain, *sys.argv[3:5])
    else:
        sys.exit(bad(domain, *sys.argv[3:5]))
