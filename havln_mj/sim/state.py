"""What the simulator reports: MatterSim's ``ViewPoint`` and ``SimState``, plus HA3D's fields.

Attribute names follow MatterSim (camelCase) so agent code written for it runs unchanged. A
``SimState`` is a snapshot: ``makeAction`` makes new ones instead of changing old ones. Both
are read-only records, as MatterSim's are: named tuples underneath, since every action makes
a state and its navigable locations, and a tuple is made in one call where a class with an
``__init__`` runs Python code per field (the simulator makes them with :data:`make`). They
compare by identity, as objects do (a state holds image arrays).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

make = tuple.__new__
"""``make(ViewPoint, (viewpointId, ix, ...))``: a record from all its fields, in order, at once."""

_ViewPointFields = namedtuple(
    "_ViewPointFields",
    ("viewpointId", "ix", "x", "y", "z", "rel_heading", "rel_elevation", "rel_distance"),
    defaults=(0.0, 0.0, 0.0),
)

_SimStateFields = namedtuple(
    "_SimStateFields",
    (
        "scanId",
        "step",
        "rgb",
        "depth",
        "location",
        "heading",
        "elevation",
        "viewIndex",
        "navigableLocations",
        "time",
        "isCrushed",
        "crushedBy",
        "minHumanDistance",
        "humanMask",
        "pose",
        "fell",
        "humanContacts",
        "arrived",
        "diverged",
        "semantic",
        "instance",
    ),
    defaults=(0.0, 0, (), float("inf"), None, None, False, 0, True, False, None, None),
)


class ViewPoint(_ViewPointFields):
    """A viewpoint as seen from the agent.

    Attributes:
        viewpointId: The panorama id.
        ix: Index of the viewpoint in the scan's connectivity file.
        x: Camera position x (metres).
        y: Camera position y.
        z: Camera position z.
        rel_heading: Horizontal angle from the agent's heading to the viewpoint, in (−π, π],
            right positive; 0 for the agent's own location.
        rel_elevation: Elevation of the viewpoint above the horizontal minus the agent's
            camera elevation.
        rel_distance: 3-D distance from the agent's camera (metres).
    """

    __slots__ = ()
    __eq__, __ne__, __hash__ = object.__eq__, object.__ne__, object.__hash__

    @property
    def position(self) -> np.ndarray:
        """``(x, y, z)`` as an array."""
        return np.array([self.x, self.y, self.z])

    def __repr__(self) -> str:
        return (
            f"ViewPoint({self.viewpointId!r}, ix={self.ix}, xyz=({self.x:.3f}, {self.y:.3f}, "
            f"{self.z:.3f}), rel_heading={self.rel_heading:.3f}, "
            f"rel_elevation={self.rel_elevation:.3f}, rel_distance={self.rel_distance:.3f})"
        )


class SimState(_SimStateFields):
    """One batch element's state after ``newEpisode`` or ``makeAction``.

    Attributes:
        scanId: The scan.
        step: 0 at ``newEpisode``, +1 per ``makeAction`` (staying in place included).
        rgb: H×W×3 ``uint8`` image, BGR by default (MatterSim); zeros when rendering is off.
        depth: H×W×1 ``uint16`` planar depth in 0.25 mm units by default (0 = no reading);
            zeros unless depth is enabled. ``float32`` metres when the simulator is set to.
        location: The current viewpoint (all ``rel_*`` are 0).
        heading: Radians in [0, 2π), 0 facing +y, turning right positive.
        elevation: Radians, up positive.
        viewIndex: 0–35 in discretised mode (heading step + 12 × elevation level, level 0
            looking down); always 0 otherwise.
        navigableLocations: ``location`` first, then the reachable viewpoints, nearest to the
            view centre first.
        time: Simulated seconds since ``newEpisode``.
        isCrushed: 1 when the agent came within the collision distance of a person at any
            time during the last action (HA3D's flag), else 0.
        crushedBy: Indices of those people in ``getHumanState()``.
        minHumanDistance: Smallest horizontal distance to a person during the last action
            (metres; ``inf`` in a scene without people).
        humanMask: H×W ``bool``, True where a person is seen; None unless the human mask is
            enabled (and rendering is on).
        pose: The body's true pose ``(x, y, z, heading)``: the camera rig's for the point
            body, the trunk's for the GO1.
        fell: With the GO1: the robot has fallen (the episode is over).
        humanContacts: With the GO1 and solid people: most robot–person contacts at once
            during the last action.
        arrived: Whether the last action's move reached its target viewpoint. When False,
            ``location`` is the last viewpoint the body stood at, not the target.
        diverged: With the GO1: the physics diverged (the episode is over).
        semantic: H×W ``uint8`` mpcat40 class of each pixel (42: a person; 0: unlabelled);
            None unless segmentation is enabled (and rendering is on).
        instance: H×W ``int32`` object instance of each pixel (people from 65536, one id
            each for the life of the scene); None unless segmentation is enabled.
    """

    __slots__ = ()
    __eq__, __ne__, __hash__ = object.__eq__, object.__ne__, object.__hash__

    def __repr__(self) -> str:
        return (
            f"SimState(scanId={self.scanId!r}, step={self.step}, "
            f"location={self.location.viewpointId!r}, heading={self.heading:.3f}, "
            f"elevation={self.elevation:.3f}, viewIndex={self.viewIndex}, "
            f"navigable={len(self.navigableLocations)}, time={self.time:.2f}, "
            f"isCrushed={self.isCrushed})"
        )
