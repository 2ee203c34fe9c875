#!/usr/bin/env python3
"""Measure the figures of docs/performance.md and write them into it.

Each section of docs/performance.md that this script measures sits between the markers

    <!-- performance.py SECTION -->
    ...
    <!-- end performance.py SECTION -->

and `--write` replaces what is between them with a fresh table: the figures, the command
that gives them, the machine (cores, CPU), the load average before and after, and the
date. Without `--write` the tables are printed. Wall times are dfem's own `wall_time_s`
(summary.json), so that start-up and output are not in them; counts (iterations,
factorizations) do not depend on the load, wall times do: run it on a quiet machine
(`uptime` near 0) and nothing else beside it.

    python3 benches/performance.py capacity --walls 30,60 --write
    python3 benches/performance.py layer --old /path/to/old/dfem --rounds 5 --write

Sections:
  capacity  capacity searches against the gravity-only analysis of the same wall
  layer     a new binary against an old one (alternated, paired ratios) on the
            scenes of every analysis type: the cost of a change to the analysis layer
  output    a dynamic run's output: the 39 s Imperial Valley record at 0.5 ms steps on one
            block with the default output and without frames (--record names the .AT2)
  dynamics  error against time, dfem beside OpenSees (benches/peers/block_dynamic.py) on
            one block under El Centro 1940 and Imperial Valley 1979 (--record names the
            .AT2): the sliding block's largest slip against Newmark's rigid block, the
            rocking column's largest rotation against Housner's, at the record's step and
            its fractions
  p2        the P2 wall (40 x 40 blocks, gravity then 0.3 g) against OpenSees
            (benches/peers/wall_static.py; --python names an interpreter with openseespy)
"""

import argparse
import datetime
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC = os.path.join(ROOT, "docs", "performance.md")

# The issue-45 wall: 40 courses of 14 bricks 0.22 m x 0.075 m (3.08 m x 3 m), the
# built-in wall's joints and materials (benches/scenes/capacity_wall40x14.toml).
WALL = os.path.join(ROOT, "benches", "scenes", "capacity_wall40x14.toml")
G = 9.81  # m/s², dfem's g (units = "g" records)


def read_record(path):
    """(times s, accelerations m/s²) of a CSV (time, acceleration in g; a header line) or
    a PEER .AT2 (in g, `DT=` on its 4th line)."""
    lines = open(path).read().splitlines()
    if path.lower().endswith(".at2"):
        dt = float(lines[3].upper().split("DT=")[1].split()[0])
        a = [G * float(v) for line in lines[4:] for v in line.split()]
        return [k * dt for k in range(len(a))], a
    rows = [line.split(",") for line in lines[1:] if line.strip()]
    return [float(r[0]) for r in rows], [G * float(r[1]) for r in rows]


def sampler(t, a):
    """a(x): the record interpolated linearly, zero after its end (as dfem reads it)."""
    dt = t[1] - t[0]

    def at(x):
        k = int(x / dt)
        if k + 1 >= len(a):
            return 0.0
        w = x / dt - k
        return a[k] + w * (a[k + 1] - a[k])

    return at


def sliding_reference(t, a, mu, h=1e-4):
    """The largest slip (m) of Newmark's (1965) rigid block on a base shaken by the record,
    Coulomb friction μ: relative velocity v, ground acceleration at each step's middle;
    the block sticks while v = 0 and |a_g| ≤ μ g, and stops (v = 0) in a step where v would
    change sign. First order in h; 10⁻⁴ s is converged to 0.1 % on El Centro
    (tests/dynamics_step_accuracy.rs integrates the same model)."""
    at = sampler(t, a)
    x = v = peak = 0.0
    for k in range(int(round(t[-1] / h))):
        ag = at((k + 0.5) * h)
        if v == 0.0 and abs(ag) <= mu * G:
            continue
        direction = v if v != 0.0 else -ag
        w = v + (-ag - math.copysign(mu * G, direction)) * h
        if v != 0.0 and w * v < 0.0:
            w = 0.0
        x += 0.5 * (v + w) * h
        v = w
        peak = max(peak, abs(x))
    return peak


