#!/usr/bin/env python3
"""Independent check of `gripopt export`'s MuJoCo models with the PyPI `mujoco` package.

Usage: check_mjcf.py GRIPOPT_BIN PROBLEM CHECK_DIR [--nominal] [--report]

Exports the problem's nominal design (centred and free scenes, build sheet) with the built
`gripopt` binary into CHECK_DIR, asks the same binary for its own results at test time
(`evaluate --json`, `simulate --no-contact --csv`), and checks MuJoCo against them:

1. the models load; the open pose (qpos0 and the keyframe `grasp`) equals gripopt's open
   angles to 1e-9 rad; MuJoCo's forward kinematics puts O12, O22, O13 and the tips where
   gripopt's lengths and angles put them (1e-12 m), finger 2 the mirror of finger 1, and
   the loop closes at O13 to 1e-9 m;
2. masses and inertias about the joints equal gripopt's (`evaluate`) and, with --nominal,
   MODEL.md §3.4's numbers (1e-9 relative); the spring actuator holds τ_s0, and MuJoCo's
   own closed-loop dynamics confirm it: at rest at the open pose with the motor torque τ,
   θ̈2 = 0 (the definition of τ_s^min, MODEL.md §6.2);
3. closing on nothing (contacts off, the distal stop's Hunt–Crossley law of §8.4 applied
   as a passive force, the file's joint-limit stop off), θ1 and θ2 follow gripopt's
   `simulate --no-contact` to 1e-4 rad over the first 10 ms, the loop stays closed to
   1e-9 m and finger 2 mirrors finger 1; with the file's own joint-limit stop, to 1e-4 rad;
4. the centred scene's first contact (the phalanx–object distance, capsule to cylinder on
   MuJoCo's body poses, root-found by bisection on RK4 sub-steps) equals gripopt's
   t_first_contact to 1e-5 relative, on the same phalanx;
5. restitution: a 1-DOF impact with the file's contact solref/solimp, step and integrator
   rebounds with e within 0.05 of MODEL.md's e (the file's `gripopt_restitution`);
6. the build sheet (JSON and CSV) holds gripopt's lengths and MuJoCo's joint positions (mm);
7. a run's front design (CHECK_DIR/run, written by tests/export.rs, its first pareto.csv
   id) exported as `RUN_DIR --design ID`: its first contact as in 4, against `gripopt
   evaluate` of its parameters; in both scenes, and the nominal free scene, it simulates
   0.2 s with the file as it is: no MuJoCo warning, finite state, loop closed;
8. `--object can` of kitchen.toml (beside PROBLEM): the object body's mass and cylinder are
   the can's of kitchen.toml (read with tomllib), and it simulates as in 7.

--report prints the side-by-side table of docs/export.md (gripopt and MuJoCo on the design).
Prints one line per check and 'mjcf: N passed, N failed'; exits non-zero on any failure.
"""
import copy
import csv
import json
import math
import pathlib
import subprocess
import sys
import tomllib

import mujoco
import numpy as np

# MODEL.md §3.4 (nominal design and scene), compared at 1e-9 relative
NOMINAL = {
    "l11": 0.01976, "l22": 0.0090896, "l12": 0.045419424436,
    "q11_0": -44.441240127, "q21_0": 45.558759873, "q12_0": 106.332636305, "q22_0": -129.76,
    "m": [2.141686543805e-3, 4.922781889786e-3, 5.354216359513e-3, 5.060449800387e-3],
    "I": [2.921314701809e-7, 3.415875879736e-6, 4.388868997281e-6, 1.979246277171e-6],
    "s22": [-8.798342151567e-3, 1.163856653168e-2],
}
BODIES = ["link11", "link12", "link21", "body22"]


# ------------------------------------------------------------------------ gripopt side
def gripopt(binary, *args):
    r = subprocess.run([binary, *map(str, args)], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"gripopt {' '.join(map(str, args))} exited {r.returncode}: {r.stderr.strip()}")
    return r.stdout


def export(binary, source, out, *extra):
    gripopt(binary, "export", source, "--out", out, "--force", *extra)
    return out


def read_csv(path):
    with open(path, newline="") as f:
        # the `#` title and units lines first (docs/outputs.md)
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(l for l in f if not l.startswith("#"))]


# ------------------------------------------------------------------------- MuJoCo side
def load(path):
    m = mujoco.MjModel.from_xml_path(str(path))
    return m, mujoco.MjData(m)


def num(m, name):
    return float(m.numeric(name).data[0])


