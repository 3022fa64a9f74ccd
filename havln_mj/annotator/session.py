"""One scan being annotated: its people, what the simulator makes of them, and their pictures.

The people the simulator would create from the current placements are built with the same
function it uses (:func:`havln_mj.humans.population.populate_ha3d`), so the page shows which
activity each person will really play (a walking activity needs a neighbouring viewpoint to
pace to; without one the simulator plays a standing activity of the region instead). Views
are rendered through the simulator's own frame pipeline
(:class:`havln_mj.sim.point.Stage`), people posed at the asked time.
"""

from __future__ import annotations

import math
import numbers
import tempfile
import zlib
from pathlib import Path

import numpy as np

from havln_mj.annotator.placements import (
    HA3D_NAME,
    MODELS,
    Placement,
    check_people,
    load_people,
    save_people,
    to_entry,
)
from havln_mj.annotator.plan import scene_plan
from havln_mj.errors import InvalidArgumentError
from havln_mj.frames import heading_to
from havln_mj.humans.catalog import Catalog, load_catalog
from havln_mj.humans.crowd import Crowd
from havln_mj.humans.population import populate_ha3d
from havln_mj.render.video import VideoWriter
from havln_mj.scene.scan import Scan
from havln_mj.sim.frame import ViewSettings
from havln_mj.sim.point import Stage
from havln_mj.sim.world import WorldOptions

