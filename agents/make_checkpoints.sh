#!/usr/bin/env bash
# Trains, releases and evaluates the small checkpoints shipped in agents/ (agents/README.md):
#   agents/vln_cm_small.pt   agents/configs/vln_cm_small.json (seed 0)
#   agents/vln_dt_small.pt   agents/configs/vln_dt_small.json (seed 0)
# Each is evaluated on the procedural benchmark's val_seen (proc-0 … proc-39, 3 new paths each)
# and val_unseen (proc-100 … proc-109, 12 paths each), and on the small "check" split a test
# re-runs (val_seen's 3 paths of proc-31). Writes agents/checkpoints.md (the table) and
# agents/checkpoints.json (every metric, with the commands).
# Usage: agents/make_checkpoints.sh [RUNS_DIR]   (default: runs/shipped; THREADS=1)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-runs/shipped}
THREADS=${THREADS:-1}
SEEN=(--scenes proc-0:40 --per-scene 3 --skip 20 --split val_seen)
UNSEEN=(--scenes proc-100:110 --per-scene 12 --split val_unseen)
CHECK=(--scenes proc-31 --per-scene 3 --skip 20 --split check)

for agent in vln_cm vln_dt; do
    name="${agent}_small"
    python -m havln_mj.agents.train --config "$name" --out "$RUNS/$name" --threads "$THREADS" \
        --no-progress
    python -m havln_mj.agents.release "$RUNS/$name/best.pt" "agents/$name.pt"
    for split in SEEN UNSEEN CHECK; do
        declare -n args=$split
        python -m havln_mj.eval "${args[@]}" --agent "agents/$name.pt" --threads "$THREADS" \
            --out "$RUNS/eval/$name/$split" >/dev/null
    done
done

python - "$RUNS" "${CHECK[*]}" <<'PY'
import json, sys
from pathlib import Path
runs, check = Path(sys.argv[1]), sys.argv[2].split()
manifest, timing = {}, ("seconds", "instructions_per_s")
for agent in ("vln_cm", "vln_dt"):
    name = f"{agent}_small"
    rows = [json.loads((runs / "eval" / name / s / "summary.json").read_text())[0]
            for s in ("SEEN", "UNSEEN", "CHECK")]
    (runs / "eval" / name / "summary.json").write_text(json.dumps(rows, indent=1))
    manifest[f"{name}.pt"] = {
        "agent": agent,
        "train": f"python -m havln_mj.agents.train --config {name} --out runs/shipped/{name}",
        "release": f"python -m havln_mj.agents.release runs/shipped/{name}/best.pt agents/{name}.pt",
        "check": check,
        "splits": {r["split"]: {k: v for k, v in r.items() if k not in timing} for r in rows},
    }
Path("agents/checkpoints.json").write_text(json.dumps(manifest, indent=1) + "\n")
PY
python -m havln_mj.eval.tables --out "$RUNS/eval/table.md" --splits val_seen val_unseen check \
    --row "VLN-CM small (agents/vln_cm_small.pt)=$RUNS/eval/vln_cm_small" \
    --row "VLN-DT small (agents/vln_dt_small.pt)=$RUNS/eval/vln_dt_small"
cp "$RUNS/eval/table.md" agents/checkpoints.md
