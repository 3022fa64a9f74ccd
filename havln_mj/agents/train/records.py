"""What a run writes beside its checkpoints: the log, the history, TensorBoard and a plot.

* ``config.json``: the resolved configuration (every default filled in); it reads back as a
  ``--config`` to the same run;
* ``train.log``: plain-text lines;
* ``history.json``: one entry per logged iteration (loss, and val metrics when evaluated);
* ``tensorboard/``: the same numbers as TensorBoard scalars (``train/loss``, ``val/sr``, ...;
  ``tensorboard --logdir OUT``), resumed runs drop the events past their checkpoint;
* ``loss.png``: the training loss and val SR.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

from tqdm import tqdm

from havln_mj.cache import atomic_write_bytes, atomic_write_json
from havln_mj.errors import DependencyNotInstalledError


class RunRecords:
    """The run folder's logs.

    Args:
        out: The run folder.
        progress: Echo log lines through tqdm.
        tensorboard: Write TensorBoard events.

    Raises:
        DependencyNotInstalledError: ``tensorboard`` asked for but not installed.
    """

    def __init__(self, out: Path, progress: bool = True, tensorboard: bool = True) -> None:
        self.out, self.progress = Path(out), progress
        self._writer = None
        self._writer_class = None
        if tensorboard:
            try:
                from torch.utils.tensorboard import SummaryWriter
            except ImportError as exc:
                raise DependencyNotInstalledError(
                    "TensorBoard logs need the tensorboard package: pip install "
                    f"'havln_mj[agents]' (or train with --no-tensorboard); {exc}"
                ) from None
            self._writer_class = SummaryWriter

    def write_config(self, resolved: dict[str, Any]) -> None:
        """Writes ``config.json``."""
        atomic_write_json(self.out / "config.json", resolved, indent=1)

    def log(self, line: str) -> None:
        """Appends a line to ``train.log`` (and the progress bar)."""
        with open(self.out / "train.log", "a", encoding="utf-8") as f:
            f.write(line + "\n")
        if self.progress:
            tqdm.write(line)

    def start(self, iteration: int) -> None:
        """Opens the TensorBoard writer; events after ``iteration`` (a resumed run's) go."""
        if self._writer_class is not None:
            self._writer = self._writer_class(
                str(self.out / "tensorboard"), purge_step=iteration + 1 if iteration else None
            )

    def scalars(self, entry: dict[str, Any]) -> None:
        """One history entry as TensorBoard scalars (``train/loss``, ``val/<metric>``)."""
        if self._writer is None:
            return
        step = entry["iteration"]
        for key, value in entry.items():
            if key in ("iteration", "seconds"):
                continue
            tag = f"val/{key[4:]}" if key.startswith("val_") else f"train/{key}"
            self._writer.add_scalar(tag, value, step)
        self._writer.flush()

    def history(self, history: list[dict[str, Any]]) -> None:
        """Writes ``history.json``."""
        atomic_write_json(self.out / "history.json", history, indent=1)

    def close(self) -> None:
        """Closes the TensorBoard writer."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def plot(self, history: list[dict[str, Any]], title: str) -> None:
        """Writes ``loss.png``: the training loss, and val SR on a second axis."""
        if not history:
            return
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        it = [h["iteration"] for h in history]
        fig, ax = plt.subplots(figsize=(6, 3.5))
        ax.plot(it, [h["loss"] for h in history], label="training loss")
        ax.set_xlabel("iteration")
        ax.set_ylabel("cross-entropy")
        val = [(h["iteration"], h["val_sr"]) for h in history if "val_sr" in h]
        if val:
            ax2 = ax.twinx()
            ax2.plot(*zip(*val, strict=True), "o-", color="tab:green", label="val SR")
            ax2.set_ylabel("val SR")
            ax2.set_ylim(0, 1)
        ax.set_title(title)
        fig.tight_layout()
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=100)
        plt.close(fig)
        atomic_write_bytes(self.out / "loss.png", buf.getvalue())
