"""sawgui: a desktop GUI for a sawrt system over DDS.

usage: sawgui [--domain N] [--interface NAME] [--peer ADDRESS ...] [--enclave DIR] [--full-rate]
              [--headless SECONDS]
"""
import argparse
import json
import os
import signal
import sys
import threading
import time


# Loopback's name is Linux's; elsewhere (lo0, "Loopback Pseudo-Interface 1") its address names it.
LOOPBACK = "lo" if sys.platform.startswith("linux") else "127.0.0.1"


def parse(argv):
    p = argparse.ArgumentParser(prog="sawgui", description="A desktop GUI for sawrt over DDS (Cyclone DDS): "
                                "the system's components and states, each component's values, events and "
                                "commands, the teleoperation and the tasks' health.")
    p.add_argument("--domain", type=int, default=0, help="DDS domain of the gateways (default 0)")
    p.add_argument("--interface", default=LOOPBACK,
                   help=f"network interface DDS uses, by name or address (default {LOOPBACK}: this machine only; "
                        "a remote GUI names the interface that reaches the gateway's host)")
    p.add_argument("--peer", action="append", default=None, metavar="ADDRESS",
                   help="a host to discover by unicast (default: $ROS_STATIC_PEERS, ';'-separated; else "
                        "127.0.0.1 on lo, none elsewhere: multicast)")
    p.add_argument("--enclave", metavar="DIR",
                   help="join a secure domain with this SROS2 enclave (KEYSTORE/enclaves/NAME, from sawctl security "
                        "enroll; or ROS_SECURITY_* as ROS 2 has it); needs a Cyclone DDS with its security plugins")
    p.add_argument("--headless", type=float, metavar="SECONDS",
                   help="no window: read what the window reads for SECONDS, then print what arrived as JSON")
    p.add_argument("--all-reads", action="store_true", help="with --headless: read every mapped topic")
    p.add_argument("--full-rate", action="store_true",
                   help="read every row of each state (the topics a recorder reads) rather than the gateway's "
                        "display streams (50 samples/s by default)")
    p.add_argument("--settle", type=float, default=0.0, metavar="SECONDS",
                   help="with --headless: also count what arrives after the first SECONDS (discovery done)")
    p.add_argument("--window-stdin", action="store_true",
                   help="with --headless: print 'ready' once reading, then read 'START END' (wall clock, s) from "
                        "stdin and count each topic's samples written in that window (and those DDS counted lost); "
                        "stop after END (the scale benchmark: every subscriber counts the same window)")
    return p.parse_args(argv)


def configure_dds(args):
    """CYCLONEDDS_URI from the options (unless the user set it), with DDS Security when an enclave is
    named, before any participant exists. Raises sawdds.security.SecurityError."""
    from sawdds.client import discovery_range, interface_uri, static_peers
    from sawdds.security import resolve_enclave, secure_uri
    if "CYCLONEDDS_URI" in os.environ and args.interface == LOOPBACK and args.peer is None:
        uri = os.environ["CYCLONEDDS_URI"]
    else:
        # --peer, else ROS 2's $ROS_STATIC_PEERS, else this machine on loopback and multicast
        # elsewhere; ROS 2's $ROS_AUTOMATIC_DISCOVERY_RANGE narrows it (OFF: the peers alone).
        reach = discovery_range()
        loopback = args.interface in ("lo", "lo0", "127.0.0.1")
        peers = args.peer if args.peer is not None else static_peers()
        if not peers and loopback and reach != "OFF":
            peers = ["127.0.0.1"]
        here = args.interface if args.interface[:1].isdigit() else "127.0.0.1"
        if reach == "LOCALHOST" and here not in peers:
            peers = peers + [here]
        uri = interface_uri(args.interface, peers, multicast=None if reach == "SUBNET" else False)
    enclave = resolve_enclave(args.enclave)
    if enclave is not None:
        uri = secure_uri(uri, enclave)
    os.environ["CYCLONEDDS_URI"] = uri


def open_live(args):
    """sawdds.Live on the domain, or None after saying why DDS would not start (with an enclave:
    Cyclone DDS refused the certificates, or its plugins do not match its libddsc)."""
    from cyclonedds.core import DDSException
    from sawdds.live import Live
    try:
        return Live(args.domain, full_rate=args.full_rate)
    except DDSException as e:
        secure = " with DDS Security (check the enclave, and that the plugins are this Cyclone DDS's)" \
            if "<Security>" in os.environ.get("CYCLONEDDS_URI", "") else ""
        print(f"sawgui: DDS did not start in domain {args.domain}{secure}: {e}", file=sys.stderr)
        return None


