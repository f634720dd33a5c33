"""Mean in-hand shift (mm) and turn (deg) of the held trials in handwritten-sweep JSON files (session 17).

    python benchmarks/results/experiments/s17_windex/sweep_means.py FILE.json [FILE.json ...]

Each FILE is a ``diagrams/handwritten_sweep.py --json`` output. The table "bottles / grasp / mean in-hand
shift / turn" in docs/station.md (session 17) came from sweeps of the spray bottles:
- session 17's bottles: ``python diagrams/handwritten_sweep.py --categories spray_bottle --json FILE``;
- session 16's bottles and grasp: the same in a worktree of 61f7891 (``git worktree add DIR 61f7891``), and
  there with ``--posture closed.svh_index_proximal=0.7985 closed.svh_index_distal=1.334`` for the index to its
  limits.
"""
import json
import sys

for path in sys.argv[1:]:
    held = [r for r in json.load(open(path)) if r.get("in_hand_shift_m") is not None]
    if not held:
        print(f"{path}: no held trials")
        continue
    shift = 1000 * sum(r["in_hand_shift_m"] for r in held) / len(held)
    turn = sum(r["in_hand_turn_deg"] for r in held) / len(held)
    print(f"{path}: {len(held)} held trials, mean in-hand shift {shift:.1f} mm, turn {turn:.1f} deg")
