"""What the simulator reports: MatterSim's ``ViewPoint`` and ``SimState``, plus HA3D's fields.

Attribute names follow MatterSim (camelCase) so agent code written for it runs unchanged. A
``SimState`` is a snapshot: ``makeAction`` makes new ones instead of changing old ones.
"""

from __future__ import annotations

import numpy as np


class ViewPoint:
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

    __slots__ = ("ix", "rel_distance", "rel_elevation", "rel_heading", "viewpointId", "x", "y", "z")

    def __init__(
        self,
        viewpointId: str,  # noqa: N803 - MatterSim's name
        ix: int,
        x: float,
        y: float,
        z: float,
        rel_heading: float = 0.0,
        rel_elevation: float = 0.0,
        rel_distance: float = 0.0,
    ) -> None:
        self.viewpointId = viewpointId
        self.ix = ix
        self.x = x
        self.y = y
        self.z = z
        self.rel_heading = rel_heading
        self.rel_elevation = rel_elevation
        self.rel_distance = rel_distance

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


class SimState:
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
    """

    __slots__ = (
        "arrived",
        "crushedBy",
        "depth",
        "diverged",
        "elevation",
        "fell",
        "heading",
        "humanContacts",
        "humanMask",
        "isCrushed",
        "location",
        "minHumanDistance",
        "navigableLocations",
        "pose",
        "rgb",
        "scanId",
        "step",
        "time",
        "viewIndex",
    )

    def __init__(
        self,
        scanId: str,  # noqa: N803 - MatterSim's names
        step: int,
        rgb: np.ndarray,
        depth: np.ndarray,
        location: ViewPoint,
        heading: float,
        elevation: float,
        viewIndex: int,  # noqa: N803
        navigableLocations: list[ViewPoint],  # noqa: N803
        time: float = 0.0,
        isCrushed: int = 0,  # noqa: N803
        crushedBy: tuple[int, ...] = (),  # noqa: N803
        minHumanDistance: float = float("inf"),  # noqa: N803
        humanMask: np.ndarray | None = None,  # noqa: N803
        pose: np.ndarray | None = None,
        fell: bool = False,
        humanContacts: int = 0,  # noqa: N803
        arrived: bool = True,
        diverged: bool = False,
    ) -> None:
        self.scanId = scanId
        self.step = step
        self.rgb = rgb
        self.depth = depth
        self.location = location
        self.heading = heading
        self.elevation = elevation
        self.viewIndex = viewIndex
        self.navigableLocations = navigableLocations
        self.time = time
        self.isCrushed = isCrushed
        self.crushedBy = crushedBy
        self.minHumanDistance = minHumanDistance
        self.humanMask = humanMask
        self.pose = pose
        self.fell = fell
        self.humanContacts = humanContacts
        self.arrived = arrived
        self.diverged = diverged

    def __repr__(self) -> str:
        return (
            f"SimState(scanId={self.scanId!r}, step={self.step}, "
            f"location={self.location.viewpointId!r}, heading={self.heading:.3f}, "
            f"elevation={self.elevation:.3f}, viewIndex={self.viewIndex}, "
            f"navigable={len(self.navigableLocations)}, time={self.time:.2f}, "
            f"isCrushed={self.isCrushed})"
        )
