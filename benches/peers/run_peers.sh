#!/usr/bin/env bash
# Times dfem's sparse solvers and the peer solvers (MKL PARDISO, MUMPS, CHOLMOD, SciPy
# SuperLU) on the same matrix, in one run, and prints the ratios.
#
# usage: bash benches/peers/run_peers.sh [install|run|all]   (default: all)
#   install  apt packages (OpenBLAS first) and a Python venv with the peers
#   run      writes the P1 matrix with dfem's Matrix Market writer, times the peers,
#            then dfem's bench, and prints one table with ratios
# environment:
#   PEERS_VENV   venv directory            (default: ~/.cache/dfem-peers-venv)
#   PEERS_OUT    matrices and results      (default: /tmp/dfem-peers)
#   PEERS_N      grid size n (n × n squares; 353 → 249,924 unknowns)  (default: 353)
#   PEERS_REPS   repetitions per solver; median and best are reported    (default: 3)
#   CARGO_TARGET_DIR is passed through to cargo.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
VENV="${PEERS_VENV:-$HOME/.cache/dfem-peers-venv}"
OUT="${PEERS_OUT:-/tmp/dfem-peers}"
N="${PEERS_N:-353}"
REPS="${PEERS_REPS:-3}"
PHASE="${1:-all}"

install() {
    export DEBIAN_FRONTEND=noninteractive
    # OpenBLAS before anything that links BLAS: with the reference BLAS CHOLMOD and
    # MUMPS are 2-3x slower, which would flatter dfem.
    apt-get update -qq
    apt-get install -y -qq libopenblas0-pthread >/dev/null
    apt-get install -y -qq libsuitesparse-dev libmumps-seq-dev pkg-config >/dev/null
    if [ ! -x "$VENV/bin/python" ]; then
        python3 -m venv "$VENV"
    fi
    "$VENV/bin/pip" install -q --upgrade pip
    "$VENV/bin/pip" install -q numpy scipy
    # each peer on its own line: one that fails to build does not stop the others
    "$VENV/bin/pip" install -q pypardiso || echo "pypardiso: install failed" >&2
    "$VENV/bin/pip" install -q scikit-sparse==0.4.16 || echo "scikit-sparse: install failed" >&2
    "$VENV/bin/pip" install -q python-mumps || echo "python-mumps: install failed" >&2
}

run() {
    mkdir -p "$OUT"
    local name="elast2d_$N"
    echo "# machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
    local bench
    bench="$(cd "$ROOT" && cargo bench -q -p dfem-kernels --bench solvers --no-run --message-format=json 2>/dev/null \
        | "$VENV/bin/python" -c 'import sys, json
for l in sys.stdin:
    m = json.loads(l)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == "solvers" and m.get("executable"):
        print(m["executable"])' | tail -1)"
    # the matrix and the right-hand side, written by dfem's own Matrix Market writer
    if [ ! -f "$OUT/$name.mtx" ]; then
        "$bench" --n "$N" --write-mtx "$OUT" --no-time
    fi
    rm -f "$OUT/results.jsonl"
    echo "# load before the timed part: $(cut -d' ' -f1-3 /proc/loadavg)"
    # the peers with their libraries' default threading (MKL, OpenBLAS: all cores) ...
    (cd "$OUT" && "$VENV/bin/python" "$HERE/bench_peers.py" --matrix "$OUT/$name" --reps "$REPS" \
        --out "$OUT/results.jsonl" --label " [BLAS: default threads]")
    echo "# load: $(cut -d' ' -f1-3 /proc/loadavg)"
    "$bench" --n "$N" --reps "$REPS" --json "$OUT/results.jsonl" | tee "$OUT/dfem_table.md"
    echo "# load: $(cut -d' ' -f1-3 /proc/loadavg)"
    # ... and with one BLAS thread (threaded BLAS suffers most when the machine is shared)
    (cd "$OUT" && OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \
        "$VENV/bin/python" "$HERE/bench_peers.py" --matrix "$OUT/$name" --reps "$REPS" \
        --out "$OUT/results.jsonl" --label " [BLAS: 1 thread]")
    echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"
    "$VENV/bin/python" "$HERE/compare.py" "$OUT/results.jsonl"
}

case "$PHASE" in
    install) install ;;
    run) run ;;
    all) install; run ;;
    *) echo "usage: $0 [install|run|all]" >&2; exit 2 ;;
esac
