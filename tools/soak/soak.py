"""The soak: the three teleoperations (simulated, CANopen, bilateral) under stress-ng, with faults
injected at random (faults.py), and a report of what held.

usage: soak.py --bin DIR --src DIR [--minutes N] [--seed S] [--interval S] [--out DIR]

Fails (exit 1) when an RT process died, a FAULT came that no injection explains, an injection did
not recover, the RT processes' open files grew or their resident memory grew by more than
--rss-growth-kib, a recording lost a row, or saw-rt's orderly stop did not end in exit 0."""
import argparse
import os
import random
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "nonrt", "python"))
from deployments import Deployment  # noqa: E402
from faults import ARM_GONE, INJECTORS, MARGIN, allow_device_faults, applies  # noqa: E402
from watch import FaultLog, fds, rss_kib  # noqa: E402
from sawdds import Client, msgs  # noqa: E402
from cyclonedds.internal import InvalidSample  # noqa: E402

RECENTRE_S = 3.0  # s between re-centrings of an arm the law lets walk (Soak.recentre)


class Soak:
    def __init__(self, args):
        self.dir, self.domain = args.out, args.domain
        self.client = Client(self.domain)
        prefix = f"sk{os.getpid()}"
        self.deps = [Deployment(k, prefix + k[0], args.bin, args.src, self.dir, self.domain, can_bus=args.can_bus,
                                firmware=args.falcon_firmware, loose=args.loose_timing)
                     for k in args.deployments.split(",")]
        for d in self.deps:
            d.faults = FaultLog(d.log("err"))
            d.state = d.opstate = d.home = None
            d.homings = 0
        self.timing_recoveries, self.failures = [], []

    # ---- what recovery is judged by ----

    def readers(self, d):
        if d.state is None:
            # (An emulated guest takes tens of seconds to start a saw-rt and its gateway.)
            d.state = self.client.reader_for(self.client.find(f"rt/{d.teleop}/tracking_error", 90))
            d.opstate = self.client.reader_for(self.client.find(f"rt/{d.teleop}/operating_state", 30), reliable=True)

    def drain(self, d):
        d.state.take(N=1024)

    def wait_state(self, d, timeout):
        """A fresh tracking_error sample of the teleoperation arrived within `timeout` s."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if any(not isinstance(x, InvalidSample) for x in d.state.take(N=64)):
                return True
            time.sleep(0.01)
        return False

    def enabled(self, d, timeout=5.0):
        deadline = time.monotonic() + timeout
        last = None
        while time.monotonic() < deadline:
            for x in d.opstate.read(N=16):
                if not isinstance(x, InvalidSample):
                    last = x.state
            if last == "ENABLED":
                return True
            time.sleep(0.02)
        return False

    def ensure_enabled(self, d, timeout=20.0):
        """The teleoperation ENABLED again: the operator's enable of each device (the CANopen arm's
        or the Falcon's first), then of the teleoperation."""
        if self.enabled(d, 1.0):
            return True
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.poll_faults()
            if d.kind == "canopen" and "joint limit" in d.faults.last_line:
                self.home_arm(d)
            # Every device first (any may have faulted: a late loop faults each task that saw
            # it), then the teleoperation.
            for device in d.devices:
                self.client.send(f"rt/{device}/state_command", msgs.StringStamped(string="enable"), 5)
            time.sleep(1.0 if d.slow_enable else 0.3)
            self.client.send(f"rt/{d.teleop}/state_command", msgs.StringStamped(string="enable"), 5)
            if self.enabled(d, 3.0):
                if d.home is not None:
                    # As an operator would: the arm carried back to where the first enable had it
                    # (each enable keeps the arm where it lies, and faults that recur walk it off).
                    self.client.send(f"rt/{d.teleop}/set_slave_offset", d.home, 5)
                return True
        return False

    def device_reader(self, d, device):
        """A reader of a device's operating state (made before the fault it is to see)."""
        key = "reader_" + device
        if getattr(d, key, None) is None:
            e = self.client.find(f"rt/{d.p}{device}/operating_state", 30)
            setattr(d, key, self.client.reader_for(e, reliable=True))
        return getattr(d, key)

    def device_ready(self, d, device, timeout=30.0):
        """The device ENABLED, homed and no longer busy (its homing done: what it needs to be of
        use), and the teleoperation ENABLED; enabled again whenever it faulted meanwhile.
        Returns (ready, the device's last state seen)."""
        reader = self.device_reader(d, device)
        deadline = time.monotonic() + timeout
        last, seen = None, "no state"
        while time.monotonic() < deadline:
            for x in reader.read(N=1):  # latched: its latest state
                if not isinstance(x, InvalidSample):
                    last = x
                    seen = f"{x.state}{' homed' if x.is_homed else ''}{' busy' if x.is_busy else ''}"
            if last is not None and last.state == "FAULT":
                if not self.ensure_enabled(d, timeout=max(1.0, deadline - time.monotonic())):
                    return False, seen
                time.sleep(0.5)
            elif (last is not None and last.state == "ENABLED" and last.is_homed and not last.is_busy
                  and self.enabled(d, 0.5)):
                return True, seen
            time.sleep(0.05)
        return False, seen

    def home_arm(self, d):
        """An arm beyond its soft limit cannot be enabled (rightly); a lab moves it back by hand
        or homes it. Here the drives are simulated: started again, they are at their home."""
        d.homings += 1
        allow_device_faults(d, "slave", ARM_GONE + "|limit", 30, "homing")
        d.drives.kill()
        d.drives.wait()
        d.start_drives()
        time.sleep(0.5)
        d.faults.last_line = ""

    def first_offset(self, d):
        """The slave offset o_s the first enable made: the law's e_s = (p_s + o_s) − p_m at scale 1
        (docs/teleop-laws.md) is about zero, so o_s = p_m − p_s, from one row of the recording (the
        same cycle's master and slave)."""
        time.sleep(1.0)
        with open(d.log("csv")) as f:
            rows = [line for line in f.readlines()[-50:] if line.endswith("\n")]
        cells = [float(x) for x in rows[-1].split(",")]
        v = msgs.Vector3Stamped()
        v.vector.x, v.vector.y, v.vector.z = (cells[1 + i] - cells[8 + i] for i in range(3))
        return v

    def recentre(self):
        """As an operator keeps the arm in its workspace: the CANopen arm's offset set back to
        the first enable's. The paper's law lets the offset walk while a force is at its limit
        (its ratchet), and the arm's 3 N under gravity is at it: the slave drifts, and would
        reach a joint limit within a minute under stress-ng (up to 5 cm in 3 s was seen). In any
        state: while not ENABLED the next engagement starts from where the arm is anyway."""
        for d in self.deps:
            if d.home is not None:
                self.client.send(f"rt/{d.teleop}/set_slave_offset", d.home, 1)

    def rt_alive(self):
        return [d for d in self.deps if d.rt.poll() is not None]

    def sample(self):
        return {d.kind: (rss_kib(d.rt.pid), fds(d.rt.pid)) for d in self.deps}

    def poll_faults(self):
        for d in self.deps:
            d.faults.poll()

    def recover_timing(self):
        """After a timing FAULT, the operator's enable (the soak goes on teleoperating)."""
        for d in self.deps:
            if d.faults.timing_pending:
                d.faults.timing_pending = False
                ok = self.ensure_enabled(d)
                self.timing_recoveries.append(ok)
                if not ok:
                    self.failures.append(f"{d.kind}: not ENABLED again after a timing FAULT")


