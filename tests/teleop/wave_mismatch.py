#!/usr/bin/env python3
"""A wave law whose impedance is not its master port's does not start: saw-rt exits 1 with one line
naming both values and the teleoperation component, in one process and with the port in another
process (read through the shared-memory bridge); with the same impedance both start.
usage: wave_mismatch.py SAW_RT WORKDIR"""
import dataclasses
import os
import pathlib
import re
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "tools" / "experiments"))
import bilateral_run as br  # noqa: E402

SAW_RT, WORK = sys.argv[1], pathlib.Path(sys.argv[2])
WORK.mkdir(parents=True, exist_ok=True)
WAVE = next(law for law in br.LAWS if law.key == "wave")  # b = 3 at both ends
MISMATCHED = dataclasses.replace(WAVE, port=WAVE.port.replace("wave_impedance: 3", "wave_impedance: 2"))
assert MISMATCHED.port != WAVE.port and "impedance: 3" in WAVE.params
failures = []


def expect_refused(name, rt):
    lines = [line for line in rt.stderr.splitlines() if line.startswith("saw-rt:")]
    line = lines[0] if lines else ""
    ok = (rt.returncode == 1 and len(lines) == 1 and line.startswith("saw-rt: component 'teleop': ")
          and "impedance 3 N·s/m" in line
          and re.search(r"port_wave_impedance from the master \('w?port\d*\.arm', through 'link\.arm'\) "
                        r"is 2 N·s/m", line) is not None)
    print(f"{'ok  ' if ok else 'FAIL'} {name}: exit {rt.returncode}: {line}")
    if not ok:
        failures.append(f"{name}: exit {rt.returncode}, not 1 with one line naming both values:\n{rt.stderr}")


def one_process(law):
    cfg = WORK / f"one_{law is WAVE}.yaml"
    cfg.write_text(br.deployment(law, 20, 0.0))  # with a link: the port is read through the delay task
    return subprocess.run([SAW_RT, str(cfg), "--duration", "0.5"], capture_output=True, text=True, timeout=60)


def two_processes(law, patient_s):
    """The port on "operator", the link and the law on "patient", joined by the bridge."""
    port = f"wport{os.getpid()}"
    cfg = WORK / f"two_{law is WAVE}.yaml"
    cfg.write_text(br.hosts_deployment(law, 20, 0.0, port=port))
    operator = subprocess.Popen([SAW_RT, str(cfg), "--host", "operator", "--duration", str(patient_s + 5)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        segment, deadline = pathlib.Path(f"/dev/shm/saw.{port}"), time.monotonic() + 20
        while not segment.exists() and operator.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        return subprocess.run([SAW_RT, str(cfg), "--host", "patient", "--duration", str(patient_s)],
                              capture_output=True, text=True, timeout=60)
    finally:
        operator.terminate()
        operator.wait(timeout=30)


expect_refused("one process, b = 3 at the law, 2 at the port", one_process(MISMATCHED))
rt = one_process(WAVE)
print(f"{'ok  ' if rt.returncode == 0 else 'FAIL'} one process, b = 3 at both ends: exit {rt.returncode}")
if rt.returncode != 0:
    failures.append(f"the matched wave deployment did not run: {rt.stderr}")

expect_refused("two processes, b = 3 at the law, 2 at the port", two_processes(MISMATCHED, 1))
rt = two_processes(WAVE, 1)
print(f"{'ok  ' if rt.returncode == 0 else 'FAIL'} two processes, b = 3 at both ends: exit {rt.returncode}")
if rt.returncode != 0:
    failures.append(f"the matched wave deployment over the bridge did not run: {rt.stderr}")

if failures:
    print("\n".join(failures), file=sys.stderr)
    sys.exit(1)
