#!/usr/bin/env python3
"""Times the peer sparse solvers on one SPD system, in one process, and appends one JSON
line per measurement to --out (the format that kernels/benches/solvers.rs writes too).

usage: python bench_peers.py --matrix DIR/elast2d_353 [--reps 3] [--out results.jsonl]
reads DIR/elast2d_353.mtx (symmetric, lower triangle) and DIR/elast2d_353_rhs.mtx.

Measured (median and best of --reps runs, each from scratch: analysis + factorization + solve):
  MKL PARDISO (pypardiso), SPD Cholesky (mtype 2, upper triangle)
  MUMPS 5.5 sequential (python-mumps), symmetric LDLT, ordering auto and amd
  CHOLMOD (scikit-sparse 0.4.16), supernodal, plus refactorization with the same pattern
  SciPy SuperLU splu with a symmetric ordering (one run: it is slow)
A peer whose module is missing is skipped with a note. Each line has factor_solve_s
(analysis + factorization + solve, seconds) and relres = ||b - A x|| / ||b||.
"""
import argparse
import json
import statistics
import sys
import time
from importlib.metadata import version, PackageNotFoundError

import numpy as np
import scipy
import scipy.io as sio
import scipy.sparse as sp


def pkg(name):
    try:
        return version(name)
    except PackageNotFoundError:
        return "?"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--matrix", required=True)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--out", default="results.jsonl")
    ap.add_argument("--label", default="", help="appended to every method name")
    args = ap.parse_args()
    name = args.matrix.rstrip("/").split("/")[-1]

    t = time.perf_counter()
    L = sio.mmread(args.matrix + ".mtx")
    A = sp.csr_matrix(L)
    A.sort_indices()
    b = np.asarray(sio.mmread(args.matrix + "_rhs.mtx")).ravel()
    print(f"# loaded {name}: n={A.shape[0]} nnz(full)={A.nnz} in {time.perf_counter() - t:.1f}s", flush=True)
    bnorm = np.linalg.norm(b)

    def relres(x):
        return float(np.linalg.norm(A @ np.real(x) - b) / bnorm)

    out = open(args.out, "a")

    def report(tool, method, runs, **extra):
        """runs: list of dicts of phase times (s); the median of each key is reported."""
        d = dict(tool=tool, matrix=name, method=method + args.label, kind="direct", reps=len(runs))
        for k in runs[0]:
            if k != "relres":
                d[k] = statistics.median(r[k] for r in runs)
        d["factor_solve_best_s"] = min(r["factor_solve_s"] for r in runs)
        d["relres"] = runs[-1]["relres"]
        d.update(extra)
        line = json.dumps(d)
        print(line, flush=True)
        out.write(line + "\n")
        out.flush()

    # --- MKL PARDISO -------------------------------------------------------------
    try:
        import pypardiso
        U = sp.triu(A, format="csr")
        U.sort_indices()
        runs = []
        for _ in range(args.reps):
            s = pypardiso.PyPardisoSolver(mtype=2)
            t0 = time.perf_counter()
            s.factorize(U)
            t1 = time.perf_counter()
            x = s.solve(U, b)
            t2 = time.perf_counter()
            runs.append(dict(factor_s=t1 - t0, solve_s=t2 - t1, factor_solve_s=t2 - t0, relres=relres(x)))
            s.free_memory(everything=True)
        report(f"MKL PARDISO (pypardiso {pkg('pypardiso')}, mkl {pkg('mkl')})", "SPD Cholesky (mtype 2)", runs)
    except ImportError as e:
        print(f"# PARDISO skipped: {e}", file=sys.stderr)

    # --- MUMPS -------------------------------------------------------------------
    try:
        import mumps
        T = sp.triu(A).tocoo()
        for order in ("auto", "amd"):
            runs = []
            for _ in range(args.reps):
                ctx = mumps.Context()
                ctx.set_matrix(T, symmetric=True)
                t0 = time.perf_counter()
                ctx.analyze(ordering=order)
                t1 = time.perf_counter()
                ctx.factor(ordering=order, reuse_analysis=True)
                t2 = time.perf_counter()
                x = ctx.solve(b)
                t3 = time.perf_counter()
                # refactorization with the analysis kept
                ctx.factor(ordering=order, reuse_analysis=True)
                t4 = time.perf_counter()
                runs.append(dict(analyze_s=t1 - t0, factor_s=t2 - t1, solve_s=t3 - t2,
                                 factor_solve_s=t3 - t0, refactor_s=t4 - t3, relres=relres(x)))
                del ctx
            report(f"MUMPS 5.5 seq (python-mumps {pkg('python-mumps')})", f"symmetric LDLT, ordering {order}", runs)
    except ImportError as e:
        print(f"# MUMPS skipped: {e}", file=sys.stderr)

    # --- CHOLMOD -----------------------------------------------------------------
    try:
        from sksparse.cholmod import analyze
        C = A.tocsc()
        runs = []
        for _ in range(args.reps):
            t0 = time.perf_counter()
            an = analyze(C, mode="supernodal", ordering_method="default")
            t1 = time.perf_counter()
            F = an.cholesky(C)
            t2 = time.perf_counter()
            x = F(b)
            t3 = time.perf_counter()
            F.cholesky_inplace(C * 1.001)
            t4 = time.perf_counter()
            runs.append(dict(analyze_s=t1 - t0, factor_s=t2 - t1, solve_s=t3 - t2,
                             factor_solve_s=t3 - t0, refactor_s=t4 - t3, relres=relres(x)))
            del F, an
        report(f"CHOLMOD (scikit-sparse {pkg('scikit-sparse')})", "supernodal Cholesky", runs)
    except ImportError as e:
        print(f"# CHOLMOD skipped: {e}", file=sys.stderr)

    # --- SciPy SuperLU -----------------------------------------------------------
    import scipy.sparse.linalg as spla
    C = A.tocsc()
    t0 = time.perf_counter()
    lu = spla.splu(C, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options=dict(SymmetricMode=True))
    t1 = time.perf_counter()
    x = lu.solve(b)
    t2 = time.perf_counter()
    report(f"SciPy {scipy.__version__} SuperLU", "splu, MMD_AT_PLUS_A, symmetric mode",
           [dict(factor_s=t1 - t0, solve_s=t2 - t1, factor_solve_s=t2 - t0, relres=relres(x))])


if __name__ == "__main__":
    main()
