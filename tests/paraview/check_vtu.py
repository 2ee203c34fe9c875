#!/usr/bin/env python3
"""Read dfem's ParaView files with meshio, a reader independent of dfem, for
tests/paraview_meshio.rs.

    check_vtu.py DIR/results.pvd

Lists the data sets of the .pvd (parsed here with xml.etree), reads every .vtu it names
with meshio and prints one JSON document on stdout:

    {"meshio": VERSION, "datasets": [{"timestep", "part", "file", "points",
      "cells": [{"type", "count", "nodes"}], "point_data": {NAME: COMPONENTS},
      "cell_data": {NAME: COMPONENTS}, "rows": {NAME: ROWS},
      "values": {NAME: [repr of each value, row by row]}, "warnings": [...]}]}

Values are passed as Python's repr of each float (the shortest string that reads back
to the same float), so the Rust side compares them bit for bit. Without meshio it prints
{"skipped": ...} and exits with status 3.
"""
import json
import os
import sys
import warnings
import xml.etree.ElementTree as ET


def flat(array):
    return [repr(float(v)) for v in array.reshape(-1)]


def components(array):
    return 1 if array.ndim == 1 else int(array.shape[1])


def dataset(base, d, meshio):
    path = os.path.join(base, d.get("file"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mesh = meshio.read(path)
    out = {
        "timestep": d.get("timestep"),
        "part": d.get("part"),
        "file": d.get("file"),
        "points": int(mesh.points.shape[0]),
        # meshio groups consecutive cells of one type (and, for polygons, one size)
        "cells": [
            {"type": c.type, "count": int(c.data.shape[0]), "nodes": int(c.data.shape[1])}
            for c in mesh.cells
        ],
        "point_data": {},
        "cell_data": {},
        "rows": {},
        "values": {"Points": flat(mesh.points)},
        "warnings": [str(w.message) for w in caught],
    }
    for name, a in mesh.point_data.items():
        out["point_data"][name] = components(a)
        out["rows"][name] = int(a.shape[0])
        out["values"][name] = flat(a)
    for name, blocks in mesh.cell_data.items():
        # one array per cell block, in the order of the cells
        out["cell_data"][name] = components(blocks[0])
        out["rows"][name] = sum(int(b.shape[0]) for b in blocks)
        out["values"][name] = [v for b in blocks for v in flat(b)]
    return out


def main():
    pvd = sys.argv[1]
    try:
        import meshio
    except ImportError as e:
        print(json.dumps({"skipped": "meshio is missing ({}): install python3-meshio".format(e)}))
        return 3
    root = ET.parse(pvd).getroot()
    base = os.path.dirname(pvd)
    datasets = [dataset(base, d, meshio) for d in root.iter("DataSet")]
    print(json.dumps({"meshio": getattr(meshio, "__version__", "unknown"), "datasets": datasets}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
