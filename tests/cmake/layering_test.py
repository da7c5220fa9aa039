"""The layering check (cmake/SawLayering.cmake) works by rule: on a fixture tree laid out as
sawrt's (tests/cmake/layering), a clean tree configures, and each forbidden link fails the
configure step with a message naming it — added in a folder the check names nowhere, through an
alias, behind $<LINK_ONLY:>, or two links away; the gateway, a host with a package of its own
beside it, still may not link a package; a package may build on another's library.

Usage: layering_test.py <cmake/SawLayering.cmake>
"""

import os
import subprocess
import sys
import tempfile

LAYERING = os.path.abspath(sys.argv[1])
FIXTURE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "layering")

# case -> the text its failure must show (None: it must configure)
CASES = {
    "clean": None,
    "rt_links_drivers": "layering: host (rt/host/) links dev (drivers/dev/): rt/ may link only rt/ (host -> dev)",
    "host_links_package": "layering: host (rt/host/) links pkg of the package in rt/pkg/: the framework loads a package, it does not link it (host -> pkg)",
    "transitive": "layering: host (rt/host/) links shm (bridge/): rt/ may link only rt/ (host -> core -> shm)",
    "gateway_links_a_package": "layering: gw (nonrt/gw/) links dev_lib of the package in nonrt/dev_dds/",
    "unknown_folder": "layering: stray is in other/, which no layer names",
}

failed = []
with tempfile.TemporaryDirectory(prefix="sawlayering") as tmp:
    for case, expected in CASES.items():
        r = subprocess.run(["cmake", "-S", FIXTURE, "-B", os.path.join(tmp, case), f"-DSAW_CASE={case}",
                            f"-DSAW_LAYERING={LAYERING}"], capture_output=True, text=True)
        text = " ".join((r.stdout + r.stderr).split())  # CMake wraps its messages
        if expected is None:
            ok = r.returncode == 0 and "layering: 15 targets checked" in text
            print(f"{'ok' if ok else 'FAIL'}: {case}: configures, every target checked")
        else:
            ok = r.returncode != 0 and expected in text
            print(f"{'ok' if ok else 'FAIL'}: {case}: the configure step fails saying \"{expected}\"")
        if not ok:
            print(r.stdout[-2000:], r.stderr[-2000:], sep="\n")
            failed.append(case)
sys.exit(1 if failed else 0)
