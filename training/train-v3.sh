#!/usr/bin/env bash
# Trains the Surrogate v3 ensemble (issue 29) on the datasets of recipes/build-v3.sh and exports it
# with its int8 graph and model card into RUNS (the shipped files are copied from there by hand):
#
#   bash training/train-v3.sh DATA RUNS
#
# DATA holds training-v3.h5 and training-v3-printed.h5 (110,000 spectral labels) and training-v2-default.h5,
# training-v2-fine.h5 (FEM labels): recipes/build-v3.sh. Members are trained one after another (2 torch
# threads each; MEMBERS, EPOCHS, MINUTES, WIDTHS, HIDDEN, FEM_WEIGHT, HOLDOUT, MODEL_VERSION override the defaults below; the epochs bind,
# not the minutes, so the learning-rate schedule does not depend on how loaded the machine is); a member whose
# checkpoint exists is kept and an interrupted member resumes from its last finished epoch (--resume), so the
# script run again goes on where it stopped. Multi-fidelity: the spectral labels teach the shared features; the FEM labels converged to 3% (their estimate), each at its finest level,
# teach the finite block's departure; the graph answers as the FEM at fine (h = 0.14 mm). waffle and knurl are
# held out entirely, with every composite made of them (the out-of-family scores): the shipped model version 4.
# Model version 3 held out knit and waffle (HOLDOUT=knit,waffle MODEL_VERSION=3 remakes it).
# Targets log(V + 1e-4): V resolved down to ~1e-4 (v2: 1e-3).
set -euo pipefail
DATA=${1:?usage: train-v3.sh DATA RUNS}
RUNS=${2:?usage: train-v3.sh DATA RUNS}
MEMBERS=${MEMBERS:-5}
EPOCHS=${EPOCHS:-40}
MINUTES=${MINUTES:-600}
WIDTHS=${WIDTHS:-8,16,32,64}
HIDDEN=${HIDDEN:-32}
FEM_WEIGHT=${FEM_WEIGHT:-4}
HOLDOUT=${HOLDOUT:-waffle,knurl}
MODEL_VERSION=${MODEL_VERSION:-4}
EXTRA=("$DATA/training-v3-printed.h5" "$DATA/training-v2-default.h5" "$DATA/training-v2-fine.h5")
mkdir -p "$RUNS"
for ((k = 0; k < MEMBERS; k++)); do
    [[ -f "$RUNS/m$k/checkpoint.pt" ]] && continue
    roughness train "$DATA/training-v3.h5" --extra-data "${EXTRA[@]}" --levels all --max-label-error 0.03 \
        --query-h-mm 0.14 --fem-weight "$FEM_WEIGHT" --log-offset 1e-4 --holdout-family "$HOLDOUT" --seed "$k" \
        --max-epochs "$EPOCHS" --max-minutes "$MINUTES" --widths "$WIDTHS" --hidden "$HIDDEN" --threads 2 \
        --out "$RUNS/m$k" --resume
done
members=()
for ((k = 0; k < MEMBERS; k++)); do members+=("$RUNS/m$k/checkpoint.pt"); done
roughness ensemble "${members[@]}" --out "$RUNS/roughness-cnn.onnx" \
    --data "$DATA/training-v3.h5" "${EXTRA[@]}" --int8 "$RUNS/roughness-cnn-int8.onnx" --model-version "$MODEL_VERSION" --overwrite
roughness card "$RUNS/m0" "$RUNS/roughness-cnn.onnx" --card "$RUNS/MODEL_CARD.md" --plots "$RUNS" --overwrite
