"""Importing and starting Ray."""

from __future__ import annotations

from typing import Any

from havln_mj.errors import DependencyNotInstalledError


def import_ray() -> Any:
    """The ``ray`` module, or an actionable error when it is not installed."""
    try:
        import ray
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise DependencyNotInstalledError(
            "havln_mj.distributed needs ray: pip install 'havln_mj[distributed]' (or ray>=2.9)"
        ) from exc
    return ray


def ensure_ray(address: str | None = None) -> Any:
    """Connects to Ray unless already connected; returns the ``ray`` module.

    Args:
        address: None for a local Ray (started if none runs), ``"auto"`` for the running
            cluster, or ``"ray://host:port"`` for Ray Client.
    """
    ray = import_ray()
    if not ray.is_initialized():
        ray.init(address=address, log_to_driver=False)
    return ray