class Window:
    """The scale benchmark's common window: says "ready" on stdout, takes "START END" (wall clock,
    s) from stdin (a thread of its own: the readers keep being opened meanwhile), counts each
    topic's samples written in it (Live.tally) and the CPU this process spent in it."""

    GRACE = 0.5  # s after END for samples written before END to arrive

    def __init__(self, live):
        self.live, self.bounds, self.cpu = live, None, [None, None]
        print("ready", flush=True)
        threading.Thread(target=self._read, name="sawgui-window", daemon=True).start()

    def _read(self):
        line = sys.stdin.readline().split()
        if len(line) == 2:
            start, end = float(line[0]), float(line[1])
            self.live.tally(start, end)
            self.bounds = (start, end)

    def poll(self):
        if self.bounds:
            now = time.time()
            if self.cpu[0] is None and now >= self.bounds[0]:
                self.cpu[0] = time.process_time()
            if self.cpu[1] is None and now >= self.bounds[1]:
                self.cpu[1] = time.process_time()

    def done(self) -> bool:
        return self.bounds is not None and time.time() >= self.bounds[1] + self.GRACE

    def report(self) -> dict:
        if not self.bounds:
            return {"error": "no window was given on stdin"}
        start, end = self.bounds
        cpu = self.cpu[1] - self.cpu[0] if None not in self.cpu else None
        return {"start": start, "end": end, "topics": self.live.tallies(), "cpu_s": cpu}


def headless(args) -> int:
    """The window's DDS readers without a window (the smoke test and the scale benchmark)."""
    from . import model
    live = open_live(args)
    if live is None:
        return 2
    deadline = time.monotonic() + args.headless
    cpu0 = time.process_time()
    settle_at, settled = time.monotonic() + args.settle, None
    window = Window(live) if args.window_stdin else None
    while time.monotonic() < deadline and not (window and window.done()):
        if window:
            window.poll()
        if settled is None and args.settle and time.monotonic() >= settle_at:
            settled = {t: live.count(t) for t in live.watched()}
            cpu_settled = time.process_time()
        topics = model.default_topics(live)
        if args.all_reads:
            topics += [t for c in live.components() for t in model.component_topics(live, c)]
        for t in topics:
            live.watch(t)
        time.sleep(0.1)
    out = {"gateways": {g: {"alive": v["alive"], "components": v["components"]} for g, v in live.gateways().items()},
           "states": {c: model.shown_state(v) for c, v in live.components().items()},
           "samples": {t: live.count(t) for t in live.watched()},
           "cpu_s": round(time.process_time() - cpu0, 3), "seconds": args.headless}
    if settled is not None:
        out["settled"] = {"seconds": round(args.headless - args.settle, 3),
                          "samples": {t: live.count(t) - settled.get(t, 0) for t in live.watched()},
                          "cpu_s": round(time.process_time() - cpu_settled, 3)}
    if window:
        out["window"] = window.report()
    live.close()
    print(json.dumps(out, sort_keys=True))
    return 0


def main(argv=None) -> int:
    args = parse(sys.argv[1:] if argv is None else argv)
    from sawdds.security import SecurityError
    try:
        configure_dds(args)
    except (SecurityError, ValueError) as e:
        print(f"sawgui: {e}", file=sys.stderr)
        return 2
    if args.headless is not None:
        return headless(args)
    try:
        from PySide6 import QtWidgets
    except ImportError:
        print("sawgui: PySide6 is missing: pip install 'sawdds[gui]' (or the repository's nonrt/python[gui])",
              file=sys.stderr)
        return 2
    from .app import MainWindow
    from PySide6 import QtCore
    live = open_live(args)
    if live is None:
        return 2
    app = QtWidgets.QApplication(sys.argv[:1])
    w = MainWindow(live, args.domain, args.interface)
    w.show()
    # Ctrl-C (or SIGTERM, as tools/run.sh --gui's saw-rt gets) closes the window as its close box
    # does: Python runs signal handlers only between Qt's calls, so a timer gives it the chance.
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: app.quit())
    wake = QtCore.QTimer()
    wake.timeout.connect(lambda: None)
    wake.start(200)
    rc = app.exec()
    live.close()
    return rc


if __name__ == "__main__":
    sys.exit(main())
