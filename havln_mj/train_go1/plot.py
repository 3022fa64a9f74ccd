"""The curriculum plot of a run: mean terrain level and walk success per iteration."""

from __future__ import annotations

import json
import os
from pathlib import Path


def plot_curriculum(log: str | Path, out: str | Path) -> None:
    """Draws a run's mean terrain level and walk success per iteration to a PNG, atomically.

    Success is the share of the walks ended in an iteration that got far enough without a fall
    (dots), with its 20-iteration mean (line).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    rows = [json.loads(line) for line in Path(log).read_text().splitlines() if line.strip()]
    it = [r["iteration"] for r in rows]
    fig, ax = plt.subplots(figsize=(7, 4), dpi=100)
    ax.plot(it, [r["mean_level"] for r in rows], color="tab:blue", label="mean terrain level")
    ax.set_xlabel("iteration")
    ax.set_ylabel("mean terrain level", color="tab:blue")
    ax2 = ax.twinx()
    pts = [(r["iteration"], r["success"]) for r in rows if r["success"] is not None]
    if pts:
        x, y = np.array(pts).T
        ax2.plot(x, y, ".", color="tab:orange", alpha=0.3, markersize=3)
        k = min(20, len(y))
        ax2.plot(
            x[k - 1 :],
            np.convolve(y, np.ones(k) / k, mode="valid"),
            color="tab:orange",
            label=f"success ({k}-iteration mean)",
        )
    ax2.set_ylim(0, 1)
    ax2.set_ylabel("walk success", color="tab:orange")
    steps = rows[-1]["env_steps"] if rows else 0
    ax.set_title(f"GO1 terrain curriculum ({steps:,} policy steps)")
    fig.tight_layout()
    tmp = Path(out).with_name(Path(out).name + ".tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    os.replace(tmp, out)
