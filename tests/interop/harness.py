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


def until_no_stall(attempt, what, attempts=3):
    """Runs attempt() until a run gives a verdict. attempt() returns None (its checks are the
    verdict) or why the machine stalled it (a process starved past a staleness limit: the device
    faulted, as it must): then its checks are dropped, but for those saying the device was safe
    after the stall ("after the stall ..."), which stand; it runs again, and a stall in every
    attempt fails."""
    for n in range(1, attempts + 1):
        before = len(failures)
        why = attempt()
        if why is None:
            return
        unsafe = [f for f in failures[before:] if f.startswith("after the stall")]
        del failures[before:]
        failures.extend(unsafe)
        print(f"stalled run of {what} ({n} of {attempts}), no verdict from it: {why}", flush=True)
    check(False, f"{what}: stalled in each of {attempts} runs")


def exit_code():
    return 1 if failures else 0
