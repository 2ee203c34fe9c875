#!/usr/bin/env python3
"""One block on a fixed base under a ground-motion record in openseespy: the sliding block
and the rocking column of dfem's dynamic tests, for benches/performance.py (section
dynamics) to set beside dfem at the same time steps.

usage: python block_dynamic.py slide|rock --record FILE (.csv in g, or PEER .AT2)
                               --dt S [--mu 0.2] [--breadth B] [--height H] [--alpha 0.95]

The block is dfem's (tests/common/mod.rs, `box_on_base` and `rock_and_joint`): rock with
Lamé λ = 56 GPa, μ = 21 GPa (E = 57 GPa; ν = 0 here, docs/decisions/0040-opensees-block-dynamics.md),
unit weight 25 kN/m³, on a joint of normal modulus 50 GPa and shear modulus 5 GPa over a
band of 1 cm, friction coefficient `--mu`. `slide`: 1 m × 0.5 m, μ = 0.2 unless given;
`rock`: `--breadth` × `--height` (default 0.6 m × 3 m), μ = 1 so that it rocks without
sliding. In OpenSees the block is two tri31 triangles (plane strain, thickness 1 m, mass
lumped at its corners) and the joint two zeroLengthContact2D elements at its bottom
corners, each with the stiffness of half the joint (k = E_n / band × breadth / 2, divided
by `--soften`). Gravity is applied statically, then the record as a UniformExcitation
(displacements relative to the ground, as dfem writes them) with HHT (`--alpha`: OpenSees'
α, 1 = trapezoidal; 0.95 is dfem's default α = 0.05), Newton and UmfPack (the friction
tangent is unsymmetric); a step Newton does not converge is retried with KrylovNewton,
ModifiedNewton, then in halves down to 1/64 of the step.

Prints one JSON line: the largest slip |u_x| of the bottom-left corner (m), the largest
rotation |θ| ≈ |u_y(right) − u_y(left)| / B (rad; small rotations: tri31 is
small-displacement), the time of the first uplift of a corner by more than 10⁻⁵ m, the
steps, the wall time (s) of the whole (`total_s`, model building included) and of the
time steps alone, whether it reached the record's end and how many steps Newton alone
did not converge.
"""
import argparse
import json
import os
import time

import numpy as np
import openseespy.opensees as ops

G = 9.81
LAME_L, LAME_M, UNIT_WEIGHT = 56e9, 21e9, 25e3
JOINT_EN, JOINT_GS, JOINT_BAND = 50e9, 5e9, 0.01
UPLIFT = 1e-5  # m, a corner counts as lifted above this


def read_record(path):
    """(dt s, accelerations in g) of a CSV (time, acceleration; a header line) or PEER .AT2."""
    if path.lower().endswith(".at2"):
        lines = open(path).read().splitlines()
        head = lines[3].upper()
        dt = float(head.split("DT=")[1].split()[0])
        return dt, np.array([float(v) for line in lines[4:] for v in line.split()])
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return data[1, 0] - data[0, 0], data[:, 1]


def build(breadth, height, mu, soften=1.0):
    """The block, its two corner contacts and their fixed base; the block's mass (kg)."""
    young = LAME_M * (3 * LAME_L + 2 * LAME_M) / (LAME_L + LAME_M)
    ops.wipe()
    ops.logFile(os.devnull, "-noEcho")  # its warnings at each retried step
    ops.model("basic", "-ndm", 2, "-ndf", 2)
    # ν = 0: the weight would spread the corners against the friction (at μ = 0.1 both
    # slip apart and the static gravity step is singular); the mass is lumped below, not ρ
    ops.nDMaterial("ElasticIsotropic", 1, young, 0.0, 0.0)
    corners = [(0.0, 0.0), (breadth, 0.0), (breadth, height), (0.0, height)]
    mass = UNIT_WEIGHT / G * breadth * height
    for n, (x, y) in enumerate(corners, start=1):
        ops.node(n, x, y)
        ops.mass(n, mass / 4, mass / 4)
    ops.element("tri31", 1, 1, 2, 3, 1.0, "PlaneStrain", 1)
    ops.element("tri31", 2, 1, 3, 4, 1.0, "PlaneStrain", 1)
    kn = JOINT_EN / JOINT_BAND * breadth / 2 / soften
    kt = JOINT_GS / JOINT_BAND * breadth / 2 / soften
    for n in (1, 2):
        x, y = corners[n - 1]
        ops.node(10 + n, x, y)
        ops.fix(10 + n, 1, 1)
        # the block's corner is the constrained node, the base's the retained one (normal up)
        ops.element("zeroLengthContact2D", 20 + n, n, 10 + n, kn, kt, mu, "-normal", 0.0, 1.0)
    return mass