def rocking_reference(t, a, breadth, height, h=1e-4):
    """The largest rotation (rad) of Housner's (1963) rigid block (docs/validation.md V4) on
    a base shaken by the record: about the corner it rocks on,
    θ̈ = p² (a_g/g · cos(α − |θ|) − sgn θ · sin(α − |θ|)) with p² = 3g / (4R), α = atan(b/h),
    R the half-diagonal, θ > 0 where a_g > 0 tips it further; it starts
    when |a_g| > g tan α; at each impact (θ through 0, located by linear interpolation
    within the step) the angular velocity is multiplied by r = 1 − 3/2 sin² α and it goes
    on about the other corner; it rests when the velocity left is below 10⁻⁶ rad/s.
    Midpoint rule with step h."""
    at = sampler(t, a)
    alpha = math.atan(breadth / height)
    p2 = 3 * G / (2 * math.hypot(breadth, height))
    r = 1 - 1.5 * math.sin(alpha) ** 2

    def acc(theta, ag):
        return p2 * (ag / G * math.cos(alpha - abs(theta)) - math.copysign(math.sin(alpha - abs(theta)), theta))

    th = w = peak = 0.0
    for k in range(int(round(t[-1] / h))):
        ag = at((k + 0.5) * h)
        if th == 0.0:
            if w == 0.0 and abs(ag) <= G * breadth / height:
                continue
            th = math.copysign(1e-15, w if w != 0.0 else ag)
        k1 = acc(th, ag)
        mid_th, mid_w = th + 0.5 * h * w, w + 0.5 * h * k1
        new_th, new_w = th + h * mid_w, w + h * acc(mid_th, ag)
        if new_th * th < 0.0:
            f = th / (th - new_th)
            w_impact = r * (w + f * (new_w - w))
            new_th, new_w = w_impact * (1 - f) * h, w_impact
            if abs(w_impact) < 1e-6:
                new_th = new_w = 0.0
        th, w = new_th, new_w
        peak = max(peak, abs(th))
        if peak > math.pi / 2:
            break
    return peak


def machine():
    cpu = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} cores, {cpu}"


def load():
    return os.getloadavg()[0]


def variant(path, changes):
    """The scene at `path` with the values of `changes` ({(table, key): value}) in place
    of the scene's, written to a temporary file."""
    lines = open(path).read().split("\n")
    for (table, key), value in changes.items():
        inside, done = False, False
        for i, line in enumerate(lines):
            if line.startswith("["):
                inside = line.strip("[] ") == table
            elif inside and re.match(rf"{key}\s*=", line):
                lines[i] = f"{key} = {value}"
                done = True
                break
        if not done:
            sys.exit(f"{path}: no `{key} =` in [{table}] to change")
    f = tempfile.NamedTemporaryFile("w", suffix=".toml", delete=False)
    f.write("\n".join(lines))
    f.close()
    return f.name


def run(dfem, scene, threads=2):
    """Run dfem on `scene`; its summary.json."""
    with tempfile.TemporaryDirectory() as out:
        cmd = [dfem, "run", scene, "--out", out, "--no-plots", "--quiet", "--threads", str(threads)]
        p = subprocess.run(cmd, capture_output=True, text=True)
        path = os.path.join(out, "summary.json")
        if not os.path.exists(path):
            sys.exit(f"{' '.join(cmd)} wrote no summary (exit {p.returncode}):\n{p.stderr}")
        return json.load(open(path))


def table(arguments, loads, columns, align, rows):
    """A measured table: what measured it (`benches/performance.py arguments`), where,
    under which load, and its rows under `columns` aligned by `align`."""
    date = datetime.date.today().isoformat()
    return "\n".join(
        [
            f"Measured {date} by `python3 benches/performance.py {arguments}` on {machine()}; "
            f"load average {min(loads):.2f}–{max(loads):.2f} during the run. Release build.",
            "",
            f"| {columns} |",
            f"|{align}",
            *rows,
        ]
    )


