"""What a CANopen teleoperation run came to: control, or a deadline FAULT — nothing in between.

A machine that cannot run the 1 kHz loops (a software-emulated guest on a loaded host) must not
turn a control check into a pass by skipping it, nor drive an arm astray: the loops' deadline
policy faults them instead. So a run is judged on one of two outcomes, from saw-rt's summary:
- "control": the arm and the teleoperation ended ENABLED (the caller checks the tracking);
- "deadline": the teleoperation or the arm ended in FAULT naming its missed deadline; then the
  tracking error over the cycles it was ENABLED is bounded (TRACKING_MAX_MM) and the caller
  checks the drives were left safe.
Anything else (a fault for another reason, an end without either) is the caller's failure.
"""

import re

# The hand's amplitude is 30 mm; the arm's normal run tracks within 16 mm at worst; a loop that
# ran a third of its cycles without faulting reached 238-306 mm (a joint at its limit).
TRACKING_MAX_MM = 25.0


def deadline_fault(stdout):
    """The first summary line of a component in FAULT for a missed deadline, or None."""
    m = re.search(r"^\s*(\w+): .*deadline missed.*$", stdout, re.M)
    return m.group(0).strip() if m else None


def tracking(stdout):
    """(RMS mm, max mm, enabled cycles) of the teleoperation's summary, or None."""
    m = re.search(r"^\s*teleop: .*tracking error \|e_s\| RMS ([0-9.]+) mm, max ([0-9.]+) mm over (\d+) enabled",
                  stdout, re.M)
    return (float(m.group(1)), float(m.group(2)), int(m.group(3))) if m else None


def outcome(stdout):
    """"control", "deadline" or None; with "deadline", the tracking up to the fault is checked here."""
    if deadline_fault(stdout):
        t = tracking(stdout)
        if t is None or t[1] > TRACKING_MAX_MM:
            return None
        return "deadline"
    if re.search(r"^\s*slave: ENABLED", stdout, re.M) and re.search(r"^\s*teleop: ENABLED", stdout, re.M):
        return "control"
    return None
