#!/bin/sh
# The perception worked example: 26 stimuli (the standard scale, flat tops, natural-like textures), a
# simulated experiment (truth: the surrogate's V), the embedding, and the fit of coarse-FEM V to it.
#   sh examples/perception/run.sh OUT [--overwrite]
# writes into the folder OUT (created; stimuli.csv copied there); existing outputs are refused without
# --overwrite. The committed outputs: sh examples/perception/run.sh examples/perception --overwrite
# (about 30 min on a shared 2-core machine, most of it the 78 coarse FEM runs)
set -e
if [ $# -lt 1 ] || [ $# -gt 2 ] || { [ $# -eq 2 ] && [ "$2" != "--overwrite" ]; }; then
    echo "usage: sh examples/perception/run.sh OUT [--overwrite]" >&2
    exit 2
fi
HERE=$(cd "$(dirname "$0")" && pwd)
W=${2:-}
mkdir -p "$1"
cd "$1"
[ -e stimuli.csv ] || cp "$HERE/stimuli.csv" stimuli.csv
R="python -m roughness.cli"
$R perception design --stimuli stimuli.csv --trials 1500 --seed 1 --out design.csv $W
$R perception simulate --stimuli stimuli.csv --engine surrogate --trials 1500 --seed 1 --out simulated $W
$R perception embed simulated/trials.csv --stimuli stimuli.csv --roughest standard-1.625 --workers 2 \
    --out embedding $W
$R perception fit embedding/embedding.csv --stimuli stimuli.csv --engine fem:coarse --forces 5,20 --cache /tmp/roughness-fem-cache \
    --out fit $W
$R perception plan --stimuli stimuli.csv --truth simulated/truth.csv --trials 250,500,1000,1500,3000 --experiments 20 \
    --out plan $W
