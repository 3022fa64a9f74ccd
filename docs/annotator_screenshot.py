"""Makes the README's screenshot of ``havln_mj annotate`` (docs/annotator.png).

Serves proc-0, places two people through the page in a headless Chromium (Debian's
``chromium`` and ``chromium-driver``), selects one so its motion preview plays, and saves a
screenshot. Run: ``python docs/annotator_screenshot.py [--out docs/annotator.png]``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import threading
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

from havln_mj.annotator.browser import AnnotatorPage, headless_chromium
from havln_mj.annotator.server import AnnotationServer
from havln_mj.annotator.session import AnnotationSession
from havln_mj.scene.scan import load_scan


def main() -> None:
    """Writes the screenshot."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "annotator.png")
    args = ap.parse_args()
    scan = load_scan("proc-0")
    in_room = {}
    for vp in scan.graph.nodes:
        region = scan.regions.region_of(vp)
        if region is not None:
            in_room.setdefault(region.label, vp)
    with tempfile.TemporaryDirectory() as tmp:
        session = AnnotationSession(scan, Path(tmp) / "human_placements.json")
        server = AnnotationServer(session, port=0)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        try:
            with headless_chromium(1400, 940) as driver:
                page = AnnotatorPage(driver, server.url)
                for vp, activity in ((in_room["k"], "kitchen/stir-pot"),
                                     (in_room["l"], "living-room/guest-chat")):  # fmt: skip
                    page.new_person()
                    page.click_viewpoint(vp)
                    page.choose(activity)
                    page.place(vp)
                page.preview()
                page.wait_view()
                time.sleep(1.5)  # let the preview play a moment
                driver.save_screenshot(str(args.out))
        finally:
            server.shutdown()
            server.server_close()
            session.close()
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
