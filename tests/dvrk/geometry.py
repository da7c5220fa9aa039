"""Small vector and quaternion helpers of the simulated dVRK arm (tuples; quaternions as x, y, z, w)."""
import math

def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def scale(a, s):
    return tuple(x * s for x in a)


def norm(a):
    return math.sqrt(sum(x * x for x in a))


def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def qconj(q):
    return (-q[0], -q[1], -q[2], q[3])


def qnormalize(q):
    n = norm(q)
    return (0.0, 0.0, 0.0, 1.0) if n == 0.0 else scale(q, 1.0 / n)


def rotate(q, v):
    x, y, z, _ = qmul(qmul(q, (v[0], v[1], v[2], 0.0)), qconj(q))
    return (x, y, z)


def to_rotvec(q):
    q = qnormalize(q)
    if q[3] < 0.0:
        q = scale(q, -1.0)
    s = norm(q[:3])
    if s < 1e-12:
        return (0.0, 0.0, 0.0)
    angle = 2.0 * math.atan2(s, q[3])
    return scale(q[:3], angle / s)


def from_rotvec(r):
    angle = norm(r)
    if angle < 1e-12:
        return (0.0, 0.0, 0.0, 1.0)
    s = math.sin(angle / 2.0) / angle
    return (r[0] * s, r[1] * s, r[2] * s, math.cos(angle / 2.0))


def qangle(a, b):
    """The rotation angle from a to b (rad, 0..pi)."""
    d = abs(sum(x * y for x, y in zip(a, b)))
    return 2.0 * math.acos(min(1.0, d))


def slerp(a, b, s):
    if sum(x * y for x, y in zip(a, b)) < 0.0:
        b = scale(b, -1.0)  # the short way round
    rel = to_rotvec(qmul(qconj(a), b))
    return qnormalize(qmul(a, from_rotvec(scale(rel, s))))


def finite(*values):
    return all(math.isfinite(v) for v in values)