def summary_figures(out):
    cycles = [int(m.group(1)) for m in re.finditer(r"^\s+\S+\s+[0-9.]+ms\s+(\d+)\s", out, re.M)]
    rec = re.search(r"recorder: (\d+) rows to \S+, (\d+) rows lost", out)
    return (min(cycles) if cycles else 0, max(cycles) if cycles else 0,
            int(rec.group(1)) if rec else None, int(rec.group(2)) if rec else None)


def latency_max(out):
    """The largest wake-up latency of the run's tasks, from saw-rt's summary."""
    lat = [float(m.group(1)) for m in re.finditer(r"^\s+\S+\s+[0-9.]+ms\s+\d+\s+\d+\s+\d+\s+\S+\s+\S+\s+\S+\s+([0-9.]+)us",
                                                  out, re.M)]
    return f"{max(lat) / 1000:.1f} ms" if lat else "?"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--src", required=True)
    ap.add_argument("--minutes", type=float, default=60)
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("--interval", type=float, default=10.0, help="mean seconds between injections")
    ap.add_argument("--out", required=True)
    ap.add_argument("--domain", type=int, default=None)
    ap.add_argument("--rss-growth-kib", type=int, default=8192)
    ap.add_argument("--no-stress", action="store_true")
    ap.add_argument("--deployments", default="sim,canopen,bilateral",
                    help="of sim, canopen, bilateral, falcon (a Falcon on USB: the guest's gadget)")
    ap.add_argument("--can-bus", default=None, help="the CANopen arm's bus (default: a private virtual one), "
                                                     "e.g. socketcan:vcan0 (then can_bus_down applies)")
    ap.add_argument("--falcon-firmware", default=None, help="the firmware file of the falcon deployment")
    ap.add_argument("--loose-timing", action="store_true",
                    help="timing limits for a software-emulated machine (deployments.loosen)")
    ap.add_argument("--kinds", default=",".join(INJECTORS), help="the faults to inject, of " + ", ".join(INJECTORS))
    args = ap.parse_args()
    args.seed = args.seed if args.seed is not None else int(time.time()) % 100000
    args.domain = args.domain if args.domain is not None else 100 + os.getpid() % 100
    os.makedirs(args.out, exist_ok=True)
    rng = random.Random(args.seed)
    print(f"soak: {args.minutes:g} min, seed {args.seed}, DDS domain {args.domain} (loopback), logs in {args.out}",
          flush=True)

    s = Soak(args)
    failures, injections, timeline = s.failures, [], []
    stress = None
    start = end_sample = None
    try:
        for d in s.deps:
            d.start()
        for d in s.deps:
            s.readers(d)
            # A late loop in the first seconds (a FAULT for time, counted) is enabled again.
            s.poll_faults()
            if not s.enabled(d, 10) and not s.ensure_enabled(d, 30):
                raise SystemExit(f"soak: {d.kind}: the teleoperation did not reach ENABLED (see {d.log('err')})")
            d.faults.timing_pending = False
            if d.kind == "canopen":
                d.home = s.first_offset(d)
        if not args.no_stress:
            stress = subprocess.Popen(["stress-ng", "--cpu", "2", "--cpu-load", "50", "--vm", "1", "--vm-bytes", "128M",
                                       "--io", "1", "--timeout", f"{int(args.minutes * 60) + 120}s", "--quiet"],
                                      cwd=args.out, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(5)
        start = s.sample()
        timeline.append((0.0, start))
        t0 = time.monotonic()
        end = t0 + args.minutes * 60
        # Each kind on each deployment it applies to once, in a random order; then at random.
        kinds = [k for k in args.kinds.split(",") if any(applies(k, d) for d in s.deps)]
        plan = [(k, d) for k in kinds for d in s.deps if applies(k, d)]
        rng.shuffle(plan)
        next_sample = t0 + 60
        next_recentre = t0 + RECENTRE_S
        while time.monotonic() < end:
            wait_until = time.monotonic() + rng.uniform(0.5, 1.5) * args.interval
            while time.monotonic() < min(wait_until, end):
                s.poll_faults()
                s.recover_timing()
                if s.rt_alive():
                    break
                if time.monotonic() >= next_sample:
                    timeline.append((time.monotonic() - t0, s.sample()))
                    next_sample += 60
                if time.monotonic() >= next_recentre:
                    s.recentre()
                    next_recentre = time.monotonic() + RECENTRE_S
                time.sleep(0.2)
            if dead := s.rt_alive():
                failures.append(f"saw-rt of {', '.join(d.kind for d in dead)} died "
                                f"(exit {', '.join(str(d.rt.returncode) for d in dead)})")
                break
            if time.monotonic() >= end:
                break
            if plan:
                kind, d = plan.pop()
            else:
                kind = rng.choice(kinds)
                d = rng.choice([d for d in s.deps if applies(kind, d)])
            fn = INJECTORS[kind][0]
            s.poll_faults()
            s.recover_timing()
            at = time.monotonic() - t0
            began = time.monotonic()
            try:
                ok, note = fn(s, d, rng)
            except Exception as e:  # an injector that broke is a failed injection, said
                ok, note = False, f"{type(e).__name__}: {e}"
            took = time.monotonic() - began
            for x in s.deps:
                x.faults.close(kind, time.monotonic() + MARGIN)
            injections.append((at, kind, d.kind, ok, took, note))
            print(f"  {at:7.1f} s [{began:.3f}] {kind:17s} {d.kind:9s} {'recovered' if ok else 'NOT RECOVERED'} "
                  f"in {took:.1f} s: {note}", flush=True)
            if not ok:
                failures.append(f"{kind} on {d.kind} at {at:.1f} s did not recover: {note}")
        if plan:
            failures.append(f"the run ended before every kind of fault was injected on every deployment: "
                            f"{', '.join(f'{k} on {d.kind}' for k, d in plan)} not done (a longer --minutes)")
        time.sleep(MARGIN)
        s.poll_faults()
        end_sample = s.sample()
        timeline.append((time.monotonic() - t0, end_sample))
    finally:
        if stress and stress.poll() is None:
            stress.terminate()
            stress.wait()
        codes = {d.kind: d.stop() for d in s.deps}
    s.poll_faults()

    lines = [f"soak report: {args.minutes:g} min, seed {args.seed}, stress-ng {'off' if args.no_stress else 'on'}", ""]
    by_kind = {}
    for _, kind, _, ok, took, _ in injections:
        n, r, worst = by_kind.get(kind, (0, 0, 0.0))
        by_kind[kind] = (n + 1, r + ok, max(worst, took))
    lines.append("| fault injected | times | recovered | slowest recovery |")
    lines.append("|---|---|---|---|")
    for kind, (n, r, worst) in sorted(by_kind.items()):
        lines.append(f"| {kind} | {n} | {r} | {worst:.1f} s |")
    lines.append("")
    lines.append("| deployment | saw-rt exit | RSS start → end (KiB) | fds start → end | cycles (min task) | "
                 "rows recorded | rows lost | FAULTs injected | FAULTs for time | wake-up max | FAULTs at a joint limit | "
                 "FAULTs unexpected |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    safe_lines = []
    for d in s.deps:
        out = open(d.log("out")).read()
        cmin, _, rows, lost = summary_figures(out)
        r0, f0 = start[d.kind] if start else (None, None)
        r1, f1 = end_sample[d.kind] if end_sample else (None, None)
        lines.append(f"| {d.kind} | {codes[d.kind]} | {r0} → {r1} | {f0} → {f1} | {cmin} | {rows} | {lost} | "
                     f"{len(d.faults.expected)} | {len(d.faults.timing)} | {latency_max(out)} | {len(d.faults.limit)} | "
                     f"{len(d.faults.unexpected)} |")
        if codes[d.kind] != 0:
            failures.append(f"{d.kind}: saw-rt's orderly stop exited {codes[d.kind]}")
        if d.kind == "canopen":
            # saw-rt left every drive safe as it stopped: disabled, then pre-operational.
            left = d.drives_left()
            unsafe = [f"node {n} {nmt}, {st}" for n, nmt, st in left
                      if nmt != "pre-operational" or st != "switch on disabled"]
            if len(left) != 3 or unsafe:
                failures.append(f"{d.kind}: drives not left safe at the end: {unsafe or 'no table of drives'}")
            else:
                safe_lines.append(f"{d.kind}: its 3 drives left pre-operational and switch on disabled")
        if r0 is not None and r1 is not None and r1 - r0 > args.rss_growth_kib:
            failures.append(f"{d.kind}: saw-rt's resident memory grew {r1 - r0} KiB")
        if f0 is not None and f1 is not None and f1 > f0:
            failures.append(f"{d.kind}: saw-rt's open files grew from {f0} to {f1}")
        if lost is None:
            failures.append(f"{d.kind}: no recorder summary")
        elif lost > 0:
            failures.append(f"{d.kind}: the recording lost {lost} rows")
        if rows is not None and rows < cmin - 10:
            failures.append(f"{d.kind}: {rows} rows recorded for {cmin} cycles")
        for line in d.faults.unexpected:
            failures.append(f"{d.kind}: unexpected {line.strip()}")
    if s.timing_recoveries:
        lines.append(f"\nFAULTs for time (a late task or drive, each safe): {sum(len(d.faults.timing) for d in s.deps)}; "
                     f"the soak enabled the teleoperation again {sum(s.timing_recoveries)} of {len(s.timing_recoveries)} times")
    if safe_lines:
        lines.append("\nAt the end: " + "; ".join(safe_lines))
    homed = sum(d.homings for d in s.deps)
    if homed:
        lines.append(f"\nArms homed (beyond a soft limit, the CANopen drives started again at their home, as a lab "
                     f"moves the arm back): {homed}")
    lines.append("")
    lines.append("resident memory (KiB) and open files of each saw-rt, by minute: " + "; ".join(
        f"{t / 60:.0f} min " + ", ".join(f"{k} {v[0]}/{v[1]}" for k, v in smp.items()) for t, smp in timeline))
    lines.append("")
    lines += [f"FAIL: {f}" for f in failures] or ["ok: every injection recovered, no unexpected FAULT, "
                                                  "nothing lost, memory and files flat, every stop orderly"]
    report = "\n".join(lines)
    print(report)
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write(report + "\n")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
