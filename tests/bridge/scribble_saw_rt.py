"""Black box: random 8-byte words at random offsets of a running saw-rt's exported segment.

saw-rt runs config/teleop-sim-master.yaml (the master device, exported; renamed for this run so
that another suite on the host, which shares /dev/shm, cannot hold its segment); this
process maps the segment read-write, as any local process may, and writes about 2,000 random
words a second over all of it for 10 s. saw-rt must survive (exit 0, not SIGSEGV as it did when
the server re-read its layout from the segment) and its device task must keep cycling.
Usage: scribble_saw_rt.py SAW_RT CONFIG"""
import mmap
import os
import random
import re
import subprocess
import sys
import tempfile
import time

saw_rt, shipped = sys.argv[1], sys.argv[2]
name = f"scr{os.getpid()}"
with open(shipped) as f:
    text = f.read()
if text.count("name: master") != 1 or text.count("component: master") != 1:
    sys.exit("the deployment file changed: this test's renaming no longer applies")
with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
    f.write(text.replace("name: master", f"name: {name}").replace("component: master", f"component: {name}"))
    config = f.name
segment = f"/dev/shm/saw.{name}"
rt = subprocess.Popen([saw_rt, config, "--duration", "14"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                      text=True)
deadline = time.monotonic() + 10
while not os.path.exists(segment) and rt.poll() is None and time.monotonic() < deadline:
    time.sleep(0.01)
if not os.path.exists(segment):
    rt.kill()
    print(rt.communicate()[0])
    sys.exit(f"saw-rt did not export {segment}")
time.sleep(0.5)  # let it run a while before the first word

rng = random.Random(20261123)
written = 0
with open(segment, "r+b") as f:
    m = mmap.mmap(f.fileno(), 0)
    words = len(m) // 8
    end = time.monotonic() + 10
    while time.monotonic() < end and rt.poll() is None:
        for _ in range(20):
            at = rng.randrange(words) * 8
            m[at:at + 8] = rng.getrandbits(64).to_bytes(8, "little")
            written += 1
        time.sleep(0.01)
    m.close()
out = rt.communicate(timeout=30)[0]
os.unlink(config)
print(out)
print(f"scribble: {written} random words written over {words * 8} bytes in 10 s")
if rt.returncode != 0:
    sys.exit(f"saw-rt exited with {rt.returncode} under the scribbler")
row = re.search(rf"^\s*{name}\s+\S+\s+(\d+)", out, re.M)
if row is None or int(row.group(1)) < 5000:
    sys.exit("the master task did not keep cycling (summary row: %s)" % (row.group(0) if row else "none"))
print("ok: saw-rt survived and its device task cycled", row.group(1), "times")