class ExactStop:
    """MODEL.md §8.4's Hunt–Crossley stop on both distal joints as a passive force, with the
    file's joint-limit approximation switched off (a context manager)."""

    def __init__(self, m):
        self.m = m
        self.k, self.c, self.psi = num(m, "gripopt_k_stop"), num(m, "gripopt_c_stop"), num(m, "gripopt_psi")
        self.joints = [(m.joint(f"f{i}_q22").qposadr[0], m.joint(f"f{i}_q22").dofadr[0]) for i in (1, 2)]

    def __call__(self, m, d):
        for qa, da in self.joints:
            phi, phid = -(d.qpos[qa] + self.psi), -d.qvel[da]
            if phi > 0:
                d.qfrc_passive[da] += max(0.0, self.k * phi * (1.0 + self.c * phid))

    def __enter__(self):
        self.flags = self.m.opt.disableflags
        self.m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_LIMIT
        mujoco.set_mjcb_passive(self)
        return self

    def __exit__(self, *exc):
        mujoco.set_mjcb_passive(None)
        self.m.opt.disableflags = self.flags


def grasp_start(m, d):
    mujoco.mj_resetDataKeyframe(m, d, m.key("grasp").id)
    mujoco.mj_forward(m, d)


def step_to(m, d, t):
    """Advance to time t exactly (the last step shortened)."""
    dt = m.opt.timestep
    while d.time < t - 1e-15:
        m.opt.timestep = min(dt, t - d.time)
        mujoco.mj_step(m, d)
    m.opt.timestep = dt


def angles(m, d, finger=1):
    psi = num(m, "gripopt_psi")
    q = lambda n: d.qpos[m.joint(f"f{finger}_{n}").qposadr[0]]  # noqa: E731
    return q("q21"), q("q22") + psi


def loop_gap(d):
    return max(np.linalg.norm(d.site(f"f{i}_O13_bar").xpos - d.site(f"f{i}_O13").xpos) for i in (1, 2))


def segment(m, d, g):
    c, ax, h = d.geom_xpos[g], d.geom_xmat[g].reshape(3, 3)[:, 2], m.geom_size[g][1]
    return c - h * ax, c + h * ax


def segment_distance(p1, q1, p2, q2):
    """Closest distance between segments [p1, q1] and [p2, q2], and the parameter on the second."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f, c, b = d1 @ d1, d2 @ d2, d2 @ r, d1 @ r, d1 @ d2
    den = a * e - b * b
    s = min(max((b * f - c * e) / den, 0.0), 1.0) if den > 1e-300 else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t, s = 0.0, min(max(-c / a, 0.0), 1.0)
    elif t > 1.0:
        t, s = 1.0, min(max((b - c) / a, 0.0), 1.0)
    return float(np.linalg.norm(p1 + s * d1 - (p2 + t * d2))), t


def phalanx_gaps(m, d):
    """Phalanx capsule to object cylinder distance (side contact: axis distance − R − w)."""
    ob = m.geom("object").id
    a, b = segment(m, d, ob)
    out = {}
    for name in ("f1_proximal", "f1_distal", "f2_proximal", "f2_distal"):
        g = m.geom(name).id
        p, q = segment(m, d, g)
        dist, t = segment_distance(p, q, a, b)
        if not 0.0 < t < 1.0:
            raise ValueError(f"{name} meets the object's rim, not its side")
        out[name] = dist - m.geom_size[ob][0] - m.geom_size[g][0]
    return out


def first_contact(m, d):
    """Time and phalanx of the first zero of the phalanx–object distance: step, then bisect
    the last step with shortened RK4 steps from a copy of the state before it."""
    grasp_start(m, d)
    dt = m.opt.timestep
    while True:
        before = copy.copy(d)
        mujoco.mj_step(m, d)
        gaps = phalanx_gaps(m, d)
        if min(gaps.values()) <= 0.0:
            break
        if d.time > 0.1:
            raise ValueError("no contact within 0.1 s")
    name = min(gaps, key=gaps.get)
    lo, hi = 0.0, dt
    while hi - lo > 1e-15:
        mid = 0.5 * (lo + hi)
        probe = copy.copy(before)
        m.opt.timestep = mid
        mujoco.mj_step(m, probe)
        if phalanx_gaps(m, probe)[name] <= 0.0:
            hi = mid
        else:
            lo = mid
    m.opt.timestep = dt
    return before.time + hi, name.split("_")[1]


def restitution(m, v_in):
    """e of a 1-DOF impact (a capsule of the phalanx radius on a slide joint onto a plane,
    no gravity) with the file's object-contact solref/solimp, step and integrator."""
    p = m.pair("f1_proximal_object").id
    solref, solimp = m.pair_solref[p], m.pair_solimp[p]
    w = num(m, "gripopt_w")
    integ = mujoco.mjtIntegrator(m.opt.integrator).name.replace("mjINT_", "")
    xml = f"""<mujoco><option timestep="{float(m.opt.timestep)!r}" integrator="{integ}" gravity="0 0 0"/>
      <worldbody><geom name="wall" type="plane" size="1 1 0.1"/>
      <body pos="0 0 {w + 1e-4!r}"><joint type="slide" axis="0 0 1"/>
      <inertial pos="0 0 0" mass="0.05" diaginertia="1e-6 1e-6 1e-6"/>
      <geom name="rod" type="capsule" fromto="-0.02 0 0 0.02 0 0" size="{w!r}" contype="0" conaffinity="0"/></body>
      </worldbody><contact><pair geom1="rod" geom2="wall" condim="1"
      solref="{' '.join(repr(float(x)) for x in solref)}" solimp="{' '.join(repr(float(x)) for x in solimp)}"/></contact></mujoco>"""
    mm = mujoco.MjModel.from_xml_string(xml)
    dd = mujoco.MjData(mm)
    dd.qvel[0] = -v_in
    touched = False
    for _ in range(200000):
        mujoco.mj_step(mm, dd)
        touched |= dd.ncon > 0
        if touched and dd.ncon == 0:
            return dd.qvel[0] / v_in
    raise ValueError("no rebound")


