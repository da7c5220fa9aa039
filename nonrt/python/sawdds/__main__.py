"""usage: sawdds list | echo TOPIC [N] | state-command TOPIC CMD   (or python -m sawdds ...)"""
import sys

from . import msgs
from .client import Client


def main(argv=None):
    # The console script calls main() bare: its arguments are in sys.argv.
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0
    if not argv or argv[0] not in ("list", "echo", "state-command"):
        print(__doc__)
        return 2
    c = Client()
    if argv[0] == "list":
        for name, m in sorted(c.manifests().items()):
            print(f"{name} on {m.host} (pid {m.pid}): {m.state}")
            for e in m.endpoints:
                print(f"  {e.kind:15} {e.component_name}.{e.name:20} {(e.saw_type + ' v' + str(e.saw_version)) if e.saw_type else '':28} {e.topic or '(not mapped)'}")
    elif argv[0] == "echo":
        for _ in range(int(argv[2]) if len(argv) > 2 else 1):
            print(c.read(argv[1]))
    else:
        c.send(argv[1], msgs.StringStamped(string=argv[2]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
