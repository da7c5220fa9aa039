"""sawdds (nonrt/python) is an installable pure-Python package: a wheel built from it offline is
py3-none-any with no compiled file, carries every module of the source packages (sawdds and
sawgui), the console scripts, the cyclonedds pin of tools/requirements.txt and the GUI's pins as
the extra "gui", and installs with pip into a fresh venv, where `import sawdds` and `import sawgui`
find the installed copies, `sawdds --help` and `sawgui --help` run, and `sawgui --headless` runs
(reads the DDS domain for a second, with no gateway on it, and says so as JSON).

usage: wheel_installs.py   (the tools venv's python, which has setuptools from tools/requirements.txt)
"""
import json
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import tomllib
import unittest
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "support" / "python"))
from saw_testing.dds_domain import claim_fixed  # noqa: E402
SOURCE = ROOT / "nonrt" / "python"
PACKAGES = ("sawdds", "sawgui")
COMPILED = (".so", ".pyd", ".dylib", ".dll", ".c", ".cpp", ".pyx")
# Nothing from the caller's PYTHONPATH: what the fresh venv imports must be what it has.
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}


def run(*args, **kw):
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=60, env=ENV, **kw)


class TheWheelIsPureAndInstalls(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="sawdds-wheel-")
        tmp = Path(cls.tmp.name)
        # Built from a copy: setuptools builds in the tree it is given (build/, *.egg-info), and
        # another build of the same checkout may be running.
        src = tmp / "src"
        shutil.copytree(SOURCE, src, ignore=shutil.ignore_patterns("build", "dist", "*.egg-info", "__pycache__"))
        # --no-build-isolation --no-index: the tools venv's setuptools, nothing fetched.
        r = run(sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index",
                "--disable-pip-version-check", "--no-cache-dir", "-w", tmp / "dist", src)
        if r.returncode != 0:
            raise AssertionError(f"pip wheel failed (does the tools venv have tools/requirements.txt's setuptools? "
                                 f"tools/bootstrap.sh --tests installs it):\n{r.stdout}\n{r.stderr}")
        cls.wheels = sorted((tmp / "dist").glob("*.whl"))
        cls.project = tomllib.loads((SOURCE / "pyproject.toml").read_text(encoding="utf-8"))["project"]

        cls.venv = tmp / "venv"
        bindir = cls.venv / ("Scripts" if os.name == "nt" else "bin")
        cls.python = bindir / ("python.exe" if os.name == "nt" else "python")
        cls.script = bindir / ("sawdds.exe" if os.name == "nt" else "sawdds")
        # No pip of its own: the tools venv's pip installs into it (--python), which saves the seconds
        # ensurepip takes.
        r = run(sys.executable, "-m", "venv", "--without-pip", cls.venv)
        if r.returncode != 0:
            raise AssertionError(f"python -m venv failed:\n{r.stderr}")
        site = run(cls.python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])").stdout.strip()
        # cyclonedds, which the wheel depends on, from the tools venv (--no-deps: nothing fetched).
        # A .pth entry comes after the venv's own site-packages, so the installed sawdds is found first.
        paths = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
        Path(site, "tools_venv.pth").write_text("\n".join(sorted(paths)) + "\n", encoding="utf-8")
        cls.install = None
        if len(cls.wheels) == 1:
            cls.install = run(sys.executable, "-m", "pip", "--python", cls.python, "install", "--no-deps", "--no-index",
                              "--disable-pip-version-check", "--no-cache-dir", cls.wheels[0])

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def wheel_file(self, name):
        with zipfile.ZipFile(self.wheels[0]) as z:
            return z.read(f"sawdds-{self.project['version']}.dist-info/{name}").decode()

    def test_one_pure_wheel_for_any_python_3_and_platform(self):
        self.assertEqual([w.name for w in self.wheels], [f"sawdds-{self.project['version']}-py3-none-any.whl"])
        wheel = self.wheel_file("WHEEL")
        self.assertIn("Root-Is-Purelib: true", wheel)
        self.assertEqual(re.findall(r"^Tag: (.+)$", wheel, re.M), ["py3-none-any"])

    def test_the_wheel_holds_the_source_package_and_nothing_compiled(self):
        with zipfile.ZipFile(self.wheels[0]) as z:
            names = z.namelist()
        self.assertEqual([n for n in names if n.endswith(COMPILED)], [])
        for package in PACKAGES:
            source = [f"{package}/{p.name}" for p in (SOURCE / package).glob("*.py")]
            # and the message types' IDL, from which sawdds.msgs makes its classes
            source += [f"{package}/{p.relative_to(SOURCE / package).as_posix()}"
                       for p in (SOURCE / package).glob("idl/*/msg/*.idl")]
            self.assertEqual(sorted(n for n in names if n.startswith(f"{package}/")), sorted(source))
        self.assertIn("sawdds/idl/geometry_msgs/msg/PoseStamped.idl", names)

    def test_metadata_pins_cyclonedds_and_the_gui_as_the_tools_venv_does(self):
        pins = [line.split("#")[0].strip() for line in (ROOT / "tools" / "requirements.txt").read_text().splitlines()]
        core = sorted(p for p in pins if p.startswith(("cyclonedds==", "numpy==")))
        requires = re.findall(r"^Requires-Dist: (.+)$", self.wheel_file("METADATA"), re.M)
        self.assertEqual(sorted(r for r in requires if ";" not in r), core)
        gui = sorted(r.split(";")[0].strip() for r in requires if re.search(r"extra\s*==\s*[\"']gui[\"']", r))
        self.assertEqual(gui, sorted(p for p in pins if p.startswith(("PySide6-Essentials==", "pyqtgraph==", "mcap=="))))

    def test_the_console_script_is_declared(self):
        entry_points = self.wheel_file("entry_points.txt")
        self.assertRegex(entry_points, r"\[console_scripts\]\s*\n(.+\n)*sawdds = sawdds\.__main__:main")
        self.assertRegex(entry_points, r"\[console_scripts\]\s*\n(.+\n)*sawgui = sawgui\.__main__:main")

    def test_pip_installs_it_into_a_fresh_venv(self):
        self.assertIsNotNone(self.install, "no single wheel to install")
        self.assertEqual(self.install.returncode, 0, self.install.stdout + self.install.stderr)
        # -I: no PYTHONPATH, no current directory, no user site: only what the venv has.
        for package in PACKAGES:
            r = run(self.python, "-I", "-c", f"import {package}; print({package}.__file__)", cwd=self.tmp.name)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertTrue(Path(r.stdout.strip()).resolve().is_relative_to(self.venv.resolve()),
                            f"{package} imported from {r.stdout.strip()}, not from the fresh venv")

    def test_the_installed_command_runs(self):
        self.assertIsNotNone(self.install, "no single wheel to install")
        for command in ([self.script, "--help"], [self.python, "-I", "-m", "sawdds", "--help"]):
            with self.subTest(command=command):
                r = run(*command, cwd=self.tmp.name)
                self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
                self.assertIn("usage: sawdds [--enclave DIR] list", r.stdout)
        gui = self.venv / ("Scripts" if os.name == "nt" else "bin") / ("sawgui.exe" if os.name == "nt" else "sawgui")
        for command in ([gui, "--help"], [self.python, "-I", "-m", "sawgui", "--help"]):
            with self.subTest(command=command):
                r = run(*command, cwd=self.tmp.name)
                self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
                self.assertIn("usage: sawgui", r.stdout)

    def test_a_headless_sawgui_runs_from_the_install(self):
        """The window's readers without a window, on a DDS domain no test starts a gateway on (229,
        loopback; kept out of the tests' pool, and claimed as they claim theirs): it ends when asked
        and reports no gateway; the window's modules all import (PySide6 and pyqtgraph from the tools
        venv, as the extra "gui" would install them)."""
        self.assertIsNotNone(self.install, "no single wheel to install")
        claim = claim_fixed(229, timeout=30)  # (another run of this test may hold it a moment)
        self.addCleanup(claim.release)
        r = run(self.python, "-I", "-m", "sawgui", "--domain", str(claim.domain), "--headless", "1",
                cwd=self.tmp.name)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        report = json.loads(r.stdout.strip().splitlines()[-1])
        self.assertEqual(report["gateways"], {})
        self.assertEqual(report["seconds"], 1)
        r = run(self.python, "-I", "-c", "import sawgui.app, sawgui.__main__", cwd=self.tmp.name)
        self.assertEqual(r.returncode, 0, r.stderr)


if __name__ == "__main__":
    unittest.main(verbosity=2)
