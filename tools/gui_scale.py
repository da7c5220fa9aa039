"""What remote GUIs cost the RT loop: the 1 kHz simulated teleoperation (config/teleop-sim.yaml's
components, their tasks on one CPU) and its gateway (on another CPU, as docs/deploy.md says),
beside 0, 1 and 10 GUI-equivalent subscribers: `sawgui --headless`, the window's own DDS readers
(sawdds.Live, what the window reads when it opens on the teleoperation: the states' display streams,
which the gateway publishes at --display-rate), each a process of its own on the gateway's CPU. A
count written "10full" is ten subscribers reading every row instead (`sawgui --full-rate`, what
the window read before the gateway had display streams). One run, the configurations one after
the other; prints a Markdown table and writes JSON (figures, no assertion).

Every subscriber counts the same window, which starts once all of them read (ten python processes
starting at once on one CPU take seconds to import) and ends while saw-rt still runs (it is stopped
after): a subscriber counts the state samples the gateway wrote in the window (by their source
time), and what it did not take is split into what Cyclone DDS counted lost on the way (or
rejected), reader histories that filled (samples overwritten), and the rest (not written).

The configurations alternate (0, 1, 10, 10full, 0, 1, ...) for --rounds rounds, so that what the
machine's other load does to the RT CPU falls on each alike; the table gives each one's median.

usage: gui_scale.py SAW_RT SAW_GATEWAY [--seconds S] [--counts 0,1,10,10full] [--rounds N]
                    [--display-rate HZ] [--json OUT]
"""
import argparse
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "support", "python"))
from saw_testing.dds_domain import dds_domain  # noqa: E402  (a DDS domain no test beside this run holds)
TICK = os.sysconf("SC_CLK_TCK")
DEPLOYMENT = """deployment:
  name: gui-scale-{tag}
components:
  - name: master_{tag}
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80, cpu: {cpu}}}
    params:
      model: omni
      hand: {{type: sinusoid, amplitude: [0.03, 0.0, 0.0], frequency: 0.5, stiffness: 200, damping: 2}}
  - name: slave_{tag}
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80, cpu: {cpu}}}
    params: {{model: omni}}
  - name: teleop_{tag}
    type: teleop
    task: {{period: 1ms, priority: 79, offset: 300us, cpu: {cpu}}}
    params:
      scale: 1.0
      gains: {{master: 300, slave: 300}}
      force_limits: {{master: 3.0, slave: 3.0}}
      stale_timeout: 200ms
connections:
  - {{client: teleop_{tag}, required: master, server: master_{tag}, provided: arm}}
  - {{client: teleop_{tag}, required: slave, server: slave_{tag}, provided: arm}}
exports:
  - {{component: master_{tag}, provided: arm}}
  - {{component: slave_{tag}, provided: arm}}
  - {{component: teleop_{tag}, provided: teleop}}
"""
GATEWAY = re.compile(r"published (\d+) state samples \(and (\d+) on display streams; (\d+) rows skipped\)")
ROW = re.compile(r"^\s+(\S+)\s+1\.00ms\s+(\d+)\s+(\d+)\s+(\d+)\s+([\d.]+)us\s+([\d.]+)us\s+([\d.]+)us\s+([\d.]+)us",
                 re.M)


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a live process."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def state_rate_hz(full_rate: bool, display_rate: float) -> float:
    """What one subscriber's state topics carry per second: both arms' measured_cp and the tracking
    error (what the teleoperation panel draws) and three tasks' period_statistics; every row of the
    first three at 1 kHz and a tenth of the statistics' rows, or all six at the display rate."""
    return 3 * 1000 + 3 * 100 if full_rate else 6 * display_rate


def parse_count(text: str):
    """"10" -> (10, False); "10full" -> (10, True)."""
    full = text.endswith("full")
    return int(text[:-4] if full else text), full


def label(n: int, full: bool) -> str:
    return f"{n}, every row" if full else str(n)


