#!/usr/bin/env bash
# Trains the Surrogate v2 ensemble (issue 12) on the datasets of recipes/build-v2.sh and exports it
# with its int8 graph and model card into RUNS (the shipped files are copied from there by hand):
#
#   bash training/train-v2.sh DATA RUNS
#
# DATA holds training-v2-default.h5 and training-v2-fine.h5. Members are trained one after another
# (2 torch threads each; MEMBERS, MINUTES, WIDTHS and HIDDEN override the defaults below); a member
# whose checkpoint exists is kept, so an interrupted run goes on where it stopped. Multi-fidelity:
# every level of every label (coarse and default from the default build, default and fine from the
# fine build), the contact spacing an input; the graph answers at the finest (fine, 0.14 mm).
# knit and waffle are held out entirely (the out-of-family scores).
set -euo pipefail
DATA=${1:?usage: train-v2.sh DATA RUNS}
RUNS=${2:?usage: train-v2.sh DATA RUNS}
MEMBERS=${MEMBERS:-5}
MINUTES=${MINUTES:-20}
WIDTHS=${WIDTHS:-8,16,32,64}  # 5 members at 75k parameters each: about 0.44 ms per graph call at batch 1
HIDDEN=${HIDDEN:-32}
mkdir -p "$RUNS"
for ((k = 0; k < MEMBERS; k++)); do
    [[ -f "$RUNS/m$k/checkpoint.pt" ]] && continue
    roughness train "$DATA/training-v2-default.h5" --extra-data "$DATA/training-v2-fine.h5" --levels all \
        --holdout-family knit,waffle --seed "$k" --max-minutes "$MINUTES" --widths "$WIDTHS" --hidden "$HIDDEN" \
        --threads 2 --out "$RUNS/m$k" --overwrite
done
members=()
for ((k = 0; k < MEMBERS; k++)); do members+=("$RUNS/m$k/checkpoint.pt"); done
roughness ensemble "${members[@]}" --out "$RUNS/roughness-cnn.onnx" \
    --data "$DATA/training-v2-default.h5" "$DATA/training-v2-fine.h5" --int8 "$RUNS/roughness-cnn-int8.onnx" \
    --overwrite
roughness card "$RUNS/m0" "$RUNS/roughness-cnn.onnx" --card "$RUNS/MODEL_CARD.md" --plots "$RUNS" --overwrite
