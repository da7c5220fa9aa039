"""A CiA 402 drive played by python `canopen` (an independent stack): the peer that checks sawrt's master.

python canopen's LocalNode is the drive's CiA 301 side: its SDO server over an object dictionary
read from an EDS, its NMT slave and heartbeat producer, its EMCY producer. What LocalNode leaves
to the application is written here from CiA 301/402, not from sawrt's code:

- NMT resets restore the communication objects and send the boot-up message; NMT start makes
  the PDOs configured by SDO (0x1400.., 0x1600.., 0x1800.., 0x1A00..) live;
- synchronous PDOs: the RPDOs received are applied at the next SYNC, then every valid TPDO is sent;
- the CiA 402 state machine (figure 10 of CiA 402-2) on the controlword, 0x6061 following 0x6060,
  a position that follows 0x607A in CSP;
- the heartbeat consumer (0x1016, CiA 301 7.2.8.3.2.2): once a watched node's first heartbeat
  came, no heartbeat within its time is a heartbeat event: EMCY 0x8130 and the abort-connection
  option code 0x6007 (CiA 402: 0 nothing, 1 fault, 2 disable voltage, 3 quick stop);
- RPDO deadline monitoring (CiA 301: an RPDO's event timer, 0x1400+k sub 5, ms, is a deadline on
  the receiving side): in operational, once an RPDO came, none within its event timer is EMCY
  0x8250 (RPDO timeout) and the same 0x6007 reaction, once per silence; the drive stays operational.

Scenario knobs: start in FAULT (and whether a fault reset clears it), a mode display that does
not follow 0x6060, a state it does not leave, a different identity, and calls to fault, warn,
leave operational and reboot (a power cycle: every object back to the EDS's default).
"""

import struct
import threading
import time

import canopen
from canopen.objectdictionary import ODArray, ODVariable, UNSIGNED8, UNSIGNED32

# Statusword of each CiA 402 state (bit 9 remote, bit 4 voltage enabled where the power is on).
STATUSWORD = {
    "not ready to switch on": 0x0200,
    "switch on disabled": 0x0240,
    "ready to switch on": 0x0231,
    "switched on": 0x0233,
    "operation enabled": 0x0237,
    "quick stop active": 0x0217,
    "fault reaction active": 0x021F,
    "fault": 0x0218,
}


def _consumer_od(od):
    """0x1016 (consumer heartbeat time, one entry) for an EDS that lacks it."""
    if 0x1016 in od:
        return
    array = ODArray("Consumer heartbeat time", 0x1016)
    count = ODVariable("Highest sub-index supported", 0x1016, 0)
    count.data_type, count.access_type, count.default = UNSIGNED8, "ro", 1
    entry = ODVariable("Consumer heartbeat time 1", 0x1016, 1)
    entry.data_type, entry.access_type, entry.default = UNSIGNED32, "rw", 0
    array.add_member(count)
    array.add_member(entry)
    od.add_object(array)