def section_capacity(args):
    """λ, the counts and the time of a capacity search on the 40 × 14 wall, rigid and
    deformable, against the same wall's gravity-only analysis, each the median of
    `rounds` runs alternated; then the same for the square walls of `--walls` (n courses
    of n bricks of the same size), one run each."""
    rows = []
    loads = [load()]
    walls = [("40 × 14", {}, args.rounds)]
    for n in (int(v) for v in args.walls.split(",") if v):
        walls.append((f"{n} × {n}", {("generate", "courses"): n, ("generate", "bricks_per_course"): n}, 1))
    for name, size, rounds in walls:
        for kind in ("rigid", "deformable"):
            cap = variant(WALL, {("generate", "kind"): f'"{kind}"', **size})
            grav = variant(WALL, {("generate", "kind"): f'"{kind}"', ("analysis", "type"): '"static"', **size})
            tc, tg, s = [], [], None
            for _ in range(rounds):
                s = run(args.dfem, cap)
                tc.append(s["stats"]["wall_time_s"])
                g = run(args.dfem, grav)
                tg.append(g["stats"]["wall_time_s"])
                loads.append(load())
            st = s["stats"]
            c, g = statistics.median(tc), statistics.median(tg)
            lam = s["load_factor"]
            rows.append(
                f"| {name}, {kind} | {st['dofs']:,} | {s['status']} | "
                + (f"{lam:.4f}" if lam is not None else "–")
                + f" | {st['increments']} | {st['iterations']:,} "
                f"| {st['factorizations']:,} ({st.get('tangent_factorizations', 0):,} tangent LU) "
                f"| {c:.2f} s | {g:.3f} s | {c / g:,.0f}× |"
            )
            os.unlink(cap)
            os.unlink(grav)
    columns = (
        "wall, blocks | unknowns | status | λ | increments | iterations | numeric factorizations "
        "| capacity run | gravity-only run | ratio"
    )
    walls_arg = f" --walls {args.walls}" if args.walls else ""
    return table(
        f"capacity --rounds {args.rounds}{walls_arg}", loads, columns, "---|---:|---|" + "---:|" * 7, rows
    )


LAYER_SCENES = [
    ("P2 rigid", "benches/scenes/p2_wall40_rigid.toml"),
    ("P2 deformable", "benches/scenes/p2_wall40_deformable.toml"),
    ("40 × 14 wall, rigid, capacity", "benches/scenes/capacity_wall40x14.toml"),
    ("tunnel earthquake (3 s)", "examples/tunnel_earthquake/earthquake.toml"),
]


def section_layer(args):
    """The new binary against `--old`: each scene run by both, alternated, `rounds`
    times; the median time of each and the median of the paired ratios new / old, with
    a check that both give the same status, load factor and iterations."""
    if not args.old:
        sys.exit("layer: give the binary to compare with, --old PATH")
    rows = []
    loads = [load()]
    for name, scene in LAYER_SCENES:
        path = os.path.join(ROOT, scene)
        old, new, ratio = [], [], []
        same = True
        for _ in range(args.rounds):
            a = run(args.old, path)
            b = run(args.dfem, path)
            loads.append(load())
            old.append(a["stats"]["wall_time_s"])
            new.append(b["stats"]["wall_time_s"])
            ratio.append(new[-1] / old[-1])
            keys = ("status", "load_factor")
            same &= all(a[k] == b[k] for k in keys)
            same &= a["stats"]["iterations"] == b["stats"]["iterations"]
        rows.append(
            f"| {name} (`{scene}`) | {statistics.median(old):.2f} s | {statistics.median(new):.2f} s "
            f"| {statistics.median(ratio):.2f} ({min(ratio):.2f}–{max(ratio):.2f}) "
            f"| {'same' if same else '**differ**'} |"
        )
    columns = "scene | old, median | new, median | new / old (paired, median; range) | status, λ, iterations"
    return table(f"layer --old OLD --rounds {args.rounds}", loads, columns, "---|---:|---:|---|---|", rows)