PREVIEW_SECONDS = 4.0
PREVIEW_FPS = 10.0
VIEWER_DISTANCE = 3.0  # metres: preferred distance of the preview camera from the person


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidArgumentError(f"{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise InvalidArgumentError(f"{name} must be finite, got {value!r}")
    return float(value)


def _png(rgb: np.ndarray) -> bytes:
    import cv2

    ok, buf = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    assert ok, "PNG encoding of a uint8 image cannot fail"
    return buf.tobytes()


class AnnotationSession:
    """The state behind the annotation page.

    Args:
        scan: The scan to annotate.
        placements: The HA3D placement file to load from and save to (need not exist).
        size: ``(width, height)`` of the agent's view in pixels.
        vfov_deg: Vertical field of view of the agent's view.
        catalog: Activities by region (default: the built-in catalog).
    """

    def __init__(
        self,
        scan: Scan,
        placements: Path,
        size: tuple[int, int] = (320, 240),
        vfov_deg: float = 60.0,
        catalog: Catalog | None = None,
    ) -> None:
        self.scan = scan
        self.catalog = catalog or load_catalog()
        self.path = Path(placements)
        self.settings = ViewSettings(size[0], size[1], math.radians(vfov_deg), False)
        self.plan = scene_plan(scan)
        self.people: list[Placement] = load_people(self.path, scan.scene_id, self.catalog)
        self._crowd: Crowd | None = None
        self._view: Stage | None = None

    # ------------------------------------------------------------------ people

    def catalog_json(self) -> dict:
        """Regions with their activities, HA3D's region names and which sit or walk."""
        return {
            "models": list(MODELS),
            "regions": [
                {
                    "code": code,
                    "name": HA3D_NAME[code],
                    "activities": [
                        {"id": a.id, "text": a.text, "sits": a.needs_seat, "walks": a.needs_path}
                        for a in self.catalog.activities(code)
                    ],
                }
                for code in self.catalog.regions()
            ],
        }

    def people_json(self) -> list[dict]:
        """Each person as the page shows them, with the activity the simulator will play."""
        plays = {p.viewpoint: p.activity for p in self.crowd().people}
        out = []
        for p in self.people:
            played, note = plays[p.viewpoint], ""
            if played != p.activity:
                if self.catalog.get(p.activity).needs_seat:
                    why = "sitting needs a seat, which placements do not give"
                elif p.sentence:  # HA3D's own words; ours always map back onto themselves
                    why = "the sentence fits several of the room's activities or needs what "
                    why += "this viewpoint lacks; which one plays depends on the simulator's seed"
                else:
                    why = "walking needs a neighbouring viewpoint on the same floor, 1-6 m away"
                note = f"The simulator plays: {self.catalog.get(played).text} ({why})."
            out.append(
                {
                    "viewpoint": p.viewpoint,
                    "activity": p.activity,
                    "model": p.model,
                    "heading_deg": round(math.degrees(p.heading) % 360.0, 2),
                    "sentence": to_entry(p, self.catalog)[0],
                    "plays": played,
                    "note": note,
                }
            )
        return out

    def set_people(self, raw: object) -> None:
        """Replaces the people with those the page sends.

        Args:
            raw: A list of ``{viewpoint, activity, model, heading_deg[, sentence]}``.

        Raises:
            InvalidArgumentError: Not such a list, or a person that cannot be placed (see
                :func:`havln_mj.annotator.placements.check_people`).
            UnknownViewpointError: A viewpoint the scan does not have.
        """
        if not isinstance(raw, list) or not all(isinstance(p, dict) for p in raw):
            raise InvalidArgumentError(
                "people must be a list of {viewpoint, activity, model, heading_deg}"
            )
        # A sentence read from a file stays while its person keeps the activity it maps to.
        known = {(q.sentence, q.activity) for q in self.people if q.sentence}
        people = []
        for p in raw:
            try:
                vp, activity = str(p["viewpoint"]), str(p["activity"])
            except KeyError as exc:
                raise InvalidArgumentError(f"a person needs {exc.args[0]!r}; got {p!r}") from None
            heading = math.radians(_number("heading_deg", p.get("heading_deg", 0.0)))
            sentence = str(p.get("sentence") or "")
            kept = sentence if (sentence, activity) in known else ""
            people.append(Placement(vp, activity, p.get("model", 0), heading % (2 * math.pi), kept))
        check_people(people, self.scan.graph, self.catalog)
        self.people = people
        self._forget()

    def crowd(self) -> Crowd:
        """The people the simulator makes of the current placements."""
        if self._crowd is None:
            entries = {p.viewpoint: tuple(to_entry(p, self.catalog)) for p in self.people}
            rng = np.random.default_rng(zlib.crc32(self.scan.scene_id.encode()))
            self._crowd = populate_ha3d(self.scan.graph, entries, rng, self.catalog)
        return self._crowd

    def _forget(self) -> None:
        self._crowd = None
        if self._view is not None:
            self._view.close()
            self._view = None

    # ------------------------------------------------------------------ files

    def save(self, path: Path | None = None) -> Path:
        """Writes the people into the placement file (default: the one given at start)."""
        target = self.path if path is None else Path(path).expanduser().resolve()
        save_people(target, self.scan.scene_id, self.people, self.catalog)
        self.path = target
        return target

    def load(self, path: Path | None = None) -> None:
        """Replaces the people with a placement file's (default: the one given at start)."""
        source = self.path if path is None else Path(path).expanduser().resolve()
        self.people = load_people(source, self.scan.scene_id, self.catalog)
        self.path = source
        self._forget()

    # ------------------------------------------------------------------ pictures

    def _scene_view(self) -> Stage:
        if self._view is None:
            s = self.settings
            options = WorldOptions(collision="none", offscreen=(s.width, s.height))
            self._view = Stage(self.scan, options, self.crowd())
        return self._view

    def view_png(self, viewpoint: str, heading_deg: float, elevation_deg: float, t: float) -> bytes:
        """The agent's view from a viewpoint (PNG), people posed at ``t`` seconds.

        Raises:
            UnknownViewpointError: A viewpoint the scan does not have.
            InvalidArgumentError: A non-finite angle or time.
        """
        pos = self.scan.graph.position(viewpoint)
        heading = math.radians(_number("heading", heading_deg))
        elevation = math.radians(_number("elevation", elevation_deg))
        view = self._scene_view().render((pos, heading, elevation), self.settings, _number("t", t))
        return _png(view.rgb)

    def _viewer(self, viewpoint: str, facing: float) -> np.ndarray:
        """Where to film a person on ``viewpoint`` from (``facing``: their heading, radians).

        A viewpoint that sees theirs, about 3 m off, in front of them rather than behind.
        """
        graph = self.scan.graph
        c = graph.connectivity
        here, i = graph.position(viewpoint), graph.index(viewpoint)
        front = np.array([math.sin(facing), math.cos(facing)])
        best, score = None, math.inf
        for vp in graph.nodes:
            offset = graph.position(vp)[:2] - here[:2]
            d = float(np.linalg.norm(offset))
            if (
                vp == viewpoint
                or d < 1.2
                or abs(graph.floor_z(vp) - graph.floor_z(viewpoint)) > 0.5
            ):
                continue
            seen = c.visible[graph.index(vp), i] or c.unobstructed[graph.index(vp), i]
            behind = 1.0 - float(front @ offset) / d  # 0 straight ahead, 2 right behind
            s = abs(d - VIEWER_DISTANCE) + 1.5 * behind + (0.0 if seen else 100.0)
            if s < score:
                best, score = graph.position(vp), s
        if best is None:
            return here + np.array([*(VIEWER_DISTANCE * front), 0.0])
        return best

    def preview_mp4(self, viewpoint: str) -> bytes:
        """A short H.264 clip of the person on ``viewpoint`` doing their activity.

        Raises:
            InvalidArgumentError: Nobody stands on that viewpoint.
        """
        k = next((k for k, p in enumerate(self.crowd().people) if p.viewpoint == viewpoint), None)
        if k is None:
            raise InvalidArgumentError(f"no person on viewpoint {viewpoint!r} to preview")
        crowd, view = self.crowd(), self._scene_view()
        camera = self._viewer(viewpoint, crowd.people[k].heading)
        s = self.settings
        n = round(PREVIEW_SECONDS * PREVIEW_FPS)
        with tempfile.TemporaryDirectory(prefix="havln-preview-") as tmp:
            path = Path(tmp) / "preview.mp4"
            with VideoWriter(path, PREVIEW_FPS, (s.width, s.height)) as video:
                for f in range(n):
                    t = f / PREVIEW_FPS
                    pelvis = crowd.positions(np.array([t]), np.array([k]))[0, 0]
                    flat = math.hypot(*(pelvis[:2] - camera[:2]))
                    elevation = math.atan2(pelvis[2] - camera[2], max(flat, 1e-6))
                    rgb = view.render((camera, heading_to(camera, pelvis), elevation), s, t).rgb
                    video.write(rgb)
            return path.read_bytes()

    def close(self) -> None:
        """Releases the renderer."""
        self._forget()
