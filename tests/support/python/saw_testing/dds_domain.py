"""DDS domains for tests and benchmarks: each process gets a domain that no other running test or
benchmark on this host holds, so `sawctl list` or a participant count sees only its own entities.

A domain is claimed by an exclusive, non-blocking flock(2) on the lock file DIR/<id>
(/tmp/sawrt-test-domains, or $SAW_TEST_DOMAIN_DIR). The kernel releases the lock when the last
descriptor of that open file closes, so a killed claimer never leaks its domain, and nothing of
a claim outlives its process (a process id is reused over a CI run; a lock is not). The same
protocol is implemented in C++ (tests/support/include/saw/testing/dds_domain.hpp): a C++ test and
a Python test never hold the same domain.

Ids are tried in a random order, over the pool: 1-228 (the valid range for Fast DDS's default
ports is 0-232; a default keystore's governance covers 0-230) less the ids the repository uses as
fixed defaults (RESERVED). A test that needs one particular id claims it with claim_fixed().

As a command (for shell scripts): `dds_domain.py --exec CMD [ARG...]` runs CMD with the claim's
descriptor inherited and $SAW_TEST_DOMAIN set, so CMD (and what it starts) holds the domain for
its lifetime; `dds_domain.py [--dir D] [--ids 5,6] --hold` claims, prints the id, and holds it
until its standard input closes (the allocator's own tests use it as a claimer in another
process)."""
import errno
import fcntl
import os
import random
import stat
import sys
import time

DEFAULT_DIR = "/tmp/sawrt-test-domains"
# Ids the repository uses as fixed defaults: never given out.
RESERVED = {
    0: "every tool's default domain (saw-gateway, sawctl, sawgui; tools/run.sh --gui)",
    3: "docs/gui.md's example, the fuzz corpus' deployments",
    7: "docs/security.md's example; tests/security/sros2_enroll.py's refused domain",
    42: "examples/lab_message's deployment",
    229: "tests/python's headless sawgui (claimed there with claim_fixed)",
}
POOL = tuple(d for d in range(1, 229) if d not in RESERVED)


def lock_dir():
    return os.environ.get("SAW_TEST_DOMAIN_DIR") or DEFAULT_DIR


class Claim:
    """A DDS domain held through the flock on its lock file: until release(), or the process's end."""

    def __init__(self, domain: int, fd: int):
        self.domain = domain
        self.fd = fd

    def release(self):
        if self.fd >= 0:
            os.close(self.fd)  # closing the only descriptor drops the lock
            self.fd = -1

    def __repr__(self):
        return f"Claim(domain={self.domain})"


def _open_lock_file(directory: str, domain: int) -> int:
    """The lock file of `domain`, opened read-only (flock needs no more), created if missing.

    An existing file is opened without O_CREAT: in a sticky, world-writable directory the kernel
    (fs.protected_regular) refuses O_CREAT on a file another user owns, even when it exists."""
    path = os.path.join(directory, str(domain))
    while True:
        try:
            return os.open(path, os.O_RDONLY | os.O_CLOEXEC)
        except FileNotFoundError:
            pass
        try:
            fd = os.open(path, os.O_RDONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o644)
        except FileExistsError:
            continue  # another claimer made it in between: open theirs
        os.fchmod(fd, 0o644)  # whatever the umask: other users open it to lock it
        return fd


def _ensure_dir(directory: str):
    """The shared directory: made world-writable and sticky by whoever makes it first."""
    try:
        os.mkdir(directory, 0o777)
    except FileExistsError:
        return
    try:
        os.chmod(directory, 0o777 | stat.S_ISVTX)  # mkdir's mode passed through the umask
    except PermissionError:
        pass  # made by someone else in between: theirs is right


def _try_lock(directory: str, domain: int):
    fd = _open_lock_file(directory, domain)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as e:
        os.close(fd)
        if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
            return None
        raise
    return Claim(domain, fd)


def claim(pool=POOL, directory=None) -> Claim:
    """A domain of `pool` that nobody holds, tried in a random order; RuntimeError if none is free."""
    directory = directory or lock_dir()
    _ensure_dir(directory)
    order = list(pool)
    random.SystemRandom().shuffle(order)
    for domain in order:
        c = _try_lock(directory, domain)
        if c is not None:
            return c
    raise RuntimeError(f"no free DDS domain: all {len(order)} of the pool are held (lock files in {directory})")


def claim_fixed(domain: int, timeout: float = 60.0, directory=None) -> Claim:
    """`domain` itself, for a test that needs that id: waits up to `timeout` s for its holder to
    end (RuntimeError after, naming the lock file)."""
    directory = directory or lock_dir()
    _ensure_dir(directory)
    deadline = time.monotonic() + timeout
    while True:
        c = _try_lock(directory, domain)
        if c is not None:
            return c
        if time.monotonic() >= deadline:
            raise RuntimeError(f"DDS domain {domain} still held after {timeout} s "
                               f"({os.path.join(directory, str(domain))})")
        time.sleep(0.05)


_process_claim = None


def dds_domain() -> int:
    """This process's DDS domain: claimed on the first call, held until the process ends."""
    global _process_claim
    if _process_claim is None:
        _process_claim = claim()
    return _process_claim.domain


def _main(argv):
    directory, pool = None, POOL
    while argv and argv[0] in ("--dir", "--ids"):
        if len(argv) < 2:
            break
        if argv[0] == "--dir":
            directory = argv[1]
        else:
            pool = tuple(int(i) for i in argv[1].split(","))
        argv = argv[2:]
    if argv[:1] == ["--hold"] and len(argv) == 1:
        try:
            c = claim(pool, directory)
        except RuntimeError as e:
            print(f"dds_domain: {e}", file=sys.stderr)
            return 1
        print(c.domain, flush=True)
        sys.stdin.read()  # until the other end closes: then the lock goes with this process
        return 0
    if argv[:1] == ["--exec"] and len(argv) > 1:
        c = claim(pool, directory)
        os.set_inheritable(c.fd, True)
        os.environ["SAW_TEST_DOMAIN"] = str(c.domain)
        os.execvp(argv[1], argv[1:])
    print("usage: dds_domain.py [--dir DIR] [--ids A,B,...] --hold | --exec CMD [ARG...]", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
