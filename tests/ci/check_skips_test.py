#!/usr/bin/env python3
"""The skip checker (tools/ci/check_skips.py) on junit files shaped as CTest 3.25 writes them,
and the list of structural skips itself: a checker that passed everything would leave CI green
while it exercised nothing, so it is tested like the code.

Usage: check_skips_test.py [CTEST BUILD_DIR]   (with them, every entry of the list must name a
  test that build registers; left out where a build registers part of the suite only, e.g. under
  the sanitizers, which build neither the guard nor the kernel tests)
"""

from __future__ import annotations

import html
import json
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CHECKER = ROOT / "tools" / "ci" / "check_skips.py"
LIST = ROOT / "tests" / "structural-skips.txt"
BUILD: list[str] = []  # [ctest, build directory], or empty

CASES = {
    "pass": '<testcase name="{name}" classname="{name}" time="0.1" status="run"><system-out>ok</system-out></testcase>',
    "fail": '<testcase name="{name}" classname="{name}" time="0.1" status="fail"><failure message=""/>'
    "<system-out>bad</system-out></testcase>",
    "exit77": '<testcase name="{name}" classname="{name}" time="0" status="notrun">'
    '<skipped message="SKIP_RETURN_CODE=77"/><system-out>SKIP: no qemu-system-x86_64 here\n</system-out></testcase>',
    "gtest": '<testcase name="{name}" classname="{name}" time="0" status="notrun">'
    '<skipped message="SKIP_REGULAR_EXPRESSION_MATCHED"/><system-out>[ RUN      ] {name}\n'
    "/src/t.cpp:9: Skipped\nmlockall failed: Cannot allocate memory\n[  SKIPPED ] {name} (0 ms)\n"
    "</system-out></testcase>",
    "disabled": '<testcase name="{name}" classname="{name}" time="0" status="disabled">'
    "<system-out>Disabled</system-out></testcase>",
}


def junit(*cases: tuple[str, str]) -> str:
    body = "".join(CASES[kind].format(name=html.escape(name)) for name, kind in cases)
    return f'<?xml version="1.0" encoding="UTF-8"?>\n<testsuite name="(empty)" tests="{len(cases)}">{body}</testsuite>'


