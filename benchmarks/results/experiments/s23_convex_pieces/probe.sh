#!/bin/bash
# The probe of session 23 (issue 17, convex pieces): the hand-written grasp on the four objects of
# make_pieces.py in each collision mode, 2 seeded placements each, twice, one trial at a time (no other
# load), modes interleaved. Usage: bash probe.sh OUT_DIR   (OUT_DIR made by make_pieces.py --out OUT_DIR)
set -euo pipefail
out=$1
for rep in 0 1; do
  for obj in drill/drill_00 drill/drill_03 spray_bottle/spray_bottle_00 mug/mug_00; do
    for mode in mesh rigid compliant; do
      python diagrams/handwritten_sweep.py --objects "$out/$mode/$obj" --placements 2 --no-cache --workers 1 \
        --json "$out/res_${mode}_$(basename "$obj")_$rep.json" > /dev/null
    done
  done
done
