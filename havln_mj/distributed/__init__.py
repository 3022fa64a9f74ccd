"""Ray-distributed evaluation and scene builds (the ``distributed`` extra: ``ray>=2.9``).

This is the only package that imports ray; the simulator core and :mod:`havln_mj.eval`
stay ray-free. Every entry point takes an ``address``: None starts (or joins) a local Ray,
``"auto"`` joins the running cluster, ``"ray://host:10001"`` a remote one through Ray Client.

* :func:`~havln_mj.distributed.sharded.evaluate_split_ray`:
  :func:`havln_mj.eval.run.evaluate_split` sharded over Ray actors
  (same per-instruction metrics and summary); ``python -m havln_mj.distributed.evaluate``.
* :func:`~havln_mj.distributed.builds.build_scenes_ray`: ``havln_mj scenes build`` as Ray tasks.
"""

from __future__ import annotations

from typing import Any

__all__ = ["build_scenes_ray", "evaluate_split_ray"]


def __getattr__(name: str) -> Any:
    # Lazy: ray loads only when a distributed entry point is used.
    if name == "build_scenes_ray":
        from havln_mj.distributed.builds import build_scenes_ray

        return build_scenes_ray
    if name == "evaluate_split_ray":
        from havln_mj.distributed.sharded import evaluate_split_ray

        return evaluate_split_ray
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
