"""The docs' lists that the tree can derive, checked against the tree: the CMake package's
components (docs/architecture.md, every saw_library's COMPONENT) and the device conformance rigs
(docs/extending.md, every tests/device/*_rig.cpp). Each list sits after a marker comment
(`<!-- components: ...`, `<!-- rigs: ...`) and ends at the first name followed by ';' or '.'.
And each package README's table of headers (rows `| \`name.hpp\` |`): the headers of the
package's include/ folder, no more and no fewer. And the types the gateway and its mapping
modules map (every `registry.add<T, ...>` and `add_fields<T, ...>` under nonrt/): each named in
the paragraph after `<!-- mapped types:` (docs/architecture.md), which also names the DDS types
they map to.

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


def mentioned(doc, marker):
    """The backquoted names in the paragraph after `<!-- marker:` (to the next list item or blank line)."""
    text = open(doc).read()
    at = text.find(f"<!-- {marker}:")
    if at < 0:
        raise SystemExit(f"{doc}: no '<!-- {marker}:' marker")
    body = re.split(r"\n(?:- |\s*\n)", text[text.index("-->", at) + 3:], maxsplit=1)[0]
    return set(re.findall(r"`([A-Za-z0-9_:]+)`", body))


def mapped_types(root):
    """The rt types registered with a DDS mapping in nonrt/ (std::int64_t as the docs say it: int64)."""
    found = set()
    for path in glob.glob(os.path.join(root, "nonrt", "**", "*.cpp"), recursive=True):
        found |= set(re.findall(r"\badd(?:_fields)?<\s*([A-Za-z0-9_:]+)\s*,", open(path).read()))
    return {"int64" if t == "std::int64_t" else t for t in found}


def components(root):
    found = set()
    for d in ("rt", "bridge", "nonrt", "drivers"):
        for path in glob.glob(os.path.join(root, d, "**", "CMakeLists.txt"), recursive=True):
            found |= set(re.findall(r"saw_library\(\s*\S+\s+COMPONENT\s+(\w+)", open(path).read()))
    return found


def header_tables(root):
    """(README, the headers its table lists, the headers of its package's include/) for each package README with one."""
    for readme in sorted(glob.glob(os.path.join(root, "drivers", "*", "README.md"))):
        says = set(re.findall(r"^\| `([A-Za-z0-9_]+\.hpp)` \|", open(readme).read(), re.M))
        if not says:
            continue
        include = os.path.join(os.path.dirname(readme), "include")
        truth = {os.path.basename(p) for p in glob.glob(os.path.join(include, "**", "*.hpp"), recursive=True)
                 if "/detail/" not in p}
        yield os.path.relpath(readme, root), says, truth


def main(root):
    failures = 0
    for readme, says, truth in header_tables(root):
        ok = says == truth
        failures += not ok
        print(("ok   " if ok else "FAIL ") + f"{readme} lists the {len(truth)} headers of its include/"
              + ("" if ok else f": missing {sorted(truth - says)}, not in the tree {sorted(says - truth)}"))
    for doc, marker, truth in (
            ("docs/architecture.md", "components", components(root)),
            ("docs/extending.md", "rigs",
             {os.path.basename(p) for p in glob.glob(os.path.join(root, "tests", "device", "*_rig.cpp"))})):
        says = listed(os.path.join(root, doc), marker)
        ok = says == truth
        failures += not ok
        print(("ok   " if ok else "FAIL ") + f"{doc} lists the {marker} of the tree"
              + ("" if ok else f": missing {sorted(truth - says)}, not in the tree {sorted(says - truth)}"))
    types = mapped_types(root)
    missing = types - mentioned(os.path.join(root, "docs/architecture.md"), "mapped types")
    failures += bool(missing) or not types
    print(("FAIL " if missing or not types else "ok   ") + f"docs/architecture.md names the {len(types)} mapped types"
          + (f": missing {sorted(missing)}" if missing else ""))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
