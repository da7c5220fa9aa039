#!/usr/bin/env python3
"""The bilateral laws across two processes and two hosts, with the verdicts of the stepped clock:
the passive law stable at 50 ms with 10 % loss and jitter each way, the same coupling without
passivity unstable at 20 ms (the delay task makes the network: the kernel here has no netem). The run is placed on hosts
"operator" (the master and its passivity port) and "patient" (the slave, the delay task and the
law). `bridge`: both hosts on this machine, joined by the shared-memory bridge. `netns`: two network
namespaces joined by a veth pair, each with its own /dev/shm, joined by their gateways over DDS.
Exit 77 (skipped, the reason printed) where namespaces cannot be made.

A run whose loop was late (a VM's stall of 50 ms: a task's deadline FAULT) stopped itself safely
and gives no verdict either way: its FAULT is printed, every device's last output is checked to
be the safe one, and the run is made again, up to ATTEMPTS times. No verdict is ever taken from a
late run, and a law late in every attempt fails the test.
usage: bilateral_hosts.py bridge|netns SAW_RT WORKDIR"""
import os
import pathlib
import re
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "tools" / "experiments"))
import numpy as np  # noqa: E402
import bilateral_run as br  # noqa: E402
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "support" / "python"))
from saw_testing.dds_domain import dds_domain  # noqa: E402

MODE, SAW_RT, WORK = sys.argv[1], sys.argv[2], pathlib.Path(sys.argv[3])
WORK.mkdir(parents=True, exist_ok=True)
LAWS = {law.key: law for law in br.LAWS}
# Real threads on a shared VM: long enough for the unstable law to show, short enough for CI.
PATIENT_S, OPERATOR_S = 8, 11
ATTEMPTS = 3
LATE = re.compile(r"FAULT.*deadline missed")
UNSAFE = re.compile(r"^\s*\S+: FAULT, its last output NOT the safe one", re.M)


def sh(*args):
    return subprocess.run(args, capture_output=True, text=True)


class Namespaces:
    """Two network namespaces ("hosts") joined by a veth pair."""

    def __init__(self):
        tag = str(os.getpid())
        self.ns = {"operator": f"sbo-{tag}", "patient": f"sbp-{tag}"}
        net = f"10.212.{os.getpid() % 200 + 10}"
        self.ip = {"operator": f"{net}.1", "patient": f"{net}.2"}
        veth = {"operator": f"bo{tag}"[:15], "patient": f"bp{tag}"[:15]}
        r = sh("ip", "netns", "add", self.ns["operator"])
        if r.returncode != 0:
            print(f"SKIP: cannot create a network namespace here: {r.stderr.strip()}")
            sys.exit(77)
        cmds = [["ip", "netns", "add", self.ns["patient"]],
                ["ip", "link", "add", veth["operator"], "type", "veth", "peer", "name", veth["patient"]]]
        for h in ("operator", "patient"):
            cmds += [["ip", "link", "set", veth[h], "netns", self.ns[h]],
                     ["ip", "-n", self.ns[h], "addr", "add", f"{self.ip[h]}/24", "dev", veth[h]],
                     ["ip", "-n", self.ns[h], "link", "set", veth[h], "up"],
                     ["ip", "-n", self.ns[h], "link", "set", "lo", "up"]]
        for cmd in cmds:
            r = sh(*cmd)
            if r.returncode != 0:
                self.close()
                print(f"SKIP: cannot build the two-host network ({' '.join(cmd)}): {r.stderr.strip()}")
                sys.exit(77)

    def command(self, host, shell):
        # Each host its own /dev/shm (a mount namespace), so the bridge cannot shortcut the link.
        return ["ip", "netns", "exec", self.ns[host], "unshare", "--mount", "--propagation", "private", "sh",
                "-c", "mount -t tmpfs tmpfs /dev/shm && exec sh -c \"$0\"", shell]

    def close(self):
        for n in self.ns.values():
            sh("ip", "netns", "del", n)


def run(law, net, delay_ms, loss, jitter_ms):
    name = f"{MODE}_{law.key}"
    cfg = WORK / f"{name}.yaml"
    addresses = net.ip if net else None
    port = f"port{os.getpid()}"  # the segment the operator exports: /dev/shm is shared with other suites
    cfg.write_text(br.hosts_deployment(law, delay_ms, loss, jitter_ms, addresses, dds_domain(), port))
    csv = {h: WORK / f"{name}_{h}.csv" for h in ("operator", "patient")}
    lines = {h: f"{SAW_RT} {cfg} --host {h} --duration {d} --record {csv[h]} > {WORK}/{name}_{h}.log 2>&1"
             for h, d in (("patient", PATIENT_S), ("operator", OPERATOR_S))}
    # The operator first. Over the bridge the patient finds the port's segment at its start, so
    # it starts once the segment is there; over DDS its gateway mirrors the port when it appears.
    procs = {"operator": subprocess.Popen(net.command("operator", lines["operator"]) if net
                                          else ["sh", "-c", lines["operator"]])}
    segment = pathlib.Path(f"/dev/shm/saw.{port}")
    deadline = time.monotonic() + 20
    while not net and not segment.exists() and procs["operator"].poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    procs["patient"] = subprocess.Popen(net.command("patient", lines["patient"]) if net
                                        else ["sh", "-c", lines["patient"]])
    try:
        codes = {h: p.wait(timeout=90) for h, p in procs.items()}
    finally:
        for p in procs.values():
            if p.poll() is None:
                p.kill()
    logs = {h: (WORK / f"{name}_{h}.log").read_text().strip() for h in procs}
    for h in procs:
        print(f"--- {name} {h}\n{logs[h]}")
    if any(codes.values()):
        return None, f"saw-rt exited {codes}"
    unsafe = [m.group(0).strip() for h in logs for m in UNSAFE.finditer(logs[h])]
    if unsafe:
        return None, f"a FAULT whose last output was not the safe one: {unsafe[0]}"
    late = [line.strip() for h in logs for line in logs[h].splitlines() if LATE.search(line)]
    if late:
        return "late", late[0]
    data = {h: np.genfromtxt(csv[h], delimiter=",", names=True) for h in csv}
    stable, why, tracking, energy = br.split_figures(data["operator"], data["patient"], port)
    print(f"figure: {MODE} {law.key} at {delay_ms} ms, {loss * 100:.0f} % loss, ±{jitter_ms} ms: {why}; "
          f"tracking RMS {tracking * 1e3:.2f} mm; channel energy over the second half {energy:.4f} J")
    return stable, why


net = Namespaces() if MODE == "netns" else None
failures = []
try:
    for key, delay_ms, loss, jitter_ms, want in (("tdpa", 50, 0.1, 10, True), ("coupling", 20, 0, 0, False)):
        for attempt in range(1, ATTEMPTS + 1):
            stable, why = run(LAWS[key], net, delay_ms, loss, jitter_ms)
            if stable != "late":
                break
            print(f"late run of {key} ({attempt} of {ATTEMPTS}), stopped safely, no verdict from it: {why}")
        if stable == "late":
            failures.append(f"{key}: late in each of {ATTEMPTS} runs, no verdict (the last: {why})")
        elif stable is None or stable != want:
            failures.append(f"{key}: expected {'stable' if want else 'unstable'}, got {why}")
finally:
    if net:
        net.close()
if failures:
    print("\n".join(failures), file=sys.stderr)
    sys.exit(1)
