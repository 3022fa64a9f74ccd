#!/usr/bin/env bash
# Reproduces eval/ha_r2r_proxies.md: VLN-CM and VLN-DT trained on R2R train in the graph
# proxies of the real buildings (people from HA3D's placements), evaluated on HA-R2R val_seen,
# beside the baselines.
# Usage: eval/ha_r2r_proxies.sh DATA_DIR [RUNS_DIR]
#   DATA_DIR holds mp3d_connectivity/, r2r/R2R_train.json, ha_r2r/HA_val_seen.json and
#   ha3d/human_placements.json (CI: ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
D=$(realpath "$1"); RUNS=${2:-runs/ha_r2r}; THREADS=${THREADS:-1}
WHERE=(--set data_dir="$D" --set connectivity_dir="$D/mp3d_connectivity"
       --set human_placements="$D/ha3d/human_placements.json")
EVAL=(--dataset HA_val_seen --split val_seen --data-dir "$D" --threads "$THREADS"
      --connectivity-dir "$D/mp3d_connectivity" --human-placements "$D/ha3d/human_placements.json")
for agent in cm dt; do
    resume=()
    [[ -f "$RUNS/$agent/checkpoint.pt" ]] && resume=(--resume)  # an interrupted run goes on
    python -m havln_mj.agents.train --config "vln_${agent}_r2r" --out "$RUNS/$agent" \
        --threads "$THREADS" "${resume[@]}" --no-progress "${WHERE[@]}"
    python -m havln_mj.eval "${EVAL[@]}" --agent "$RUNS/$agent/best.pt" --out "$RUNS/eval/$agent"
done
for agent in shortest oracle random; do
    python -m havln_mj.eval "${EVAL[@]}" --agent "$agent" --out "$RUNS/eval/$agent"
done
E="$RUNS/eval"
python -m havln_mj.eval.tables --paper --splits val_seen --out eval/ha_r2r_proxies.md \
    --row "optimal expert (shortest)=$E/shortest" --row "sub-optimal expert (oracle)=$E/oracle" \
    --row "random walk=$E/random" --row "VLN-CM 0 % random=$E/cm" \
    --row "VLN-DT 100 % random, paper reward=$E/dt"