class Checker(unittest.TestCase):
    def setUp(self) -> None:
        self.dir = tempfile.TemporaryDirectory()
        self.tmp = Path(self.dir.name)
        self.list = self.tmp / "skips.txt"
        self.list.write_text(
            "# comment\n"
            "Kernel.Boot the guest needs a PREEMPT_RT kernel\n"
            "^Family\\.[A-Z]+/hw$ a family that needs hardware\n"
        )

    def tearDown(self) -> None:
        self.dir.cleanup()

    def check(self, text: str, *flags: str, listing: Path | None = None) -> subprocess.CompletedProcess[str]:
        path = self.tmp / "junit.xml"
        path.write_text(text)
        return subprocess.run(
            [sys.executable, str(CHECKER), "--list", str(listing or self.list), *flags, str(path)],
            capture_output=True,
            text=True,
            check=False,
        )

    def test_a_listed_skip_passes_and_is_reported_once_with_its_reason(self) -> None:
        r = self.check(junit(("A.Runs", "pass"), ("Kernel.Boot", "exit77"), ("Family.ONE/hw", "gtest")), "--strict")
        self.assertEqual(r.returncode, 0, r.stdout)
        self.assertEqual(r.stdout.count("Kernel.Boot: the guest needs a PREEMPT_RT kernel"), 1, r.stdout)
        self.assertIn("SKIP: no qemu-system-x86_64 here", r.stdout)
        self.assertIn("Family.ONE/hw: a family that needs hardware", r.stdout)

    def test_an_unlisted_skip_fails_strict_naming_the_test_and_its_reason(self) -> None:
        r = self.check(junit(("A.Runs", "pass"), ("Guard.Faults", "gtest"), ("Two.Hosts", "exit77")), "--strict")
        self.assertEqual(r.returncode, 1, r.stdout)
        self.assertIn("UNEXPECTED SKIP Guard.Faults: mlockall failed: Cannot allocate memory", r.stdout)
        self.assertIn("UNEXPECTED SKIP Two.Hosts: SKIP: no qemu-system-x86_64 here", r.stdout)

    def test_without_strict_an_unlisted_skip_is_printed_and_does_not_fail(self) -> None:
        r = self.check(junit(("A.Runs", "pass"), ("Guard.Faults", "gtest")))
        self.assertEqual(r.returncode, 0, r.stdout)
        self.assertIn("UNEXPECTED SKIP Guard.Faults", r.stdout)

    def test_a_parameterized_gtest_is_named_without_ctests_getparam_suffix(self) -> None:
        listing = self.tmp / "param.txt"
        listing.write_text("Suite/Conf.Case/socketcan no AF_CAN on the host\n")
        name = 'Suite/Conf.Case/socketcan  # GetParam() = "socketcan"'
        r = self.check(junit(("A.Runs", "pass"), (name, "gtest")), "--strict", listing=listing)
        self.assertEqual(r.returncode, 0, r.stdout)
        r = self.check(junit(("A.Runs", "pass"), ('Suite/Conf.Case/virtual  # GetParam() = "virtual"', "gtest")),
                       "--strict", listing=listing)
        self.assertEqual(r.returncode, 1, r.stdout)

    def test_a_pattern_matches_whole_names_only(self) -> None:
        r = self.check(junit(("A.Runs", "pass"), ("Family.ONE/hw2", "exit77")), "--strict")
        self.assertEqual(r.returncode, 1, r.stdout)
        self.assertIn("UNEXPECTED SKIP Family.ONE/hw2", r.stdout)

    def test_a_disabled_test_is_a_skip(self) -> None:
        r = self.check(junit(("A.Runs", "pass"), ("A.Off", "disabled")), "--strict")
        self.assertEqual(r.returncode, 1, r.stdout)
        self.assertIn("UNEXPECTED SKIP A.Off", r.stdout)

    def test_a_failure_is_not_the_checkers_business(self) -> None:
        r = self.check(junit(("A.Runs", "pass"), ("A.Fails", "fail")), "--strict")
        self.assertEqual(r.returncode, 0, r.stdout)

    def test_no_test_run_fails(self) -> None:
        self.assertEqual(self.check(junit(), "--strict").returncode, 1)
        r = self.check(junit(("Kernel.Boot", "exit77")), "--strict")
        self.assertEqual(r.returncode, 1, r.stdout)
        self.assertIn("no test ran", r.stdout)

    def test_a_missing_junit_fails(self) -> None:
        r = subprocess.run(
            [sys.executable, str(CHECKER), "--strict", "--list", str(self.list), str(self.tmp / "none.xml")],
            capture_output=True,
            text=True,
            check=False,
        )
        self.assertEqual(r.returncode, 1, r.stderr)

    def test_a_list_entry_without_a_reason_or_half_anchored_is_refused(self) -> None:
        for bad in ("Kernel.Boot\n", "^Kernel\\..* unanchored at the end\n"):
            listing = self.tmp / "bad.txt"
            listing.write_text(bad)
            r = self.check(junit(("A.Runs", "pass")), "--strict", listing=listing)
            self.assertEqual(r.returncode, 2, bad)


class TheList(unittest.TestCase):
    def test_every_entry_names_a_registered_test(self) -> None:
        sys.path.insert(0, str(CHECKER.parent))
        import check_skips  # noqa: PLC0415 (the checker's own parser, as CI uses it)

        entries = check_skips.read_list(LIST)
        if not BUILD:
            return  # part of the suite only in this build: nothing to compare the names with
        ctest, build = BUILD
        listing = subprocess.run(
            [ctest, "--test-dir", build, "-N", "--show-only=json-v1"], capture_output=True, text=True, check=True
        )
        tests = [t["name"] for t in json.loads(listing.stdout)["tests"]]
        self.assertTrue(tests, "the listing names no test")
        stale = [f"{LIST.name}:{e.line}: {e.name}" for e in entries if not any(e.matches(t) for t in tests)]
        self.assertEqual(stale, [], "entries that name no registered test (renamed or removed?)")


if __name__ == "__main__":
    BUILD = sys.argv[1:3]
    del sys.argv[1:3]
    unittest.main()
