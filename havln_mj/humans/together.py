"""People together: small conversations, walking side by side, handing something over.

Each function turns one placed person into a group around the same spot, drawing bodies,
clips and start offsets from the caller's generator (so a seed gives the same groups).
People of a group share their clip timing where they act together (walking in step,
reaching toward each other at once).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from havln_mj.humans.body import BodyShape
from havln_mj.humans.crowd import Person
from havln_mj.humans.motion.behaviours import reach, talk

CIRCLE_M = 0.6  # radius of a conversation circle (pelvis to centre)
SIDE_M = 0.6  # lateral spacing of people walking side by side
HANDOVER_M = 0.45  # half the distance between two people handing something over


def conversation(
    first: Person, rng: np.random.Generator, body: Callable[[], BodyShape], size: int
) -> list[Person]:
    """``size`` people (2 or 3) talking in a circle where ``first`` stood, facing its centre."""
    centre = first.anchor
    turn = float(rng.uniform(0, 2 * math.pi))
    out = []
    for k in range(size):
        bearing = turn + 2 * math.pi * k / size
        shape = first.shape if k == 0 else body()
        spot = centre + CIRCLE_M * np.array([math.sin(bearing), math.cos(bearing), 0.0])
        clip = talk(shape.height, rng)
        out.append(
            Person(
                shape, clip, spot, (bearing + math.pi) % (2 * math.pi), "together/conversation",
                "People talking together.", first.region, first.viewpoint,
                float(rng.uniform(0, clip.duration)),
            )
        )  # fmt: skip
    return out


def handover(
    first: Person, rng: np.random.Generator, body: Callable[[], BodyShape]
) -> list[Person]:
    """Two people facing each other, reaching forward together: one hands the other something."""
    heading = float(rng.uniform(0, 2 * math.pi))
    ahead = np.array([math.sin(heading), math.cos(heading), 0.0])
    out = []
    start = None
    for k, shape in enumerate((first.shape, body())):
        clip = reach(shape.height, rng, kind="forward")
        start = float(rng.uniform(0, clip.duration)) if start is None else start
        spot = first.anchor + (HANDOVER_M if k == 0 else -HANDOVER_M) * ahead
        face = heading + (math.pi if k == 0 else 0.0)
        out.append(
            Person(
                shape, clip, spot, face % (2 * math.pi), "together/handover",
                "Someone handing something over.", first.region, first.viewpoint, start,
            )
        )  # fmt: skip
    return out


def side_by_side(
    first: Person, rng: np.random.Generator, body: Callable[[], BodyShape], make_clip: Callable
) -> list[Person]:
    """``first`` (a walker) and a companion walking the same path in step, a shoulder apart.

    Args:
        first: The walker.
        rng: Source of the companion's body.
        body: Makes a body.
        make_clip: ``make_clip(height, lateral_offset_m)`` gives a walk along the walker's
            path shifted sideways (anchor frame).
    """
    shape = body()
    clip = make_clip(shape.height, SIDE_M)
    companion = Person(
        shape, clip, first.anchor, first.heading, first.activity, "People walking together.",
        first.region, first.viewpoint, first.start,
    )  # fmt: skip
    return [first, companion]
