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
  p2        the P2 wall (40 x 40 blocks, gravity then 0.3 g) against OpenSees
            (benches/peers/wall_static.py; --python names an interpreter with openseespy)
"""

import argparse
import datetime
import json
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


SECTIONS = {"capacity": section_capacity, "output": section_output, "layer": section_layer, "p2": section_p2}


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
    p.add_argument("--record", help="the Imperial Valley 1979 .AT2 record (section output)")
    p.add_argument("--python", default=sys.executable, help="a Python with openseespy (section p2)")
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
