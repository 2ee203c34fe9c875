#!/usr/bin/env python3
"""Reads the JSON lines written by bench_peers.py and kernels/benches/solvers.rs in one
run and prints one markdown table, fastest first, with each solver's factor + solve time
as a ratio to dfem's default direct solver (faer LLT, AMD, 1 thread) and to the fastest
peer. usage: python compare.py results.jsonl"""
import json
import sys


def fmt(v, spec=".3f"):
    return "" if v is None else format(v, spec)


def main(path):
    rows = [json.loads(l) for l in open(path) if l.strip()]
    direct = [r for r in rows if r.get("kind", "direct") == "direct" and r.get("factor_solve_s")]
    ours = [r for r in direct if r["tool"] == "dfem-kernels"]
    peers = [r for r in direct if r["tool"] != "dfem-kernels"]
    ref = next((r for r in ours if r["method"].startswith("faer LLT, AMD, 1 thread")), None)
    best_peer = min(peers, key=lambda r: r["factor_solve_s"]) if peers else None
    print("| solver | method | analysis (s) | factorization (s) | refactorization (s) | solve (s) "
          "| factor + solve, median (s) | best (s) | / dfem default | / fastest peer | ‖b − Ax‖/‖b‖ |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in sorted(direct, key=lambda r: r["factor_solve_s"]):
        fs = r["factor_solve_s"]
        print(f"| {r['tool']} | {r['method']} | {fmt(r.get('analyze_s'))} | {fmt(r.get('factor_s'))} "
              f"| {fmt(r.get('refactor_s'))} | {fmt(r.get('solve_s'))} | **{fs:.3f}** | {fmt(r.get('factor_solve_best_s'))} "
              f"| {fmt(fs / ref['factor_solve_s'], '.2f') if ref else ''} "
              f"| {fmt(fs / best_peer['factor_solve_s'], '.2f') if best_peer else ''} "
              f"| {fmt(r.get('relres'), '.1e')} |")
    iters = [r for r in rows if r.get("kind") == "iterative"]
    if iters:
        print()
        print("| iterative solver | set-up (s) | solve (s) | total (s) | iterations | / fastest peer (direct) | true ‖b − Ax‖/‖b‖ |")
        print("|---|---|---|---|---|---|---|")
        for r in iters:
            tot = r.get("factor_solve_s")
            ratio = fmt(tot / best_peer["factor_solve_s"], ".2f") if (best_peer and tot) else ""
            print(f"| {r['method']} | {fmt(r.get('setup_s'))} | {fmt(r.get('solve_s'))} | **{fmt(tot)}** "
                  f"| {r.get('iters')} | {ratio} | {fmt(r.get('relres'), '.1e')} |")
    if ref and peers:
        print()
        for r in sorted(peers, key=lambda r: r["factor_solve_s"]):
            verdict = "faster" if ref["factor_solve_s"] < r["factor_solve_s"] else "slower"
            print(f"- dfem default ({ref['factor_solve_s']:.3f} s) is {verdict} than {r['tool']} "
                  f"{r['method']} ({r['factor_solve_s']:.3f} s)")
        for r in direct:
            if r.get("refactor_s") and r.get("factor_s"):
                first = r["factor_s"] + (r.get("analyze_s") or 0.0)
                print(f"- {r['tool']} {r['method']}: refactorization = "
                      f"{100 * r['refactor_s'] / r['factor_s']:.0f} % of the first numeric factorization, "
                      f"{100 * r['refactor_s'] / first:.0f} % of analysis + first factorization (target <= 70 %)")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "results.jsonl")
