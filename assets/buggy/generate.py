#!/usr/bin/env python3
"""Generate the soilsim buggy: buggy.urdf, its visual meshes (OBJ) and
README.md, all from the numbers in this file.

Run from anywhere:  python3 assets/buggy/generate.py
Everything written is committed; the simulator never runs this script.
The derivations (motion ratio, spring and damper rates, preloads) are done
here so that the URDF, the README table and the physics agree.

Frames: chassis x forward, y left, z up; z = 0 at the wheel-centre height of
the design ride height.  Every number is SI.
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
G = 9.81

# ---------------------------------------------------------------------------
# vehicle parameters (sources and reasoning in README.md)

WHEELBASE = 2.30          # m
TRACK_F, TRACK_R = 1.50, 1.56
R_WHEEL = 0.3611          # m (DESIGN 7)
W_FRONT, W_REAR = 0.126, 0.1562  # contact widths (DESIGN 7)

M_WHEEL = 20.0            # wheel + tyre
M_HUB = 3.0
M_UPRIGHT = 6.0
M_LOWER = 4.0
M_UPPER = 3.0
M_RACK = 2.0
M_TOTAL = 896.0
M_CHASSIS = M_TOTAL - 4 * (M_WHEEL + M_HUB + M_UPRIGHT + M_LOWER + M_UPPER) - M_RACK
CG_X, CG_Z = -0.25, 0.20  # chassis centre of mass (rear engine), above wheel centres
I_CHASSIS = (320.0, 820.0, 950.0)  # roll, pitch, yaw about the chassis COM

RIDE_F = {"f": 1.45, "r": 1.60}    # Hz, target ride frequencies
ZETA = 0.35                        # damping ratio of the ride mode
K_TYRE = 150e3                     # N/m radial tyre stiffness
C_TYRE = 300.0                     # N s/m radial tyre damping

# suspension hard points relative to the axle line (x_a, +/-y, z); s = side
def hard_points(axle, side):
    x = WHEELBASE / 2 if axle == "f" else -WHEELBASE / 2
    yw = (TRACK_F if axle == "f" else TRACK_R) / 2
    s = side
    return {
        "x": x, "yw": yw,
        "lower_in": (x, s * 0.28, -0.12),
        "lower_ball": (x, s * (yw - 0.13), -0.14),
        "upper_in": (x, s * 0.33, 0.14),
        "upper_ball": (x, s * (yw - 0.16), 0.13),
        "spindle": (x, s * yw, 0.0),
        "arm_point": (x + 0.13, s * (yw - 0.15), -0.06),   # steering / toe arm
        "inner_point": (x + 0.13, s * 0.30, -0.06),       # rack end / toe mount
        "coil_chassis": (x, s * 0.38, 0.42),
        "coil_frac": 0.70,                                 # along the lower arm
    }

def sub(a, b): return tuple(p - q for p, q in zip(a, b))
def add(a, b): return tuple(p + q for p, q in zip(a, b))
def scl(a, k): return tuple(p * k for p in a)
def norm(a): return math.sqrt(sum(p * p for p in a))

def coil_lower(hp):
    return add(hp["lower_in"], scl(sub(hp["lower_ball"], hp["lower_in"]), hp["coil_frac"]))

def motion_ratio(hp):
    """spring length change per unit vertical travel of the lower ball
    joint, rotating the lower arm about its x axis (finite difference)"""
    def rot(p, th):
        d = sub(p, hp["lower_in"])
        y = d[1] * math.cos(th) - d[2] * math.sin(th)
        z = d[1] * math.sin(th) + d[2] * math.cos(th)
        return add(hp["lower_in"], (d[0], y, z))
    h = 1e-6
    s = 1 if hp["spindle"][1] > 0 else -1
    th = s * h  # wheel up
    L0 = norm(sub(hp["coil_chassis"], coil_lower(hp)))
    L1 = norm(sub(hp["coil_chassis"], rot(coil_lower(hp), th)))
    z0 = hp["lower_ball"][2]
    z1 = rot(hp["lower_ball"], th)[2]
    return abs((L1 - L0) / (z1 - z0)), L0

def derive():
    """corner loads, rates and preloads"""
    front_frac = (CG_X + WHEELBASE / 2) / WHEELBASE
    out = {}
    for axle in ("f", "r"):
        hp = hard_points(axle, 1)
        mr, L0 = motion_ratio(hp)
        frac = front_frac if axle == "f" else 1 - front_frac
        m_sprung = M_CHASSIS * frac / 2 + (M_RACK / 2 if axle == "f" else 0)
        # arms count half sprung, half unsprung
        m_corner_sprung = m_sprung + 0.5 * (M_LOWER + M_UPPER)
        f = RIDE_F[axle]
        k_ride = m_corner_sprung * (2 * math.pi * f) ** 2
        k_wheel = k_ride * K_TYRE / (K_TYRE - k_ride)     # tyre in series
        k_spring = k_wheel / mr ** 2
        c_wheel = 2 * ZETA * math.sqrt(k_wheel * m_corner_sprung)
        c_spring = c_wheel / mr ** 2
        f_spring = m_corner_sprung * G / mr                # static force
        rest = L0 + f_spring / k_spring
        # the tyre carries everything above the hub
        m_above_tyre = m_sprung + M_LOWER + M_UPPER + M_UPRIGHT
        tyre_ref = m_above_tyre * G / K_TYRE
        out[axle] = dict(mr=mr, L0=L0, m_sprung=m_corner_sprung, k_ride=k_ride,
                         k_wheel=k_wheel, k_spring=k_spring, c_wheel=c_wheel,
                         c_spring=c_spring, f_spring=f_spring, rest=rest,
                         tyre_ref=tyre_ref, m_above_tyre=m_above_tyre,
                         corner_load=(m_sprung + M_LOWER + M_UPPER + M_UPRIGHT +
                                      M_HUB + M_WHEEL) * G)
    out["front_frac"] = front_frac
    return out

# ---------------------------------------------------------------------------
# meshes (OBJ, counter-clockwise faces, normals recomputed by the loader)

class Obj:
    def __init__(self):
        self.v, self.f = [], []

    def quad(self, a, b, c, d):
        self.f.append((a, b, c))
        self.f.append((a, c, d))

    def box(self, c, size):
        hx, hy, hz = (s / 2 for s in size)
        base = len(self.v) + 1
        for k in range(8):
            self.v.append((c[0] + (hx if k & 1 else -hx), c[1] + (hy if k & 2 else -hy),
                           c[2] + (hz if k & 4 else -hz)))
        b = base
        for q in ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)):
            self.quad(*(b + i for i in q))

    def tube(self, p0, p1, r, n=10):
        """a cylinder between two points"""
        d = sub(p1, p0)
        L = norm(d)
        u = scl(d, 1 / L)
        a = (1, 0, 0) if abs(u[0]) < 0.9 else (0, 1, 0)
        e1 = (u[1] * a[2] - u[2] * a[1], u[2] * a[0] - u[0] * a[2], u[0] * a[1] - u[1] * a[0])
        e1 = scl(e1, 1 / norm(e1))
        e2 = (u[1] * e1[2] - u[2] * e1[1], u[2] * e1[0] - u[0] * e1[2], u[0] * e1[1] - u[1] * e1[0])
        base = len(self.v) + 1
        for end in (p0, p1):
            for k in range(n):
                t = 2 * math.pi * k / n
                self.v.append(add(end, add(scl(e1, r * math.cos(t)), scl(e2, r * math.sin(t)))))
        for k in range(n):
            k2 = (k + 1) % n
            self.quad(base + k, base + k2, base + n + k2, base + n + k)
        c0, c1 = len(self.v) + 1, len(self.v) + 2
        self.v += [p0, p1]
        for k in range(n):
            k2 = (k + 1) % n
            self.f.append((c0, base + k2, base + k))
            self.f.append((c1, base + n + k, base + n + k2))

    def lathe(self, profile, n=48):
        """revolve (radius, y) points about the y axis (a wheel)"""
        base = len(self.v) + 1
        m = len(profile)
        for k in range(n):
            t = 2 * math.pi * k / n
            for r, y in profile:
                self.v.append((r * math.cos(t), y, r * math.sin(t)))
        for k in range(n):
            k2 = (k + 1) % n
            for j in range(m - 1):
                self.quad(base + k * m + j, base + k * m + j + 1,
                          base + k2 * m + j + 1, base + k2 * m + j)

    def write(self, path, comment):
        with open(path, "w") as f:
            f.write("# %s\n# generated by assets/buggy/generate.py (soilsim, CC0)\n" % comment)
            for v in self.v:
                f.write("v %.5f %.5f %.5f\n" % v)
            for t in self.f:
                f.write("f %d %d %d\n" % t)

def wheel_mesh(width):
    w = width / 2
    r = R_WHEEL
    rim = 0.22
    prof = [(0.02, -w * 0.6), (rim, -w * 0.6), (rim, -w), (r - 0.04, -w),
            (r - 0.01, -w * 0.8), (r, -w * 0.4), (r, w * 0.4), (r - 0.01, w * 0.8),
            (r - 0.04, w), (rim, w), (rim, w * 0.6), (0.02, w * 0.6)]
    o = Obj()
    o.lathe(prof)
    return o

def chassis_mesh():
    o = Obj()
    L = WHEELBASE / 2
    # floor pan and a tube roll cage around the seats
    o.box((CG_X + 0.05, 0, -0.02), (2.2, 0.62, 0.04))
    for s in (1, -1):
        o.tube((L + 0.35, s * 0.3, 0.0), (-L - 0.35, s * 0.3, 0.0), 0.025)
        o.tube((0.55, s * 0.3, 0.0), (0.15, s * 0.28, 0.95), 0.022)
        o.tube((-0.55, s * 0.3, 0.0), (-0.35, s * 0.28, 0.95), 0.022)
        o.tube((0.15, s * 0.28, 0.95), (-0.35, s * 0.28, 0.95), 0.022)
        o.tube((L + 0.35, s * 0.3, 0.0), (0.55, s * 0.3, 0.45), 0.02)
    o.tube((0.15, 0.28, 0.95), (0.15, -0.28, 0.95), 0.022)
    o.tube((-0.35, 0.28, 0.95), (-0.35, -0.28, 0.95), 0.022)
    o.tube((L + 0.35, 0.3, 0.0), (L + 0.35, -0.3, 0.0), 0.025)
    o.tube((-L - 0.35, 0.3, 0.0), (-L - 0.35, -0.3, 0.0), 0.025)
    # seats and engine block behind them
    o.box((0.0, 0.0, 0.15), (0.45, 0.5, 0.26))
    o.box((-0.85, 0.0, 0.22), (0.55, 0.5, 0.4))
    return o

def arm_mesh(p_in, p_out):
    """an A-arm in its own frame (origin at the inboard pivot)"""
    o = Obj()
    out = sub(p_out, p_in)
    o.tube((-0.12, 0, 0), out, 0.016, 8)
    o.tube((0.12, 0, 0), out, 0.016, 8)
    o.tube((-0.14, 0, 0), (0.14, 0, 0), 0.02, 8)
    return o

def upright_mesh(hp):
    o = Obj()
    lb = hp["lower_ball"]
    ub = sub(hp["upper_ball"], lb)
    sp = sub(hp["spindle"], lb)
    ap = sub(hp["arm_point"], lb)
    o.tube((0, 0, 0), ub, 0.03, 8)
    o.tube(scl(ub, 0.5), sp, 0.035, 8)
    o.tube(scl(ub, 0.25), ap, 0.015, 6)
    return o

# ---------------------------------------------------------------------------
# URDF

def fmt(v):
    return " ".join("%.6g" % x for x in v)

def inertial(m, com, ixx, iyy, izz):
    return ('    <inertial>\n      <origin xyz="%s"/>\n      <mass value="%.6g"/>\n'
            '      <inertia ixx="%.6g" ixy="0" ixz="0" iyy="%.6g" iyz="0" izz="%.6g"/>\n'
            '    </inertial>\n' % (fmt(com), m, ixx, iyy, izz))

def visual(mesh, rgba, origin=(0, 0, 0)):
    return ('    <visual>\n      <origin xyz="%s"/>\n      <geometry><mesh filename="meshes/%s"/></geometry>\n'
            '      <material name="%s"><color rgba="%s"/></material>\n    </visual>\n'
            % (fmt(origin), mesh, mesh[:-4], fmt(rgba)))

def main():
    d = derive()
    os.makedirs(os.path.join(HERE, "meshes"), exist_ok=True)
    chassis_mesh().write(os.path.join(HERE, "meshes", "chassis.obj"), "buggy chassis")
    wheel_mesh(W_FRONT).write(os.path.join(HERE, "meshes", "wheel_front.obj"), "front wheel")
    wheel_mesh(W_REAR).write(os.path.join(HERE, "meshes", "wheel_rear.obj"), "rear wheel")

    u = []
    u.append('<?xml version="1.0"?>\n<!-- soilsim buggy: generated by assets/buggy/generate.py; '
             'edit the script, not this file.\n     Parameters and their derivation: README.md. -->\n'
             '<robot name="buggy">\n')
    u.append('  <link name="chassis">\n' +
             inertial(M_CHASSIS, (CG_X, 0, CG_Z), *I_CHASSIS) +
             visual("chassis.obj", (0.85, 0.45, 0.1, 1)) + '  </link>\n')
    # steering rack: prismatic along y in front of the front axle
    hpf = hard_points("f", 1)
    rack_origin = (hpf["inner_point"][0], 0, hpf["inner_point"][2])
    u.append('  <link name="rack">\n' + inertial(M_RACK, (0, 0, 0), 0.03, 1e-3, 0.03) +
             '    <visual><geometry><box size="0.03 0.62 0.03"/></geometry>'
             '<material name="metal"><color rgba="0.6 0.6 0.65 1"/></material></visual>\n  </link>\n')
    u.append('  <joint name="rack_joint" type="prismatic">\n    <parent link="chassis"/><child link="rack"/>\n'
             '    <origin xyz="%s"/>\n    <axis xyz="0 1 0"/>\n'
             '    <limit lower="-0.06" upper="0.06" effort="5000" velocity="0.5"/>\n'
             '    <dynamics damping="50"/>\n  </joint>\n' % fmt(rack_origin))
    closures, springs = [], []
    for axle in ("f", "r"):
        for side, sn in ((1, "l"), (-1, "r")):
            c = axle + sn
            hp = hard_points(axle, side)
            dd = d[axle]
            width = W_FRONT if axle == "f" else W_REAR
            # lower arm (revolute about x at its inboard pivot)
            lo_out = sub(hp["lower_ball"], hp["lower_in"])
            up_out = sub(hp["upper_ball"], hp["upper_in"])
            arm_mesh(hp["lower_in"], hp["lower_ball"]).write(
                os.path.join(HERE, "meshes", "lower_arm_%s.obj" % c), "lower arm " + c)
            arm_mesh(hp["upper_in"], hp["upper_ball"]).write(
                os.path.join(HERE, "meshes", "upper_arm_%s.obj" % c), "upper arm " + c)
            upright_mesh(hp).write(os.path.join(HERE, "meshes", "upright_%s.obj" % c), "upright " + c)
            for name, m, out, mesh in (("lower_arm_" + c, M_LOWER, lo_out, "lower_arm_%s.obj" % c),
                                       ("upper_arm_" + c, M_UPPER, up_out, "upper_arm_%s.obj" % c)):
                L = norm(out)
                u.append('  <link name="%s">\n' % name +
                         inertial(m, scl(out, 0.5), m * L * L / 12 + 0.01, 0.02, m * L * L / 12 + 0.01) +
                         visual(mesh, (0.25, 0.25, 0.28, 1)) + '  </link>\n')
            u.append('  <joint name="lower_arm_%s_joint" type="revolute">\n    <parent link="chassis"/>'
                     '<child link="lower_arm_%s"/>\n    <origin xyz="%s"/>\n    <axis xyz="1 0 0"/>\n'
                     '    <limit lower="-0.6" upper="0.6" effort="0" velocity="0"/>\n'
                     '    <dynamics damping="2"/>\n  </joint>\n' % (c, c, fmt(hp["lower_in"])))
            u.append('  <joint name="upper_arm_%s_joint" type="revolute">\n    <parent link="chassis"/>'
                     '<child link="upper_arm_%s"/>\n    <origin xyz="%s"/>\n    <axis xyz="1 0 0"/>\n'
                     '    <dynamics damping="2"/>\n  </joint>\n' % (c, c, fmt(hp["upper_in"])))
            # upright on a ball joint at the lower ball joint
            u.append('  <link name="upright_%s">\n' % c +
                     inertial(M_UPRIGHT, scl(sub(hp["spindle"], hp["lower_ball"]), 0.5), 0.06, 0.06, 0.03) +
                     visual("upright_%s.obj" % c, (0.3, 0.3, 0.35, 1)) + '  </link>\n')
            u.append('  <joint name="upright_%s_joint" type="spherical">\n    <parent link="lower_arm_%s"/>'
                     '<child link="upright_%s"/>\n    <origin xyz="%s"/>\n    <dynamics damping="1"/>\n  </joint>\n'
                     % (c, c, c, fmt(lo_out)))
            # hub on the radial tyre spring, wheel on its axle
            u.append('  <link name="hub_%s">\n' % c + inertial(M_HUB, (0, 0, 0), 0.01, 0.01, 0.01) + '  </link>\n')
            u.append('  <joint name="tyre_%s" type="prismatic">\n    <parent link="upright_%s"/><child link="hub_%s"/>\n'
                     '    <origin xyz="%s"/>\n    <axis xyz="0 0 -1"/>\n'
                     '    <dynamics damping="%.6g" stiffness="%.6g" spring_mount="%.6g"/>\n  </joint>\n'
                     % (c, c, c, fmt(sub(hp["spindle"], hp["lower_ball"])), C_TYRE, K_TYRE, dd["tyre_ref"]))
            mesh = "wheel_front.obj" if axle == "f" else "wheel_rear.obj"
            iax = 0.75 * M_WHEEL * R_WHEEL ** 2
            u.append('  <link name="wheel_%s">\n' % c + inertial(M_WHEEL, (0, 0, 0), 1.05, iax, 1.05) +
                     visual(mesh, (0.12, 0.12, 0.12, 1)) +
                     '    <collision>\n      <origin rpy="1.5707963267948966 0 0"/>\n'
                     '      <geometry><cylinder radius="%.6g" length="%.6g"/></geometry>\n    </collision>\n'
                     '  </link>\n' % (R_WHEEL, width))
            u.append('  <joint name="wheel_%s_joint" type="continuous">\n    <parent link="hub_%s"/>'
                     '<child link="wheel_%s"/>\n    <axis xyz="0 1 0"/>\n    <dynamics damping="0.5"/>\n'
                     '  </joint>\n' % (c, c, c))
            closures.append('    <pin body1="upper_arm_%s" body2="upright_%s" anchor="%s"/>\n' % (c, c, fmt(up_out)))
            arm_in_upright = sub(hp["arm_point"], hp["lower_ball"])
            if axle == "f":
                closures.append('    <distance body1="rack" anchor1="%s" body2="upright_%s" anchor2="%s"/>\n'
                                % (fmt((0, side * 0.30, 0)), c, fmt(arm_in_upright)))
            else:
                closures.append('    <distance body1="chassis" anchor1="%s" body2="upright_%s" anchor2="%s"/>\n'
                                % (fmt(hp["inner_point"]), c, fmt(arm_in_upright)))
            springs.append('  <spring name="coilover_%s" body1="chassis" anchor1="%s" body2="lower_arm_%s" '
                           'anchor2="%s" stiffness="%.6g" damping="%.6g" rest_length="%.6g"/>\n'
                           % (c, fmt(hp["coil_chassis"]), c, fmt(sub(coil_lower(hp), hp["lower_in"])),
                              dd["k_spring"], dd["c_spring"], dd["rest"]))
    u.append('  <constraints>\n' + "".join(closures) + '  </constraints>\n')
    u.append("".join(springs))
    u.append('</robot>\n')
    with open(os.path.join(HERE, "buggy.urdf"), "w") as f:
        f.write("".join(u))

    with open(os.path.join(HERE, "README.md"), "w") as f:
        f.write(parameters_md(d))

def parameters_md(d):
    rows = []
    for axle, name in (("f", "front"), ("r", "rear")):
        x = d[axle]
        rows.append("| %s | %.3f | %.1f | %.0f | %.0f | %.0f | %.0f | %.0f | %.4f | %.4f | %.1f |" % (
            name, x["mr"], x["m_sprung"], x["k_ride"], x["k_wheel"], x["k_spring"], x["c_wheel"],
            x["c_spring"], x["L0"], x["rest"], x["corner_load"]))
    return PARAM_TEMPLATE.format(
        m_chassis=M_CHASSIS, m_total=M_TOTAL, front_frac=100 * d["front_frac"],
        rows="\n".join(rows), wb=WHEELBASE, tf=TRACK_F, tr=TRACK_R, r=R_WHEEL,
        wf=W_FRONT, wr=W_REAR, kt=K_TYRE / 1e3, ct=C_TYRE, zeta=ZETA,
        ff=RIDE_F["f"], fr=RIDE_F["r"], cgx=CG_X, cgz=CG_Z, ic=I_CHASSIS,
        mw=M_WHEEL, mh=M_HUB, mu=M_UPRIGHT, ml=M_LOWER, mup=M_UPPER, mr=M_RACK)

PARAM_TEMPLATE = """# The soilsim buggy (assets/buggy)