class PythonDrive:
    def __init__(self, network, node_id, eds, *, boot_fault=None, reset_clears=True, mode_follows=True,
                 vendor=None, stuck_in=None, od=None):
        od = od if od is not None else canopen.import_od(eds, node_id)
        _consumer_od(od)
        if vendor is not None:
            od[0x1018][1].default = vendor
        self.id = node_id
        self.network = network
        self.node = canopen.LocalNode(node_id, od)
        network.add_node(self.node)
        self.node.add_write_callback(self._on_write)
        network.subscribe(0, self._on_nmt)
        network.subscribe(0x80, self._on_sync)
        self.lock = threading.RLock()
        self.reset_clears = reset_clears
        self.mode_follows = mode_follows
        self.stuck_in = stuck_in  # a state the drive does not leave towards operation enabled
        self.state = "switch on disabled"
        self.controlword = 0
        self.previous_controlword = 0
        self.fault_resets = 0  # rising edges of bit 7 seen in FAULT
        self.history = []  # (time, what): state changes, heartbeat events, NMT
        self.rpdos, self.tpdos, self.received = [], [], {}
        self.watched = {}  # node -> consumer time (s)
        self.last_heartbeat = {}  # node -> time of its last heartbeat
        self.consumer_events = []  # (node, time)
        self.rpdo_deadlines = {}  # RPDO identifier -> its event timer (s), from NMT start; 0: off
        self.rpdo_seen = {}  # RPDO identifier -> time of its last reception in operational
        self.rpdo_timeouts = []  # (identifier, time)
        self.enabled_with_mode = set()  # 0x6061 values seen while operation enabled
        self.syncs = 0
        self.writes = []  # (time, index, subindex) of every SDO write the drive took
        self.targets = []  # (time, 0x607A) applied from an RPDO at a SYNC
        if boot_fault is not None:
            self._fault(boot_fault, 0x03, send=False)
        self._stop = threading.Event()
        self._watcher = threading.Thread(target=self._watch, daemon=True)
        self._watcher.start()

    # ---- the object dictionary -------------------------------------------------------------
    def _get(self, index, sub=0):
        obj = self.node.object_dictionary[index]
        if not isinstance(obj, ODVariable):
            obj = obj[sub]
        return obj.decode_raw(self.node.get_data(index, sub))

    def _has(self, index, sub):
        od = self.node.object_dictionary
        return index in od and (isinstance(od[index], ODVariable) or sub in od[index])

    def _set(self, index, sub, value):
        obj = self.node.object_dictionary[index]
        if not isinstance(obj, ODVariable):
            obj = obj[sub]
        self.node.data_store.setdefault(index, {})[sub] = obj.encode_raw(value)

    def _note(self, what):
        self.history.append((time.monotonic(), what))

    def _enter(self, state):
        if state != self.state:
            self._note(f"state {state}")
        self.state = state
        if 0x6041 in self.node.object_dictionary:
            self._set(0x6041, 0, STATUSWORD[state])

    # ---- NMT -----------------------------------------------------------------------------------
    def boot(self):
        """Power-on: the boot-up message, then pre-operational with 0x1017's heartbeat."""
        with self.lock:
            self.node.nmt.send_command(0x81)  # initialising: LocalNode sends the boot-up message
            self.node.nmt.send_command(0x80)  # pre-operational: the heartbeat starts
            self._enter(self.state)
            self._note("boot-up")

    def _on_nmt(self, can_id, data, timestamp):
        if len(data) != 2 or data[1] not in (0, self.id):
            return
        with self.lock:
            command = data[0]
            self._note(f"NMT {command:#04x}")
            if command in (0x81, 0x82):
                first = 0x1000 if command == 0x82 else 0x0000
                last = 0x1FFF if command == 0x82 else 0xFFFF
                for index in [i for i in self.node.data_store if first <= i <= last]:
                    del self.node.data_store[index]
                self.node.nmt.stop_heartbeat()
                self.watched, self.last_heartbeat, self.rpdos, self.tpdos = {}, {}, [], []
                self.rpdo_deadlines, self.rpdo_seen = {}, {}
                if command == 0x81 and self.state != "fault":
                    self._enter("switch on disabled")
                self.boot()
            elif command == 0x01:
                self._load_pdos()
            elif command in (0x02, 0x80) and self.state == "operation enabled":
                self._enter("quick stop active")  # leaving operational stops the motion

    def reboot(self):
        """A power cycle mid-run: the object dictionary back to the EDS's defaults (the PDO maps,
        0x1016, 0x6007, 0x6060 and 0x1017 the master wrote are gone), the CiA 402 state machine
        from its start, NMT initialising: the boot-up message, then pre-operational."""
        with self.lock:
            self.node.nmt.stop_heartbeat()
            for cob, _ in self.rpdos:
                self.network.unsubscribe(cob, self._on_rpdo)
            self.node.data_store.clear()
            self.watched, self.last_heartbeat, self.rpdos, self.tpdos, self.received = {}, {}, [], [], {}
            self.rpdo_deadlines, self.rpdo_seen = {}, {}
            self.previous_controlword = 0
            self._note("reboot")
            self._enter("switch on disabled")
            self.boot()

    def leave_operational(self):
        """The drive goes pre-operational by itself (its heartbeat says so)."""
        with self.lock:
            self.node.nmt.send_command(0x80)
            self._note("left operational")

    # ---- SDO writes the drive acts on ------------------------------------------------------
    def _on_write(self, index, subindex, od, data):
        self.writes.append((time.monotonic(), index, subindex))
        if index == 0x1016 and subindex >= 1:
            value, = struct.unpack("<I", bytes(data))
            node, ms = (value >> 16) & 0x7F, value & 0xFFFF
            with self.lock:
                self.watched = {n: t for n, t in self.watched.items() if n != node}
                if node != 0 and ms != 0:
                    self.watched[node] = ms / 1000
                    self.network.subscribe(0x700 + node, self._on_heartbeat)

    def _on_heartbeat(self, can_id, data, timestamp):
        node = can_id - 0x700
        with self.lock:
            if node in self.watched and len(data) == 1:
                self.last_heartbeat[node] = time.monotonic()

    def _watch(self):
        fired = set()
        while not self._stop.wait(0.005):
            with self.lock:
                now = time.monotonic()
                self._watch_rpdos(now)
                for node, limit in self.watched.items():
                    seen = self.last_heartbeat.get(node)
                    if seen is None:
                        continue  # monitoring starts with the first heartbeat
                    if now - seen > limit and node not in fired:
                        fired.add(node)
                        self.consumer_events.append((node, now))
                        self._note(f"heartbeat event for node {node}")
                        self._abort_connection()
                    elif now - seen <= limit:
                        fired.discard(node)

    def _watch_rpdos(self, now):
        if self.node.nmt.state != "OPERATIONAL":
            self.rpdo_seen = {}  # watched again from the first RPDO in operational
            return
        for cob, limit in self.rpdo_deadlines.items():
            seen = self.rpdo_seen.get(cob)
            if limit > 0 and seen is not None and now - seen > limit:
                del self.rpdo_seen[cob]  # once per silence: the next RPDO arms it again
                self.rpdo_timeouts.append((cob, now))
                self._note(f"RPDO 0x{cob:03X} missed its {limit * 1000:.0f} ms deadline")
                self._abort_connection(0x8250)

    def _abort_connection(self, code=0x8130):
        self.node.emcy.send(code, 0x11)
        option = self._get(0x6007) if 0x6007 in self.node.object_dictionary else 0
        self._note(f"abort connection option {option}")
        if self.state not in ("operation enabled", "quick stop active"):
            return
        if option == 1:
            self._fault(code, 0x11)
        elif option == 2:
            self._enter("switch on disabled")
        elif option == 3:
            self._enter("quick stop active")

    # ---- PDOs --------------------------------------------------------------------------------
    def _mapping(self, parameter, mapping):
        if parameter not in self.node.object_dictionary:
            return None  # a node with fewer than 4 PDOs
        cob = self._get(parameter, 1)
        if cob & 0x80000000:
            return None
        entries = []
        for k in range(1, self._get(mapping, 0) + 1):
            e = self._get(mapping, k)
            entries.append((e >> 16, (e >> 8) & 0xFF, (e & 0xFF) // 8))
        return cob & 0x7FF, entries

    def _load_pdos(self):
        for old, _ in self.rpdos:
            self.network.unsubscribe(old, self._on_rpdo)
        self.rpdos = [m for m in (self._mapping(0x1400 + n, 0x1600 + n) for n in range(4)) if m]
        self.rpdo_deadlines, self.rpdo_seen = {}, {}
        for n in range(4):
            m = self._mapping(0x1400 + n, 0x1600 + n)
            if m and self._has(0x1400 + n, 5):
                self.rpdo_deadlines[m[0]] = self._get(0x1400 + n, 5) / 1000
        self.tpdos = [m for m in (self._mapping(0x1800 + n, 0x1A00 + n) for n in range(4)) if m]
        for cob, _ in self.rpdos:
            self.network.subscribe(cob, self._on_rpdo)

    def _on_rpdo(self, can_id, data, timestamp):
        with self.lock:
            self.received[can_id] = bytes(data)
            if self.node.nmt.state == "OPERATIONAL":
                self.rpdo_seen[can_id] = time.monotonic()

    def _on_sync(self, can_id, data, timestamp):
        with self.lock:
            if self.node.nmt.state != "OPERATIONAL":
                return
            self.syncs += 1
            for cob, entries in self.rpdos:
                payload = self.received.get(cob)
                if payload is None or len(payload) != sum(size for _, _, size in entries):
                    continue
                at = 0
                for index, sub, size in entries:
                    self.node.data_store.setdefault(index, {})[sub] = payload[at:at + size]
                    at += size
                    if index == 0x607A:
                        self.targets.append((time.monotonic(), self._get(0x607A)))
            self._step()
            for cob, entries in self.tpdos:
                payload = b"".join(self.node.get_data(index, sub)[:size] for index, sub, size in entries)
                self.network.send_message(cob, payload)

    # ---- CiA 402 -----------------------------------------------------------------------------
    def _step(self):
        cw = self._get(0x6040)
        rising_reset = (cw & 0x80) != 0 and (self.previous_controlword & 0x80) == 0
        self.previous_controlword = cw
        requested = self._get(0x6060)
        self._set(0x6061, 0, requested if self.mode_follows else 0)
        s = self.state
        if s == "fault":
            if rising_reset:
                self.fault_resets += 1
                if self.reset_clears:
                    self._set(0x603F, 0, 0)
                    self.node.emcy.reset(0)
                    self._enter("switch on disabled")
            return
        if s == "fault reaction active":
            return self._enter("fault")
        if s == self.stuck_in and (cw & 0x02) != 0 and (cw & 0x06) != 0x02:
            return  # e.g. a brake that never reports released: disable and quick stop still act
        if (cw & 0x02) == 0:  # disable voltage: 7, 9, 10, 12
            if s != "not ready to switch on":
                self._enter("switch on disabled")
        elif (cw & 0x06) == 0x02:  # quick stop: 7, 10, 11
            if s == "operation enabled":
                self._enter("quick stop active")
            elif s in ("ready to switch on", "switched on"):
                self._enter("switch on disabled")
        elif (cw & 0x0F) == 0x06:  # shutdown: 2, 6, 8
            if s in ("switch on disabled", "switched on", "operation enabled"):
                self._enter("ready to switch on")
        elif (cw & 0x0F) == 0x07:  # switch on: 3, 5
            if s in ("ready to switch on", "operation enabled"):
                self._enter("switched on")
        elif (cw & 0x0F) == 0x0F:  # enable operation: 4 (3 and 4 at once from ready to switch on)
            if s in ("switched on", "ready to switch on"):
                self._enter("operation enabled")
        if self.state == "operation enabled":
            self.enabled_with_mode.add(self._get(0x6061))
            if self._get(0x6061) == 8:  # CSP: the position follows the target
                self._set(0x6064, 0, self._get(0x607A))

    def _fault(self, code, register, send=True):
        self._set(0x603F, 0, code)
        if send:
            self.node.emcy.send(code, register)
        self._enter("fault")

    def fault(self, code, register):
        """An error: EMCY with the code, then the drive in FAULT (0x603F holds the code)."""
        with self.lock:
            self._fault(code, register)

    def warn(self, code, register):
        """A warning: EMCY with the code, the drive goes on as it was."""
        with self.lock:
            self.node.emcy.send(code, register)
            self._note(f"warning {code:#06x}")

    def close(self):
        self._stop.set()
        self._watcher.join()
        self.node.nmt.stop_heartbeat()
