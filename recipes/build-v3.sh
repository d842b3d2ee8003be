#!/usr/bin/env bash
# Remakes the Surrogate v3 training set (issue 29) in folder OUT (default: the current folder):
#   training-v3.h5          recipes/training-v3.json, 100,000 samples labelled by the spectral engine
#   training-v3-printed.h5  recipes/training-v3-printed.json: the printed twins of its first 10,000
# and the FEM datasets it is trained beside (recipes/build-v2.sh: training-v2-default.h5, training-v2-fine.h5,
# validation-converged.h5; restored from their committed labels). The spectral build takes about 2-3 hours on
# 2 cores and resumes when run again; WORKERS (default 2) sets its local Dask workers. The inputs checksum is
# then checked against the committed recipes/<name>.sha256.json, where there is one.
#
#   bash recipes/build-v3.sh [OUT]
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
OUT=${1:-.}
mkdir -p "$OUT"
build() {  # name, samples
    OMP_NUM_THREADS=1 roughness dataset build --recipe "$HERE/$1.json" --n "$2" --engine spectral \
        --workers "${WORKERS:-2}" --out "$OUT/$1.h5"
    python - "$OUT/$1.h5" "$HERE/$1.sha256.json" <<'PY'
import json, sys
from pathlib import Path
from roughness.dataset.digest import inputs_sha256
got, committed = inputs_sha256(sys.argv[1]), Path(sys.argv[2])
if committed.exists() and json.loads(committed.read_text())["inputs_sha256"] != got:
    sys.exit(f"{sys.argv[1]}: inputs_sha256 {got} differs from {committed}")
print(f"{sys.argv[1]}: inputs_sha256 {got}" + (" (as committed)" if committed.exists() else ""))
PY
}

build training-v3 100000
build training-v3-printed 10000
bash "$HERE/build-v2.sh" "$OUT"