def simulate_plain(path, seconds):
    """The file as it is (its own stop and contacts) from the keyframe `grasp`."""
    m, d = load(path)
    grasp_start(m, d)
    mujoco.mj_step(m, d, nstep=int(round(seconds / m.opt.timestep)))
    warnings = {mujoco.mjtWarning(i).name: int(d.warning[i].number) for i in range(len(d.warning)) if d.warning[i].number}
    return m, d, warnings


# ------------------------------------------------------------------------------ checks
class Checks:
    def __init__(self):
        self.ok = self.bad = 0

    def __call__(self, name, passed, detail):
        print(f"{'ok  ' if passed else 'FAIL'} {name}: {detail}")
        if passed:
            self.ok += 1
        else:
            self.bad += 1

    def run(self, name, fn):
        try:
            fn()
        except Exception as e:  # noqa: BLE001 - report every failure
            self(name, False, f"{type(e).__name__}: {e}")


def check_open_pose(chk, m, d, ev, nominal):
    grasp_start(m, d)
    want = [ev["q11_0"], ev["q12_0"], ev["q21_0"], ev["q22_0"]]
    got = [[m.qpos0[m.joint(f"f{i}_{j}").qposadr[0]] for j in ("q11", "q12", "q21", "q22")] for i in (1, 2)]
    key = [[d.qpos[m.joint(f"f{i}_{j}").qposadr[0]] for j in ("q11", "q12", "q21", "q22")] for i in (1, 2)]
    err = max(abs(a - b) for g in got + key for a, b in zip(g, want))
    chk("open pose", err <= 1e-9, f"qpos0 and keyframe vs gripopt's open angles: max |Δq| = {err:.2e} rad (≤ 1e-9)")
    if nominal:
        deg = [NOMINAL[k] for k in ("q11_0", "q12_0", "q21_0", "q22_0")]
        rel = max(abs(math.degrees(a) - b) / abs(b) for a, b in zip(got[0], deg))
        chk("open pose, MODEL.md §3.4", rel <= 1e-9, f"max relative difference {rel:.2e} (≤ 1e-9)")
    # forward kinematics against gripopt's lengths and angles (finger 1; finger 2 mirrored)
    o11 = np.array([ev["b"] / 2, 0.0])
    e = lambda a: np.array([math.cos(a), math.sin(a)])  # noqa: E731
    q11, q12, q21, q22 = want
    pts = {"O12": o11 + ev["l11"] * e(q11), "O22": o11 + ev["l21"] * e(q21)}
    pts["O13"] = pts["O22"] + ev["l22"] * e(q21 + q22)
    pts["O13_bar"] = pts["O12"] + ev["l12"] * e(q11 + q12)
    pts["tip"] = pts["O22"] + ev["t22"] * e(q21 + q22 + math.radians(ev["psi_deg"]))
    worst = 0.0
    for i, sign in ((1, 1.0), (2, -1.0)):
        for name, p in pts.items():
            x = d.site(f"f{i}_{name}").xpos
            worst = max(worst, abs(x[0] - sign * p[0]), abs(x[1] - p[1]), abs(x[2]))
    chk("joint points", worst <= 1e-12, f"MuJoCo's O12, O22, O13, tips vs gripopt's lengths and angles, finger 2 mirrored: max {worst:.2e} m (≤ 1e-12)")
    gap = loop_gap(d)
    chk("loop closure", gap <= 1e-9, f"|O13 (link 12) − O13 (body 22)| = {gap:.2e} m at the open pose (≤ 1e-9)")
    if nominal:
        rel = max(abs(ev[k] - NOMINAL[k]) / NOMINAL[k] for k in ("l11", "l12", "l22"))
        chk("lengths, MODEL.md §3.4", rel <= 1e-9, f"l11, l12, l22 of the exported design: max relative difference {rel:.2e}")


