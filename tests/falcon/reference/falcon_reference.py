#!/usr/bin/env python3
"""Independent reference model of the Novint Falcon, after libnifalcon.

Written from the *equations and constants* of libnifalcon (https://github.com/libnifalcon/libnifalcon,
branch master, commit f7c727aa24403ea10dc1507d7d396eeb7d55564a, 2019-05-10), NOT from sawrt's driver
and without copying libnifalcon code.  Plain Python 3 (math only), so it runs on any python3.

Model (libnifalcon's "Stamper" kinematics, src/kinematic/FalconKinematicStamper.cpp, itself after
R.E. Stamper's thesis, papers/REStamper-AThreeDOFParallelManipulatorWithOnlyTranslationalDOFs.pdf):

  World frame (libnifalcon's): z along the delta's axis, from the motor plane (z = 0) towards the
  user/grip; arm 1 at the top, arms numbered clockwise seen from the front.  Metres.

  Leg i frame (u, v, w):  (u, v, w) = Rz(-phi_i) * (x, y, z) - (r, s, 0)
      u: radial, v: tangential (parallel to the motor axis), w = z.
  Leg i geometry, with theta1 = motor/thigh angle, theta2 = knee, theta3 = shin angle:
      u = a cos(theta1) - c + K cos(theta2)
      v = b cos(theta3) - f
      w = a sin(theta1) + K sin(theta2),        K = d + e + b sin(theta3)
  so, per leg, the constraint between theta1 and the tip is
      g = (u + c - a cos theta1)^2 + (w - a sin theta1)^2 - K(v)^2 = 0,
      K(v) = d + e + b*sqrt(1 - ((v + f)/b)^2).
  Inverse kinematics solves g = 0 for theta1 with the tangent half-angle t = tan(theta1/2):
      l2 t^2 + l1 t + l0 = 0,  l0 = (u+c-a)^2 + w^2 - K^2,  l1 = -4 a w,  l2 = (u+c+a)^2 + w^2 - K^2,
  taking the root t = (-l1 - sqrt(l1^2 - 4 l0 l2)) / (2 l2)  (the root libnifalcon selects).

Jacobian: ANALYTIC, by implicit differentiation of g (derivation in README.md):
      d theta1_i / d(u, v, w) = -[cos theta2, cot theta3, sin theta2] / (a sin(theta1 - theta2)),
  rotated back to the world frame; J = (d theta / d x)^-1 = d x / d theta (m/rad).  --check verifies
  it against central differences of the forward kinematics.

Forward kinematics: solved here EXACTLY (Newton on the analytic Jacobian to < 1e-13 rad), i.e. the
true forward map of libnifalcon's geometric model.  libnifalcon's own FK is a loose iteration
(stops at |delta theta| < 0.01 rad, see libnifalcon_fk_emulated) and is only ~mm accurate.

Usage:  python3 falcon_reference.py --check     # self-checks, non-zero exit on failure
        python3 falcon_reference.py --write     # regenerate positions.csv and jacobians.csv
        python3 falcon_reference.py --compare   # reference vs sawrt's driver formulas (ours_*)
"""

import argparse
import csv
import math
import os
import sys

# ----------------------------------------------------------------------------------------------
# Constants.  Source: libnifalcon include/falcon/core/FalconGeometry.h (master f7c727a) unless noted.
# (The values there are "adjusted geometry measurements by Niall Begley", ChangeLog.txt; older
#  libnifalcon releases had c = 0.014, r = 0.037233758, s = -0.027330909.)
# ----------------------------------------------------------------------------------------------
WHEEL_SLOTS_NUMBER = 320.0      # FalconGeometry.h: transparent slots on the motor's encoder wheel
SHAFT_DIAMETER = 0.01425        # FalconGeometry.h: motor shaft (capstan) diameter, m
SMALL_ARM_DIAMETER = 0.110      # FalconGeometry.h: "small diameter of the arm" (arm drum), m
THETA_OFFSET_ANGLE_DEG = 35.0   # FalconGeometry.h: arm angle at encoder value 0 ("approx"), degrees

A = 0.060      # FalconGeometry.h a: leg base to knee (thigh length), m
B = 0.1025     # FalconGeometry.h b: shin parallelogram side, m
C = 0.01443    # FalconGeometry.h c: shin connection point to effector centre, u component, m
D = 0.01125    # FalconGeometry.h d: shin to effector connection joint, m
E = D          # FalconGeometry.h e = d: knee to shin connection joint, m
F = -0.025     # FalconGeometry.h f: shin connection point to effector centre, v component, m
R = 0.0400     # FalconGeometry.h r: frame origin to leg base, u component, m
S = -0.02309   # FalconGeometry.h s: frame origin to leg base, v component, m

