"""Beyond one subnet: discovery without multicast. Three network namespaces — operator, router,
patient — routed, with no multicast forwarding (as a router between a lab's subnets, a VPN).
The patient runs saw-rt with its gateway on its own address; the operator runs `sawctl list`
on its own. Multicast discovery cannot cross the router, so:
(a) with no peer list, the operator finds nothing (the test's premise: were this found, the
    network would not be the one claimed);
(b) with the patient's address as the operator's peer (`sawctl --peer`), it finds the gateway;
(c) with $ROS_STATIC_PEERS instead of the flag, too;
(d) with the operator's address as the patient gateway's peer (`gateway: {peers: [...]}` in the
    deployment), a sawctl without any peer list finds it too (the gateway announces itself);
(e) the GUI (`sawgui --headless`, Cyclone DDS) with `--peer PATIENT` sees the component and its
    values, and without it sees nothing; (f) with $ROS_STATIC_PEERS instead, too;
(g) secure: the gateway with its enclave (DDS Security, a keystore `sawctl security` makes), a
    sawctl with an operator's enclave and `--peer` finds it, one with the peer but no enclave does
    not;
(h) a discovery server (Debian's `fast-discovery-server`, Fast DDS's own) on the router: the
    gateway and sawctl, each given only $ROS_DISCOVERY_SERVER, find each other
    through it.
(i) on the patient's own subnet (sawctl on the router), multicast finds the gateway, but not with
    ROS 2's ROS_AUTOMATIC_DISCOVERY_RANGE=OFF or LOCALHOST; OFF with ROS_STATIC_PEERS does; sawgui
    there finds it, and not with OFF.
A peer list that is ignored fails (b), (c), (d), (e), (f) or (g); a server address ignored, (h);
the range ignored, (i).

With --netem SPEC (the PREEMPT_RT guest's kernel has netem; the host's has not) the patient's
link is a wireless hop shaped both ways by `tc qdisc ... netem SPEC`, and the packets it carried
and dropped are printed; --patience K multiplies every bound on a wait (software emulation);
--brief runs (a), (b), (e) with --peer and (g) only (the guest's: each start costs there).

Exit 77 (ctest: skipped, the reason printed) where namespaces cannot be created.
usage: routed_peers.py SAW_RT SAWCTL PYTHON [--netem SPEC] [--patience K]
       (PYTHON: the venv's, with cyclonedds)
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

from harness import check, dds_domain, exit_code  # noqa: E402


def sh(*args):
    return subprocess.run(args, capture_output=True, text=True)


ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def main(saw_rt, sawctl, python, netem=None, patience=1.0, brief=False):
    tag = str(os.getpid())
    ns = {n: f"saw-{n}-{tag}" for n in ("op", "rt", "pat")}
    net = f"10.{os.getpid() % 200 + 20}"
    op_ip, rt_op_ip, rt_pat_ip, pat_ip = f"{net}.1.2", f"{net}.1.1", f"{net}.2.1", f"{net}.2.2"
    links = (f"so{tag}"[:15], f"sro{tag}"[:15], f"srp{tag}"[:15], f"sp{tag}"[:15])
    r = sh("ip", "netns", "add", ns["op"])
    if r.returncode != 0:
        print(f"SKIP: cannot create a network namespace here: {r.stderr.strip()}")
        return 77
    work = tempfile.mkdtemp()
    rt = None
    try:
        steps = [["ip", "netns", "add", ns["rt"]], ["ip", "netns", "add", ns["pat"]],
                 ["ip", "link", "add", links[0], "type", "veth", "peer", "name", links[1]],
                 ["ip", "link", "add", links[2], "type", "veth", "peer", "name", links[3]],
                 ["ip", "link", "set", links[0], "netns", ns["op"]], ["ip", "link", "set", links[1], "netns", ns["rt"]],
                 ["ip", "link", "set", links[2], "netns", ns["rt"]], ["ip", "link", "set", links[3], "netns", ns["pat"]],
                 ["ip", "-n", ns["op"], "addr", "add", f"{op_ip}/24", "dev", links[0]],
                 ["ip", "-n", ns["rt"], "addr", "add", f"{rt_op_ip}/24", "dev", links[1]],
                 ["ip", "-n", ns["rt"], "addr", "add", f"{rt_pat_ip}/24", "dev", links[2]],
                 ["ip", "-n", ns["pat"], "addr", "add", f"{pat_ip}/24", "dev", links[3]]]
        for n, link in ((ns["op"], links[0]), (ns["rt"], links[1]), (ns["rt"], links[2]), (ns["pat"], links[3])):
            steps.append(["ip", "-n", n, "link", "set", link, "up"])
        for n in ns.values():
            steps.append(["ip", "-n", n, "link", "set", "lo", "up"])
        steps += [["ip", "netns", "exec", ns["rt"], "sysctl", "-qw", "net.ipv4.ip_forward=1"],
                  ["ip", "-n", ns["op"], "route", "add", "default", "via", rt_op_ip],
                  ["ip", "-n", ns["pat"], "route", "add", "default", "via", rt_pat_ip]]
        for cmd in steps:
            r = sh(*cmd)
            if r.returncode != 0:
                print(f"SKIP: cannot build the routed network ({' '.join(cmd)}): {r.stderr.strip()}")
                return 77
        hop = ((ns["rt"], links[2]), (ns["pat"], links[3]))  # the wireless hop, both directions
        if netem:
            for n, link in hop:
                r = sh("ip", "netns", "exec", n, "tc", "qdisc", "add", "dev", link, "root", "netem", *netem.split())
                check(r.returncode == 0, f"netem {netem} on {link}: {r.stderr.strip() or 'in place'}")
        domain = dds_domain()
        host = "mount -t tmpfs tmpfs /dev/shm && exec sh -c \"$0\""

        def patient(name, peers, enclave=None, env=None):
            """saw-rt on the patient, its gateway on the patient's address (its own /dev/shm: a
            machine of its own), plain or with `enclave`."""
            deploy = os.path.join(work, f"{name}.yaml")
            with open(deploy, "w") as f:
                f.write(f"""deployment:
  name: routed-{tag}
