"""The scale benchmark's count (tools/gui_scale.py): headless subscribers that start at different
moments count the same samples, those the gateway wrote in one wall-clock window they are given,
and say what DDS lost on the way. (Each counting from its own start, ten subscribers that took
seconds to start on a busy CPU counted past the end of the teleoperation: 87 % "taken".)"""
import json
import os
import subprocess
import sys
import time

from conftest import ROOT

SECONDS = 4.0


def headless(domain):
    env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "nonrt", "python"))
    p = subprocess.Popen([sys.executable, "-m", "sawgui", "--domain", str(domain), "--headless", "60",
                          "--window-stdin"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
    assert p.stdout.readline().strip() == "ready"
    return p


def test_subscribers_started_apart_count_the_same_window(deployment):
    first = headless(deployment.domain)
    time.sleep(2.0)  # the second starts later, as the tenth of ten does on a busy CPU
    second = headless(deployment.domain)
    start = time.time() + 3.0  # discovery, the readers opened
    for p in (first, second):
        p.stdin.write(f"{start!r} {start + SECONDS!r}\n")
        p.stdin.flush()
    reports = []
    for p in (first, second):
        out, _ = p.communicate(timeout=60)
        assert p.returncode == 0
        reports.append(json.loads(out.strip().splitlines()[-1])["window"])
    a, b = (r["topics"] for r in reports)
    streams = [t for t in a if a[t]["samples"] > 2]  # the state streams (not the latched states)
    assert len(streams) == 6, a  # both arms' measured_cp, the tracking error, three period_statistics
    for t in streams:
        # The same samples, but for any DDS counted lost on the way (best effort).
        assert a[t]["samples"] > 0, (t, a[t])
        assert abs(a[t]["samples"] - b[t]["samples"]) <= a[t]["lost"] + b[t]["lost"], (t, a[t], b[t])
        # Counted by the writer's time: never more than the display streams' 50 Hz in the window.
        assert a[t]["samples"] <= 50 * SECONDS + 1, (t, a[t])
        for r in (a[t], b[t]):
            assert {"lost", "rejected", "full_takes"} <= set(r) and r["full_takes"] == 0, (t, r)