PI_LIBNIFALCON = 3.14159265                 # FalconGeometry.h PI (truncated; used in phy)
OFFSET_ANGLE = PI_LIBNIFALCON / 12          # FalconGeometry.h: 15 deg tilt of each axis
PHY = (PI_LIBNIFALCON / 2 + OFFSET_ANGLE,   # FalconGeometry.h phy[]: leg azimuths, rad
       -PI_LIBNIFALCON / 6 + OFFSET_ANGLE,  #   = 105 deg, -15 deg, -135 deg (to ~3.6e-9 rad)
       -5 * PI_LIBNIFALCON / 6 + OFFSET_ANGLE)

DEG_TO_RAD_LIBNIFALCON = 0.0174532925       # src/kinematic/FalconKinematicStamper.cpp getPosition()

# libnifalcon's notion of the workspace centre:
WORKSPACE_ORIGIN_API = (0.0, 0.0, 0.150)    # include/falcon/kinematic/FalconKinematicStamper.h
                                            #   getWorkspaceOrigin() (inherited from the older
                                            #   Ouellet kinematics, boneyard/.../DirectKinematic.cpp)
WORKSPACE_CENTRE_EXAMPLES = (0.0, 0.0, 0.11)  # examples/barrow_mechanics/main.cpp ("roughly the
                                            #   centre"), FalconSphereTest.cpp (pos[2] -= 0.11);
                                            #   FalconCubeTest.cpp cube: x,y in [-.03,.03], z in [.095,.155]
FK_SEED = (0.0, 0.0, 0.08)                  # FalconKinematicStamper.cpp constructor pos_ (first guess)

# Force conversion (src/kinematic/FalconKinematicStamper.cpp getForces()):
TORQUE_LIMIT = 30.0            # |torque| above which all three are scaled down together ("rather random")
DAC_PER_TORQUE = -10000.0      # DAC count = -10000 * torque (torque = J^T F, N*m when F in N)

# ----------------------------------------------------------------------------------------------
# Encoder <-> angle  (include/falcon/core/FalconKinematic.h getTheta(), + deg->rad in getPosition())
#   theta_deg = enc * (SHAFT_DIAMETER*pi/(WHEEL_SLOTS*4)) / (pi*SMALL_ARM_DIAMETER/360) + 35
#             = enc * 0.0364346591 deg + 35 deg
#   -> 1280 counts per motor turn, 110/14.25 = 7.719 reduction, 9880.7 counts per arm turn.
# ----------------------------------------------------------------------------------------------
DEG_PER_COUNT = (SHAFT_DIAMETER / (WHEEL_SLOTS_NUMBER * 4)) / (SMALL_ARM_DIAMETER / 360.0)
COUNTS_PER_MOTOR_TURN = WHEEL_SLOTS_NUMBER * 4
COUNTS_PER_ARM_TURN = 360.0 / DEG_PER_COUNT


def angle_from_encoder(enc):
    """Arm (thigh) angle theta1 in rad for a signed 16-bit encoder count, as libnifalcon computes it."""
    return (enc * DEG_PER_COUNT + THETA_OFFSET_ANGLE_DEG) * DEG_TO_RAD_LIBNIFALCON


def encoder_from_angle(theta):
    """Inverse of angle_from_encoder (real-valued; round it yourself)."""
    return (theta / DEG_TO_RAD_LIBNIFALCON - THETA_OFFSET_ANGLE_DEG) / DEG_PER_COUNT


def angles_from_encoders(encs):
    return [angle_from_encoder(e) for e in encs]


# ----------------------------------------------------------------------------------------------
# small 3x3 helpers (no numpy)
# ----------------------------------------------------------------------------------------------
def det3(m):
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


