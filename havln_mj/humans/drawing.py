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
"""

from __future__ import annotations

import mujoco

from havln_mj.humans.anny_mujoco import AnnySkinWriter
from havln_mj.humans.crowd import Crowd
from havln_mj.humans.mujoco_people import DRAW_STYLES, PeopleWriter, add_people
from havln_mj.humans.skinned import SkinWriter


class PeopleDrawing:
    """How a crowd is drawn (see the module docstring for the calls)."""

    def __init__(self, crowd: Crowd, style: str = "pieces") -> None:
        """Draws ``crowd`` in ``style`` (one of :data:`DRAW_STYLES`)."""
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
            InvalidArgumentError: The style is not one of :data:`DRAW_STYLES`.
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

    def pose(self, data: mujoco.MjData, t: float) -> list[int]:
        """Poses everyone at simulated time ``t`` (kinematics not run).

        Returns:
            Ids of the meshes whose vertices changed: upload each to every renderer.
        """
        if not self._joints.n_people:
            return []  # nobody drawn
        positions, quats = self.crowd.pose(t)
        self._joints.write(data, positions, quats)
        changed = []
        if self._anny is not None:
            changed += self._anny.write(self.model, data, positions, quats)
        if self._smpl is not None:
            changed += self._smpl.write(self.model, data, self.crowd.skin_vertices(t))
        return changed


__all__ = ["DRAW_STYLES", "PeopleDrawing", "PeoplePoser"]