def joint_inertia(m, body):
    """Inertia about the body's joint axis (its z axis through its origin)."""
    b = m.body(body).id
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, m.body_iquat[b])
    rot = rot.reshape(3, 3)
    izz = (rot @ np.diag(m.body_inertia[b]) @ rot.T)[2, 2]
    p = m.body_ipos[b]
    return izz + m.body_mass[b] * (p[0] ** 2 + p[1] ** 2)


def check_masses(chk, m, d, ev, nominal):
    for i in (1, 2):
        masses = [m.body_mass[m.body(f"f{i}_{b}").id] for b in BODIES]
        rel = max(abs(a - b) / b for a, b in zip(masses, ev["masses"]))
        chk(f"masses f{i}", rel <= 1e-12, f"m11, m12, m21, m22 vs gripopt evaluate: max relative difference {rel:.2e}")
        if nominal:
            inert = [joint_inertia(m, f"f{i}_{b}") for b in BODIES]
            rel_i = max(abs(a - b) / b for a, b in zip(inert, NOMINAL["I"]))
            rel_m = max(abs(a - b) / b for a, b in zip(masses, NOMINAL["m"]))
            s22 = m.body_ipos[m.body(f"f{i}_body22").id][:2]
            rel_s = max(abs(a - b) / abs(b) for a, b in zip(s22, NOMINAL["s22"]))
            worst = max(rel_i, rel_m, rel_s)
            chk(f"masses f{i}, MODEL.md §3.4", worst <= 1e-9,
                f"masses {rel_m:.1e}, inertias about the joints {rel_i:.1e}, COM of body 22 {rel_s:.1e} (relative, ≤ 1e-9)")
    ob = m.body("object").id
    mc = math.pi * num(m, "gripopt_radius") ** 2 * num(m, "gripopt_length") * 1000.0 if nominal else None
    if nominal:
        chk("object mass", abs(m.body_mass[ob] - mc) <= 1e-12 * mc, f"m_c = {m.body_mass[ob]:.9f} kg (MODEL.md §4: ρ_c π R² L_c)")


def check_spring(chk, m, d, ev, nominal):
    bias = [m.actuator_biasprm[m.actuator(f"f{i}_spring").id][0] for i in (1, 2)]
    err = max(abs(-b - ev["tau_s0"]) for b in bias)
    chk("spring preload", err <= 1e-15, f"actuator bias −τ_s0 vs gripopt's τ_s0 = {ev['tau_s0']:.12g} N·m: |Δ| = {err:.1e}")
    # MODEL.md §6.2: τ_s^min makes θ̈2 = 0 at rest at the open pose under τ (no contact). The
    # loop constraint solved hard with MuJoCo's own mass matrix and constraint Jacobian (its
    # soft constraint lets 1 − d = 1e-4 of the unconstrained acceleration through)
    grasp_start(m, d)
    full = np.zeros((m.nv, m.nv))
    try:  # MuJoCo ≥ 3.3: mj_fullM(m, d, dst); before: mj_fullM(m, dst, d.qM)
        mujoco.mj_fullM(m, d, full)
    except TypeError:
        mujoco.mj_fullM(m, full, d.qM)
    rows = [i for i in range(d.nefc) if d.efc_type[i] == mujoco.mjtConstraint.mjCNSTR_EQUALITY]
    jac = d.efc_J.reshape(d.nefc, m.nv)[rows] if not mujoco.mj_isSparse(m) else None
    force = d.qfrc_actuator + d.qfrc_passive - d.qfrc_bias
    kkt = np.block([[full, jac.T], [jac, np.zeros((len(rows), len(rows)))]])
    sol = np.linalg.lstsq(kkt, np.concatenate([force, np.zeros(len(rows))]), rcond=1e-14)[0]
    a2 = [sol[m.joint(f"f{i}_q22").dofadr[0]] for i in (1, 2)]
    a1 = sol[m.joint("f1_q21").dofadr[0]]
    ratio = max(abs(a) for a in a2) / abs(a1)
    ok = ev["tau_s_min"] <= 0 or ratio <= 1e-9
    chk("spring balance", ok, f"at rest at the open pose, MuJoCo's closed-loop |θ̈2| / |θ̈1| = {ratio:.1e} (τ_s0 = τ_s^min ⇒ 0; ≤ 1e-9), θ̈1 = {a1:.5g} rad/s²")
    if nominal:
        chk("initial acceleration, MODEL.md §9.4", abs(a1 / 1.65e4 - 1) <= 0.005, f"|q̈(0)| = {a1:.5g} rad/s² (MODEL.md: 1.65e4, 3 digits)")