Generated by `generate.py`; edit the script, not this file.

All numbers below are written by `generate.py` from the constants at its
top; the URDF is generated from the same numbers.

## Layout
- wheelbase {wb} m, track {tf} m front / {tr} m rear, wheel radius {r} m,
  contact width {wf} m front / {wr} m rear (DESIGN 7);
- chassis frame: x forward, y left, z up, z = 0 at the wheel centres at the
  design ride height.

## Masses (total {m_total:.0f} kg)
| part | kg | each of |
|---|---|---|
| chassis (frame, engine, driver) | {m_chassis:.0f} | 1 |
| wheel + tyre | {mw} | 4 |
| hub | {mh} | 4 |
| upright | {mu} | 4 |
| lower wishbone | {ml} | 4 |
| upper wishbone | {mup} | 4 |
| steering rack | {mr} | 1 |

Chassis centre of mass {cgx} m behind the wheelbase centre and {cgz} m above
the wheel centres (rear engine: {front_frac:.1f} % of the chassis weight on the
front axle, a typical rear-engined buggy split). Chassis inertia (roll,
pitch, yaw) {ic} kg m^2: those of a uniform 2.3 x 1.1 x 0.9 m block of the
chassis mass, rounded; wheel inertia about the axle 0.75 m r^2 (most of a
tyre's mass is near its tread).

## Suspension (per corner, derived)
Ride frequencies {ff} Hz front / {fr} Hz rear and a damping ratio of {zeta}
are typical choices for an off-road car: the usual guidance puts passenger
cars at 1.0-1.5 Hz, sporty and off-road cars at 1.5-2.0 Hz, with the rear a
little stiffer than the front, and ride damping ratios of 0.2-0.4 (see e.g.
Milliken & Milliken, *Race Car Vehicle Dynamics*, ch. 16, and Gillespie,
*Fundamentals of Vehicle Dynamics*, ch. 5). Radial tyre stiffness
{kt:.0f} kN/m and damping {ct} N s/m: a large, low-pressure off-road tyre.

Derivation, done by `derive()`:
1. corner sprung mass m_s = chassis share + half of each wishbone;
2. ride rate k_ride = m_s (2 pi f)^2; wheel rate k_w = k_ride k_t / (k_t - k_ride)
   (the tyre acts in series);
3. motion ratio MR = d(spring length) / d(wheel travel), from the lower
   arm's kinematics (finite difference about the design position; the
   upright's small rotation is ignored);
4. spring rate k_s = k_w / MR^2, damper c_s = 2 zeta sqrt(k_w m_s) / MR^2;
5. preload: the spring's rest length is its design length plus
   m_s g / (MR k_s), so the car sits at the design ride height; the tyre's
   spring_mount likewise offsets the static load it carries.

| axle | MR | m_s kg | k_ride N/m | k_w N/m | k_s N/m | c_w N s/m | c_s N s/m | design length m | rest length m | corner load N |
|---|---|---|---|---|---|---|---|---|---|---|
{rows}

## Linkage
Each corner: lower and upper wishbones on revolute joints to the chassis,
the upright on a ball joint at the lower wishbone and pinned (RaiSim <pin>)
to the upper one, the hub on a radial prismatic joint with the tyre's
spring-damper, and the wheel on a continuous joint. Steering: a rack on a
prismatic joint in the chassis (travel +/- 0.06 m) with tie rods as
distance closures to the front uprights' steering arms; rear toe links are
distance closures from the chassis to the rear uprights. 35 degrees of
freedom, 16 closure equations: 19 free motions (6 chassis, rack, and per
corner heave, tyre and wheel spin).

## Credits and licence
The meshes in meshes/ and this URDF are made by this project with
generate.py (simple tubes, boxes and lathed profiles); released under CC0
(public domain). No third-party data.
"""

if __name__ == "__main__":
    main()
