#!/bin/bash
# Session 17 controls (scratch experiment, not the product): which part of the spray-bottle change moved the
# test-split figure? Both run the latent method, single view, on the session-17 test split (domed shoulders),
# through the benchmark, each in a git worktree of the session-17 commit with one model file swapped:
#   s16model   the session-16 model (git show 61f7891:models/trained/spray_bottle.npz): the old model and grasp
#   noindex    the session-17 model with the index finger's closed posture in its (mean) regressor set back to
#              session 16's 0.7227 / 0.496 rad: the new model without the squeezing index
# Usage (from the repository root, venv active, ~5 min each on 2 cores):
#   bash benchmarks/results/experiments/s17_controls/run_controls.sh [COMMIT]
set -euo pipefail
REPO=$(pwd); COMMIT=${1:-HEAD}; OUT=benchmarks/results/experiments/s17_controls
DATA=$REPO/out/benchmark/data
for variant in s16model noindex; do
  wt=$(mktemp -d)/wt; git worktree add -q "$wt" "$COMMIT"
  if [ $variant = s16model ]; then
    git show 61f7891:models/trained/spray_bottle.npz > "$wt/models/trained/spray_bottle.npz"
  else
    PYTHONPATH="$wt" python - "$wt/models/trained/spray_bottle.npz" <<'PY'
import sys
from dataclasses import replace
from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.robot.models import HAND_ACTUATED_JOINTS
path = sys.argv[1]
m = CategoryModel.load(path)
assert abs(m.regressor.coef).max() < 1e-9, "expects a regressor without shape dependence (the mean)"
b = m.regressor.intercept.copy()
closed = len(b) - len(HAND_ACTUATED_JOINTS)  # the descriptor ends with the closed posture (REGRESSED_POSTURES)
for joint, angle in (("svh_index_proximal", 0.7227), ("svh_index_distal", 0.496)):
    b[closed + HAND_ACTUATED_JOINTS.index(joint)] = angle
m = replace(m, regressor=replace(m.regressor, intercept=b))
m.save(path)
PY
  fi
  (cd "$wt" && PYTHONPATH="$wt" python -m catgrasp_drake.cli benchmark --categories spray_bottle --methods latent \
      --cache "$(mktemp -d)" --data "$DATA" --out "$REPO/$OUT/$variant.jsonl")
  git worktree remove --force "$wt"
done