def check_closing(chk, m, d, rows, plain):
    """θ1, θ2 against gripopt's --no-contact trajectory over 10 ms; returns the max error."""
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    try:
        def follow():
            grasp_start(m, d)
            worst = gap = mirror = 0.0
            for r in rows:
                if r["t"] > 0.010:
                    break
                step_to(m, d, r["t"])
                t1, t2 = angles(m, d)
                worst = max(worst, abs(t1 - r["q21"]), abs(t2 - r["theta2"]))
                mirror = max(mirror, *(abs(a - b) for a, b in zip(angles(m, d, 2), (t1, t2))))
                gap = max(gap, loop_gap(d))
            return worst, gap, mirror, len([r for r in rows if r["t"] <= 0.010])
        if plain:
            worst, gap, mirror, n = follow()
            chk("closing on nothing, file's stop", worst <= 1e-4,
                f"the file's joint-limit stop: max |Δθ| = {worst:.2e} rad over 10 ms (≤ 1e-4)")
            return worst
        with ExactStop(m):
            worst, gap, mirror, n = follow()
        chk("closing on nothing", worst <= 1e-4,
            f"θ1, θ2 vs gripopt simulate --no-contact at its {n} samples in 10 ms: max |Δθ| = {worst:.2e} rad (≤ 1e-4)")
        chk("loop closure while closing", gap <= 1e-9, f"max |O13 gap| over 10 ms = {gap:.2e} m (≤ 1e-9)")
        chk("mirror", mirror <= 1e-12, f"finger 2's angles equal finger 1's to {mirror:.1e} rad")
        return worst
    finally:
        m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_CONTACT)


def check_first_contact(chk, m, d, ev):
    with ExactStop(m):
        t, phalanx = first_contact(m, d)
    rel = abs(t - ev["t_first_contact"]) / ev["t_first_contact"]
    chk("first contact", rel <= 1e-5 and phalanx == ev["first_contact_phalanx"],
        f"MuJoCo {t:.10e} s on the {phalanx} vs gripopt {ev['t_first_contact']:.10e} s on the "
        f"{ev['first_contact_phalanx']}: relative {rel:.1e} (≤ 1e-5)")
    return t, phalanx


def check_restitution(chk, m):
    e = num(m, "gripopt_restitution")
    es = [restitution(m, v) for v in (0.05, 0.2, 0.5, 1.0, 1.55, 2.5)]
    ok = all(abs(x - e) <= 0.05 for x in es)
    chk("restitution", ok, f"1-DOF impacts at 0.05–2.5 m/s rebound with e = {min(es):.3f}…{max(es):.3f} (mean {np.mean(es):.3f}; MODEL.md e = {e}, ±0.05)")
    return es


def check_sheet(chk, sheet_json, sheet_csv, m, d, ev):
    s = json.loads(pathlib.Path(sheet_json).read_text())
    grasp_start(m, d)
    worst = 0.0
    for i in (1, 2):
        for pt in ("O12", "O22", "O13", "tip"):
            x = d.site(f"f{i}_{pt}").xpos * 1e3
            sx, sy = s["open_pose"][f"finger{i}_{pt}_x_mm"], s["open_pose"][f"finger{i}_{pt}_y_mm"]
            worst = max(worst, abs(sx - x[0]), abs(sy - x[1]))
    lens = max(abs(s["lengths"][f"{k}_mm"] - ev[k] * 1e3) for k in ("l11", "l12", "l21", "l22", "t22"))
    with open(sheet_csv, newline="") as f:
        rows = {(r["section"], r["name"]): float(r["value"]) for r in csv.DictReader(line for line in f if not line.startswith("#"))}
    pairs = [(("lengths", "l12"), s["lengths"]["l12_mm"]), (("torques", "tau_s0"), s["torques"]["tau_s0_Nm"]),
             (("masses", "m22"), s["masses"]["m22_g"]), (("open_pose", "finger2_tip_x"), s["open_pose"]["finger2_tip_x_mm"])]
    same = all(rows[k] == v for k, v in pairs)
    ok = worst <= 1e-9 and lens <= 1e-12 and same and abs(s["torques"]["tau_s0_Nm"] - ev["tau_s0"]) <= 1e-15
    chk("build sheet", ok, f"joint positions vs MuJoCo's sites: max {worst:.1e} mm; lengths vs gripopt: {lens:.1e} mm; CSV = JSON: {same}")


