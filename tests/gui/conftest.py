"""What sawgui's window tests share: the source tree's packages, a running teleoperation
deployment (saw-rt with its gateway) on a DDS domain it holds alone, the window on it, and where
screenshots go."""
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
# The source tree's sawdds and sawgui, not installed ones: the venv is shared by every checkout.
sys.path.insert(0, os.path.join(ROOT, "nonrt", "python"))
sys.path.insert(0, os.path.join(ROOT, "tests", "support", "python"))
os.environ.setdefault("PYTHONDONTWRITEBYTECODE", "1")

from saw_testing import dds_domain  # noqa: E402

# A shared test machine stalls for tens of ms now and then: the tasks' deadline policies are
# loosened as the staleness limit is (the window is under test here, not the timing; a late loop's
# FAULT is System.AStarvedTeleoperation...'s).

DEPLOYMENT = """deployment:
  name: gui-{tag}
components:
  - name: {master}
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80, deadline: {{in_a_row: 500, share: 0.5}}}}
    params:
      model: omni
      hand: {{type: sinusoid, amplitude: [0.03, 0.0, 0.0], frequency: 0.5, stiffness: 200, damping: 2}}
  - name: {slave}
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80, deadline: {{in_a_row: 500, share: 0.5}}}}
    params: {{model: omni}}
  - name: teleop_{tag}
    type: teleop
    task: {{period: 1ms, priority: 79, offset: 300us, deadline: {{in_a_row: 500, share: 0.5}}}}
    params:
{law_params}
      # A shared test machine stalls for tens of ms now and then: the shipped 20 ms would fault.
      stale_timeout: 500ms
connections:
  - {{client: teleop_{tag}, required: master, server: {master}, provided: arm}}
  - {{client: teleop_{tag}, required: slave, server: {slave}, provided: arm}}
exports:
  - {{component: {master}, provided: arm}}
  - {{component: {slave}, provided: arm}}
  - {{component: teleop_{tag}, provided: teleop}}
gateway:
  domain: {domain}
"""


# The teleoperation's law and its settings (the deployment's keys are the law's declared settings).
LAWS = {
    "collaborative": """      scale: 1.0
      gains: {master: 300, slave: 300}
      force_limits: {master: 3.0, slave: 3.0}""",
    "position_position": """      law: position_position
      scale: 1.0
      stiffness: 250
      damping: 5
      force_limit: 2.5""",
}


class Deployment:
    """saw-rt running the simulated teleoperation, its gateway started by the deployment."""

    def __init__(self, saw_rt: str, law: str = "collaborative", names=("master", "slave")):
        """`names`: the master's and the slave's component names (before the tag)."""
        self.tag = f"g{os.getpid()}"
        self.claim = dds_domain.claim()  # held until close()
        self.domain = self.claim.domain
        self.master, self.slave, self.teleop = (f"{n}_{self.tag}" for n in (*names, "teleop"))
        fd, self.yaml = tempfile.mkstemp(suffix=".yaml", prefix="sawgui-")
        with os.fdopen(fd, "w") as f:
            f.write(DEPLOYMENT.format(tag=self.tag, domain=self.domain, master=self.master, slave=self.slave,
                                      law_params=LAWS[law]))
        self.saw_rt = saw_rt
        self.rt = subprocess.Popen([saw_rt, self.yaml], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    def kill_rt(self):
        self.rt.send_signal(signal.SIGKILL)

    def restart_rt(self):
        """saw-rt again, the same deployment (after kill_rt): its gateway is a new one."""
        self.rt.wait()
        self._unlink_segments()
        self.rt = subprocess.Popen([self.saw_rt, self.yaml], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                   text=True)

    def _unlink_segments(self):
        for n in (self.master, self.slave, self.teleop):  # kill -9 leaves segments behind
            if os.path.exists(f"/dev/shm/saw.{n}"):
                os.unlink(f"/dev/shm/saw.{n}")

    def gateway_pids(self):
        out = subprocess.run(["pgrep", "-P", str(self.rt.pid), "saw-gateway"], capture_output=True, text=True)
        return [int(p) for p in out.stdout.split()]

    def close(self):
        gateways = self.gateway_pids() if self.rt.poll() is None else []
        if self.rt.poll() is None:
            self.rt.send_signal(signal.SIGTERM)
        try:
            out, _ = self.rt.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            self.rt.kill()
            out, _ = self.rt.communicate()
        print(out[-3000:] if out else "(no saw-rt output)")
        deadline = time.monotonic() + 5
        for g in gateways:  # the gateway exits with its RT process
            while os.path.exists(f"/proc/{g}") and time.monotonic() < deadline:
                time.sleep(0.05)
        os.unlink(self.yaml)
        self._unlink_segments()
        self.claim.release()


def saw_rt_path():
    saw_rt = os.environ.get("SAW_RT")
    if not saw_rt:
        pytest.skip("SAW_RT (the saw-rt executable) not set: run through run_under_xvfb.py")
    return saw_rt


@pytest.fixture
def deployment():
    d = Deployment(saw_rt_path())
    yield d
    d.close()


@pytest.fixture
def position_position_deployment():
    """The position-position law, its arms named so that neither their names nor their order say
    which is the master: the right one is, the left one the slave."""
    d = Deployment(saw_rt_path(), law="position_position", names=("right", "left"))
    yield d
    d.close()


@pytest.fixture
def window(qtbot, request):
    """sawgui's main window (1200x820, shown) with its own Live readers, on the DDS domain of the
    deployment fixture the test asks for (set up first, so torn down after the window). After the
    test its refresh timer is stopped and its readers closed; qtbot closes the window."""
    from sawdds.live import Live
    from sawgui.app import MainWindow

    asked = "position_position_deployment" if "position_position_deployment" in request.fixturenames else "deployment"
    d = request.getfixturevalue(asked)
    live = Live(d.domain)
    w = MainWindow(live, d.domain, "lo")
    qtbot.addWidget(w)
    w.resize(1200, 820)
    w.show()
    yield w
    w.timer.stop()
    live.close()


@pytest.fixture
def shots():
    """Where screenshots go: $SAW_GUI_SHOTS, or a directory in the system's temp."""
    d = os.environ.get("SAW_GUI_SHOTS") or os.path.join(tempfile.gettempdir(), f"sawgui-shots-{os.getpid()}")
    os.makedirs(d, exist_ok=True)
    return d


def figure(text: str):
    print("figure: " + re.sub(r"\s+", " ", text), flush=True)
