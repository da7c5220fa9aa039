"""Runs sawgui's pytest-qt tests in real windows on a private Xvfb display (a display number Xvfb
picks itself, so tests side by side do not collide). Exit 77 (skipped) when there is no Xvfb or no
PySide6 / pytest-qt in this Python, with the reason.

usage: run_under_xvfb.py SAW_RT [pytest arguments...]
"""
import importlib.util
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SKIP = 77


def main(argv):
    if len(argv) < 1:
        print(__doc__)
        return 2
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        print("SKIP: no Xvfb (Debian package xvfb; tools/bootstrap.sh installs it)")
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
    try:
        return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-v", "-s", HERE, *argv[1:]],
                              env=env, cwd=HERE).returncode
    finally:
        server.terminate()
        server.wait(timeout=10)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