def check_runs(chk, files, seconds=0.2):
    for path in files:
        m, d, warn = simulate_plain(path, seconds)
        finite = bool(np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all())
        gap = loop_gap(d)
        extra = ""
        if num(m, "gripopt_free"):
            a = d.xmat[m.body("object").id].reshape(3, 3)[:, 2]
            extra = f", object tilt {math.degrees(math.acos(min(1.0, a[2]))):.3f}°"
        chk(f"simulate {pathlib.Path(path).name}", not warn and finite and gap <= 1e-6,
            f"{seconds} s from the keyframe: warnings {warn or 'none'}, finite state {finite}, loop gap {gap:.1e} m{extra}")


def front_design(run_dir):
    """The first design of a run's pareto.csv: its id and `--design` assignments."""
    with open(pathlib.Path(run_dir) / "pareto.csv", newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    if not rows:
        raise ValueError(f"{run_dir}/pareto.csv: no feasible design")
    r = rows[0]
    return r["id"], ",".join(f"{k}={r[k]}" for k in ("l21", "b", "t22", "r", "p", "psi_deg"))


def check_front(chk, binary, run_dir, out):
    """The run's front design exported by id: its first contact against gripopt's
    evaluation of the same parameters with the run's problem; returns the exported files."""
    ident, assign = front_design(run_dir)
    files = [export(binary, run_dir, out / f"front-{ident}-{sc}.xml", "--design", ident, "--scene", sc) for sc in ("centred", "free")]
    ev = json.loads(gripopt(binary, "evaluate", pathlib.Path(run_dir) / "problem.toml", "--design", assign, "--json"))
    m, d = load(files[0])
    with ExactStop(m):
        t, phalanx = first_contact(m, d)
    rel = abs(t - ev["t_first_contact"]) / ev["t_first_contact"]
    chk(f"first contact, front design {ident}", rel <= 1e-5 and phalanx == ev["first_contact_phalanx"],
        f"MuJoCo {t:.10e} s on the {phalanx} vs gripopt {ev['t_first_contact']:.10e} s on the {ev['first_contact_phalanx']}: relative {rel:.1e}")
    return files


def check_object(chk, binary, problem, out):
    """`--object can` of kitchen.toml (beside PROBLEM): MuJoCo's object body has the can's
    mass rho pi R^2 L and cylinder, read from kitchen.toml with tomllib, not the reference
    object's; returns the exported file (simulated with the others)."""
    kitchen = pathlib.Path(problem).with_name("kitchen.toml")
    with open(kitchen, "rb") as f:
        spec = tomllib.load(f)
    can = next(o for o in spec["robust"]["objects"] if o["name"] == "can")
    ref = spec["object"]
    mass = lambda o: o["density"] * math.pi * o["radius"] ** 2 * o["length"]  # noqa: E731
    path = export(binary, kitchen, out / "kitchen-can.xml", "--object", "can")
    m, _ = load(path)
    body = m.body("object")
    got, size = float(m.body_mass[body.id]), m.geom("object").size
    rel = abs(got - mass(can)) / mass(can)
    ok = rel <= 1e-12 and abs(size[0] - can["radius"]) <= 1e-15 and abs(size[1] - can["length"] / 2) <= 1e-15
    chk("--object can", ok and abs(got - mass(ref)) > 0.1,
        f"object body mass {got:.10f} kg vs kitchen.toml's can {mass(can):.10f} kg (relative {rel:.1e}; reference object {mass(ref):.4f} kg), "
        f"cylinder R {size[0]} m, L/2 {size[1]} m")
    return path


# ------------------------------------------------------------------- docs/export.md table
def phalanx_forces(m, d):
    """Normal force on each of finger 1's phalanges (N)."""
    f, out = np.zeros(6), {"proximal": 0.0, "distal": 0.0}
    for i in range(d.ncon):
        c = d.contact[i]
        for ph in out:
            if m.geom(f"f1_{ph}").id in (c.geom1, c.geom2):
                mujoco.mj_contactForce(m, d, i, f)
                out[ph] += f[0]
    return out


def free_run(path, seconds, phalanx_friction=True):
    """The free scene with the exact stop: largest horizontal displacement and tilt of the
    object, friction work on the phalanx contacts in the first 0.5 ms of contact, the
    object's peak translational kinetic energy then."""
    m, d = load(path)
    if not phalanx_friction:
        for i in (1, 2):
            for p in ("proximal", "distal"):
                m.pair_friction[m.pair(f"f{i}_{p}_object").id][:2] = 0.0
    ph = {m.geom(f"f{i}_{p}").id for i in (1, 2) for p in ("proximal", "distal")}
    ob = m.body("object").id
    out = {"disp": 0.0, "tilt": 0.0, "work": 0.0, "e_trans": 0.0}
    with ExactStop(m):
        grasp_start(m, d)
        g0, t_on = d.xpos[ob][:2].copy(), None
        for _ in range(int(round(seconds / m.opt.timestep))):
            mujoco.mj_step(m, d)
            power = 0.0
            for c in d.contact[: d.ncon]:
                if (c.geom1 in ph or c.geom2 in ph) and c.efc_address >= 0:
                    t_on = d.time if t_on is None else t_on
                    a = c.efc_address
                    power += d.efc_force[a + 1] * d.efc_vel[a + 1] + d.efc_force[a + 2] * d.efc_vel[a + 2]
            if t_on is not None and d.time - t_on <= 5e-4:
                out["work"] += power * m.opt.timestep
                v = d.qvel[m.joint("object_free").dofadr[0]:][:3]
                out["e_trans"] = max(out["e_trans"], 0.5 * m.body_mass[ob] * float(v @ v))
            out["disp"] = max(out["disp"], float(np.linalg.norm(d.xpos[ob][:2] - g0)))
            axis = d.xmat[ob].reshape(3, 3)[:, 2]
            out["tilt"] = max(out["tilt"], math.degrees(math.acos(min(1.0, axis[2]))))
    return out


def report(binary, problem, out, centred, free, ev):
    """The side-by-side table of docs/export.md, in Markdown."""
    grasp_csv = out / "grasp.csv"
    gripopt(binary, "simulate", problem, "--force", "--csv", grasp_csv)
    rows = read_csv(grasp_csv)
    tight = json.loads(gripopt(binary, "simulate", problem, "--rtol", "1e-10", "--json"))
    gfree = json.loads(gripopt(binary, "simulate", problem, "--scene", "free", "--json"))
    nc = read_csv(out / "no-contact.csv")
    m, d = load(centred)
    with ExactStop(m):
        t_fc, ph = first_contact(m, d)
    t_fc_file, ph_file = first_contact(m, d)
    quiet = Checks()
    import io
    import contextlib
    with contextlib.redirect_stdout(io.StringIO()):
        nc_exact = check_closing(quiet, m, d, nc, plain=False)
        nc_file = check_closing(quiet, m, d, nc, plain=True)
    es = [restitution(m, v) for v in (0.05, 0.2, 0.5, 1.0, 1.55, 2.5)]
    print("\n| quantity | gripopt | MuJoCo (exported file) |\n|---|---|---|")
    print(f"| first contact time (s) | {ev['t_first_contact']:.10e} (rtol 1e-6); {tight['t_first_contact']:.10e} (rtol 1e-10) "
          f"| {t_fc:.10e} (exact stop, rel. {abs(t_fc / tight['t_first_contact'] - 1):.1e}); {t_fc_file:.10e} (the file's stop) |")
    print(f"| first contact phalanx | {ev['first_contact_phalanx']} | {ph} ({ph_file}) |")
    print(f"| closing on nothing, max abs(Δθ) over 10 ms | — | {nc_exact:.1e} rad (exact stop), {nc_file:.1e} rad (the file's stop) |")
    with ExactStop(m):
        grasp_start(m, d)
        # at gripopt's own samples nearest to these times (its steps are long: no interpolation)
        picks = sorted({min(rows, key=lambda r: abs(r["t"] - t))["t"] for t in (0.002, 0.004, 0.005, 0.006, 0.008, 0.010, 0.015)} | {rows[-1]["t"]})
        for t in picks:
            r = next(r for r in rows if r["t"] == t)
            step_to(m, d, t)
            t1, t2 = angles(m, d)
            print(f"| θ1, θ2 at t = {t * 1e3:.4f} ms (deg) | {math.degrees(r['q21']):.4f}, {math.degrees(r['theta2']):.4f} "
                  f"| {math.degrees(t1):.4f}, {math.degrees(t2):.4f} |")
        step_to(m, d, 0.1)
        f = phalanx_forces(m, d)
    print(f"| normal forces at rest (N), proximal, distal | f* = {ev['fstar_1']:.3f}, {ev['fstar_2']:.3f} (f⁰ = {ev['f0_1']:.3f}, {ev['f0_2']:.3f}) "
          f"| {f['proximal']:.3f}, {f['distal']:.3f} at 100 ms |")
    print(f"| restitution e (1-DOF impact) | 0.2562 (Flores law at e = 0.3, MODEL.md §11.7) | {min(es):.3f}…{max(es):.3f} (mean {np.mean(es):.3f}) |")
    fr = free_run(free, 0.1)
    print(f"| free object: max horizontal displacement in 0.1 s | {gfree['object_max_displacement'] * 1e3:.4f} mm | {fr['disp'] * 1e3:.4f} mm |")
    print(f"| free object: max tilt in 0.1 s | {gfree['object_max_tilt_deg']:.4f}° | {fr['tilt']:.4f}° |")
    print(f"| free object: peak translational energy, first contact | {gfree['object_peak_e_trans'] * 1e3:.4f} mJ | {fr['e_trans'] * 1e3:.4f} mJ |")
    print(f"| friction work on the phalanx contacts, first 0.5 ms of contact | ≤ 0 (MODEL.md §8.6: F_t u ≤ 0) | {fr['work'] * 1e3:+.4f} mJ |")
    nf = free_run(free, 0.1, phalanx_friction=False)
    print(f"| free object, phalanx friction off in MuJoCo: max displacement, peak energy | — | {nf['disp'] * 1e3:.4f} mm, {nf['e_trans'] * 1e3:.4f} mJ |")


def main(argv):
    flags = {a for a in argv if a.startswith("--")}
    args = [a for a in argv if not a.startswith("--")]
    if len(args) != 3:
        print(__doc__)
        return 2
    binary, problem, out = args
    nominal = "--nominal" in flags
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    chk = Checks()
    ev = json.loads(gripopt(binary, "evaluate", problem, "--json"))
    nc_csv = out / "no-contact.csv"
    gripopt(binary, "simulate", problem, "--no-contact", "--force", "--csv", nc_csv)
    rows = read_csv(nc_csv)
    centred = export(binary, problem, out / "nominal-centred.xml", "--scene", "centred")
    free = export(binary, problem, out / "nominal-free.xml", "--scene", "free")
    sheet_json = export(binary, problem, out / "nominal-sheet.json")
    sheet_csv = export(binary, problem, out / "nominal-sheet.csv")
    print(f"mujoco {mujoco.__version__}; {binary}; {problem}")
    m, d = load(centred)
    chk("load", True, f"{centred.name}: nq {m.nq}, nv {m.nv}, {m.neq} loop constraints, {m.npair} contact pairs")
    chk.run("open pose", lambda: check_open_pose(chk, m, d, ev, nominal))
    chk.run("masses", lambda: check_masses(chk, m, d, ev, nominal))
    chk.run("spring", lambda: check_spring(chk, m, d, ev, nominal))
    chk.run("closing", lambda: check_closing(chk, m, d, rows, plain=False))
    chk.run("closing, file's stop", lambda: check_closing(chk, m, d, rows, plain=True))
    chk.run("first contact", lambda: check_first_contact(chk, m, d, ev))
    chk.run("restitution", lambda: check_restitution(chk, m))
    chk.run("build sheet", lambda: check_sheet(chk, sheet_json, sheet_csv, m, d, ev))
    runs = [free]
    run_dir = out / "run"
    try:
        runs += check_front(chk, binary, run_dir, out)
    except Exception as e:  # noqa: BLE001
        chk("front design", False, f"{run_dir} (written by tests/export.rs): {type(e).__name__}: {e}")
    try:
        runs.append(check_object(chk, binary, problem, out))
    except Exception as e:  # noqa: BLE001
        chk("--object can", False, f"{type(e).__name__}: {e}")
    chk.run("simulate", lambda: check_runs(chk, runs))
    if "--report" in flags:
        report(binary, problem, out, centred, free, ev)
    print(f"mjcf: {chk.ok} passed, {chk.bad} failed")
    return 1 if chk.bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
