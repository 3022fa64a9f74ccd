"""What a run records: filmed walks, per-episode reports, the best frame, the map, staging.

:class:`Recording` films a simulator's walks through its frame pipeline
(:meth:`~havln_mj.sim.extensions.SimulatorExtensions.set_film`), keeps the body's track and the view
showing people best, and reports each episode from the states the simulator published (what
the body really did: where it stood, whether it arrived or fell, whom it came near).
:func:`staged_outputs` makes a run's folder change all at once, or not at all.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

import numpy as np

from havln_mj.cache import pid_alive
from havln_mj.ctrl_c import CtrlC
from havln_mj.errors import OutputError
from havln_mj.frames import heading_to, wrap_angle
from havln_mj.render.video import SizedOnFirstFrame
from havln_mj.sim.crowd import COLLISION_DISTANCE

OUTPUTS = {
    "video": "egocentric.mp4",
    "go1_video": "go1.mp4",
    "frame": "frame.png",
    "topdown": "topdown.png",
    "summary": "summary.json",
}
_STAGING = ".havln-staging-"

Walk = Callable[[object, str, Sequence[str]], list]


class _Stage:
    """A staging folder whose files replace the run folder's outputs at :meth:`finish`."""

    def __init__(self, out: Path, ctrl_c: CtrlC) -> None:
        self.out = out
        self.path = out / f"{_STAGING}{os.getpid()}"
        self._ctrl_c = ctrl_c

    def __truediv__(self, name: str) -> Path:
        return self.path / name

    def finish(self, summary: dict) -> dict:
        """Writes the summary (listing the run's files), then moves everything into place.

        Raises:
            KeyboardInterrupt: Ctrl-C was pressed during the run: nothing is moved.
        """
        if self._ctrl_c.seen:
            raise KeyboardInterrupt
        made = {k: n for k, n in OUTPUTS.items() if k != "summary" and (self.path / n).exists()}
        summary = {**summary, "files": {k: str(self.out / n) for k, n in made.items()}}
        (self.path / OUTPUTS["summary"]).write_text(json.dumps(summary, indent=1))
        # The summary goes last: a folder whose summary names a file always holds it.
        (self.out / OUTPUTS["summary"]).unlink(missing_ok=True)
        for key, name in OUTPUTS.items():
            if key == "summary":
                continue
            if key in made:
                os.replace(self.path / name, self.out / name)
            else:
                (self.out / name).unlink(missing_ok=True)  # an earlier run's, not this one's
        os.replace(self.path / OUTPUTS["summary"], self.out / OUTPUTS["summary"])
        return summary


@contextlib.contextmanager
def staged_outputs(out: Path) -> Iterator[_Stage]:
    """A staging folder inside ``out``; removed if the run does not finish.

    Staging folders of runs that were killed (their process is gone) are removed first. A
    Ctrl-C while the stage is open keeps the folder as it was, even if the KeyboardInterrupt
    it raised was swallowed on the way: the stage's ``finish`` then raises it again.

    Raises:
        HavlnError: ``out`` cannot be created or written.
    """
    try:
        out.mkdir(parents=True, exist_ok=True)
        for old in out.glob(f"{_STAGING}*"):
            pid = old.name.removeprefix(_STAGING)
            if not pid.isdigit() or not pid_alive(int(pid)):
                shutil.rmtree(old, ignore_errors=True)
        ctrl_c = CtrlC()
        stage = _Stage(out, ctrl_c)
        stage.path.mkdir()
    except OSError as exc:
        raise OutputError(f"cannot write the output folder {out}: {exc.strerror or exc}") from None
    ctrl_c.install()
    try:
        yield stage
    finally:
        ctrl_c.restore()
        shutil.rmtree(stage.path, ignore_errors=True)


