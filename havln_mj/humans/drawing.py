"""One object that draws a crowd in MuJoCo: built into the model once, posed before each frame.

The frame pipeline uses it in three calls::

    drawing = PeopleDrawing.from_crowd(crowd, style="pieces")
    drawing.add_to(spec, solid=False)          # while building the world
    model = spec.compile()
    poser = drawing.poser(model)
    ...
    for mesh_id in poser.pose(data, t):        # before each render at simulated time t
        camera.upload_mesh(mesh_id)            # (none in the default "pieces" style)
    mujoco.mj_kinematics(model, data)          # or the body's own write, which runs it

``pose`` writes the mocap poses of every joint body (capsules and rigid pieces follow them),
skins the meshes that need it (SMPL skins, Anny bodies in the "skinned" style) and returns
the ids of the meshes whose vertices changed, which each renderer must re-upload.

A renderer draws every geom it is given, in view or not, and a dressed person is thousands
of textured triangles: :meth:`PeoplePoser.hide_unseen` leaves out of the scene (alpha 0, which
MuJoCo skips) what lies wholly outside a camera's view: each rigid piece whose bounding sphere
does (a person half in view keeps only the pieces that may show), and each skinned person
whose sphere around the pelvis does, and, given the rooms the camera cannot see
(:mod:`havln_mj.render.culling`), what lies wholly in them. :meth:`PeoplePoser.show_all` puts
them back after the frame. The image does not change.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable

import mujoco
import numpy as np

from havln_mj import groups
from havln_mj.humans.anny_mujoco import AnnySkinWriter
from havln_mj.humans.crowd import Crowd
from havln_mj.humans.mujoco_people import DRAW_STYLES, PeopleWriter, add_people
from havln_mj.humans.skinned import SkinWriter

Walled = Callable[[np.ndarray, np.ndarray], np.ndarray | None]
"""Which spheres ``(centres (N, 3), radii (N,))`` lie wholly in rooms a camera cannot see."""


class PeopleDrawing:
    """How a crowd is drawn (see the module docstring for the calls)."""

    def __init__(self, crowd: Crowd, style: str = "pieces") -> None:
        """Draws ``crowd`` in a ``style`` of :data:`~havln_mj.humans.mujoco_people.DRAW_STYLES`."""
        self.crowd = crowd
        self.style = style

    @classmethod
    def from_crowd(cls, crowd: Crowd, style: str = "pieces") -> PeopleDrawing:
        """The drawing of ``crowd``: ``"pieces"`` (default), ``"skinned"`` or ``"capsules"``."""
        return cls(crowd, style)

    def add_to(self, spec: mujoco.MjSpec, solid: bool = False) -> None:
        """Adds every person's bodies, meshes and textures to ``spec`` (before compiling).

        Args:
            spec: The world being built.
            solid: People's capsules make contacts (a simulated robot bumps into them).

        Raises:
            InvalidArgumentError: The style is not one of
                :data:`~havln_mj.humans.mujoco_people.DRAW_STYLES`.
        """
        add_people(spec, self.crowd.shapes, self.crowd.skins, solid, self.style)

    def poser(self, model: mujoco.MjModel) -> PeoplePoser:
        """The per-frame poser of a model compiled from a spec this drawing was added to."""
        return PeoplePoser(self, model)


class PeoplePoser:
    """Poses a drawn crowd in one compiled model at a simulated time."""

    def __init__(self, drawing: PeopleDrawing, model: mujoco.MjModel) -> None:
        crowd = drawing.crowd
        self.crowd = crowd
        self.model = model
        self._joints = PeopleWriter(model, len(crowd.shapes))  # the people drawn
        skins = crowd.skins
        smpl = [k for k, s in enumerate(skins) if s is not None]
        self._smpl = SkinWriter(model, smpl) if smpl else None
        anny = {}
        if drawing.style == "skinned":
            anny = {
                k: (f"human{k}", shape.look)
                for k, (shape, skin) in enumerate(zip(crowd.shapes, skins, strict=True))
                if shape.look is not None and skin is None
            }
        self._anny = AnnySkinWriter(model, anny) if anny else None
        self._visibility(model, [shape.height for shape in crowd.shapes], set(smpl) | set(anny))

    def _visibility(self, model: mujoco.MjModel, heights: list[float], skinned: set[int]) -> None:
        """Each person's geoms, their alphas and the spheres that hold them in any pose.

        A rigid piece (or capsule) is held by its own bounding sphere about its frame; a
        skinned mesh changes shape every frame, so its person is held by a sphere about the
        pelvis instead.
        """
        owner = re.compile(r"human(\d+)/")
        geoms, people = [], []
        for g in np.flatnonzero(model.geom_group == groups.HUMANS):
            found = owner.match(model.body(int(model.geom_bodyid[g])).name)
            if found is not None and int(found.group(1)) < len(heights):
                geoms.append(int(g))
                people.append(int(found.group(1)))
        self._geoms = np.asarray(geoms, int)
        self._owner = np.asarray(people, int)
        self._alpha = model.geom_rgba[self._geoms, 3].copy()
        self._skinned = np.isin(self._owner, sorted(skinned))
        self._bound = model.geom_rbound[self._geoms] + PIECE_MARGIN_M
        # Nothing of a person (limbs, hair, a skirt) reaches farther from the pelvis than
        # their height: a sphere of that radius plus a margin holds them in any pose.
        self._radius = np.asarray(heights, float) + SPHERE_MARGIN_M
        self._pelvis: np.ndarray | None = None

    def pose(self, data: mujoco.MjData, t: float) -> list[int]:
        """Poses everyone at simulated time ``t`` (kinematics not run).

        Returns:
            Ids of the meshes whose vertices changed, to upload to every renderer.
        """
        if not self._joints.n_people:
            return []  # nobody drawn
        positions, quats = self.crowd.pose(t)
        self._pelvis = positions[:, 0]
        self._joints.write(data, positions, quats)
        changed = []
        if self._anny is not None:
            changed += self._anny.write(self.model, data, positions, quats)
        if self._smpl is not None:
            changed += self._smpl.write(self.model, data, self.crowd.skin_vertices(t))
        return changed

    def hide_unseen(
        self, data: mujoco.MjData, camera: int, aspect: float, walled: Walled | None = None
    ) -> bool:
        """Leaves out of the next frame what lies wholly outside camera ``camera``'s view.

        Call after :meth:`pose` and kinematics; ``aspect`` is the image's width / height.
        ``walled`` says which spheres lie wholly in rooms the camera cannot see (None where
        it cannot tell); what they hold is left out too. Returns whether anything was left
        out (then call :meth:`show_all` after the frame).
        """
        if self._pelvis is None or not len(self._geoms):
            return False
        cam_pos, cam_rot = data.cam_xpos[camera], data.cam_xmat[camera].reshape(3, 3)
        tan_v = math.tan(math.radians(float(self.model.cam_fovy[camera])) / 2)
        view = (tan_v * aspect, tan_v)
        centres = data.geom_xpos[self._geoms]
        outside = _outside(centres - cam_pos, cam_rot, view, self._bound)
        behind = None if walled is None else walled(centres, self._bound)
        if behind is not None:
            outside |= behind
        if self._skinned.any():
            people = _outside(self._pelvis - cam_pos, cam_rot, view, self._radius)
            if behind is not None:
                people |= walled(self._pelvis, self._radius)
            outside = np.where(self._skinned, people[self._owner], outside)
        if not outside.any():
            return False
        self.model.geom_rgba[self._geoms, 3] = np.where(outside, 0.0, self._alpha)
        return True

    def show_all(self) -> None:
        """Puts back everyone :meth:`hide_unseen` left out."""
        self.model.geom_rgba[self._geoms, 3] = self._alpha


SPHERE_MARGIN_M = 0.3
"""Metres added to a person's height for the sphere around the pelvis that holds them."""

PIECE_MARGIN_M = 0.01
"""Metres added to a rigid piece's bounding sphere (its vertices are drawn in single precision)."""


def _outside(rel: np.ndarray, cam_rot: np.ndarray, view: tuple, radius: np.ndarray) -> np.ndarray:
    """Which spheres (centres ``rel`` from the camera, world axes) lie wholly outside its view.

    ``view`` holds the tangents of the half field of view, horizontally and vertically.
    """
    x, y, depth = (rel @ cam_rot).T
    depth = -depth  # the camera looks along its −z
    tan_h, tan_v = view
    # Distances to the four side planes (positive outside) and behind the camera.
    return (
        (depth < -radius)
        | ((np.abs(x) - depth * tan_h) / math.hypot(1.0, tan_h) > radius)
        | ((np.abs(y) - depth * tan_v) / math.hypot(1.0, tan_v) > radius)
    )


__all__ = ["DRAW_STYLES", "PeopleDrawing", "PeoplePoser"]
