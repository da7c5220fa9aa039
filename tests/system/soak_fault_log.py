"""The soak's judge of FAULT lines (tools/soak/watch.py FaultLog): a FAULT an injection may cause
is expected when it was *logged* within the injection's window, however late the soak reads it;
one logged after the window, or matching no injection, is unexpected; a teleoperation's FAULT
that follows its device's goes with it. Usage: soak_fault_log.py SRC"""
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(sys.argv[1], "tools", "soak"))
from watch import FaultLog  # noqa: E402

failures = []


def check(what, ok):
    print(f"{'ok  ' if ok else 'FAIL'} {what}")
    if not ok:
        failures.append(what)


with tempfile.TemporaryDirectory() as d:
    path = os.path.join(d, "rt.err")
    log = FaultLog(path)
    now = time.monotonic()
    # The window of an injection on the master ended 1 s ago; the soak reads the lines only now.
    log.allow(r"^xmaster$", r"unplugged|answer", now - 1.0, "falcon_replug")
    with open(path, "w") as f:
        f.write(f"[{now - 1.5:.6f}] error xmaster: FAULT (zero force): usb no answer, exchange after exchange\n")
        f.write(f"[{now - 1.5:.6f}] error xteleop: FAULT: master device in FAULT: 0 ns old, last read ok\n")
        f.write(f"[{now - 0.5:.6f}] error xmaster: FAULT (zero force): usb no answer, exchange after exchange\n")
        f.write(f"[{now - 0.4:.6f}] error xslave: FAULT: something no injection explains\n")
        f.write(f"[{now - 0.3:.6f}] warning xslave: no servo command for 5 ms: zero force\n")
    log.poll()
    check("a FAULT logged within the window but read after it is expected",
          [e[0] for e in log.expected if isinstance(e, tuple)] == ["falcon_replug"])
    check("the teleoperation's FAULT after its device's goes with it (not unexpected)",
          any("xteleop" in e for e in log.expected if isinstance(e, str))
          and not any("xteleop" in u for u in log.unexpected))
    check("a FAULT logged after the window is unexpected",
          any("xmaster" in u and f"{now - 0.5:.6f}" in u for u in log.unexpected))
    check("a FAULT no injection explains is unexpected", any("xslave" in u for u in log.unexpected))
    check("a warning is not a FAULT", len(log.unexpected) == 2)

print("soak_fault_log: " + (f"{len(failures)} failed" if failures else "all passed"))
sys.exit(1 if failures else 0)
