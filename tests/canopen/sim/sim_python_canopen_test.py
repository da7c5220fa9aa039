"""saw-can-sim against python `canopen` (an independent CANopen master) through saw-socketcand.

Real processes: saw-can-sim simulates nodes 3 and 4 on a virtual bus of this test's own;
saw-socketcand serves that bus on 127.0.0.1 (a free port); python canopen connects with
interface='socketcand' and reads the drive's EDS like any master. Checks: SDO expedited
(0x1000, 0x1018) and segmented (0x1008) uploads, a download read back, an abort, NMT reset with
the boot-up message, the heartbeat after 0x1017 is set and its state after NMT start, canopen's
BaseNode402 taking the drive to operation enabled over its own PDOs and SYNC, a move in CSP, a
fault injected through the bus (0x2F00) seen as EMCY 0x2310 and reset by BaseNode402, and
saw-can-sim's exit summary.

Usage: sim_python_canopen_test.py <saw-can-sim> <saw-socketcand> <sim_drive.eds>
Exits 77 (skipped) when the tools venv has no `canopen`.
"""

import os
import re
import signal
import subprocess
import sys
import time

try:
    import canopen
    from canopen.sdo import SdoAbortedError
except ImportError as e:
    print(f"SKIP: python canopen is not installed in this venv ({e}); tools/requirements.txt has it")
    sys.exit(77)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "can"))
from child_tools import check, fail, read_line, start_socketcand  # noqa: E402

SIM, SERVER, EDS = sys.argv[1:4]
BUS = f"sawcansim{os.getpid()}"
DRIVE, OTHER = 3, 4


def wait_for(condition, timeout, what):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return
        time.sleep(0.01)
    fail(f"{what}: not within {timeout} s")


def start_processes():
    sim = subprocess.Popen(
        [SIM, "--bus", f"virtual:{BUS}", "--node", str(DRIVE), "--node", str(OTHER), "--duration", "100"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    line = read_line(sim.stdout, 10, "ready line from saw-can-sim")
    check(line.startswith(f"saw-can-sim: 2 drives on virtual:{BUS} (nodes 3, 4)"), f"saw-can-sim said {line!r}")
    server, port = start_socketcand(SERVER, BUS)
    return sim, server, port


def sdo(network):
    node = canopen.BaseNode402(DRIVE, EDS)
    other = canopen.RemoteNode(OTHER, EDS)
    network.add_node(node)
    network.add_node(other)
    for n in (node, other):
        n.sdo.RESPONSE_TIMEOUT = 2.0  # a loaded machine's scheduling, not the drive, sets the pace
    check(node.sdo[0x1000].raw == 0x00020192, f"0x1000 is {node.sdo[0x1000].raw:#x}")
    check(len(node.sdo.upload(0x1000, 0)) == 4, "0x1000 is 4 bytes")
    identity = [node.sdo[0x1018][i].raw for i in range(1, 5)]
    check(identity == [0x5A7, 0x00402100, 0x00010000, 0x53490000 + DRIVE], f"0x1018: {identity}")
    check(other.sdo[0x1018][4].raw == 0x53490000 + OTHER, "node 4 is its own drive")
    name = node.sdo[0x1008].raw
    check(name == "sawrt simulated CiA 402 drive", f"0x1008 (segmented) is {name!r}")
    node.sdo[0x6065].raw = 1234
    check(node.sdo[0x6065].raw == 1234, "0x6065 written and read back")
    try:
        node.sdo.download(0x1000, 0, b"\x01\x00\x00\x00")
        fail("writing 0x1000 was accepted")
    except SdoAbortedError as e:
        check(e.code == 0x06010002, f"abort {e.code:#010x}, expected read-only 0x06010002")
    return node, other


def nmt(node):
    node.nmt.state = "RESET"
    node.nmt.wait_for_bootup(5)
    check(node.sdo[0x6065].raw == 2000, "reset node restored 0x6065")
    node.sdo[0x1017].raw = 50
    state = node.nmt.wait_for_heartbeat(2)
    check(state == "PRE-OPERATIONAL", f"heartbeat says {state}")
    node.nmt.state = "OPERATIONAL"
    wait_for(lambda: node.nmt.wait_for_heartbeat(1) == "OPERATIONAL", 3, "a heartbeat saying operational")


def cia402(network, node):
    node.setup_402_state_machine()  # reads the drive's PDO configuration by SDO
    position = node.sdo[0x6064].raw
    node.rpdo[1]["Target position"].raw = position
    node.rpdo[1].start(0.01)  # RPDO1 is synchronous: the master sends it every cycle
    network.sync.start(0.01)
    node.state = "OPERATION ENABLED"
    check(node.state == "OPERATION ENABLED", f"402 state {node.state}")
    check(node.op_mode == "CYCLIC SYNCHRONOUS POSITION", f"mode {node.op_mode}")
    target = position + 1000  # within the following error window (2000): a step the servo takes
    node.rpdo[1]["Target position"].raw = target
    wait_for(lambda: abs(node.tpdo[1]["Position actual value"].raw - target) <= 3, 3, "CSP move to the target")


def fault(node):
    node.sdo[0x2F00][1].raw = 1  # inject an over-current through the bus
    wait_for(lambda: any(e.code == 0x2310 for e in node.emcy.log), 3, "EMCY 0x2310")
    emcy = next(e for e in node.emcy.log if e.code == 0x2310)
    check(emcy.register & 0x03 == 0x03, f"error register {emcy.register:#x}: generic and current")
    wait_for(lambda: node.state == "FAULT", 3, "the drive in FAULT")
    check(node.sdo[0x603F].raw == 0x2310, "0x603F holds the error code")
    node.state = "OPERATION ENABLED"  # BaseNode402 resets the fault (controlword bit 7) and walks up
    check(node.state == "OPERATION ENABLED", f"after fault reset: {node.state}")
    wait_for(lambda: node.emcy.log[-1].code == 0, 2, "the error reset EMCY")
    check(not node.emcy.active, f"active EMCYs {node.emcy.active}")


def stop(process, name):
    process.send_signal(signal.SIGTERM)
    try:
        out, err = process.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
        fail(f"{name} did not stop on SIGTERM")
    check(process.returncode == 0, f"{name}: status {process.returncode}: {err.decode()}")
    return out.decode()


def main():
    sim, server, port = start_processes()
    network = canopen.Network()
    try:
        network.connect(interface="socketcand", host="127.0.0.1", port=port, channel=BUS)
        time.sleep(0.2)  # saw-socketcand holds frames 50 ms after the handshake
        node, _ = sdo(network)
        nmt(node)
        cia402(network, node)
        fault(node)
        node.rpdo[1].stop()
        network.sync.stop()
        network.disconnect()
    finally:
        server_out = stop(server, "saw-socketcand")
        summary = stop(sim, "saw-can-sim")
        try:
            os.unlink(f"/dev/shm/saw-can.{BUS}")
        except FileNotFoundError:
            pass
    rows = {int(line.split()[0]): line for line in summary.splitlines() if re.match(r"^\s+\d+\s", line)}
    check(set(rows) == {DRIVE, OTHER}, f"summary:\n{summary}")
    check("operational" in rows[DRIVE] and "operation enabled" in rows[DRIVE], f"node 3 in the summary: {rows[DRIVE]}")
    check("pre-operational" in rows[OTHER], f"node 4 in the summary: {rows[OTHER]}")
    print(summary, end="")
    print(server_out, end="")
    print("ok: SDO expedited and segmented, NMT, heartbeat, BaseNode402 over PDOs, CSP move, EMCY and fault reset")


if __name__ == "__main__":
    main()
