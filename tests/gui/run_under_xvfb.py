"""Runs sawgui's pytest-qt tests in real windows on a private Xvfb display (a display number Xvfb
picks itself, so tests side by side do not collide). Exit 77 (skipped) when there is no Xvfb or no
PySide6 / pytest-qt in this Python, with the reason, and also when pytest itself skipped a test:
pytest exits 0 then, and CTest would count the run as a pass of everything.

usage: run_under_xvfb.py SAW_RT [pytest arguments...]
"""
import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
SKIP = 77


def main(argv):
    if len(argv) < 1:
        print(__doc__)
        return 2
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        print("SKIP: no Xvfb (Debian package xvfb; tools/bootstrap.sh --tests installs it)")
        return SKIP
    missing = [m for m in ("PySide6", "pyqtgraph", "pytestqt") if importlib.util.find_spec(m) is None]
    if missing:
        print(f"SKIP: {', '.join(missing)} missing from {sys.executable} (tools/requirements.txt)")
        return SKIP
    r, w = os.pipe()
    server = subprocess.Popen([xvfb, "-displayfd", str(w), "-screen", "0", "1280x900x24", "-nolisten", "tcp"],
                              pass_fds=(w,), stderr=subprocess.DEVNULL)
    os.close(w)
    with os.fdopen(r) as f:
        display = f.readline().strip()
    if not display:
        server.kill()
        print("FAIL: Xvfb did not start")
        return 1
    env = dict(os.environ, DISPLAY=":" + display, QT_QPA_PLATFORM="xcb", SAW_RT=os.path.abspath(argv[0]),
               PYTHONDONTWRITEBYTECODE="1")
    env.pop("WAYLAND_DISPLAY", None)
    report = tempfile.NamedTemporaryFile(suffix=".xml", delete=False)
    report.close()
    try:
        # pytest's output is held and printed after a summary of what failed: a log cut to its first
        # lines (CTest's, CI's) still names the failing test and its assertion.
        run = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-v", "-s", "-rs",
                              f"--junitxml={report.name}", HERE, *argv[1:]], env=env, cwd=HERE,
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace")
        rc = run.returncode
        if rc != 0 and os.path.getsize(report.name) > 0:
            for name, why in pytest_failures(report.name):
                print(f"FAILED: {name}\n{why}\n")
        print(run.stdout, flush=True)
        skipped = pytest_skips(report.name) if rc == 0 else []
        if skipped:
            for name, why in skipped:
                print(f"SKIP: pytest skipped {name}: {why}")
            return SKIP
        return rc
    finally:
        server.terminate()
        server.wait(timeout=10)
        os.unlink(report.name)


def pytest_skips(path):
    """(test, reason) of each test pytest skipped, from its junit report."""
    return [(f"{case.get('classname')}.{case.get('name')}", skipped.get("message", ""))
            for case in ET.parse(path).getroot().iter("testcase")
            for skipped in case.findall("skipped")]


def pytest_failures(path, lines=25):
    """(test, the last `lines` lines of its traceback) of each failed or errored test, from its junit report."""
    return [(f"{case.get('classname')}.{case.get('name')}",
             "\n".join((bad.get("message", "") + "\n" + (bad.text or "")).strip().splitlines()[-lines:]))
            for case in ET.parse(path).getroot().iter("testcase")
            for bad in case.findall("failure") + case.findall("error")]


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
