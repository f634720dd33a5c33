#!/usr/bin/env bash
# Session 42's check of one grasp file on the bottles held out of the search (two seeded placements each):
#   bash benchmarks/results/experiments/s42_shroud_search/check.sh GRASP_FILE LABEL [OUT_DIR]
# writes OUT_DIR/{plain_committed,plain_val,shroud}_LABEL.json (default OUT_DIR: out/s42/check).
# Needs the bottles of make_sets.py under out/s42.
set -euo pipefail
grasp=$1; label=$2; out=${3:-out/s42/check}
mkdir -p "$out"
sweep="python diagrams/handwritten_sweep.py --placements 2 --grasp $grasp --no-cache"
$sweep --categories spray_bottle --instances spray_bottle_{01,03,05,07,09,11,12,13,14,15,16} \
    --json "$out/plain_committed_$label.json"
$sweep --objects out/s42/val_objects/spray_bottle_val_{01,03,05,07,09,11,12,13,14,15,16} \
    --json "$out/plain_val_$label.json"
$sweep --objects out/s42/shroud/spray_bottle_{03,10,16}_shroud out/s42/shroud_val/spray_bottle_val_{05,13,16}_shroud \
    --json "$out/shroud_$label.json"
