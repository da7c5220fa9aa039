"""A generic CANopen I/O node played by python `canopen`: a gripper's controller beside the drives.

Its object dictionary is built here from CiA 301 and CiA 401 (no EDS, nothing of sawrt's):
device type 0x1000 (401, analog in and out), 0x1016/0x1017 heartbeats, identity 0x1018, RPDO1 and
TPDO1 (communication and mapping, both remappable by SDO), 0x6411:01 "write analog output 16-bit"
(the jaw's commanded opening, counts), 0x6401:01 "read analog input 16-bit" (its measured
opening), and the output's error behaviour: 0x6443:01 "analog output error mode" (1, the default:
take the error value on a device failure or communication loss; 0: keep the output) and 0x6444:01
"analog output error value" (INTEGER32, default 0), which the output takes when its heartbeat
consumer fires or RPDO1 misses its deadline (its event timer 0x1400:05, EMCY 0x8250). What python canopen's LocalNode leaves to the application is PythonDrive's (NMT, PDOs
at SYNC, the heartbeat consumer); the application here is a jaw that moves towards the command
by at most `rate` counts per SYNC.
"""

import canopen
from canopen.objectdictionary import (ODArray, ODRecord, ODVariable, INTEGER16, INTEGER32, UNSIGNED8,
                                      UNSIGNED16, UNSIGNED32)

from python_drive import PythonDrive


def _var(name, index, sub, kind, access="rw", default=0):
    v = ODVariable(name, index, sub)
    v.data_type, v.access_type, v.default = kind, access, default
    return v


def _record(cls, name, index, subs, count_access="ro"):
    r = cls(name, index)
    r.add_member(_var("Highest sub-index supported", index, 0, UNSIGNED8, count_access, len(subs)))
    for k, (sub_name, kind, default) in enumerate(subs, start=1):
        r.add_member(_var(sub_name, index, k, kind, "rw", default))
    return r


def io_dictionary(node_id):
    od = canopen.ObjectDictionary()
    od.node_id = node_id
    od.add_object(_var("Device type", 0x1000, 0, UNSIGNED32, "ro", 0x000C0191))
    od.add_object(_var("Error register", 0x1001, 0, UNSIGNED8, "ro", 0))
    od.add_object(_var("Producer heartbeat time", 0x1017, 0, UNSIGNED16, "rw", 0))
    od.add_object(_record(ODArray, "Consumer heartbeat time", 0x1016, [("Consumer 1", UNSIGNED32, 0)]))
    od.add_object(_record(ODRecord, "Identity", 0x1018, [("Vendor-ID", UNSIGNED32, 0x5A5), ("Product code", UNSIGNED32, 401)]))
    rpdo1 = _record(ODRecord, "RPDO1 communication", 0x1400,
                    [("COB-ID", UNSIGNED32, 0x200 + node_id), ("Transmission type", UNSIGNED8, 1)])
    # CiA 301's event timer (ms): on an RPDO, its deadline (PythonDrive watches it).
    rpdo1.add_member(_var("Event timer", 0x1400, 5, UNSIGNED16, "rw", 0))
    rpdo1[0].default = 5
    od.add_object(rpdo1)
    od.add_object(_record(ODRecord, "TPDO1 communication", 0x1800,
                          [("COB-ID", UNSIGNED32, 0x180 + node_id), ("Transmission type", UNSIGNED8, 1)]))
    for index, name in ((0x1600, "RPDO1 mapping"), (0x1A00, "TPDO1 mapping")):
        # The number of entries is written by the master (CiA 301's remapping procedure).
        od.add_object(_record(ODRecord, name, index, [(f"Entry {k}", UNSIGNED32, 0) for k in range(1, 9)], "rw"))
    od.add_object(_record(ODArray, "Read analog input 16-bit", 0x6401, [("Input 1", INTEGER16, 0)]))
    od.add_object(_record(ODArray, "Write analog output 16-bit", 0x6411, [("Output 1", INTEGER16, 0)]))
    od.add_object(_record(ODArray, "Analog output error mode", 0x6443, [("Output 1", UNSIGNED8, 1)]))
    od.add_object(_record(ODArray, "Analog output error value integer", 0x6444, [("Output 1", INTEGER32, 0)]))
    return od


class PythonIoNode(PythonDrive):
    def __init__(self, network, node_id, rate=20):
        super().__init__(network, node_id, None, od=io_dictionary(node_id))
        self.rate = rate
        self.outputs = []  # 0x6411:01 as each SYNC applied it

    def _step(self):
        out = self._get(0x6411, 1)
        now = self._get(0x6401, 1)
        self.outputs.append(out)
        self._set(0x6401, 1, now + max(-self.rate, min(self.rate, out - now)))

    def _abort_connection(self, code=0x8130):
        """A heartbeat event (EMCY 0x8130) or an RPDO deadline missed (0x8250): the EMCY, and the
        output at its error value if its mode says so."""
        self.node.emcy.send(code, 0x11)
        if self._get(0x6443, 1) == 1:
            value = max(-0x8000, min(0x7FFF, self._get(0x6444, 1)))
            self._set(0x6411, 1, value)
            self._note(f"output at its error value {value}")

    def nmt_state(self):
        return self.node.nmt.state


def main():
    """Plays the node until SIGINT/SIGTERM, through saw-socketcand on 127.0.0.1."""
    import argparse
    import signal
    import threading

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=29536, help="saw-socketcand's port on 127.0.0.1")
    parser.add_argument("--channel", required=True, help="the bus's name as saw-socketcand serves it")
    parser.add_argument("--node", type=int, default=10)
    args = parser.parse_args()
    network = canopen.Network()
    network.connect(interface="socketcand", host="127.0.0.1", port=args.port, channel=args.channel)
    node = PythonIoNode(network, args.node)
    node.boot()
    print(f"python_io_node: node {args.node} on {args.channel}", flush=True)
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    signal.signal(signal.SIGINT, lambda *_: done.set())
    done.wait()
    node.close()
    network.disconnect()


if __name__ == "__main__":
    main()
