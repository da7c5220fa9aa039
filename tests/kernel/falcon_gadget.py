"""A Novint Falcon at the USB level, as a Linux USB gadget (configfs + FunctionFS on dummy_hcd).

Written from the public descriptions of the FTDI FT232 (the vendor control requests libftdi
sends; bulk IN packets led by two modem-status bytes) and of the Falcon (libnifalcon's wiki and
documentation: the firmware loader's handshake, the echoed upload, the 16-byte reports), not from
sawrt's driver, so that a misunderstanding in the driver does not cancel out here.

The device, 0403:cb48, one vendor interface with a bulk IN (0x81) and a bulk OUT (0x02) endpoint
of 64 bytes (full speed, as the FT232). Its behaviour follows the baud rate the host sets:
- a slow rate (9600 baud, the loader): `0a 43 0d` is answered `0a 44 2c 0d`;
- a middle rate (140000 baud, the upload): every byte is echoed;
- a fast rate (the packet protocol): each 16-byte command `<` 12 force nibbles, control, pad `>`
  (each value byte 'A' + a nibble) is answered with a report `<` 12 encoder nibbles, status, pad
  `>`, once a firmware was uploaded (before that nothing answers: a probe for a running firmware
  finds none). The encoders stay at 0; once the host has asked for homing mode for HOMING_REPORTS
  commands, the status says all three arms are homed.

It prints `ready` once bound, then one line per phase (each ending `at T`, T its CLOCK_MONOTONIC
seconds, the clock of saw-rt's log lines), a line `gap G s before T` when the host went G > 0.2 s
without a report while a firmware ran (a host that stopped asking, or a gadget starved), and on
SIGTERM or when the host goes away a last line `exchanges=N seconds=S rate=R firmware_bytes=B homed=0|1 homings=H` (homed: it ever
homed; an unplug takes the homing, as the firmware, away).
Needs root, configfs, usb_f_fs and dummy_hcd. Usage: falcon_gadget.py
"""

import os
import queue
import signal
import struct
import sys
import threading
import time

GADGET = "/sys/kernel/config/usb_gadget/sawfalcon"
FFS = "/dev/ffs-sawfalcon"
HOMING_REPORTS = 50
STATUS = bytes([0x01, 0x60])  # FT232 modem status: CTS/DSR-like bits, then line status (THRE, TEMT)

# FunctionFS (linux/usb/functionfs.h).
DESCRIPTORS_MAGIC_V2 = 3
STRINGS_MAGIC = 2
HAS_FS_DESC = 1
ALL_CTRL_RECIP = 64
EVENT_SETUP = 4
EVENT_UNBIND = 1
EVENT_DISABLE = 3

# FTDI SIO requests (bRequest of vendor requests, as libftdi names them).
SIO_RESET, SIO_MODEM_CTRL, SIO_SET_FLOW_CTRL, SIO_SET_BAUDRATE, SIO_SET_DATA = 0, 1, 2, 3, 4
SIO_POLL_MODEM_STATUS, SIO_SET_LATENCY_TIMER, SIO_GET_LATENCY_TIMER, SIO_SET_BITMODE = 5, 9, 10, 11


def say(text):
    print(f"{text} at {time.monotonic():.3f}", flush=True)


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def make_gadget():
    os.makedirs(GADGET, exist_ok=True)
    write(f"{GADGET}/idVendor", "0x0403")
    write(f"{GADGET}/idProduct", "0xcb48")
    write(f"{GADGET}/bcdDevice", "0x0600")
    os.makedirs(f"{GADGET}/strings/0x409", exist_ok=True)
    write(f"{GADGET}/strings/0x409/manufacturer", "Novint")
    write(f"{GADGET}/strings/0x409/product", "FALCON HAPTIC")
    write(f"{GADGET}/strings/0x409/serialnumber", "SAWGADGET1")
    os.makedirs(f"{GADGET}/configs/c.1", exist_ok=True)
    os.makedirs(f"{GADGET}/functions/ffs.sawfalcon", exist_ok=True)
    if not os.path.exists(f"{GADGET}/configs/c.1/ffs.sawfalcon"):
        os.symlink(f"{GADGET}/functions/ffs.sawfalcon", f"{GADGET}/configs/c.1/ffs.sawfalcon")
    os.makedirs(FFS, exist_ok=True)
    if not os.path.ismount(FFS):
        os.system(f"mount -t functionfs sawfalcon {FFS}")


def descriptors():
    interface = struct.pack("<BBBBBBBBB", 9, 4, 0, 0, 2, 0xFF, 0xFF, 0xFF, 0)
    ep_in = struct.pack("<BBBBHB", 7, 5, 0x81, 2, 64, 0)
    ep_out = struct.pack("<BBBBHB", 7, 5, 0x02, 2, 64, 0)
    body = struct.pack("<I", 3) + interface + ep_in + ep_out  # fs_count, then the FS descriptors
    flags = HAS_FS_DESC | ALL_CTRL_RECIP
    return struct.pack("<III", DESCRIPTORS_MAGIC_V2, 12 + len(body), flags) + body


def strings():
    return struct.pack("<IIII", STRINGS_MAGIC, 16, 0, 0)


