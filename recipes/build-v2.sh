#!/usr/bin/env bash
# Remakes the Surrogate v2 datasets (issue 12) in folder OUT (default: the current folder):
#   training-v2-default.h5   recipes/training-v2.json, 6,000 samples at default (each with its coarse twin)
#   training-v2-fine.h5      the same recipe's first 1,500 samples at fine (each with its default twin)
#   validation-converged.h5  recipes/validation.json, 160 textures converged to 1% (the reference)
# Samples in the committed labels files (recipes/labels/) are restored without the FEM; any others
# are simulated (hours: the build resumes when run again). Each file's inputs checksum is then checked
# against the committed recipes/<name>.sha256.json, where there is one.
#
#   bash recipes/build-v2.sh [OUT]
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
OUT=${1:-.}
mkdir -p "$OUT"

build() {  # name, then the build's options
    local name=$1; shift
    local labels=()
    [[ -f "$HERE/labels/$name.labels.jsonl.gz" ]] && labels=(--labels "$HERE/labels/$name.labels.jsonl.gz")
    roughness dataset build "$@" --workers 2 --out "$OUT/$name.h5" "${labels[@]}"
    python - "$OUT/$name.h5" "$HERE/$name.sha256.json" <<'EOF'
import json, sys
from pathlib import Path
from roughness.dataset.digest import inputs_sha256
got, committed = inputs_sha256(sys.argv[1]), Path(sys.argv[2])
if committed.exists() and json.loads(committed.read_text())["inputs_sha256"] != got:
    sys.exit(f"{sys.argv[1]}: inputs_sha256 {got} differs from {committed}")
print(f"{sys.argv[1]}: inputs_sha256 {got}" + (" (as committed)" if committed.exists() else ""))
EOF
}

build training-v2-default --recipe "$HERE/training-v2.json" --n 6000 --fidelity default
build training-v2-fine --recipe "$HERE/training-v2.json" --n 1500 --fidelity fine
build validation-converged --recipe "$HERE/validation.json" --n 160 --fidelity converged --tolerance 0.01
