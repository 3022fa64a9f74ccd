"""``havln_mj``: one command for everything the package does.

``havln_mj <command> [options]``, ``havln_mj <command> --help`` for the options of each:

=============  ==========================================================================
run            build a scene and walk episodes through it on camera (``python -m havln_mj.run``)
eval           score an agent or expert on a split (``python -m havln_mj.eval``); with
               ``--workers N``/``--address`` on Ray actors
view           the live MuJoCo viewer with keyboard control of the agent
train          train VLN-CM or VLN-DT (``python -m havln_mj.agents.train``)
featurize      render and encode a scene's views for the agents
tables         result tables from evaluation folders (``python -m havln_mj.eval.tables``)
scenes         ``build``: pre-build scenes; ``export``: a built world as MJCF
dataset        ``build``: generate an HA-R2R style split in scenes
annotate       place people in a scan on a local web page (HA3D placements)
=============  ==========================================================================

Each command is a module with ``parser(prog)`` and ``main(argv, prog)``; the ``python -m``
forms run the same code.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Sequence

COMMANDS: dict[str, tuple[str, str]] = {
    "run": ("havln_mj.run", "build a scene and walk episodes through it on camera"),
    "eval": (
        "havln_mj.commands.evaluate",
        "score an agent or expert on a split (Ray: --workers N)",
    ),
    "view": ("havln_mj.viewer", "the live MuJoCo viewer with keyboard control of the agent"),
    "train": ("havln_mj.agents.train.cli", "train VLN-CM or VLN-DT from a config"),
    "featurize": ("havln_mj.agents.featurize", "render and encode views for the agents"),
    "tables": ("havln_mj.eval.tables", "result tables from evaluation folders"),
    "scenes": ("havln_mj.commands.scenes", "pre-build scenes, or export one as MJCF"),
    "dataset": ("havln_mj.commands.dataset", "generate an HA-R2R style split in scenes"),
    "annotate": ("havln_mj.annotator.command", "place people in a scan on a local web page"),
}
"""Each command's module and what it does."""


def command_module(name: str):
    """The module of command ``name`` (imported on demand: heavy ones load only when used)."""
    return importlib.import_module(COMMANDS[name][0])


def usage() -> str:
    """The top-level help."""
    width = max(map(len, COMMANDS))
    lines = [f"  {n:<{width}}  {what}" for n, (_, what) in COMMANDS.items()]
    return (
        "usage: havln_mj <command> [options]\n\n"
        "HA-VLN in MuJoCo: simulate, evaluate, view, train, build and annotate.\n\n"
        "commands:\n" + "\n".join(lines) + "\n\nhavln_mj <command> --help shows its options."
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``havln_mj`` command; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(usage())
        return 0 if argv else 2
    name, rest = argv[0], argv[1:]
    if name not in COMMANDS:
        from havln_mj.errors import did_you_mean

        print(
            f"havln_mj: unknown command {name!r}; valid: {', '.join(COMMANDS)}."
            f"{did_you_mean(name, COMMANDS)}",
            file=sys.stderr,
        )
        return 2
    return command_module(name).main(rest, prog=f"havln_mj {name}")


if __name__ == "__main__":
    sys.exit(main())