def solver():
    ops.constraints("Plain")
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.algorithm("Newton")


def apply_gravity(mass):
    ops.timeSeries("Linear", 1)
    ops.pattern("Plain", 1, 1)
    for n in range(1, 5):
        ops.load(n, 0.0, -mass / 4 * G)
    solver()
    ops.test("NormDispIncr", 1e-10, 50)
    ops.integrator("LoadControl", 0.2)
    ops.analysis("Static")
    if ops.analyze(5) != 0:
        raise SystemExit("block_dynamic.py: gravity did not converge")
    ops.loadConst("-time", 0.0)
    ops.wipeAnalysis()


FALLBACKS = (("KrylovNewton",), ("ModifiedNewton", "-initial"))


RETRIED = [0]  # steps Newton alone did not converge


def step(dt, depth=0):
    """One step of dt: Newton, then the FALLBACKS (Newton cycles between stick and slip
    at some events), then twice dt/2 the same way, 6 levels deep."""
    if ops.analyze(1, dt) == 0:
        return True
    RETRIED[0] += depth == 0
    for algorithm in FALLBACKS:
        ops.algorithm(*algorithm)
        ok = ops.analyze(1, dt) == 0
        ops.algorithm("Newton")
        if ok:
            return True
    return depth < 6 and step(dt / 2, depth + 1) and step(dt / 2, depth + 1)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("mode", choices=("slide", "rock"))
    p.add_argument("--record", required=True)
    p.add_argument("--dt", type=float, required=True)
    p.add_argument("--mu", type=float, default=None)
    p.add_argument("--breadth", type=float, default=None)
    p.add_argument("--height", type=float, default=None)
    p.add_argument("--alpha", type=float, default=0.95)
    p.add_argument("--soften", type=float, default=1.0, help="divide the contacts' stiffness by this")
    a = p.parse_args()
    slide = a.mode == "slide"
    breadth = a.breadth or (1.0 if slide else 0.6)
    height = a.height or (0.5 if slide else 3.0)
    mu = a.mu if a.mu is not None else (0.2 if slide else 1.0)
    dtr, ag = read_record(a.record)

    t0 = time.perf_counter()
    mass = build(breadth, height, mu, a.soften)
    apply_gravity(mass)
    ops.timeSeries("Path", 2, "-dt", dtr, "-values", *(ag * G).tolist())
    ops.pattern("UniformExcitation", 2, 1, "-accel", 2)
    solver()
    ops.test("NormDispIncr", 1e-10, 50)
    ops.integrator("HHT", a.alpha)
    ops.analysis("Transient")
    t1 = time.perf_counter()
    duration = dtr * (len(ag) - 1)
    steps = int(round(duration / a.dt))
    slip = rot = 0.0
    uplift = None
    ok = True
    for k in range(steps):
        if not step(a.dt):
            ok = False
            break
        slip = max(slip, abs(ops.nodeDisp(1, 1)))
        left, right = ops.nodeDisp(1, 2), ops.nodeDisp(2, 2)
        rot = max(rot, abs(right - left) / breadth)
        if uplift is None and max(left, right) > UPLIFT:
            uplift = ops.getTime()
    t2 = time.perf_counter()
    print(json.dumps(dict(mode=a.mode, dt=a.dt, mu=mu, breadth=breadth, height=height, alpha=a.alpha,
                          steps=k + 1 if ok else k, ok=ok, time_reached=ops.getTime(), max_slip_m=slip,
                          max_rotation_rad=rot, first_uplift_s=uplift, total_s=t2 - t0,
                          steps_s=t2 - t1, retried=RETRIED[0])), flush=True)


if __name__ == "__main__":
    main()
