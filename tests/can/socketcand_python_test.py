"""saw-socketcand against python-can's socketcand interface, with real processes.

saw-socketcand serves a virtual bus on 127.0.0.1; python-can clients connect to it; saw-cansend
and saw-candump stand for the C++ side of the bus. Checks: frames both ways arrive intact, a
client does not get its own frames back but another client does, bad lines are answered with
`< error ... >` and never end the server, and --log holds every frame as a candump -L line.

Usage: socketcand_python_test.py <saw-socketcand> <saw-cansend> <saw-candump>
"""

import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time

import can

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from child_tools import check, fail, read_line, start_socketcand  # noqa: E402

SERVER, CANSEND, CANDUMP = sys.argv[1:4]
BUS = f"sawcanpy{os.getpid()}"
LOG_LINE = re.compile(r"^\((\d+)\.(\d{6})\) (\S+) ([0-9A-F]{3}|[0-9A-F]{8})#([0-9A-F]*)$")


def start_server(log_path):
    return start_socketcand(SERVER, BUS, "--log", log_path)


def client(port):
    return can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel=BUS)


def receive(bus, count, timeout=10):
    got, deadline = [], time.monotonic() + timeout
    while len(got) < count and time.monotonic() < deadline:
        m = bus.recv(timeout=0.2)
        if m is not None:
            got.append(m)
    check(len(got) == count, f"expected {count} frames, got {len(got)}: {got}")
    return got


def same(message, arbitration_id, extended, data):
    return (
        message.arbitration_id == arbitration_id
        and message.is_extended_id == extended
        and bytes(message.data) == bytes(data)
    )


def cpp_to_python(port):
    bus = client(port)
    sent = [
        ("123#DEADBEEF", 0x123, False, b"\xde\xad\xbe\xef"),
        ("1ABCDEF0#0102030405060708", 0x1ABCDEF0, True, bytes(range(1, 9))),
        ("7FF#", 0x7FF, False, b""),
        ("000#00", 0x000, False, b"\x00"),
    ]
    subprocess.run([CANSEND, f"virtual:{BUS}", *[s[0] for s in sent]], check=True)
    got = receive(bus, len(sent))
    for message, (text, arbitration_id, extended, data) in zip(got, sent):
        check(same(message, arbitration_id, extended, data), f"sent {text}, python-can got {message}")
        check(abs(message.timestamp - time.time()) < 60, f"time stamp {message.timestamp} is not wall-clock time")
    bus.shutdown()
    return [s[0] for s in sent]


def python_to_cpp(port):
    dump = subprocess.Popen(
        [CANDUMP, f"virtual:{BUS}", "-n", "3", "--timeout", "30"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    read_line(dump.stderr, 10, "'listening' line from saw-candump")
    bus = client(port)
    messages = [
        can.Message(arbitration_id=0x42, data=[1, 2, 3], is_extended_id=False),
        can.Message(arbitration_id=0x1234567, data=[], is_extended_id=True),
        can.Message(arbitration_id=0x7FF, data=[0xFF] * 8, is_extended_id=False),
    ]
    for m in messages:
        bus.send(m)
    out, err = dump.communicate(timeout=40)
    bus.shutdown()
    check(dump.returncode == 0, f"saw-candump: status {dump.returncode}: {err.decode()}")
    lines = out.decode().splitlines()
    expected = ["042#010203", "01234567#", "7FF#FFFFFFFFFFFFFFFF"]
    check(len(lines) == 3, f"saw-candump printed {lines}")
    for line, frame in zip(lines, expected):
        match = LOG_LINE.match(line)
        check(match is not None and match.group(3) == BUS, f"not a candump -L line of {BUS}: {line!r}")
        check(f"{match.group(4)}#{match.group(5)}" == frame, f"python-can sent {frame}, saw-candump saw {line!r}")
    return expected


def between_clients(port):
    a, b = client(port), client(port)
    time.sleep(0.2)  # both past the handshake's quiet time
    a.send(can.Message(arbitration_id=0x321, data=b"\x0a\x0b", is_extended_id=False))
    got = receive(b, 1)[0]
    check(same(got, 0x321, False, b"\x0a\x0b"), f"client b got {got}")
    check(a.recv(timeout=0.3) is None, "a client got its own frame back")
    a.shutdown()
    b.shutdown()
    return ["321#0A0B"]


def talk(sock, line):
    sock.sendall(line.encode())
    time.sleep(0.05)
    return sock.recv(4096).decode()


def bad_lines(port, server):
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        check(s.recv(64).decode() == "< hi >", "no '< hi >'")
        check(talk(s, "< send 123 1 11 >").startswith("< error "), "send before open was not an error")
        check(talk(s, f"< open {BUS} >") == "< ok >", "open failed")
        for bad in [
            "< send 800 1 11 >",  # 12-bit identifier
            "< send 123 3 11 22 >",  # length 3, two bytes
            "< send 123 1 zz >",
            "< frobnicate >",
            "< add 1 0 123 1 11 >",
            "junk outside",
            "< \x01 >",
            "<" + "x" * 2000 + ">",
        ]:
            reply = talk(s, bad)
            check(reply.startswith("< error ") and reply.endswith(" >"), f"{bad[:40]!r} got {reply!r}")
        check(talk(s, "< echo >") == "< echo >", "the connection did not survive the bad lines")
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        check(s.recv(64).decode() == "< hi >", "no '< hi >'")
        reply = talk(s, "< open nosuchbus >")
        check(reply.startswith("< error "), f"opening an unknown bus: {reply!r}")
        check(s.recv(64) == b"", "the connection stayed open after opening an unknown bus")
    check(server.poll() is None, "saw-socketcand ended")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        log_path = os.path.join(tmp, "traffic.log")
        server, port = start_server(log_path)
        try:
            logged = cpp_to_python(port) + python_to_cpp(port) + between_clients(port)
            bad_lines(port, server)
        finally:
            server.send_signal(signal.SIGTERM)
            try:
                server.wait(timeout=10)
            except subprocess.TimeoutExpired:
                server.kill()
                fail("saw-socketcand did not stop on SIGTERM")
            try:
                os.unlink(f"/dev/shm/saw-can.{BUS}")
            except FileNotFoundError:
                pass
        check(server.returncode == 0, f"saw-socketcand: status {server.returncode}")
        with open(log_path) as f:
            lines = f.read().splitlines()
        frames = []
        for line in lines:
            match = LOG_LINE.match(line)
            check(match is not None and match.group(3) == BUS, f"not a candump -L line: {line!r}")
            frames.append(f"{match.group(4)}#{match.group(5)}")
        check(frames == logged, f"the log holds {frames}, the bus carried {logged}")
    print("ok: frames both ways, between clients, bad lines answered, traffic logged")


if __name__ == "__main__":
    main()
