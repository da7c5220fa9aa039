"""What the operator gets from sawgui's window beside the 1 kHz simulated teleoperation (the
deployment of tests/gui): how often the Teleoperation tab redraws (paint events of its plot), how
long a click takes to act (Disable, Enable, the clutch held) as an independent DDS monitor (a
process of its own) sees the state change and as the window's badge shows it, and the window
process's CPU with the tab open. Runs the window on a private Xvfb display; figures, no assertion.

`--source DIR` takes sawdds/sawgui from another tree (the code before a change, to compare).

usage: gui_perf.py SAW_RT [--source DIR] [--seconds S] [--rounds N] [--json OUT]
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import threading
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
TICK = os.sysconf("SC_CLK_TCK")

MONITOR = """
import sys, time
sys.path.insert(0, sys.argv[3])
from sawdds.client import Client
c = Client(int(sys.argv[1]))
r = c.reader(sys.argv[2])
print("ready", flush=True)
last = None
while True:
    for s in r.take(N=16):
        if getattr(s, "state", None) and s.state != last:
            last = s.state
            print(f"{time.monotonic():.6f} {s.state}", flush=True)
    time.sleep(0.0005)
"""


def cpu_seconds() -> float:
    with open("/proc/self/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def summary(xs):
    xs = sorted(xs)
    return {"n": len(xs), "median": round(statistics.median(xs), 1), "max": round(xs[-1], 1),
            "min": round(xs[0], 1)} if xs else {}


def measure(args) -> dict:
    sys.path.insert(0, os.path.join(ROOT, "tests", "gui"))
    from conftest import Deployment  # (it puts this tree's nonrt/python first: --source goes before it)
    sys.path.insert(0, args.source)
    from PySide6 import QtCore, QtWidgets
    from PySide6.QtTest import QTest
    from sawdds.live import Live
    from sawgui.app import MainWindow
    import sawgui
    assert sawgui.__file__.startswith(args.source), (sawgui.__file__, args.source)

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([])
    app.setApplicationName("gui_perf")
    d = Deployment(args.saw_rt)
    live = Live(d.domain)
    w = MainWindow(live, d.domain, "lo")
    w.resize(1200, 820)
    w.show()
    monitor = None

    def wait(pred, timeout=30.0):
        """Runs the event loop (idle between events, as a person's window) until pred() or timeout."""
        loop = QtCore.QEventLoop()
        poll = QtCore.QTimer()
        poll.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        poll.timeout.connect(lambda: loop.quit() if pred() else None)
        poll.start(1)
        QtCore.QTimer.singleShot(int(timeout * 1000), loop.quit)
        loop.exec()
        poll.stop()
        return pred()

    def idle(seconds):
        loop = QtCore.QEventLoop()
        QtCore.QTimer.singleShot(int(seconds * 1000), loop.quit)
        loop.exec()

    try:
        assert wait(lambda: w.teleop is not None and live.components().get(d.teleop, {}).get("state") == "ENABLED")
        panel = w.teleop
        w.tabs.setCurrentWidget(panel)
        paints = []

        class Painted(QtCore.QObject):
            def eventFilter(self, obj, ev):
                if ev.type() == QtCore.QEvent.Type.Paint:
                    paints.append(time.monotonic())
                return False
        counter = Painted()
        panel.error_plot.viewport().installEventFilter(counter)
        idle(3.0)  # discovery done, the plots full
        paints.clear()
        c0, t0 = cpu_seconds(), time.monotonic()
        idle(args.seconds)
        cpu = (cpu_seconds() - c0) / (time.monotonic() - t0)
        gaps = [(b - a) * 1e3 for a, b in zip(paints, paints[1:])]
        redraw = {"per_s": round(len(paints) / args.seconds, 1), "gap_ms": summary(gaps)}

        topic = f"rt/{d.teleop}/operating_state"
        monitor = subprocess.Popen([sys.executable, "-c", MONITOR, str(d.domain), topic, os.path.join(ROOT, "nonrt",
                                                                                                       "python")],
                                   stdout=subprocess.PIPE, text=True)
        seen = []
        assert monitor.stdout.readline().startswith("ready")
        threading.Thread(target=lambda: [seen.append((float(t), s)) for t, s in
                                         (line.split() for line in monitor.stdout)], daemon=True).start()
        wait(lambda: bool(seen) and seen[-1][1] == "ENABLED", 10.0)
        acted = {"disable": [], "enable": [], "pause": [], "resume": []}
        shown = {k: [] for k in acted}

        def click(command, act, state):
            n = len(seen)
            t = time.monotonic()
            act()
            if not wait(lambda: any(s == state for _, s in seen[n:]) and panel.badge.state == state, 10.0):
                return
            acted[command].append((next(ts for ts, s in seen[n:] if s == state) - t) * 1e3)
            shown[command].append((time.monotonic() - t) * 1e3)  # at most one event-loop pass late
            idle(0.3)

        left = QtCore.Qt.MouseButton.LeftButton
        for _ in range(args.rounds):
            click("disable", lambda: QTest.mouseClick(panel.disable, left), "DISABLED")
            click("enable", lambda: QTest.mouseClick(panel.enable, left), "ENABLED")
            click("pause", lambda: QTest.mousePress(panel.clutch, left), "PAUSED")
            click("resume", lambda: QTest.mouseRelease(panel.clutch, left), "ENABLED")
        return {"source": args.source, "seconds": args.seconds, "redraw": redraw,
                "window_cpu_percent": round(cpu * 100, 1),
                "command_to_state_ms": {k: summary(v) for k, v in acted.items()},
                "command_to_badge_ms": {k: summary(v) for k, v in shown.items()},
                "all_commands_ms": summary([x for v in acted.values() for x in v]),
                "all_badges_ms": summary([x for v in shown.values() for x in v])}
    finally:
        if monitor is not None:
            monitor.kill()
            monitor.wait()
        w.timer.stop()
        live.close()
        w.close()
        d.close()


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("saw_rt")
    p.add_argument("--source", default=os.path.join(ROOT, "nonrt", "python"),
                   help="the tree of sawdds/sawgui to measure (default: this one's)")
    p.add_argument("--seconds", type=float, default=10.0)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--json")
    p.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    args.saw_rt, args.source = os.path.abspath(args.saw_rt), os.path.abspath(args.source)
    if args.inside:
        out = measure(args)
        print("RESULT " + json.dumps(out), flush=True)
        return 0
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        print("gui_perf: no Xvfb (Debian package xvfb)", file=sys.stderr)
        return 2
    r, wfd = os.pipe()
    server = subprocess.Popen([xvfb, "-displayfd", str(wfd), "-screen", "0", "1280x900x24", "-nolisten", "tcp"],
                              pass_fds=(wfd,), stderr=subprocess.DEVNULL)
    os.close(wfd)
    with os.fdopen(r) as f:
        display = f.readline().strip()
    try:
        env = dict(os.environ, DISPLAY=":" + display, QT_QPA_PLATFORM="xcb", PYTHONDONTWRITEBYTECODE="1")
        res = subprocess.run([sys.executable, __file__, "--inside", args.saw_rt, "--source", args.source,
                              "--seconds", str(args.seconds), "--rounds", str(args.rounds)],
                             env=env, capture_output=True, text=True, timeout=600)
    finally:
        server.terminate()
        server.wait(timeout=10)
    line = next((x for x in res.stdout.splitlines() if x.startswith("RESULT ")), None)
    if line is None or res.returncode != 0:
        print(res.stdout[-3000:], res.stderr[-3000:], file=sys.stderr)
        return 1
    out = json.loads(line[7:])
    out["date"] = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    print(json.dumps(out, indent=1))
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