def one(args, conf: str, tag: str, domain: int, rt_cpu: int, other_cpu: int) -> dict:
    n, full = parse_count(conf)
    fd, yaml = tempfile.mkstemp(suffix=".yaml", prefix="gui-scale-")
    with os.fdopen(fd, "w") as f:
        f.write(DEPLOYMENT.format(tag=tag, cpu=rt_cpu))
    names = [f"{c}_{tag}" for c in ("master", "slave", "teleop")]
    settle = 3.0  # s after the last subscriber is ready: discovery, its readers opened and matched
    # saw-rt runs until the window has ended (SIGTERM then: an orderly stop with its summary), so
    # that every subscriber's window falls while the RT tasks and the gateway run.
    rt = subprocess.Popen([args.saw_rt, yaml, "--duration", str(args.seconds + 120)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    on_other = ["taskset", "-c", str(other_cpu)]
    attach = [a for c in names for a in ("--attach", c)]
    gw = subprocess.Popen(on_other + [args.saw_gateway, *attach, "--domain", str(domain), "--wait", "10",
                                      "--display-rate", str(args.display_rate)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "nonrt", "python"), PYTHONDONTWRITEBYTECODE="1")
    sawgui = [sys.executable, "-m", "sawgui", "--domain", str(domain), "--headless", str(args.seconds + 110),
              "--window-stdin"] + (["--full-rate"] if full else [])
    launched = time.time()
    subs = [subprocess.Popen(on_other + sawgui, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
            for _ in range(n)]
    rt_covered = True
    try:
        # Each subscriber says "ready" once its DDS participant reads (python and Cyclone DDS
        # imported: seconds when ten start at once on one CPU); then all count the same window.
        for s in subs:
            s.stdout.readline()
        ready_s = time.time() - launched
        start = max(time.time() + settle, launched + 3.0)
        end = start + args.seconds
        for s in subs:
            s.stdin.write(f"{start!r} {end!r}\n")
            s.stdin.flush()
        time.sleep(max(0.0, start - time.time()))
        gw_cpu0 = cpu_seconds(gw.pid)
        time.sleep(max(0.0, end - time.time()))
        gw_cpu = cpu_seconds(gw.pid) - gw_cpu0
        reports = []
        for s in subs:
            out, _ = s.communicate(timeout=60)
            reports.append(json.loads(out.strip().splitlines()[-1]) if out.strip() else {})
        rt_covered = rt.poll() is None  # still running after every subscriber's window
        rt.send_signal(signal.SIGTERM)
        rt_out, _ = rt.communicate(timeout=60)
    finally:
        for p in [*subs, rt]:
            if p.poll() is None:
                p.kill()
        gw.send_signal(signal.SIGTERM)
        gw_out, _ = gw.communicate(timeout=20)
        os.unlink(yaml)
    if not rt_covered:
        raise SystemExit(f"gui_scale: saw-rt stopped before the subscribers' window ended ({conf} subscribers)")
    tasks = {m.group(1): {"cycles": int(m.group(2)), "overruns": int(m.group(3)), "missed": int(m.group(4)),
                          "p99_us": float(m.group(7)), "max_us": float(m.group(8))}
             for m in ROW.finditer(rt_out) if m.group(1) in names}
    gwsum = GATEWAY.search(gw_out)
    expected = state_rate_hz(full, args.display_rate) * args.seconds
    shares = [share(r.get("window", {}), expected, names) for r in reports]
    return {"subscribers": n, "full_rate": full, "configuration": conf, "tasks": tasks, "overruns": sum(t["overruns"] for t in tasks.values()),
            "p99_us": max((t["p99_us"] for t in tasks.values()), default=None),
            "gateway_cpu_percent": 100 * gw_cpu / args.seconds,
            "gateway_published": int(gwsum.group(1)) if gwsum else None,
            "gateway_displayed": int(gwsum.group(2)) if gwsum else None,
            "gateway_rows_skipped": int(gwsum.group(3)) if gwsum else None,
            "ready_seconds": ready_s,
            "samples_per_subscriber": [x["samples"] for x in shares],
            "lost_per_subscriber": [x["lost"] for x in shares],
            "unaccounted_per_subscriber": [x["unaccounted"] for x in shares],
            "full_takes_per_subscriber": [x["full_takes"] for x in shares],
            "topics_per_subscriber": [len(r.get("samples", {})) for r in reports],
            "subscriber_cpu_percent": [100 * (r.get("window", {}).get("cpu_s") or 0) / args.seconds for r in reports],
            # What the subscribers' state topics carry per second (the others are events and states on change).
            "state_rate_hz": state_rate_hz(full, args.display_rate), "display_rate_hz": args.display_rate,
            "seconds": args.seconds, "rt_summary": [l for l in rt_out.splitlines() if "1.00ms" in l]}


def share(window: dict, expected: float, names) -> dict:
    """One subscriber's state samples in the common window (sawgui --window-stdin's report): those
    taken; those Cyclone DDS counted lost on the way (best effort: a gap in the gateway's sequence
    numbers) or rejected; takes that emptied a full reader history (its oldest samples overwritten);
    and the rest of `expected` (the streams' rates times the window): not written by the gateway in
    the window, or overwritten unseen."""
    # This run's components' state streams (not the latched states), by name: only what this run
    # started counts, whatever else ever joins its domain.
    topics = [t for name, t in window.get("topics", {}).items()
              if t["samples"] > 2 and any(f"/{c}/" in name for c in names)]
    taken = sum(t["samples"] for t in topics)
    lost = sum(t["lost"] + t["rejected"] for t in topics)
    return {"samples": taken, "lost": lost, "unaccounted": round(expected) - taken - lost,
            "full_takes": sum(t["full_takes"] for t in topics)}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("saw_rt")
    p.add_argument("saw_gateway")
    p.add_argument("--seconds", type=float, default=20)
    p.add_argument("--counts", default="0,1,10,10full")
    p.add_argument("--display-rate", type=float, default=50, help="the gateway's display streams, Hz")
    p.add_argument("--rounds", type=int, default=1)
    p.add_argument("--json")
    args = p.parse_args()
    cpus = sorted(os.sched_getaffinity(0))
    rt_cpu, other_cpu = cpus[-1], cpus[0]
    domain = dds_domain()
    counts = args.counts.split(",")
    runs = [one(args, c, f"s{os.getpid()}_{r}_{i}", domain, rt_cpu, other_cpu)
            for r in range(args.rounds) for i, c in enumerate(counts)]
    print(f"# RT tasks on CPU {rt_cpu}; saw-gateway and the subscribers on CPU {other_cpu}; "
          f"{args.seconds:g} s measured per configuration, {args.rounds} round(s) alternating; "
          "RT figures over the whole run of each")
    print("| subscribers | RT overruns, each round | wake-up p99 median (range), worst task (µs) | × none | "
          "gateway CPU | samples each subscriber took (min–max) | not taken, all subscribers: lost by DDS / "
          "not written or not seen; full reader histories | subscribers ready after | subscriber CPU |")
    print("|---|---|---|---|---|---|---|---|---|")
    summary = []
    for conf in counts:
        n, full = parse_count(conf)
        rate = state_rate_hz(full, args.display_rate)
        mine = [r for r in runs if r["configuration"] == conf]
        p99 = sorted(r["p99_us"] for r in mine if r["p99_us"] is not None)
        samples = [x for r in mine for x in r["samples_per_subscriber"]]
        split = {k: [x for r in mine for x in r[f"{k}_per_subscriber"]] for k in ("lost", "unaccounted", "full_takes")}
        cpu = [x for r in mine for x in r["subscriber_cpu_percent"]]
        summary.append({"subscribers": n, "full_rate": full, "configuration": conf,
                        "overruns": [r["overruns"] for r in mine],
                        "p99_median_us": p99[len(p99) // 2] if p99 else None, "p99_us": p99,
                        "gateway_cpu_percent": sum(r["gateway_cpu_percent"] for r in mine) / len(mine),
                        "samples_per_subscriber": samples, "subscriber_cpu_percent": cpu,
                        "lost_per_subscriber": split["lost"], "unaccounted_per_subscriber": split["unaccounted"],
                        "full_takes_per_subscriber": split["full_takes"],
                        "ready_seconds": max((r["ready_seconds"] for r in mine), default=0.0),
                        "gateway_rows_skipped": [r["gateway_rows_skipped"] for r in mine],
                        "state_rate_hz": rate, "display_rate_hz": args.display_rate, "seconds": args.seconds})
    base = summary[0]["p99_median_us"] or 0
    for x in summary:
        s_ = x["samples_per_subscriber"]
        ratio = f"{x['p99_median_us'] / base:.2f}" if base and x["p99_median_us"] else "–"
        rate = x["state_rate_hz"]
        print(f"| {label(x['subscribers'], x['full_rate'])} | {', '.join(map(str, x['overruns']))} | "
              f"{x['p99_median_us']} ({x['p99_us'][0]}–{x['p99_us'][-1]}) | {ratio} | {x['gateway_cpu_percent']:.1f} % | "
              + (f"{min(s_)}–{max(s_)} in {args.seconds:g} s, {min(s_) / (rate * args.seconds):.1%}–"
                 f"{max(s_) / (rate * args.seconds):.1%} of {rate:g} samples/s" if s_ else "–")
              + " | " + (f"{sum(x['lost_per_subscriber'])} / {sum(x['unaccounted_per_subscriber'])}; "
                         f"{sum(x['full_takes_per_subscriber'])}" if s_ else "–")
              + f" | {x['ready_seconds']:.1f} s | " + (f"{sum(x['subscriber_cpu_percent']) / len(x['subscriber_cpu_percent']):.1f} % each"
                         if x["subscriber_cpu_percent"] else "–") + " |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"rt_cpu": rt_cpu, "other_cpu": other_cpu, "seconds": args.seconds, "rounds": args.rounds,
                       "display_rate_hz": args.display_rate,
                   "configurations": summary, "runs": runs}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
