"""The docs' lists that the tree can derive, checked against the tree: the CMake package's
components (docs/architecture.md, every saw_library's COMPONENT) and the device conformance rigs
(docs/extending.md, every tests/device/*_rig.cpp). Each list sits after a marker comment
(`<!-- components: ...`, `<!-- rigs: ...`) and ends at the first name followed by ';' or '.'.

usage: docs_lists_test.py SOURCE_DIR
"""
import glob
import os
import re
import sys


def listed(doc, marker):
    """The backquoted names after `<!-- marker:` up to the sentence's end."""
    text = open(doc).read()
    at = text.find(f"<!-- {marker}:")
    if at < 0:
        raise SystemExit(f"{doc}: no '<!-- {marker}:' marker")
    body = text[text.index("-->", at) + 3:]
    end = re.search(r"`[;.]", body)
    body = body[:end.end() if end else len(body)]
    return {n.replace("sawrt::", "") for n in re.findall(r"`([A-Za-z0-9_:.]+)`", body)}


def components(root):
    found = set()
    for d in ("rt", "bridge", "nonrt", "drivers"):
        for path in glob.glob(os.path.join(root, d, "**", "CMakeLists.txt"), recursive=True):
            found |= set(re.findall(r"saw_library\(\s*\S+\s+COMPONENT\s+(\w+)", open(path).read()))
    return found


def main(root):
    failures = 0
    for doc, marker, truth in (
            ("docs/architecture.md", "components", components(root)),
            ("docs/extending.md", "rigs",
             {os.path.basename(p) for p in glob.glob(os.path.join(root, "tests", "device", "*_rig.cpp"))})):
        says = listed(os.path.join(root, doc), marker)
        ok = says == truth
        failures += not ok
        print(("ok   " if ok else "FAIL ") + f"{doc} lists the {marker} of the tree"
              + ("" if ok else f": missing {sorted(truth - says)}, not in the tree {sorted(says - truth)}"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
