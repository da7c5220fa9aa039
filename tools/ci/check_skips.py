#!/usr/bin/env python3
"""Reads what ctest ran (its --output-junit file) and says which tests did not run, and why.

A green run must have exercised what it claims: a test that skipped because something was
missing on the machine (a kernel, QEMU, a network namespace, mlockall) looks the same as a pass
in ctest's exit code. Every skip is therefore either on the list of structural skips
(tests/structural-skips.txt: tests that cannot run on the CI machine by its nature, each with
its reason) or it is a finding. With --strict (CI) a finding fails; without, it is printed.

CTest 3.25 writes each test as <testcase status="run|fail|notrun|disabled">. A test that exited
with its SKIP_RETURN_CODE, a discovered gtest that printed "[  SKIPPED ]", one whose
REQUIRED_FILES are missing and one whose fixture failed are all status="notrun" with a
<skipped message="..."/> (SKIP_RETURN_CODE=77, SKIP_REGULAR_EXPRESSION_MATCHED, ...); a
DISABLED test is status="disabled". All of them ran nothing, so all are skips here.

Usage: check_skips.py [--strict] [--list FILE] JUNIT
Exit: 0, or 1 with --strict when a skip is not on the list, when no test ran, or when JUNIT
cannot be read; 2 for a malformed list.
"""

from __future__ import annotations

import argparse
import re
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

DEFAULT_LIST = Path(__file__).resolve().parents[2] / "tests" / "structural-skips.txt"
# CTest 3.25's gtest_discover_tests names a value-parameterized test "GTEST_NAME  # GetParam() =
# VALUE"; the list may name it by its GoogleTest name alone, which is unique and has no spaces.
PARAM_SUFFIX = "  # GetParam() = "


@dataclass
class Entry:
    """One line of the list: an exact test name, or an anchored pattern (^...$) for a family."""

    name: str
    reason: str
    line: int

    def matches(self, test: str) -> bool:
        names = {test, test.split(PARAM_SUFFIX, 1)[0]}
        if self.name.startswith("^"):
            return any(re.fullmatch(self.name[1:-1], n) is not None for n in names)
        return self.name in names


@dataclass
class Skip:
    test: str
    kind: str  # ctest's <skipped message>, or "disabled"
    output: str

    def reason(self) -> str:
        """What the test said about why it did not run, in one line when it said so."""
        lines = self.output.splitlines()
        # Our scripts' convention: "SKIP: why".
        said = [ln.strip() for ln in lines if ln.strip().startswith("SKIP:")]
        if said:
            return "; ".join(said)
        # GTEST_SKIP() << why: "file:line: Skipped" then the message, up to "[  SKIPPED ]".
        for i, ln in enumerate(lines):
            if re.search(r":\d+: Skipped$", ln):
                message = []
                for m in lines[i + 1 :]:
                    if m.startswith("[  SKIPPED ]"):
                        break
                    message.append(m.strip())
                text = " ".join(m for m in message if m)
                return text or "GTEST_SKIP() without a message"
        last = [ln.strip() for ln in lines if ln.strip()][-3:]
        return self.kind + (": " + " | ".join(last) if last else " (the test printed nothing)")


def read_list(path: Path) -> list[Entry]:
    entries = []
    for number, raw in enumerate(path.read_text().splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        name, _, reason = line.partition(" ")
        reason = reason.strip()
        where = f"{path}:{number}"
        if not reason:
            raise ValueError(f"{where}: '{name}': no reason (a structural skip says why it cannot run in CI)")
        if name.startswith("^") != name.endswith("$"):
            raise ValueError(f"{where}: '{name}': a pattern is anchored at both ends (^...$), a name at neither")
        if name.startswith("^"):
            try:
                re.compile(name[1:-1])
            except re.error as e:
                raise ValueError(f"{where}: '{name}': not a regular expression: {e}") from e
        entries.append(Entry(name, reason, number))
    return entries


def read_junit(path: Path) -> tuple[int, list[Skip]]:
    """How many tests ran (passed or failed), and the ones that did not."""
    root = ET.parse(path).getroot()
    ran = 0
    skips = []
    for case in root.iter("testcase"):
        status = case.get("status", "")
        skipped = case.find("skipped")
        out = case.findtext("system-out") or ""
        if status == "disabled":
            skips.append(Skip(case.get("name", "?"), "disabled", out))
        elif skipped is not None or status == "notrun":
            kind = skipped.get("message", "not run") if skipped is not None else "not run"
            skips.append(Skip(case.get("name", "?"), kind, out))
        else:
            ran += 1
    return ran, skips


def indent(text: str, limit: int = 40) -> str:
    lines = text.rstrip().splitlines()
    if len(lines) > limit:
        lines = [f"... ({len(lines) - limit} lines left out)"] + lines[-limit:]
    return "\n".join("      " + ln for ln in lines)


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("junit", type=Path, help="ctest --output-junit FILE")
    p.add_argument("--list", type=Path, default=DEFAULT_LIST, help="the structural skips (default: %(default)s)")
    p.add_argument("--strict", action="store_true", help="fail on a skip not on the list, or on no test run")
    a = p.parse_args(argv)
    failing = 1 if a.strict else 0

    try:
        entries = read_list(a.list)
    except (OSError, ValueError) as e:
        print(f"check_skips: {e}", file=sys.stderr)
        return 2
    try:
        ran, skips = read_junit(a.junit)
    except (OSError, ET.ParseError) as e:
        print(f"check_skips: cannot read what ctest ran from {a.junit}: {e}", file=sys.stderr)
        return failing

    structural, unexpected = [], []
    for s in skips:
        entry = next((e for e in entries if e.matches(s.test)), None)
        (structural if entry else unexpected).append((s, entry))

    if structural:
        print(f"check_skips: {len(structural)} structural skip(s) ({a.list.name}):")
        for s, e in structural:
            print(f"  {s.test}: {e.reason}\n      it said: {s.reason()}")
    if unexpected:
        print(f"check_skips: {len(unexpected)} test(s) did not run and are not structural skips:")
        for s, _ in unexpected:
            print(f"  UNEXPECTED SKIP {s.test}: {s.reason()}")
            # A gtest's own message is its reason; a script's last lines show where it stopped.
            said = s.output.strip()
            if said and said != s.reason() and s.kind != "SKIP_REGULAR_EXPRESSION_MATCHED":
                print(indent(s.output, 20))
        print(
            "  Each is a test CI claims and did not exercise: make it run here (tools/bootstrap.sh --tests installs "
            f"what the tests need), or, if it cannot run on this machine by its nature, add it to {a.list} "
            "with the reason."
        )
    if ran == 0:
        print(f"check_skips: no test ran ({a.junit}: {len(skips)} skipped, none passed or failed)")
        return failing
    print(f"check_skips: {ran} test(s) ran, {len(structural)} structural skip(s), {len(unexpected)} unexpected")
    return failing if unexpected else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