class Recording:
    """Films one simulator's walks and reports them.

    Args:
        sim: A rendering simulator (batch size 1, RGB, human mask on).
        crowd: The scene's people.
        video: Where the video goes.
        fps: Video frames per simulated second.
        label: Written on every frame.
        chase: Put the GO1's chase camera beside the body camera.
    """

    def __init__(
        self, sim, crowd, video: Path, fps: float, label: str, chase: bool = False
    ) -> None:
        self.sim, self.crowd, self.label = sim, crowd, label
        self.video = SizedOnFirstFrame(video, fps)
        self.frames, self.render_s = 0, 0.0
        self.tracks: list[list[tuple[float, ...]]] = []
        self.collisions: list[np.ndarray] = []  # where the body was within 1 m of someone
        self.episode, self.n_episodes = 0, 0
        self._best: tuple[float, np.ndarray | None] = (-1.0, None)
        sim.set_film(fps, self._frame, ("go1/chase",) if chase else ())

    def _frame(self, i: int, t: float, views: list, pose: np.ndarray) -> None:
        import cv2

        self.tracks[-1].append((t, *pose[:3]))
        image = np.hstack([v.rgb for v in views]) if len(views) > 1 else views[0].rgb.copy()
        near, people = math.inf, self.sim.people(i)
        if len(people):
            pelvis = people.positions(np.array([t]))[0]
            near = float(np.min(np.hypot(*(pelvis[:, :2] - pose[:2]).T)))
        text = f"{self.label}  episode {self.episode}/{self.n_episodes}  t={t:5.1f}s"
        if near <= COLLISION_DISTANCE:
            text += "  COLLISION"
            self.collisions.append(np.array(pose[:3]))
        cv2.putText(image, text, (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
        self.video.write(image)
        self.frames += 1
        # Keep the view showing people best (whole people, not one up close), else the
        # most detailed view of the first episode.
        rgb, mask = views[0].rgb, views[0].human_mask
        score = float(rgb.std()) / 1e3 if self.episode == 1 else -1.0
        seen = float(mask.mean()) if mask is not None else 0.0
        score += seen if seen < 0.1 else 0.0
        if score > self._best[0]:
            self._best = (score, rgb)

    def _walk(self, scene: str, paths: Sequence[Sequence[str]], walk: Walk) -> list[list]:
        self.n_episodes = len(paths)
        out = []
        try:
            for k, path in enumerate(paths, start=1):
                self.episode = k
                self.tracks.append([])
                out.append(walk(self.sim, scene, path))
        finally:
            self.video.close()
            self.sim.set_film(None)
        self.render_s = self.sim.timing()["render_s"]
        return out

    def walk_all(self, scene: str, paths: Sequence[Sequence[str]], walk: Walk) -> list[dict]:
        """Walks and films every path; one report per episode."""
        graph = self.sim.graph(scene)
        records = []
        for path, states, track in zip(
            paths, self._walk(scene, paths, walk), self.tracks, strict=True
        ):
            hit = sorted({p for s in states for p in s.crushedBy})
            close = [s.minHumanDistance for s in states]
            end = states[-1]
            records.append(
                {
                    "start": path[0],
                    "goal": path[-1],
                    "path": list(path),
                    "steps": len(states) - 1,
                    "reached": end.arrived and end.location.viewpointId == path[-1],
                    "geodesic_m": round(graph.distance(path[0], path[-1]), 3),
                    "path_length_m": round(graph.path_length(path), 3),
                    "sim_seconds": round(end.time, 3),
                    "frames": len(track),
                    "human_collisions": len(hit),
                    "people_hit": [self.crowd.people[i].text for i in hit],
                    "min_human_distance_m": round(min(close), 3) if len(self.crowd) else None,
                }
            )
        return records

    def compare(
        self, scene: str, paths: Sequence[Sequence[str]], walk: Walk, point: Sequence[dict]
    ) -> dict:
        """Walks the paths with a robot and compares each hop with the point body's."""
        graph = self.sim.graph(scene)
        episodes = []
        for path, states, ref in zip(paths, self._walk(scene, paths, walk), point, strict=True):
            steps = []
            # A walk that stopped early (a fall, a stall) has fewer states than hops.
            for a, b, s0, s1 in zip(path, path[1:], states, states[1:], strict=False):
                target = graph.position(b)
                bearing = heading_to(graph.position(a), target)
                steps.append(
                    {
                        "to": b,
                        "arrived": bool(s1.arrived),
                        "at": s1.location.viewpointId,
                        "end_error_m": round(float(np.hypot(*(s1.pose[:2] - target[:2]))), 4),
                        "heading_error_deg": round(
                            math.degrees(wrap_angle(s1.pose[3] - bearing)), 2
                        ),
                        "seconds": round(s1.time - s0.time, 3),
                        "collided_people": list(s1.crushedBy),
                        "fell": bool(s1.fell or s1.diverged),
                    }
                )
            end = states[-1]
            episodes.append(
                {
                    "path": list(path),
                    "reached": end.arrived and end.location.viewpointId == path[-1],
                    "final_error_m": steps[-1]["end_error_m"] if steps else None,
                    "go1_seconds": round(end.time, 3),
                    "point_body_seconds": ref["sim_seconds"],
                    "fell": any(s["fell"] for s in steps),
                    "human_collisions": len({p for s in states for p in s.crushedBy}),
                    "steps": steps,
                }
            )
        return {
            "frames": self.frames,
            "episodes": episodes,
            "falls": sum(e["fell"] for e in episodes),
            "reached": sum(e["reached"] for e in episodes),
        }

    def write_frame(self, path: Path) -> None:
        """Writes the best view seen as a PNG."""
        import cv2

        best = self._best[1]
        if best is not None:
            cv2.imwrite(str(path), cv2.cvtColor(best, cv2.COLOR_RGB2BGR))

    def write_map(
        self,
        path: Path,
        scan,
        collision: str,
        episodes,
        records: list[dict],
        walked: Sequence[Sequence[tuple[float, ...]]] | None = None,
    ) -> None:
        """Writes the top-down map of the first episode's level.

        The planned paths, the tracks walked (``walked``, default this recording's: pass a
        robot's to show where it really went), the people's tracks, where the agent came
        within 1 m of someone, and the walkable area shaded.
        """
        from havln_mj.nav import NavGrid
        from havln_mj.render.topdown import draw_topdown
        from havln_mj.sim.world import WorldOptions, build_world

        graph = scan.graph
        level = graph.floor_z(episodes[0].start)
        navgrid = None
        if collision != "none":
            world = build_world(scan, WorldOptions(collision=collision))
            if world.collision != "none":
                navgrid = NavGrid.from_model(world.model, level)
                for ep, rec in zip(episodes, records, strict=True):
                    if abs(graph.floor_z(ep.goal) - level) < 0.5:
                        d = navgrid.distance(graph.position(ep.start), graph.position(ep.goal))
                        rec["grid_geodesic_m"] = round(d, 3) if math.isfinite(d) else None
        tracks = [np.array(t, float).reshape(-1, 4) for t in (walked or self.tracks)]
        times = np.unique([row[0] for t in self.tracks for row in t] or [0.0])
        times = times[:: max(1, len(times) // 300)]
        draw_topdown(
            path,
            graph,
            scan.regions,
            scan.mesh,
            [e.path for e in episodes],
            level_floor=level,
            title=scan.description,
            navgrid=navgrid,
            people=self.crowd.positions(np.array([0.0]))[0],
            walked=[t[:, 1:] for t in tracks if len(t)],
            people_tracks=self.crowd.positions(times) if len(self.crowd) else None,
            collisions=np.array(self.collisions).reshape(-1, 3),
        )