def inv3(m):
    dt = det3(m)
    if dt == 0 or not math.isfinite(dt):
        raise ZeroDivisionError("singular 3x3")
    cof = [[0.0] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(3):
            r = [k for k in range(3) if k != i]
            c = [k for k in range(3) if k != j]
            minor = m[r[0]][c[0]] * m[r[1]][c[1]] - m[r[0]][c[1]] * m[r[1]][c[0]]
            cof[i][j] = (-1) ** (i + j) * minor
    return [[cof[j][i] / dt for j in range(3)] for i in range(3)]


def matvec(m, v):
    return [sum(m[i][k] * v[k] for k in range(3)) for i in range(3)]


def transpose(m):
    return [[m[j][i] for j in range(3)] for i in range(3)]


def norm(v):
    return math.sqrt(sum(x * x for x in v))


# ----------------------------------------------------------------------------------------------
# Inverse kinematics
# ----------------------------------------------------------------------------------------------
def leg_frame(i, p):
    """World point -> leg i's (u, v, w)."""
    cp, sp = math.cos(PHY[i]), math.sin(PHY[i])
    return (cp * p[0] + sp * p[1] - R, -sp * p[0] + cp * p[1] - S, p[2])


def ik_leg(i, p):
    """(theta1, theta2, theta3) of leg i for tip p, or None when out of the model's reach.

    theta2 is taken by atan2 (equal to libnifalcon's acos form whenever w - a sin theta1 >= 0, which
    holds throughout the workspace)."""
    u, v, w = leg_frame(i, p)
    q = (v + F) / B
    if not -1.0 < q < 1.0:
        return None
    th3 = math.acos(q)
    k = D + E + B * math.sin(th3)
    l0 = (u + C - A) ** 2 + w * w - k * k
    l1 = -4 * A * w
    l2 = (u + C + A) ** 2 + w * w - k * k
    disc = l1 * l1 - 4 * l0 * l2
    if disc < 0 or l2 == 0:
        return None
    # libnifalcon's root t = (-l1 - sqrt(disc)) / (2 l2), written in the equivalent form (the product
    # of the roots is l0/l2) that does not cancel when theta1 ~ 0:
    t = 2 * l0 / (-l1 + math.sqrt(disc))
    th1 = 2 * math.atan(t)
    th2 = math.atan2(w - A * math.sin(th1), u + C - A * math.cos(th1))
    return th1, th2, th3


def ik(p):
    """Motor angles theta1 (rad) of the three legs for tip p (m); None if out of reach."""
    out = []
    for i in range(3):
        leg = ik_leg(i, p)
        if leg is None:
            return None
        out.append(leg[0])
    return out


def ik_full(p):
    legs = [ik_leg(i, p) for i in range(3)]
    return None if any(l is None for l in legs) else legs


def dtheta_dx(p):
    """Analytic d theta1_i / d x_j (rad/m) at tip p (rows: legs)."""
    legs = ik_full(p)
    if legs is None:
        raise ValueError("out of reach")
    m = []
    for i, (th1, th2, th3) in enumerate(legs):
        den = A * math.sin(th1 - th2)
        du = -math.cos(th2) / den
        dv = -(math.cos(th3) / math.sin(th3)) / den
        dw = -math.sin(th2) / den
        cp, sp = math.cos(PHY[i]), math.sin(PHY[i])
        # u = cp x + sp y - r ; v = -sp x + cp y - s ; w = z
        m.append([du * cp - dv * sp, du * sp + dv * cp, dw])
    return m


# ----------------------------------------------------------------------------------------------
# Forward kinematics (exact) and Jacobian
# ----------------------------------------------------------------------------------------------
def fk(theta, seed=(0.0, 0.0, 0.11), tol=1e-13, max_iter=60):
    """Tip position (m) for motor angles theta (rad): Newton on ik() with the analytic Jacobian.
    Returns None if it does not converge (angles outside the model's workspace)."""
    p = list(seed)
    for _ in range(max_iter):
        th = ik(p)
        if th is None:
            return None
        res = [th[i] - theta[i] for i in range(3)]
        if max(abs(x) for x in res) < tol:
            return p
        step = matvec(inv3(dtheta_dx(p)), res)
        lam = 1.0
        r0 = norm(res)
        while True:  # backtrack if the full step leaves the model's domain or does not reduce |res|
            cand = [p[k] - lam * step[k] for k in range(3)]
            thc = ik(cand)
            if thc is not None and norm([thc[i] - theta[i] for i in range(3)]) < r0:
                p = cand
                break
            lam /= 2
            if lam < 1e-9:
                return None
    th = ik(p)
    return p if th is not None and max(abs(th[i] - theta[i]) for i in range(3)) < tol * 10 else None


def fk_encoders(encs, seed=(0.0, 0.0, 0.11)):
    return fk(angles_from_encoders(encs), seed)


def jacobian(p):
    """d x / d theta (m/rad) at tip p, analytic (inverse of dtheta_dx). Row i = d x_i."""
    return inv3(dtheta_dx(p))


def jacobian_fd(theta, h=1e-6):
    """d x / d theta by central differences of fk (m/rad)."""
    p0 = fk(theta)
    cols = []
    for j in range(3):
        tp = list(theta); tp[j] += h
        tm = list(theta); tm[j] -= h
        xp, xm = fk(tp, p0), fk(tm, p0)
        cols.append([(xp[k] - xm[k]) / (2 * h) for k in range(3)])
    return [[cols[j][i] for j in range(3)] for i in range(3)]


def dtheta_dx_fd(p, h=1e-7):
    cols = []
    for j in range(3):
        pp = list(p); pp[j] += h
        pm = list(p); pm[j] -= h
        a, b = ik(pp), ik(pm)
        cols.append([(a[k] - b[k]) / (2 * h) for k in range(3)])
    return [[cols[j][i] for j in range(3)] for i in range(3)]


# ----------------------------------------------------------------------------------------------
# libnifalcon's own numerics, re-expressed for documentation (NOT the reference):
# ----------------------------------------------------------------------------------------------
def libnifalcon_dtheta_dx_as_coded(p):
    """The matrix libnifalcon's FalconKinematicStamper::jacobian() builds before inverting it.
    x and y entries equal ours (dtheta_dx); the z entry is sin(theta2)^2/den where the derivative of
    the model is sin(theta2)*sin(theta3)/den (den = -a sin theta3 sin(theta1-theta2)).  See README."""
    legs = ik_full(p)
    m = []
    for i, (th1, th2, th3) in enumerate(legs):
        den = -A * math.sin(th3) * math.sin(th1 - th2)
        cp, sp = math.cos(PHY[i]), math.sin(PHY[i])
        jx = (cp * math.cos(th2) * math.sin(th3) - sp * math.cos(th3)) / den
        jy = (sp * math.cos(th2) * math.sin(th3) + cp * math.cos(th3)) / den
        jz = math.sin(th2) ** 2 / den
        m.append([jx, jy, jz])
    return m


def libnifalcon_jacobian_as_coded(p):
    return inv3(libnifalcon_dtheta_dx_as_coded(p))


def libnifalcon_fk_emulated(theta, previous=FK_SEED):
    """Behaviour of libnifalcon's FK(): at most 15 steps x += g * J * (theta - ik(x)), g = 0.5 halved on
    overshoot, stop when |theta - ik(x)| < 0.01 rad (measured BEFORE the last step); uses the as-coded
    Jacobian and the previous position as the seed.  Returns the position libnifalcon would report."""
    pos = list(previous)
    prev_err = 10000.0
    gain = 0.5
    for _ in range(15):
        th = ik(pos)
        if th is None:
            return pos
        delta = [theta[k] - th[k] for k in range(3)]
        step = matvec(libnifalcon_jacobian_as_coded(pos), delta)
        pos = [pos[k] + gain * step[k] for k in range(3)]
        err = norm(delta)
        if err < 0.01:
            return pos
        if err > prev_err:
            gain /= 2
        prev_err = err
    return pos


def libnifalcon_force_to_dac(p, force, as_coded=True):
    """libnifalcon getForces(): torque = J^T f (J = d x / d theta, so N*m for N), scaled down together
    if any |torque| > 30, then DAC = int(-10000 * torque) (C truncation toward zero).  Note the firmware
    object keeps only the low 16 bits of each value (FalconFirmwareNovintSDK.cpp formatInput), and
    nothing in libnifalcon clamps to 4096 despite the doc comments saying so."""
    j = libnifalcon_jacobian_as_coded(p) if as_coded else jacobian(p)
    tau = matvec(transpose(j), force)
    big = max(abs(t) for t in tau)
    if big > TORQUE_LIMIT:
        tau = [t / (big / TORQUE_LIMIT) for t in tau]
    return [int(DAC_PER_TORQUE * t) for t in tau], tau


# ----------------------------------------------------------------------------------------------
# libnifalcon packet format (FalconFirmwareNovintSDK.cpp formatInput/formatOutput), for test vectors.
# ----------------------------------------------------------------------------------------------
def encode_host_packet(dac, leds=0, homing=False):
    """Host -> Falcon: '<', 3 x 4 nibbles (least significant first) + 'A', control nibble, 'A', '>'."""
    out = [0x3C]
    for v in dac:
        u = v & 0xFFFF
        out += [0x41 + ((u >> (4 * k)) & 0xF) for k in range(4)]
    ctrl = (leds | (0x01 if homing else 0)) & 0xFF  # libnifalcon adds 0x41 to the raw byte, no mask
    out += [0x41 + ctrl, 0x41, 0x3E]
    return bytes(out)


def decode_packet(pkt):
    """Either direction: (three signed 16-bit words, byte13 - 0x41, byte14 - 0x41)."""
    assert pkt[0] == 0x3C and pkt[15] == 0x3E
    words = []
    for i in range(3):
        u = 0
        for k in range(4):
            u |= ((pkt[1 + 4 * i + k] - 0x41) & 0xF) << (4 * k)
        words.append(u - 0x10000 if u >= 0x8000 else u)
    return words, pkt[13] - 0x41, pkt[14] - 0x41


# Host->device packets recorded in libnifalcon util/translate_packet.py with the forces that produced
# them (comments "F: [...]  V: [...]").  Byte 13 is 'E' (0x45): LED value 0x4 (BLUE_LED in libnifalcon's
# enum), no homing.
TRANSLATE_PACKET_VECTORS = [
    ("3c 50 50 50 41 43 45 50 41 43 4d 50 41 45 41 3e", (4095, 3906, 4034)),
    ("3c 41 4d 4b 41 4d 4e 4b 41 49 45 4c 41 45 41 3e", (2752, 2780, 2888)),
    ("3c 50 42 46 41 4e 4b 46 41 47 50 46 41 45 41 3e", (1311, 1453, 1526)),
    ("3c 46 4a 43 41 4c 4e 43 41 4f 50 43 41 45 41 3e", (661, 731, 766)),
    ("3c 4d 4b 45 50 4c 42 41 41 42 4b 44 41 45 41 3e", (-2900, 27, 929)),
    ("3c 50 49 42 41 42 50 44 50 50 47 45 41 45 41 3e", (399, -3087, 1135)),
    ("3c 50 4c 50 50 49 49 41 41 42 47 50 50 45 41 3e", (-65, 136, -159)),
    ("3c 4a 46 4e 50 42 4f 4a 41 4b 4c 49 50 45 41 3e", (-679, 2529, -1862)),
]


# ==============================================================================================
# ours_*: sawrt's driver formulas, re-typed from drivers/falcon/src/delta_kinematics.cpp and
# include/saw/drivers/falcon/delta_kinematics.hpp ONLY to measure the difference (--compare).
# Nothing above uses them.
# ==============================================================================================
OURS_A, OURS_B, OURS_R, OURS_C = 0.060, 0.1025, 0.040, 0.01443
OURS_AZ = (1.8325957145940461, -0.2617993877991494, -2.3561944901923448)
OURS_ANGLE_AT_ZERO = 0.6108652381980153
OURS_RAD_PER_COUNT = (2 * math.pi / 1280) * (0.01425 / 0.110)


def ours_angle(enc):
    return OURS_ANGLE_AT_ZERO + enc * OURS_RAD_PER_COUNT


def _ours_knee(i, th):
    ux, uy = math.cos(OURS_AZ[i]), math.sin(OURS_AZ[i])
    rad = OURS_R - OURS_C + OURS_A * math.cos(th)
    return [rad * ux, rad * uy, OURS_A * math.sin(th)]


def ours_forward(theta):
    """Ideal delta: tip = intersection (larger z) of three spheres of radius b about the shifted knees."""
    p1, p2, p3 = (_ours_knee(i, theta[i]) for i in range(3))
    sub = lambda a, b: [a[k] - b[k] for k in range(3)]
    dot = lambda a, b: sum(a[k] * b[k] for k in range(3))
    d21 = sub(p2, p1)
    dd = norm(d21)
    ex = [x / dd for x in d21]
    ii = dot(ex, sub(p3, p1))
    ey = [sub(p3, p1)[k] - ii * ex[k] for k in range(3)]
    jn = norm(ey)
    ey = [x / jn for x in ey]
    ez = [ex[1] * ey[2] - ex[2] * ey[1], ex[2] * ey[0] - ex[0] * ey[2], ex[0] * ey[1] - ex[1] * ey[0]]
    px = dd / 2
    py = (ii * ii + jn * jn) / (2 * jn) - (ii / jn) * px
    pz2 = OURS_B ** 2 - px * px - py * py
    if pz2 < 0:
        return None
    c = [p1[k] + px * ex[k] + py * ey[k] for k in range(3)]
    a = [c[k] + math.sqrt(pz2) * ez[k] for k in range(3)]
    b = [c[k] - math.sqrt(pz2) * ez[k] for k in range(3)]
    return a if a[2] > b[2] else b


def ours_inverse(p):
    out = []
    for i in range(3):
        ux, uy = math.cos(OURS_AZ[i]), math.sin(OURS_AZ[i])
        v = [p[0] - (OURS_R - OURS_C) * ux, p[1] - (OURS_R - OURS_C) * uy, p[2]]
        vu, vz = v[0] * ux + v[1] * uy, v[2]
        rho = math.hypot(vu, vz)
        k = (sum(x * x for x in v) + OURS_A ** 2 - OURS_B ** 2) / (2 * OURS_A)
        if rho <= 0 or abs(k) > rho:
            return None
        out.append(math.atan2(vz, vu) - math.acos(k / rho))
    return out


# ----------------------------------------------------------------------------------------------
# Data set
# ----------------------------------------------------------------------------------------------
HERE = os.path.dirname(os.path.abspath(__file__))


def grid_positions():
    """Target tip positions: a 5x5x5 box (x, y in +-40 mm, z 80..160 mm; libnifalcon's cube test uses
    +-30 mm, z 95..155 mm), the three axes through the examples' centre (0, 0, 0.11), the z axis from
    70 to 175 mm, and libnifalcon's getWorkspaceOrigin() (0, 0, 0.15).  All are inside the MODEL's
    reach; the Falcon's mechanical stops are not modelled by libnifalcon and not checked here."""
    pts = []
    xs = (-0.04, -0.02, 0.0, 0.02, 0.04)
    zs = (0.08, 0.10, 0.12, 0.14, 0.16)
    for z in zs:
        for y in xs:
            for x in xs:
                pts.append((x, y, z))
    for t in (-0.05, -0.03, -0.01, 0.01, 0.03, 0.05):   # x and y axes through (0, 0, 0.11)
        pts.append((t, 0.0, 0.11))
        pts.append((0.0, t, 0.11))
    for z in (0.07, 0.09, 0.11, 0.13, 0.15, 0.17, 0.175):
        pts.append((0.0, 0.0, z))
    pts.append(WORKSPACE_ORIGIN_API)
    return pts


def build_rows():
    """Integer encoder triples near the targets, and the exact tip position for those integers."""
    rows, seen = [], set()
    for p in grid_positions():
        th = ik(p)
        if th is None:
            continue
        enc = tuple(int(round(encoder_from_angle(t))) for t in th)
        if enc in seen or any(not -32768 <= e <= 32767 for e in enc):
            continue
        x = fk_encoders(enc, seed=p)
        if x is None:
            continue
        seen.add(enc)
        rows.append((enc, x))
    return rows


def write_csvs():
    rows = build_rows()
    with open(os.path.join(HERE, "positions.csv"), "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["enc0", "enc1", "enc2", "x", "y", "z"])
        for enc, x in rows:
            w.writerow(list(enc) + ["%.12f" % v for v in x])
    with open(os.path.join(HERE, "jacobians.csv"), "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["enc0", "enc1", "enc2"] + ["j%d%d" % (i, j) for i in range(3) for j in range(3)])
        for k, (enc, x) in enumerate(rows):
            if k % 4 != 0:  # every 4th pose: centre, edges and axes are all represented
                continue
            jm = jacobian(x)
            w.writerow(list(enc) + ["%.12e" % jm[i][j] for i in range(3) for j in range(3)])
    print("wrote %d positions, %d jacobians to %s" % (len(rows), (len(rows) + 3) // 4, HERE))


# ----------------------------------------------------------------------------------------------
# Self-check
# ----------------------------------------------------------------------------------------------
def check():
    ok = True

    def fail(msg):
        nonlocal ok
        ok = False
        print("FAIL:", msg)

    # encoder conversion
    if abs(DEG_PER_COUNT - 0.036434659090909) > 1e-12:
        fail("deg per count %r" % DEG_PER_COUNT)
    for e in (-32768, -5000, 0, 1, 1447, 32767):
        if abs(encoder_from_angle(angle_from_encoder(e)) - e) > 1e-7:
            fail("encoder round trip %d" % e)

    rows = build_rows()
    if len(rows) < 100:
        fail("only %d valid poses" % len(rows))
    worst_rt, worst_j, worst_md = 0.0, 0.0, 0.0
    for enc, x in rows:
        th = angles_from_encoders(enc)
        # forward o inverse round trip, both ways
        th2 = ik(x)
        worst_rt = max(worst_rt, max(abs(th2[i] - th[i]) for i in range(3)))
        x2 = fk(ik(x), seed=WORKSPACE_CENTRE_EXAMPLES)  # cold start from the centre
        worst_rt = max(worst_rt, max(abs(x2[i] - x[i]) for i in range(3)))
        # analytic d theta/d x vs central differences of ik
        ma, mf = dtheta_dx(x), dtheta_dx_fd(x)
        scale = max(abs(v) for r in ma for v in r)
        worst_md = max(worst_md, max(abs(ma[i][j] - mf[i][j]) for i in range(3) for j in range(3)) / scale)
    for enc, x in rows[::7]:
        ja, jf = jacobian(x), jacobian_fd(angles_from_encoders(enc))
        scale = max(abs(v) for r in ja for v in r)
        worst_j = max(worst_j, max(abs(ja[i][j] - jf[i][j]) for i in range(3) for j in range(3)) / scale)
    print("poses: %d; forward/inverse round trip worst %.2e (rad or m)" % (len(rows), worst_rt))
    print("d theta/d x analytic vs central differences of IK: worst relative %.2e" % worst_md)
    print("J = d x/d theta analytic vs central differences of FK: worst relative %.2e" % worst_j)
    if worst_rt > 1e-9:
        fail("round trip %.3e > 1e-9" % worst_rt)
    if worst_md > 1e-6 or worst_j > 1e-6:
        fail("Jacobian mismatch")

    # CSVs, if present, must match what the model gives now
    path = os.path.join(HERE, "positions.csv")
    if os.path.exists(path):
        with open(path) as fh:
            rd = csv.DictReader(fh)
            if rd.fieldnames != ["enc0", "enc1", "enc2", "x", "y", "z"]:
                fail("positions.csv header %r" % rd.fieldnames)
            n, worst = 0, 0.0
            for row in rd:
                enc = [int(row["enc%d" % i]) for i in range(3)]
                x = [float(row[k]) for k in "xyz"]
                xr = fk_encoders(enc, seed=x)
                worst = max(worst, max(abs(xr[i] - x[i]) for i in range(3)))
                n += 1
            print("positions.csv: %d rows, worst |fk - csv| %.2e m" % (n, worst))
            if n < 100 or worst > 1e-9:
                fail("positions.csv stale or short")
    else:
        print("positions.csv absent (run --write)")
    path = os.path.join(HERE, "jacobians.csv")
    if os.path.exists(path):
        with open(path) as fh:
            rd = csv.DictReader(fh)
            n, worst = 0, 0.0
            for row in rd:
                enc = [int(row["enc%d" % i]) for i in range(3)]
                jm = jacobian(fk_encoders(enc))
                worst = max(worst, max(abs(jm[i][j] - float(row["j%d%d" % (i, j)]))
                                       for i in range(3) for j in range(3)))
                n += 1
            print("jacobians.csv: %d rows, worst |J - csv| %.2e m/rad" % (n, worst))
            if worst > 1e-9:
                fail("jacobians.csv stale")

    # packet vectors from libnifalcon util/translate_packet.py
    for hexs, expect in TRANSLATE_PACKET_VECTORS:
        pkt = bytes(int(h, 16) for h in hexs.split())
        words, ctrl, b14 = decode_packet(pkt)
        if tuple(words) != expect or ctrl != 0x4 or b14 != 0:
            fail("packet vector %s -> %r %x" % (hexs, words, ctrl))
        if encode_host_packet(words, leds=0x4) != pkt:
            fail("packet re-encode %s" % hexs)
    print("translate_packet.py vectors: %d decoded and re-encoded" % len(TRANSLATE_PACKET_VECTORS))

    print("OK" if ok else "FAILED")
    return ok


# ----------------------------------------------------------------------------------------------
# Comparison with sawrt's driver (ours_*)
# ----------------------------------------------------------------------------------------------
def compare():
    print("Reference (libnifalcon model) vs ours (sawrt delta_kinematics.cpp formulas)")
    print("angle per count: ref %.12e rad, ours %.12e rad (rel %.1e)"
          % (angle_from_encoder(1) - angle_from_encoder(0), OURS_RAD_PER_COUNT,
             (angle_from_encoder(1) - angle_from_encoder(0)) / OURS_RAD_PER_COUNT - 1))
    print("angle at enc 0: ref %.12f rad, ours %.12f rad" % (angle_from_encoder(0), ours_angle(0)))
    print()
    print("%-22s %-36s %-36s %9s" % ("encoders", "reference x,y,z (mm)", "ours x,y,z (mm)", "|diff| mm"))
    rows = build_rows()
    diffs = []
    picks = set(range(0, len(rows), max(1, len(rows) // 12)))
    for k, (enc, x) in enumerate(rows):
        xo = ours_forward([ours_angle(e) for e in enc])
        if xo is None:
            continue
        dd = norm([xo[i] - x[i] for i in range(3)]) * 1000
        diffs.append(dd)
        if k in picks or (x[0] == 0 and x[1] == 0):
            print("%-22s %-36s %-36s %9.2f" % (
                str(enc), "%8.2f %8.2f %8.2f" % tuple(v * 1000 for v in x),
                "%8.2f %8.2f %8.2f" % tuple(v * 1000 for v in xo), dd))
    print("over %d poses: |diff| min %.1f mm, median %.1f mm, max %.1f mm"
          % (len(diffs), min(diffs), sorted(diffs)[len(diffs) // 2], max(diffs)))
    # attribute the difference: switch libnifalcon's offsets off one group at a time
    global D, E, F, S
    saved = (D, E, F, S)
    for label, vals in (("d = e = 0", (0.0, 0.0, F, S)), ("f = s = 0", (D, E, 0.0, 0.0)),
                        ("d = e = f = s = 0", (0.0, 0.0, 0.0, 0.0))):
        D, E, F, S = vals
        worst = 0.0
        for enc, _ in rows:
            xr = fk_encoders(enc)
            xo = ours_forward([ours_angle(e) for e in enc])
            if xr is not None and xo is not None:
                worst = max(worst, norm([xo[i] - xr[i] for i in range(3)]))
        print("reference with %-18s vs ours: worst |diff| %.3g mm" % (label, worst * 1000))
    D, E, F, S = saved
    # the same tip position: what angles does each model need?
    print()
    for p in ((0.0, 0.0, 0.11), (0.0, 0.0, 0.15), (0.04, 0.0, 0.11), (0.0, 0.04, 0.11)):
        tr, to = ik(p), ours_inverse(p)
        print("tip %-24s ref enc %-24s ours enc %s" % (
            str(p), str([round(encoder_from_angle(t)) for t in tr]),
            str([round((t - OURS_ANGLE_AT_ZERO) / OURS_RAD_PER_COUNT) for t in to]) if to else "out of reach"))
    # libnifalcon's own loose FK, and its Jacobian z-column
    print()
    worst_jac = 0.0
    for enc, x in rows:
        ja, jl = jacobian(x), libnifalcon_jacobian_as_coded(x)
        sc = max(abs(v) for r in ja for v in r)
        worst_jac = max(worst_jac, max(abs(ja[i][j] - jl[i][j]) for i in range(3) for j in range(3)) / sc)
    cold = [norm([a - b for a, b in zip(libnifalcon_fk_emulated(angles_from_encoders(e)), x)]) for e, x in rows]
    print("libnifalcon FK emulation (tolerance 0.01 rad), cold start from (0,0,0.08): "
          "|error| median %.2f mm, worst %.2f mm" % (sorted(cold)[len(cold) // 2] * 1000, max(cold) * 1000))
    print("libnifalcon jacobian() as coded vs the model's derivative: worst relative difference %.2f"
          % worst_jac)
    p = (0.0, 0.0, 0.11)
    for fvec in ((0, 0, -12.5), (10.0, 0, 0), (0, 10.0, 0)):
        dac_l, tau_l = libnifalcon_force_to_dac(p, fvec, as_coded=True)
        dac_r, tau_r = libnifalcon_force_to_dac(p, fvec, as_coded=False)
        print("force %-18s at %s: libnifalcon DAC %s, with the exact Jacobian %s"
              % (str(fvec), str(p), dac_l, dac_r))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="run the self-checks")
    ap.add_argument("--write", action="store_true", help="regenerate positions.csv and jacobians.csv")
    ap.add_argument("--compare", action="store_true", help="compare with sawrt's driver formulas")
    a = ap.parse_args(argv)
    if not (a.check or a.write or a.compare):
        ap.print_help()
        return 0
    if a.write:
        write_csvs()
    if a.compare:
        compare()
    if a.check:
        return 0 if check() else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
