# The first-run figures of docs/performance.md, "First run" (on a quiet machine): D, --help,
# the paper (full) and the free-base wing on empty numba caches, then warm.
cd "$(dirname "$0")/.."
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
t() { s=$(date +%s.%N); "$@" > /dev/null 2>&1; e=$(date +%s.%N); echo "$(echo "$e - $s" | bc)"; }
D=$(t .venv/bin/python -c "import numpy, scipy.integrate, pandas, numba")
echo "D $D"
C=$(mktemp -d)
echo "help $(t .venv/bin/rodval --help)"
echo "paper_full_cold $(NUMBA_CACHE_DIR=$C t .venv/bin/rodval simulate paper --model full --out $(mktemp -d)/r)"
echo "free_wing_after $(NUMBA_CACHE_DIR=$C t .venv/bin/rodval simulate studies/scenes/wing6_spacecraft.toml --model full --set t_end=0.5 --out $(mktemp -d)/r)"
C2=$(mktemp -d)
echo "free_wing_cold $(NUMBA_CACHE_DIR=$C2 t .venv/bin/rodval simulate studies/scenes/wing6_spacecraft.toml --model full --set t_end=0.5 --out $(mktemp -d)/r)"
echo "paper_full_warm $(NUMBA_CACHE_DIR=$C t .venv/bin/rodval simulate paper --model full --out $(mktemp -d)/r)"
