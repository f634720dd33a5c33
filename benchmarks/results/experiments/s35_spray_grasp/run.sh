#!/bin/bash
# session 35: spray grasp variants on committed bottles + large copies of the widest-gap committed bottles (tuning sets)
cd "$(dirname "$0")/../../../.." && . .venv/bin/activate  # the repository root
# the stress copies are written by `catgrasp benchmark --split stress` (or s26_trigger_gap/gap_vs_miss.py)
S=out/benchmark/data/stress/spray_bottle
LARGE="$S/spray_bottle_01_large $S/spray_bottle_13_large $S/spray_bottle_08_large $S/spray_bottle_09_large $S/spray_bottle_06_large $S/spray_bottle_03_large $S/spray_bottle_05_large"
run() { name=$1; shift
  python diagrams/handwritten_sweep.py --categories spray_bottle --workers 2 --cache out/s35/sweeps/cache --json benchmarks/results/experiments/s35_spray_grasp/${name}_committed.json "$@" > /dev/null
  python diagrams/handwritten_sweep.py --objects $LARGE --workers 2 --cache out/s35/sweeps/cache --json benchmarks/results/experiments/s35_spray_grasp/${name}_large.json "$@" > /dev/null
}
run A_as_committed
run V1_pitch-10_fwd8 --rotate -10 0 0 --shift 0 0.008 -0.012
run V2_pitch-10 --rotate -10 0 0 --shift 0 0 -0.012
run V4_yaw+10 --rotate 0 0 10 --shift -0.01 0 0
run V5_yaw-10 --rotate 0 0 -10 --shift 0.01 0 0
run V3_pitch+10 --rotate 10 0 0 --shift 0 0 0.012
run P1_close_slow --plan close_time=1.6
run P2_close_fast --plan close_time=0.4
run P3_clear_1mm --plan object_penetration_tol=0.001
echo DONE
