"""Failing a test script: a FAIL line (and whatever outputs explain it) on stderr, exit 1."""
import sys


def fail(message, *outputs):
    """FAIL: message, then each of `outputs` (a child's stdout and stderr, say), and exit 1."""
    print(f"FAIL: {message}", file=sys.stderr)
    for o in outputs:
        print(o, file=sys.stderr)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)
