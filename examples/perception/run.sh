#!/bin/sh
# The perception worked example: 26 stimuli (the standard scale, flat tops, natural-like textures), a
# simulated experiment (truth: the surrogate's V), the embedding, and the fit of coarse-FEM V to it.
# Run from the repository root:  sh examples/perception/run.sh   (about 30 min on a shared 2-core machine, most of it the 78 coarse FEM runs)
set -e
cd "$(dirname "$0")"
R="python -m roughness.cli"
$R perception design --stimuli stimuli.csv --trials 1500 --seed 1 --out design.csv --overwrite
$R perception simulate --stimuli stimuli.csv --engine surrogate --trials 1500 --seed 1 --out simulated --overwrite
$R perception embed simulated/trials.csv --stimuli stimuli.csv --roughest standard-1.625 --workers 2 \
    --out embedding --overwrite
$R perception fit embedding/embedding.csv --stimuli stimuli.csv --engine fem:coarse --forces 5,20 --cache /tmp/roughness-fem-cache \
    --out fit --overwrite
$R perception plan --stimuli stimuli.csv --truth simulated/truth.csv --trials 250,500,1000,1500,3000 --experiments 20 \
    --out plan --overwrite