def section_p2(args):
    """dfem on the P2 scenes against OpenSees (openseespy, MUMPS, Newton) on the same wall,
    alternated, `rounds` times: the medians and the ratio of the medians. OpenSees' time
    is its `total_s` (model building included, as dfem's `wall_time_s` includes meshing
    and contact detection)."""
    peer = os.path.join(ROOT, "benches", "peers", "wall_static.py")
    opensees = [args.python, peer, "40", "40", "--system", "Mumps", "--lat", "0.3", "--nlat", "30", "--ngrav", "5"]
    rows = []
    loads = [load()]
    for kind in ("rigid", "deformable"):
        scene = os.path.join(ROOT, "benches", "scenes", f"p2_wall40_{kind}.toml")
        ours, theirs, s = [], [], None
        for _ in range(args.rounds):
            s = run(args.dfem, scene)
            ours.append(s["stats"]["wall_time_s"])
            p = subprocess.run(opensees, capture_output=True, text=True)
            if p.returncode != 0:
                sys.exit(f"{' '.join(opensees)} failed:\n{p.stderr[-2000:]}")
            o = json.loads(p.stdout.strip().splitlines()[-1])
            if not o.get("lateral_ok"):
                sys.exit(f"OpenSees did not reach 0.3 g: {o}")
            theirs.append(o["total_s"])
            loads.append(load())
        st = s["stats"]
        a, b = statistics.median(ours), statistics.median(theirs)
        rows.append(
            f"| {kind} | {s['status']}: {st['iterations']} iterations, {st['factorizations']} factorizations, "
            f"{st.get('low_rank_corrections', 0)} low-rank corrections | {a:.2f} s | {b:.2f} s | **{b / a:.1f}×** |"
        )
    columns = "wall | dfem | dfem, median | OpenSees, median | OpenSees / dfem"
    return table(f"p2 --rounds {args.rounds}", loads, columns, "---|---|---:|---:|---:|", rows)


def section_output(args):
    """The time and the files of a long dynamic run with the default output against the
    same run without ParaView frames (`[output] vtk = false`), alternated: what the
    output costs. Time is the whole process (the output is written after the analysis
    timer too)."""
    if not args.record or not os.path.exists(args.record):
        sys.exit("output: give the Imperial Valley 1979 record (PEER, not in the repository), --record PATH.AT2")
    import shutil
    import time

    scene = os.path.join(ROOT, "benches", "scenes", "block_imperial_valley.toml")
    rows = []
    loads = [load()]
    with tempfile.TemporaryDirectory() as work:
        shutil.copy(args.record, os.path.join(work, "imperialvalley1979_H-E01140.AT2"))
        plain = os.path.join(work, "scene.toml")
        shutil.copy(scene, plain)
        novtk = os.path.join(work, "novtk.toml")
        with open(novtk, "w") as f:
            f.write(open(scene).read() + "\n[output]\nvtk = false\n")
        times = {plain: [], novtk: []}
        files = {}
        for _ in range(args.rounds):
            for sc in (plain, novtk):
                out = os.path.join(work, "out")
                shutil.rmtree(out, ignore_errors=True)
                t = time.perf_counter()
                subprocess.run([args.dfem, "run", sc, "--out", out, "--no-plots", "--quiet"], check=True)
                times[sc].append(time.perf_counter() - t)
                files[sc] = sum(len(f) for _, _, f in os.walk(out))
                loads.append(load())
        a, b = statistics.median(times[plain]), statistics.median(times[novtk])
        rows.append(f"| default | {files[plain]:,} | {a:.2f} s | {(a - b) / a * 100:.0f} % |")
        rows.append(f"| `[output] vtk = false` | {files[novtk]:,} | {b:.2f} s | – |")
    columns = "output | files | run time (process), median | share of the frames"
    return table(f"output --record PATH.AT2 --rounds {args.rounds}", loads, columns, "---|---:|---:|---:|", rows)


# The dynamic tests' block (tests/common/mod.rs, `box_on_base`): a rigid 1 m × 0.5 m block
# of their rock on a fixed base 40 m wide, on their joint.
BLOCK = os.path.join(ROOT, "benches", "scenes", "block_imperial_valley.toml")
BOX = "vertices = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.0, 0.5]]"


