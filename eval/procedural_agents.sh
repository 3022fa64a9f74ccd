#!/usr/bin/env bash
# Reproduces eval/procedural_agents.md: VLN-CM at five random-walk proportions, VLN-DT with
# three rewards, and the baselines, on the procedural HA-R2R benchmark:
#   train      proc-0 … proc-39, 20 paths each (3 instructions per path), people seed 0
#   val_seen   the same 40 houses, 3 new paths each (--skip 20)
#   val_unseen proc-100 … proc-109, 12 paths each
# Usage: eval/procedural_agents.sh [RUNS_DIR]   (default: runs/procedural)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-runs/procedural}
SEEN=(--scenes proc-0:40 --per-scene 3 --skip 20 --split val_seen)
UNSEEN=(--scenes proc-100:110 --per-scene 12 --split val_unseen)
THREADS=${THREADS:-1}

train() {  # name config overrides...
    local name=$1 config=$2; shift 2
    local sets=() resume=()
    for kv in "$@"; do sets+=(--set "$kv"); done
    [[ -f "$RUNS/$name/checkpoint.pt" ]] && resume=(--resume)  # an interrupted run goes on
    python -m havln_mj.agents.train --config "$config" --out "$RUNS/$name" --threads "$THREADS" \
        "${resume[@]}" --no-progress "${sets[@]}"
}

evaluate() {  # name agent
    local out="$RUNS/eval/$1"
    python -m havln_mj.eval "${SEEN[@]}" --agent "$2" --threads "$THREADS" --out "$out/seen" >/dev/null
    python -m havln_mj.eval "${UNSEEN[@]}" --agent "$2" --threads "$THREADS" --out "$out/unseen" >/dev/null
    python - "$out" <<'PY'
import json, sys
from pathlib import Path
out = Path(sys.argv[1])
rows = [json.loads((out / s / "summary.json").read_text())[0] for s in ("seen", "unseen")]
(out / "summary.json").write_text(json.dumps(rows, indent=1))
PY
}

for agent in shortest oracle random; do evaluate "$agent" "$agent"; done
for seed in 0 1 2; do
    train "cm_r0_s$seed" agents/configs/vln_cm.json "seed=$seed"
    evaluate "cm_r0_s$seed" "$RUNS/cm_r0_s$seed/best.pt"
    train "dt_paper_s$seed" agents/configs/vln_dt.json "seed=$seed"
    evaluate "dt_paper_s$seed" "$RUNS/dt_paper_s$seed/best.pt"
done
for pct in 3 25 50 100; do
    frac=$(python -c "print($pct / 100)")
    train "cm_r${pct}_s0" agents/configs/vln_cm.json "random_fraction=$frac"
    evaluate "cm_r${pct}_s0" "$RUNS/cm_r${pct}_s0/best.pt"
done
for reward in strategy_1 strategy_2; do
    train "dt_${reward}_s0" agents/configs/vln_dt.json "model.reward=$reward"
    evaluate "dt_${reward}_s0" "$RUNS/dt_${reward}_s0/best.pt"
done

E="$RUNS/eval"
python -m havln_mj.eval.tables --paper --out eval/procedural_agents.md \
    --row "optimal expert (shortest)=$E/shortest" \
    --row "sub-optimal expert (oracle)=$E/oracle" \
    --row "random walk=$E/random" \
    --row "VLN-CM 0 % random (3 seeds)=$E/cm_r0_s0,$E/cm_r0_s1,$E/cm_r0_s2" \
    --row "VLN-CM 3 % random=$E/cm_r3_s0" \
    --row "VLN-CM 25 % random=$E/cm_r25_s0" \
    --row "VLN-CM 50 % random=$E/cm_r50_s0" \
    --row "VLN-CM 100 % random=$E/cm_r100_s0" \
    --row "VLN-DT 100 % random, paper reward (3 seeds)=$E/dt_paper_s0,$E/dt_paper_s1,$E/dt_paper_s2" \
    --row "VLN-DT 100 % random, target reward only=$E/dt_strategy_1_s0" \
    --row "VLN-DT 100 % random, target + human=$E/dt_strategy_2_s0"
