"""``havln_mj annotate``: the command that serves the annotation page for one scan."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "place people in a scan on a local web page; save them as HA3D placements"


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Adds the ``annotate`` subcommand to a ``havln_mj`` subparser set."""
    p = sub.add_parser("annotate", help=HELP, description=HELP)
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

    if not 0 <= args.port <= 65535:
        raise InvalidArgumentError(f"--port must be in [0, 65535], got {args.port}")
    scan = load_scan(args.scene, mp3d_dir=args.mp3d_dir, connectivity_dir=args.connectivity_dir)
    path = (args.placements or Path.cwd() / "human_placements.json").expanduser().resolve()
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
