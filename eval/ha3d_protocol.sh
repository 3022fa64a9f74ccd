#!/usr/bin/env bash
# Reproduces eval/ha3d_protocol_table.md (and .json): HA-R2R val_seen at graph level, people
# from HA3D's placements, each agent under our strict protocol and under HA3D's, beside the
# HA-VLN paper's rows; and eval/ha3d_viewpoint_stats.json. See eval/ha3d_protocol.md.
# Usage: eval/ha3d_protocol.sh DATA_DIR [RUNS_DIR]
#   DATA_DIR holds mp3d_connectivity/, ha_r2r/HA_val_seen.json and ha3d/human_placements.json
#   (CI: ../shared/data). Trained agents: set CM=path/to/vln_cm.pt and DT=path/to/vln_dt.pt
#   (the table's rows: CM=agents/vln_cm_small.pt DT=agents/vln_dt_small.pt).
set -euo pipefail
cd "$(dirname "$0")/.."
D=$(realpath "$1"); RUNS=${2:-runs/ha3d_protocol}
EVAL=(--dataset "$D/ha_r2r/HA_val_seen.json" --split val_seen
      --connectivity-dir "$D/mp3d_connectivity" --human-placements "$D/ha3d/human_placements.json")
AGENTS=(shortest oracle random)
[[ -n "${CM:-}" ]] && AGENTS+=("$CM")
[[ -n "${DT:-}" ]] && AGENTS+=("$DT")
for protocol in strict ha3d; do
    for agent in "${AGENTS[@]}"; do
        name=$(basename "$agent" .pt)
        python -m havln_mj.eval "${EVAL[@]}" --agent "$agent" --protocol "$protocol" \
            --out "$RUNS/$protocol/$name"
    done
done
# HA3D's protocol with people pinned to their viewpoints, counted per step and per visit.
for agent in shortest oracle; do
    python -m havln_mj.eval "${EVAL[@]}" --agent "$agent" --protocol ha3d --pinned-people \
        --out "$RUNS/ha3d-pinned/$agent"
    python -m havln_mj.eval "${EVAL[@]}" --agent "$agent" --protocol ha3d --pinned-people \
        --count viewpoint --out "$RUNS/ha3d-pinned-visit/$agent"
done
ROWS=()
for agent in "${AGENTS[@]}"; do
    name=$(basename "$agent" .pt)
    for protocol in strict ha3d; do ROWS+=(--row "$name ($protocol)=$RUNS/$protocol/$name"); done
done
for agent in shortest oracle; do
    ROWS+=(--row "$agent (ha3d, pinned people)=$RUNS/ha3d-pinned/$agent")
    ROWS+=(--row "$agent (ha3d, pinned, per visit)=$RUNS/ha3d-pinned-visit/$agent")
done
python -m havln_mj.eval.tables --paper --splits val_seen --out eval/ha3d_protocol_table.md "${ROWS[@]}"
python -m havln_mj.eval.stats --connectivity-dir "$D/mp3d_connectivity" \
    --human-placements "$D/ha3d/human_placements.json" --out eval/ha3d_viewpoint_stats.json
