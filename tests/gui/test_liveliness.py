"""sawdds.Live (the window's model, no window) tells a vanished gateway from a quiet one: a gateway
killed with -9 (no goodbye, no FAULT) is shown gone once its participant's lease (1 s) expires,
while the RT process runs on; a new gateway attached to the same component brings it back, with
its latched state at once."""
import os
import signal
import subprocess
import tempfile
import time

import pytest

from conftest import figure
from sawdds.live import Live
from saw_testing import dds_domain  # (on the path conftest makes)

YAML = """deployment:
  name: live-{tag}
components:
  - name: arm_{tag}
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80, deadline: {{in_a_row: 500, share: 0.5}}}}  # as conftest.py's
    params: {{model: omni}}
exports:
  - {{component: arm_{tag}, provided: arm}}
"""


def wait(pred, timeout=20.0):
    """Polls pred until it holds (True) or `timeout` s pass (False)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(0.005)
    return False


def test_a_killed_gateway_is_gone_within_its_lease_and_a_new_one_brings_the_component_back():
    saw_rt = os.environ.get("SAW_RT")
    if not saw_rt:
        pytest.skip("SAW_RT (the saw-rt executable) not set: run through run_under_xvfb.py")
    gateway = os.path.join(os.path.dirname(saw_rt), "saw-gateway")
    tag = f"l{os.getpid()}"
    arm = f"arm_{tag}"
    claim = dds_domain.claim()  # a domain of this test's own, released at its end
    domain = claim.domain
    fd, yaml = tempfile.mkstemp(suffix=".yaml", prefix="sawgui-live-")
    with os.fdopen(fd, "w") as f:
        f.write(YAML.format(tag=tag))
    # Bounded, and stopped in `finally` whatever fails after it started (a missing saw-gateway too):
    # a test never leaves an RT process behind.
    rt = subprocess.Popen([saw_rt, yaml, "--duration", "120"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    start = [gateway, "--attach", arm, "--domain", str(domain), "--wait", "20"]
    gw = None
    live = None
    try:
        gw = subprocess.Popen(start, stdout=subprocess.DEVNULL)
        live = Live(domain)
        assert wait(lambda: live.components().get(arm, {}).get("state") == "ENABLED"), live.components()
        old = live.components()[arm]["gateway"]
        t0 = time.monotonic()
        gw.send_signal(signal.SIGKILL)
        gw.wait()
        assert wait(lambda: live.components()[arm]["gone_at"] is not None), live.components()[arm]
        gone_ms = (time.monotonic() - t0) * 1e3
        assert rt.poll() is None, "the RT process runs on"
        assert live.components()[arm]["state"] == "ENABLED", "no FAULT was said: the last state, shown gone"
        assert not live.gateways()[old]["alive"]

        gw = subprocess.Popen(start, stdout=subprocess.DEVNULL)
        t1 = time.monotonic()
        assert wait(lambda: live.components()[arm]["gone_at"] is None and live.components()[arm]["gateway"] != old)
        back_ms = (time.monotonic() - t1) * 1e3
        assert live.components()[arm]["state"] == "ENABLED"
        assert not live.gateways()[old]["alive"], "the killed gateway stays gone"
        figure(f"a gateway killed with -9 shown gone after {gone_ms:.0f} ms (lease 1 s); "
               f"a new gateway's component shown again {back_ms:.0f} ms after it started")
    finally:
        if live is not None:
            live.close()
        for p in (gw, rt):
            if p is not None and p.poll() is None:
                p.send_signal(signal.SIGTERM)
                p.wait(timeout=20)
        os.unlink(yaml)
        claim.release()