class Falcon:
    def __init__(self):
        self.mode = "loader"
        self.rx = bytearray()
        self.tx = queue.Queue()
        self.exchanges = 0
        self.first = None
        self.last = None
        self.prev = None  # the last report since the last plug-in
        self.firmware_bytes = 0
        self.loaded = False  # a firmware runs: uploaded, then the host switched to packet speed
        self.homing_commands = 0
        self.homed = False
        self.homings = 0  # times homed, across unplugs
        self.lock = threading.Lock()

    def unplugged(self):
        with self.lock:
            self.mode, self.loaded, self.homed, self.homing_commands = "loader", False, False, 0
            self.prev = None  # no gap counted across the unplug
            self.rx.clear()
        self.purge()

    def baud(self, divisor):
        # FT232 rates: 3 MHz / divisor (the low 14 bits; the top bits are eighths).
        whole = divisor & 0x3FFF
        mode = "loader" if whole >= 100 else "upload" if whole >= 10 else "packet"
        with self.lock:
            if mode != self.mode:
                say(f"mode {mode} (divisor {whole})")
            if self.mode == "upload" and mode == "packet" and self.firmware_bytes > 0:
                self.loaded = True
            self.mode = mode
            self.rx.clear()

    def purge(self):
        with self.lock:
            self.rx.clear()
        while not self.tx.empty():
            self.tx.get_nowait()

    def received(self, data):
        with self.lock:
            if self.mode == "upload":
                self.firmware_bytes += len(data)
                self.tx.put(bytes(data))
                return
            self.rx += data
            if self.mode == "loader":
                i = self.rx.find(b"\x0a\x43\x0d")
                if i >= 0:
                    say("loader handshake")
                    self.tx.put(b"\x0a\x44\x2c\x0d")
                    del self.rx[: i + 3]
                return
            if not self.loaded:
                # Powered up, no firmware yet: nothing speaks the report protocol (a host that
                # probes for a running firmware gets no answer, and must upload it).
                self.rx.clear()
                return
            while True:
                start = self.rx.find(b"<")
                if start < 0:
                    self.rx.clear()
                    return
                del self.rx[:start]
                if len(self.rx) < 16:
                    return
                command = bytes(self.rx[:16])
                del self.rx[:16]
                if command[15:16] != b">":
                    continue
                self.tx.put(self.report(command))

    def report(self, command):
        control = (command[13] - 0x41) & 0x0F
        if control & 1:
            self.homing_commands += 1
            if self.homing_commands >= HOMING_REPORTS and not self.homed:
                self.homed = True
                self.homings += 1
                say(f"homed after {self.homing_commands} homing commands")
        now = time.monotonic()
        if self.prev is not None and now - self.prev > 0.2:
            say(f"gap {now - self.prev:.3f} s before")
        self.prev = now
        self.first = self.first or now
        self.last = now
        self.exchanges += 1
        status = (7 << 4) if self.homed else 0
        body = bytes([0x41] * 12) + bytes([0x41 + status, 0x41])
        return b"<" + body + b">"


def serve():
    falcon = Falcon()
    stop = threading.Event()
    make_gadget()
    ep0 = os.open(f"{FFS}/ep0", os.O_RDWR)
    os.write(ep0, descriptors())
    os.write(ep0, strings())
    ep_in = os.open(f"{FFS}/ep1", os.O_RDWR)
    ep_out = os.open(f"{FFS}/ep2", os.O_RDWR)
    write(f"{GADGET}/UDC", "dummy_udc.0")
    print("ready", flush=True)

    def in_loop():
        while not stop.is_set():
            try:
                data = falcon.tx.get(timeout=0.002)
                while len(data) < 62 and not falcon.tx.empty():
                    data += falcon.tx.get_nowait()
            except queue.Empty:
                data = b""
            try:
                for i in range(0, max(len(data), 1), 62):
                    os.write(ep_in, STATUS + data[i:i + 62])
            except OSError:
                if stop.is_set():
                    return
                time.sleep(0.01)  # not enabled yet, or gone: the ep0 loop decides

    def out_loop():
        while not stop.is_set():
            try:
                data = os.read(ep_out, 64)  # one packet: a read of more waits for a short packet
            except OSError:
                if stop.is_set():
                    return
                time.sleep(0.01)
                continue
            falcon.received(data)

    threading.Thread(target=in_loop, daemon=True).start()
    threading.Thread(target=out_loop, daemon=True).start()

    def finish(*_):
        stop.set()
        seconds = (falcon.last or 0) - (falcon.first or 0)
        rate = falcon.exchanges / seconds if seconds > 0 else 0
        print(f"exchanges={falcon.exchanges} seconds={seconds:.2f} rate={rate:.0f} "
              f"firmware_bytes={falcon.firmware_bytes} homed={int(falcon.homings > 0)} homings={falcon.homings}", flush=True)
        os._exit(0)

    signal.signal(signal.SIGTERM, finish)
    while True:
        event = os.read(ep0, 12)
        if len(event) < 12:
            continue
        request_type, request, value, index, length, kind = struct.unpack("<BBHHHB3x", event)
        if kind == EVENT_UNBIND:
            # Unplugged: the Falcon's controller loses its firmware and its homing (a replug
            # finds the loader again and must upload and home anew).
            say("unbound")
            falcon.unplugged()
        if kind != EVENT_SETUP:
            continue
        if request_type & 0x80:  # device to host
            if request == SIO_POLL_MODEM_STATUS:
                reply = STATUS
            elif request == SIO_GET_LATENCY_TIMER:
                reply = bytes([1])
            else:
                reply = bytes(length)
            os.write(ep0, reply[:length])
            continue
        if length:
            os.read(ep0, length)
        else:
            os.read(ep0, 0)  # the status stage: acknowledge
        if request_type & 0x60 != 0x40:
            continue
        if request == SIO_SET_BAUDRATE:
            falcon.baud(value)
        elif request == SIO_RESET and value in (1, 2):
            falcon.purge()


if __name__ == "__main__":
    serve()
