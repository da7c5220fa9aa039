#!/usr/bin/env python3
"""A wave law's master port restarted, in its own process, with another wave_impedance while the
teleoperation runs: the running teleoperation (another process, reached through the shared-memory
bridge, whose proxy reconnects to the new port) goes to FAULT naming both values and both
components, and drives the slave no more. Real processes: saw-rt on the deployment's two hosts.
usage: wave_restart.py SAW_RT WORKDIR"""
import csv
import dataclasses
import os
import pathlib
import queue
import re
import signal
import subprocess
import sys
import threading
import time

HERE = pathlib.Path(__file__).resolve()
sys.path.insert(0, str(HERE.parents[2] / "tools" / "experiments"))
sys.path.insert(0, str(HERE.parents[1] / "system"))
import bilateral_run as br  # noqa: E402
from service_ready import NotifySocket  # noqa: E402

SAW_RT, WORK = sys.argv[1], pathlib.Path(sys.argv[2])
WORK.mkdir(parents=True, exist_ok=True)
WAVE = next(law for law in br.LAWS if law.key == "wave")  # b = 3 at both ends
RESTARTED = dataclasses.replace(WAVE, port=WAVE.port.replace("wave_impedance: 3", "wave_impedance: 2"))
assert RESTARTED.port != WAVE.port and "impedance: 3" in WAVE.params
PORT = f"wport{os.getpid()}"
# The port's process is away between the two (a saw-rt start: well under a second here): the law
# holds meanwhile (no wave, no force), and only an input silent for the longest stale_timeout a
# deployment may give would be a fault, so the FAULT is the impedance's.
STALE = "stale_timeout: 10s"


def deployment(law, name):
    text = br.hosts_deployment(law, 20, 0.0, port=PORT)
    assert "stale_timeout: 500ms" in text and "teleop.tracking_error]" in text
    path = WORK / name
    path.write_text(text.replace("stale_timeout: 500ms", STALE)
                    .replace("teleop.tracking_error]", "teleop.tracking_error, teleop.operating_state]"))
    return path


def start(cfg, host, notify, **kw):
    p = subprocess.Popen([SAW_RT, str(cfg), "--host", host, "--duration", "120"], env=notify.env(), text=True,
                         **kw)
    if not notify.wait("READY=1", p, 60):
        p.kill()
        out = p.communicate()[1] if kw.get("stderr") == subprocess.PIPE else ""
        sys.exit(f"FAIL: saw-rt --host {host} did not start: exit {p.poll()}\n{out or ''}")
    return p


def stop(p):
    if p.poll() is None:
        p.send_signal(signal.SIGTERM)
    try:
        p.wait(timeout=30)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()


matched, restarted = deployment(WAVE, "matched.yaml"), deployment(RESTARTED, "restarted.yaml")
record = WORK / "patient.csv"
notify = [NotifySocket() for _ in range(3)]
operator = patient = operator2 = None
lines, failures = queue.Queue(), []
try:
    operator = start(matched, "operator", notify[0], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    patient = subprocess.Popen([SAW_RT, str(matched), "--host", "patient", "--duration", "120", "--record",
                                str(record)], env=notify[1].env(), text=True, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT)
    threading.Thread(target=lambda: [lines.put(line) for line in patient.stdout], daemon=True).start()
    if not notify[1].wait("READY=1", patient, 60):
        sys.exit(f"FAIL: the patient did not start (b = 3 at both ends): exit {patient.poll()}")
    print("ok   the teleoperation runs, b = 3 at the law and at the port in the other process")

    stop(operator)  # the port's process ends, and comes back with b = 2 under the same name
    operator2 = start(restarted, "operator", notify[2], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    print("ok   the port's process restarted with wave_impedance 2")

    fault, seen, deadline = None, [], time.monotonic() + 30
    while fault is None and time.monotonic() < deadline and patient.poll() is None:
        try:
            line = lines.get(timeout=0.2)
        except queue.Empty:
            continue
        seen.append(line)
        if "FAULT: law" in line:
            fault = line.strip()
    if fault is None:
        failures.append("the running teleoperation did not FAULT within 30 s of the port's restart with another "
                        "b; it said:\n" + "".join(seen[-20:]))
    else:
        ok = (re.search(r"\bteleop: FAULT: law 'wave_variables' has impedance 3 N·s/m, but its input "
                        rf"port_wave_impedance from the master \('{PORT}\.arm', through 'link\.arm'\) is now "
                        r"2 N·s/m", fault)
              is not None)
        print(f"{'ok  ' if ok else 'FAIL'} the teleoperation FAULTs: {fault}")
        if not ok:
            failures.append(f"the FAULT does not name both values and both components: {fault}")
finally:
    for p in (patient, operator2, operator):
        if p is not None:
            stop(p)
    for n in notify:
        n.close()

rest = []
while not lines.empty():
    rest.append(lines.get())
summary = next((line for line in rest if line.strip().startswith("teleop: FAULT (")), "")
ok = "master configuration mismatch" in summary and "is now 2 N·s/m" in summary
print(f"{'ok  ' if ok else 'FAIL'} the run's summary says why: {summary.strip()}")
if not ok:
    failures.append("the summary does not say why:\n" + "".join(rest))

# The slave driven no more: from the cycle the teleoperation FAULTed, it stayed in FAULT and sent
# the slave zero force.
with open(record) as f:
    rows = list(csv.DictReader(f))
first = next((i for i, r in enumerate(rows) if r["teleop.operating_state"] == "FAULT"), len(rows))
after = rows[first:]
forces = [abs(float(r[f"teleop.slave_force.{a}"])) for r in after for a in "xyz"]
ok = len(after) > 0 and all(r["teleop.operating_state"] == "FAULT" for r in after) and max(forces) == 0
driven = sum(1 for r in rows[:first] if float(r["teleop.slave_force.x"] or 0) != 0)
print(f"{'ok  ' if ok else 'FAIL'} zero force to the slave from the FAULT on ({len(after)} rows; before it "
      f"{first} rows, {driven} with a force)")
if not ok:
    failures.append(f"the slave's forces around the FAULT: {first} rows before it, {len(after)} after, "
                    f"max after {max(forces, default=None)}")

if failures:
    print("\n".join(failures), file=sys.stderr)
    sys.exit(1)
