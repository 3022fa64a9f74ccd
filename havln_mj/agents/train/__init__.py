"""``python -m havln_mj.agents.train --agent {vln_cm,vln_dt} --config FILE``: train an agent.

The run reads a JSON config (``agents/configs/*.json``; ``--set key=value`` overrides a key,
the value read as JSON), checks every key against what reads it (:mod:`~.config`), builds the
feature set it needs (pretraining the view encoder the first time; both are cached), records
demos, and trains:

* **VLN-CM** on the human-aware egocentric expert: teacher forcing on the expert's demos
  (``feedback: "teacher"``), student forcing, where the agent's own sampled actions drive the
  simulator and the expert labels every state it reaches (``"sample"``, HA3D's choice), or
  both in alternate iterations (``"mixed"``). ``random_fraction`` of the training items are
  random-walk demos instead (the paper's 0 / 3 / 25 / 50 / 100 % experiment), imitated as
  recorded.
* **VLN-DT** on ``random_walks`` random walks of at most 30 steps (the paper: 10⁴), windows of
  ``context`` steps with returns-to-go under the model's ``reward``.

``--device cuda`` trains on the GPU (data-parallel over every visible GPU for the batched
forward passes; ``cuda:N`` picks one). Writes to ``--out``: ``checkpoint.pt`` (latest, for
``--resume``), ``best.pt`` (best val SR when a val split is given, else the last),
``config.json`` (the resolved configuration), ``train.log``, ``history.json``,
``tensorboard/`` and ``loss.png`` (:mod:`~.records`). The same seed gives the same run; an
interrupted run resumes where its last checkpoint left off (``--resume`` without one is an
error).

Modules: :mod:`~.config` (the configuration), :mod:`~.prepare` (episodes and features),
:mod:`~.losses` (VLN-CM's teacher and student forcing), :mod:`~.evaluation` (validation
rollouts), :mod:`~.records` (logs), :mod:`~.trainer` (the run), :mod:`~.cli` (the command).
"""

from havln_mj.agents.train.cli import main
from havln_mj.agents.train.config import TrainConfig, read_config
from havln_mj.agents.train.evaluation import evaluate
from havln_mj.agents.train.losses import student_loss, teacher_loss
from havln_mj.agents.train.prepare import RunData, prepare_data
from havln_mj.agents.train.trainer import Trainer, resolve_device

__all__ = [
    "RunData",
    "TrainConfig",
    "Trainer",
    "evaluate",
    "main",
    "prepare_data",
    "read_config",
    "resolve_device",
    "student_loss",
    "teacher_loss",
]
