"""usage: sawdds [--enclave DIR] list | echo TOPIC [N] | state-command TOPIC CMD   (or python -m sawdds ...)

--enclave DIR (KEYSTORE/enclaves/NAME), or ROS 2's ROS_SECURITY_ENABLE=true, ROS_SECURITY_KEYSTORE and
ROS_SECURITY_ENCLAVE_OVERRIDE: DDS Security with that enclave; an enclave that cannot be used is refused
with the reason (exit 1), never a plaintext participant."""
import os
import sys

from . import msgs
from .client import Client
from .security import SecurityError, check_enclave, secure_uri


def main(argv=None):
    # The console script calls main() bare: its arguments are in sys.argv.
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0
    enclave = None
    if argv and argv[0] == "--enclave":
        if len(argv) < 2:
            print(__doc__)
            return 2
        enclave, argv = argv[1], argv[2:]
    if not argv or argv[0] not in ("list", "echo", "state-command"):
        print(__doc__)
        return 2
    try:
        if enclave is not None:
            check_enclave(enclave, domain=0)  # named as given, as sawctl names it; Client() is in domain 0
            os.environ["CYCLONEDDS_URI"] = secure_uri(os.environ["CYCLONEDDS_URI"], os.path.abspath(enclave))
        c = Client()
    except SecurityError as e:
        print(f"sawdds: {e}", file=sys.stderr)
        return 1
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
