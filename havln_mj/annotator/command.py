"""``havln_mj annotate``: the command that serves the annotation page for one scan."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from havln_mj import argchecks
from havln_mj.errors import HavlnError
from havln_mj.render.camera import MAX_SIZE

HELP = "place people in a scan on a local web page; save them as HA3D placements"


def parser(prog: str = "havln_mj annotate") -> argparse.ArgumentParser:
    """The command's argument parser."""
    p = argparse.ArgumentParser(prog=prog, description=HELP)
    p.add_argument("--scene", required=True, help="scene id: proc-<seed>, a scan id, a folder")
    p.add_argument(
        "--placements",
        type=Path,
        default=None,
        help="HA3D placement file to load and save (human_motion_text.json format; created "
        "on save; default ./human_placements.json)",
    )
    p.add_argument("--port", type=int, default=8765, help="TCP port (default 8765; 0: any free)")
    p.add_argument("--width", type=int, default=320, help="agent view width, pixels (default 320)")
    p.add_argument(
        "--height", type=int, default=240, help="agent view height, pixels (default 240)"
    )
    p.add_argument("--vfov", type=float, default=60.0, help="vertical field of view, degrees")
    p.add_argument("--mp3d-dir", type=Path, default=None, help="Matterport3D data root")
    p.add_argument(
        "--connectivity-dir", type=Path, default=None, help="folder of connectivity graphs"
    )
    p.add_argument("--verbose", action="store_true", help="log every request")
    return p


def annotate(args: argparse.Namespace) -> int:
    """Loads the scan and serves the page until interrupted (Ctrl+C)."""
    from havln_mj.annotator.server import AnnotationServer
    from havln_mj.annotator.session import AnnotationSession
    from havln_mj.errors import InvalidArgumentError
    from havln_mj.scene.scan import load_scan

    path = (args.placements or Path.cwd() / "human_placements.json").expanduser().resolve()
    problems = [
        argchecks.in_range("--port", args.port, 0, 65535),
        argchecks.in_range("--width", args.width, 1, MAX_SIZE, " pixels"),
        argchecks.in_range("--height", args.height, 1, MAX_SIZE, " pixels"),
        None if 0 < args.vfov < 180 else f"--vfov must be in (0, 180) degrees, got {args.vfov:g}",
        argchecks.scene_ids("--scene", [args.scene]),
        argchecks.existing("--mp3d-dir", args.mp3d_dir),
        argchecks.existing("--connectivity-dir", args.connectivity_dir),
        None if not path.is_dir() else f"--placements {path} is a folder; give a JSON file",
        argchecks.writable_folder("the folder of --placements", path.parent),
    ]
    problems = [p for p in problems if p]
    if problems:
        raise InvalidArgumentError(problems[0])
    scan = load_scan(args.scene, mp3d_dir=args.mp3d_dir, connectivity_dir=args.connectivity_dir)
    session = AnnotationSession(scan, path, (args.width, args.height), args.vfov)
    server = AnnotationServer(session, port=args.port, verbose=args.verbose)
    print(
        f"annotating {scan.description}: {len(session.people)} people from {path}\n"
        f"open {server.url} (Ctrl+C to stop)",
        flush=True,
    )
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
        session.close()
    return 0


def main(argv: Sequence[str] | None = None, prog: str = "havln_mj annotate") -> int:
    """Entry point; returns the exit code (2 on bad input)."""
    args = parser(prog).parse_args(argv)
    try:
        return annotate(args)
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
