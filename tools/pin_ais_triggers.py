"""Write ``catgrasp_drake/benchmark/ais_triggers.json``: the AIS drills' trigger boxes, pinned (session 21).

    python tools/pin_ais_triggers.py OLD_IMPORTS_DIR

The AIS clouds carry no trigger annotation. Until session 21 the benchmark's AIS split imported each cloud
with the committed drill model and took the trigger box the model's fit transferred from its canonical drill,
so the judge of the ``ais`` split moved whenever the drill model changed: a retrained model was judged
against its own transfer (session 21: ais_drill_4's box 7 mm further back). This pins the boxes every AIS
record of sessions 18-20 was judged with -- those the session-7 drill model (sha256 8ac347cd...) transferred
-- in each cloud's own frame (the canonical frame the data set gives; before the importer's levelling of the
stated identity and its 3 mm base cut, which the import applies again). ``OLD_IMPORTS_DIR`` holds the
imports that model made (``out/benchmark/data/ais/drill`` of a checkout before session 21).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.core.fileio import atomic_write_text  # noqa: E402
from catgrasp_drake.data.importer import transform_matrix  # noqa: E402

MODEL_SHA256 = "8ac347cd99361758212240bb9861e9af8895e5663d7f8c974b5ad9250efefb38"
OUT = ROOT / "catgrasp_drake" / "benchmark" / "ais_triggers.json"


def main() -> None:
    boxes = {}
    for ann_path in sorted(Path(sys.argv[1]).glob("ais_drill_*/annotations.json")):
        ann = json.loads(ann_path.read_text())
        rec = ann["import"]
        X = transform_matrix(rec["transform"]["rpy_deg"], rec["transform"]["xyz_m"])  # the levelled identity
        box = ann["regions"]["trigger"]
        centre = np.asarray(box["center"], float) + [0.0, 0.0, rec["base_flattened_m"]]
        p = np.linalg.solve(X, np.r_[centre, 1.0])[:3]
        boxes[ann["instance"]] = {"center": [round(float(v), 6) for v in p], "half_extents": box["half_extents"],
                                  "grown_by": box["grown_by"], "transferred_from": box["transferred_from"]}
    atomic_write_text(OUT, json.dumps({
        "format": "catgrasp.ais_triggers", "format_version": 1,
        "frame": "each cloud's own (the data set's canonical frame), before the import's levelling and base cut",
        "made_by": f"the drill model sha256 {MODEL_SHA256} (sessions 7-20): its fit's transfer of drill_00's "
                   "trigger box", "triggers": boxes}, indent=1) + "\n")
    print(f"wrote {OUT} ({len(boxes)} drills)")


if __name__ == "__main__":
    main()