components:
  - name: arm{tag}
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80}}
exports:
  - {{component: arm{tag}, provided: arm}}
gateway:
  domain: {domain}
  interfaces: [{pat_ip}]
  {"peers: [" + peers + "]" if peers else ""}
  {"enclave: " + enclave if enclave else "security: none"}
""")
            return subprocess.Popen(["ip", "netns", "exec", ns["pat"], "unshare", "--mount", "--propagation",
                                     "private", "sh", "-c", host,
                                     f"{saw_rt} {deploy} --duration {600 * patience:g} > {work}/{name}.log 2>&1"],
                                    start_new_session=True, env=dict(os.environ, **(env or {})))

        def stop(p):
            try:
                os.killpg(p.pid, signal.SIGTERM)
                p.wait(timeout=20)
            except (ProcessLookupError, subprocess.TimeoutExpired):
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()

        def listed(extra, env=None):
            cmd = ["ip", "netns", "exec", ns["op"], "sh", "-c",
                   " ".join([sawctl, "--domain", str(domain), "--interface", op_ip, "--timeout", f"{4 * patience:g}", *extra, "list"])]
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=60 * patience,
                               env=dict(os.environ, **(env or {})))
            return f"arm{tag}" in r.stdout, (r.stdout + r.stderr).strip()

        def found_within(extra, seconds, env=None):
            deadline = time.monotonic() + seconds * patience
            found, out = listed(extra, env)
            while not found and time.monotonic() < deadline:  # saw-rt and its gateway starting
                found, out = listed(extra, env)
            return found, out

        rt = patient("plain", None)
        found, out = found_within(["--peer", pat_ip], 20)
        check(found, f"(b) sawctl --peer PATIENT finds the gateway across the router: {out[-300:]}")
        check(not listed([])[0], "(a) without a peer list it finds nothing: multicast does not cross the router")
        if not brief:
            check(listed([], env={"ROS_STATIC_PEERS": f" {pat_ip} ; "})[0], "(c) ROS_STATIC_PEERS=PATIENT finds it too")

        def gui(extra, env=None, where=("op", op_ip)):
            """What sawgui --headless on the operator (or `where`: namespace, address) saw of the
            patient's component: (component shown, samples of its values, the output's tail)."""
            env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "nonrt", "python"), **(env or {}))
            env.pop("CYCLONEDDS_URI", None)
            r = subprocess.run(["ip", "netns", "exec", ns[where[0]], python, "-m", "sawgui", "--domain", str(domain),
                                "--interface", where[1], "--headless", f"{6 * patience:g}", *extra],
                               capture_output=True, text=True, timeout=90 * patience, env=env)
            try:
                out = json.loads(r.stdout.strip().splitlines()[-1])
            except (ValueError, IndexError):
                return False, 0, (r.stdout + r.stderr).strip()[-300:]
            samples = sum(n for t, n in out["samples"].items() if f"arm{tag}" in t)
            return f"arm{tag}" in out["states"], samples, r.stdout.strip()[-300:]

        shown, samples, out = gui(["--peer", pat_ip])
        check(shown and samples > 0, f"(e) sawgui --peer PATIENT shows the component and {samples} samples of it: {out}")
        if not brief:
            # On the patient's own subnet (from the router), multicast finds the gateway, unless ROS
            # 2's ROS_AUTOMATIC_DISCOVERY_RANGE keeps discovery to this host or turns it off.
            def from_router(env):
                r = subprocess.run(["ip", "netns", "exec", ns["rt"], sawctl, "--domain", str(domain), "--interface",
                                    rt_pat_ip, "--timeout", f"{4 * patience:g}", "list"], capture_output=True, text=True,
                                   timeout=60 * patience, env=dict(os.environ, **env))
                return f"arm{tag}" in r.stdout
            check(from_router({}), "(i) on the patient's subnet, multicast finds the gateway")
            check(not from_router({"ROS_AUTOMATIC_DISCOVERY_RANGE": "OFF"}), "(i) ROS_AUTOMATIC_DISCOVERY_RANGE=OFF: not")
            check(not from_router({"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}), "(i) =LOCALHOST: not")
            check(from_router({"ROS_AUTOMATIC_DISCOVERY_RANGE": "OFF", "ROS_STATIC_PEERS": pat_ip}),
                  "(i) OFF with ROS_STATIC_PEERS=PATIENT: found")
            shown, samples, out = gui([], where=("rt", rt_pat_ip))
            check(shown and samples > 0, f"(i) sawgui there finds it by multicast ({samples} samples): {out}")
            shown, samples, out = gui([], env={"ROS_AUTOMATIC_DISCOVERY_RANGE": "OFF"}, where=("rt", rt_pat_ip))
            check(not shown and samples == 0, f"(i) sawgui with ROS_AUTOMATIC_DISCOVERY_RANGE=OFF: not ({samples})")
            shown, samples, out = gui([])
            check(not shown and samples == 0, f"(e) without a peer list the GUI sees nothing ({samples} samples)")
            shown, samples, out = gui([], env={"ROS_STATIC_PEERS": pat_ip})
            check(shown and samples > 0, f"(f) sawgui with ROS_STATIC_PEERS=PATIENT too ({samples} samples): {out}")
        stop(rt)
        keystore = os.path.join(work, "keystore")
        for args in (["init", keystore], ["enroll", keystore, "lab", "--role", "gateway"],
                     ["enroll", keystore, "console", "--role", "operator"]):
            r = subprocess.run([sawctl, "security", *args], capture_output=True, text=True)
            check(r.returncode == 0, f"sawctl security {args[0]} {args[-1]}: {(r.stdout + r.stderr).strip()[-200:]}")
        rt = patient("secure", None, os.path.join(keystore, "enclaves", "lab"))
        console = ["--enclave", os.path.join(keystore, "enclaves", "console")]
        found, out = found_within(console + ["--peer", pat_ip], 20)
        check(found, f"(g) secure: sawctl --enclave OPERATOR --peer PATIENT finds the secure gateway: {out[-300:]}")
        check(not listed(["--peer", pat_ip])[0], "(g) without an enclave, the same peer list finds nothing")
        stop(rt)
        if not brief:
            check(shutil.which("fast-discovery-server") is not None,
                  "fast-discovery-server is installed (tools/bootstrap.sh --tests: fastdds-tools)")
            # On the router, a machine of its own (its own /dev/shm), listening on both its addresses.
            server = subprocess.Popen(["ip", "netns", "exec", ns["rt"], "unshare", "--mount", "--propagation", "private",
                                       "sh", "-c", host, "exec fast-discovery-server -i 0 -p 11811"],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT, start_new_session=True)
            try:
                rt = patient("served", None, env={"ROS_DISCOVERY_SERVER": f"{rt_pat_ip}:11811"})
                found, out = found_within([], 20, env={"ROS_DISCOVERY_SERVER": f"{rt_op_ip}:11811"})
                check(found, f"(h) gateway and sawctl given only ROS_DISCOVERY_SERVER find each other through it: {out[-300:]}")
                stop(rt)
            finally:
                stop(server)
            rt = patient("announcing", op_ip)
            found, out = found_within([], 20)
            check(found, f"(d) the gateway's own peer list: a peerless sawctl on the operator finds it: {out[-300:]}")
        print(open(os.path.join(work, "plain.log")).read()[-1200:])
        if netem:
            for n, link in hop:
                print(f"netem on {link}: " + " ".join(sh("ip", "netns", "exec", n, "tc", "-s", "qdisc", "show", "dev",
                                                           link).stdout.split()))
    finally:
        if rt is not None and rt.poll() is None:
            os.killpg(rt.pid, signal.SIGKILL)
            rt.wait()
        for n in ns.values():
            sh("ip", "netns", "del", n)
    return exit_code()


if __name__ == "__main__":
    import argparse
    a = argparse.ArgumentParser()
    a.add_argument("saw_rt")
    a.add_argument("sawctl")
    a.add_argument("python")
    a.add_argument("--netem")
    a.add_argument("--patience", type=float, default=1.0)
    a.add_argument("--brief", action="store_true")
    o = a.parse_args()
    sys.exit(main(o.saw_rt, o.sawctl, o.python, o.netem, o.patience, o.brief))
