"""A package's sources laid out by layer include nothing of a layer above their own.

A package opts in with `src/LAYERS`: its layers bottom to top, one folder of src/ each
(drivers/canopen: protocol, bus, node, devices). A file's layer is its folder; a public header's
is the folder of the source file of the same name, or the one `src/LAYERS` names for it
(`header.hpp: layer`, for a header with no source of its own). A file of a layer includes
headers of its layer and those below, transitively through the headers; a header in no layer
fails, so that a new one is placed when it is added.

usage: package_layers_test.py SOURCE_DIR
"""
import glob
import os
import re
import sys


def read_layers(path):
    order, placed = [], {}
    for line in open(path):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        if ":" in line:
            header, layer = (s.strip() for s in line.split(":", 1))
            placed[header] = layer
        else:
            order.append(line)
    return order, placed


def check(package):
    order, placed = read_layers(os.path.join(package, "src", "LAYERS"))
    failures = []
    layer_of = dict(placed)
    for path in glob.glob(os.path.join(package, "src", "*", "*.cpp")):
        layer_of.setdefault(os.path.basename(path)[:-4] + ".hpp", os.path.basename(os.path.dirname(path)))
    headers = {os.path.basename(p): p for p in glob.glob(os.path.join(package, "include", "**", "*.hpp"),
                                                           recursive=True)}
    for h in sorted(headers):
        if h not in layer_of or layer_of[h] not in order:
            failures.append(f"{os.path.relpath(headers[h])}: in no layer (give it a source file in a layer's "
                            f"folder, or a line 'header.hpp: layer' in src/LAYERS)")
    prefix = os.path.relpath(os.path.commonpath(list(headers.values())), os.path.join(package, "include"))
    include = re.compile(r'#include "' + re.escape(prefix) + r'/([A-Za-z0-9_]+\.hpp)"')

    def reached(path, seen):
        for h in include.findall(open(path).read()):
            if h in headers and h not in seen:
                seen.add(h)
                reached(headers[h], seen)
        return seen

    files = [(p, os.path.basename(os.path.dirname(p))) for p in glob.glob(os.path.join(package, "src", "*", "*.[ch]pp"))]
    files += [(p, layer_of.get(h)) for h, p in headers.items()]
    for path, layer in files:
        if layer not in order:
            continue
        for h in sorted(reached(path, set())):
            above = layer_of.get(h)
            if above in order and order.index(above) > order.index(layer):
                failures.append(f"{os.path.relpath(path)} ({layer}) reaches {h} ({above})")
    return order, failures


def main(root):
    packages = sorted(os.path.dirname(os.path.dirname(p)) for p in glob.glob(os.path.join(root, "*", "*", "src", "LAYERS")))
    if not packages:
        print("FAIL no package has a src/LAYERS")
        return 1
    bad = 0
    for package in packages:
        order, failures = check(package)
        for f in failures:
            print("FAIL " + f)
        bad += bool(failures)
        print(("FAIL " if failures else "ok   ") + f"{os.path.relpath(package, root)}: {' < '.join(order)}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
