"""What the interop tests share: the sawdds import path, a checklist that fails the test at the
end (every check is printed, met or not), a bounded wait for a matching DDS sample, and the DDS
domain the test holds alone (dds_domain(), from tests/support/python/saw_testing)."""
import os
import sys
import time

# The source tree's sawdds, not an installed one: the venv is shared by every checkout of the repository.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "nonrt", "python"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support", "python"))
from saw_testing.dds_domain import dds_domain  # noqa: E402, F401  (for the tests that import harness)

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)
    return cond


def wait_for(reader, pred, timeout):
    """The first sample from `reader` for which pred(sample) holds, or None after `timeout` s.
    A writer's unregistration (its gateway gone) comes as an InvalidSample, which is skipped."""
    from cyclonedds.internal import InvalidSample
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for s in reader.take(N=64):
            if not isinstance(s, InvalidSample) and pred(s):
                return s
        time.sleep(0.001)
    return None


def exit_code():
    return 1 if failures else 0
