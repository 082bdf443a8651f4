#!/usr/bin/env bash
# All performance benchmarks (not part of the test suite). Usage: benchmarks/run_all.sh OUT_DIR
# One BLAS thread: the machine is shared, and multi-threaded BLAS on small matrices only adds
# contention to the numpy baseline.
set -euo pipefail
OUT=${1:-out/bench}
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
PY=${PYTHON:-python}
$PY -m rodval bench work-precision --out "$OUT/work_precision"
$PY -m rodval bench cost-n --out "$OUT/cost_n"
$PY -m rodval bench skips --out "$OUT/skips"
$PY -m rodval bench speedup --out "$OUT/speedup"
$PY -m rodval bench scale --out "$OUT/scale"
# Study runner overhead (cold fresh process per case vs warm workers) and the subnormal check:
$PY benchmarks/study_overhead.py studies/scale_study.toml --out "$OUT/study_overhead" --workers 1,2 --cold 10
$PY -m rodval bench fast-path --out "$OUT/fast_path"
$PY -m rodval bench stiffness --out "$OUT/stiffness"
$PY benchmarks/stiffness_evidence.py
$PY benchmarks/rigid_lock_scale.py
$PY benchmarks/subnormal_cost.py --reduced-only 128 1024 8192 32768