def block_scene(record, dt, duration, breadth, height, mu):
    """The scene of BLOCK with a `breadth` × `height` block, friction μ, under `record` at
    `dt`, history only: its text."""
    fmt = "at2" if record.lower().endswith(".at2") else "csv"
    path = variant(
        BLOCK,
        {
            ("joint", "friction_angle"): math.degrees(math.atan(mu)),
            ("analysis", "dt"): dt,
            ("analysis", "duration"): duration,
            ("analysis", "ground_motion"): f'{{ file = "{record}", format = "{fmt}" }}',
        },
    )
    text = open(path).read()
    os.unlink(path)
    if BOX not in text:
        sys.exit(f"{BLOCK}: no `{BOX}` (the block) to change")
    box = f"vertices = [[0.0, 0.0], [{breadth}, 0.0], [{breadth}, {height}], [0.0, {height}]]"
    return text.replace(BOX, box) + '\n[output]\ntrack = ["box"]\nvtk = false\n'


def run_dynamic(dfem, scene, column):
    """dfem on a dynamic scene: the largest |column| of history.csv and wall_time_s."""
    import csv

    with tempfile.TemporaryDirectory() as out:
        path = os.path.join(out, "scene.toml")
        with open(path, "w") as f:
            f.write(scene)
        cmd = [dfem, "run", path, "--out", out, "--no-plots", "--quiet"]
        p = subprocess.run(cmd, capture_output=True, text=True)
        summary = json.load(open(os.path.join(out, "summary.json")))
        if p.returncode != 0 or summary["status"] != "completed":
            sys.exit(f"{' '.join(cmd)}: {summary['status']} (exit {p.returncode}):\n{p.stderr}")
        peak = max(abs(float(row[column])) for row in csv.DictReader(open(os.path.join(out, "history.csv"))))
        return peak, summary["stats"]["wall_time_s"]


def section_dynamics(args):
    """Error against time, dfem (default settings) beside OpenSees
    (benches/peers/block_dynamic.py: HHT α = 0.05 in dfem's terms, Newton) on the dynamic
    tests' block at the record's step Δt, Δt/2 and Δt/4 (and Δt/16 for the column),
    alternated, `rounds` times: the sliding block's largest slip against Newmark's rigid
    block and the rocking column's largest rotation against Housner's rigid block
    (`sliding_reference`, `rocking_reference`), and the median wall time of each
    (OpenSees' `total_s`)."""
    if not args.record or not os.path.exists(args.record):
        sys.exit("dynamics: give the Imperial Valley 1979 record (PEER, not in the repository), --record PATH.AT2")
    el_centro = os.path.join(ROOT, "tests", "data", "elcentro1940_NS_g_dt0.02.csv")
    record = os.path.abspath(args.record)
    peer = os.path.join(ROOT, "benches", "peers", "block_dynamic.py")
    # (name, record, mode, breadth, height, μ, step divisions)
    cases = [
        ("El Centro 1940, sliding block, μ = 0.1", el_centro, "slide", 1.0, 0.5, 0.1, (1, 2, 4)),
        ("El Centro 1940, sliding block, μ = 0.2", el_centro, "slide", 1.0, 0.5, 0.2, (1, 2, 4)),
        ("Imperial Valley 1979, sliding block, μ = 0.05", record, "slide", 1.0, 0.5, 0.05, (1, 2, 4)),
        ("El Centro 1940, rocking column 0.6 m × 3 m", el_centro, "rock", 0.6, 3.0, 1.0, (1, 2, 4, 16)),
    ]
    rows = []
    loads = [load()]
    for name, path, mode, breadth, height, mu, divisions in cases:
        t, a = read_record(path)
        slide = mode == "slide"
        ref = sliding_reference(t, a, mu) if slide else rocking_reference(t, a, breadth, height, 1e-5)
        unit, column = ("mm", "box.ux") if slide else ("mrad", "box.rz")
        cells = {"dt": [], "dfem": [], "dfem_s": [], "peer": [], "peer_s": []}
        for div in divisions:
            dt = (t[1] - t[0]) / div
            scene = block_scene(path, dt, t[-1], breadth, height, mu)
            opensees = [args.python, peer, mode, "--record", path, "--dt", str(dt), "--mu", str(mu),
                        "--breadth", str(breadth), "--height", str(height)]
            ours, theirs = [], []
            for _ in range(args.rounds):
                u, w = run_dynamic(args.dfem, scene, column)
                ours.append(w)
                p = subprocess.run(opensees, capture_output=True, text=True)
                if p.returncode != 0:
                    sys.exit(f"{' '.join(opensees)} failed:\n{p.stderr[-2000:]}")
                o = json.loads(p.stdout.strip().splitlines()[-1])
                theirs.append(o["total_s"])
                loads.append(load())
            v = o["max_slip_m"] if slide else o["max_rotation_rad"]
            cells["dt"].append("Δt" if div == 1 else f"Δt/{div}")
            cells["dfem"].append(f"{100 * (u - ref) / ref:+.1f}")
            cells["dfem_s"].append(f"{statistics.median(ours):.2f}")
            if not o["ok"]:
                cells["peer"].append(f"stopped at {o['time_reached']:.1f} s")
            elif not slide and v > 1.0:
                cells["peer"].append(f"diverged ({v:,.0f} rad)")
            else:
                cells["peer"].append(f"{100 * (v - ref) / ref:+.1f}")
            cells["peer_s"].append(f"{statistics.median(theirs):.2f}")
        row = {k: " / ".join(c) for k, c in cells.items()}
        rows.append(
            f"| {name} | {1e3 * ref:.3f} {unit} | {t[1] - t[0]:g} s: {row['dt']} | {row['dfem']} "
            f"| {row['dfem_s']} | {row['peer']} | {row['peer_s']} |"
        )
    columns = (
        "record, block | reference | steps (Δt: the record's) | dfem, error (%) | dfem, median time (s) "
        "| OpenSees, error (%) | OpenSees, median time (s)"
    )
    return table(f"dynamics --python PYTHON --record PATH.AT2 --rounds {args.rounds}", loads, columns,
                 "---|---:|---|---|---|---|---|", rows)


SECTIONS = {
    "capacity": section_capacity,
    "dynamics": section_dynamics,
    "output": section_output,
    "layer": section_layer,
    "p2": section_p2,
}


def write(name, table):
    text = open(DOC).read()
    begin, end = f"<!-- performance.py {name} -->", f"<!-- end performance.py {name} -->"
    if begin not in text or end not in text:
        sys.exit(f"{DOC}: no markers for section `{name}` ({begin} … {end})")
    i = text.index(begin) + len(begin)
    j = text.index(end)
    text = text[:i] + "\n" + table + "\n" + text[j:]
    with open(DOC + ".tmp", "w") as f:
        f.write(text)
    os.replace(DOC + ".tmp", DOC)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("sections", nargs="+", choices=sorted(SECTIONS))
    p.add_argument("--dfem", default=os.path.join(ROOT, "target", "release", "dfem"))
    p.add_argument("--old", help="the binary to compare with (section layer)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--walls", default="", help="square walls n × n for section capacity, e.g. 30,60 (one run each)")
    p.add_argument("--record", help="the Imperial Valley 1979 .AT2 record (sections output, dynamics)")
    p.add_argument("--python", default=sys.executable, help="a Python with openseespy (sections p2, dynamics)")
    p.add_argument("--write", action="store_true", help="write the tables into docs/performance.md")
    args = p.parse_args()
    if not os.path.exists(args.dfem):
        sys.exit(f"{args.dfem}: no binary (cargo build --release first, or --dfem PATH)")
    for name in args.sections:
        table = SECTIONS[name](args)
        if args.write:
            write(name, table)
            print(f"docs/performance.md: section {name} written")
        else:
            print(table)


if __name__ == "__main__":
    main()
