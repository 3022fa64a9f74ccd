"""Procedural human motion: recipes that build looping clips, and blending between clips.

Every recipe returns a :class:`~havln_mj.humans.clip.Clip` at
:data:`~havln_mj.humans.motion.gait.FPS` in the person's anchor frame (origin on the floor at their
spot, z up, facing +y) for a person of a given height, varied per person by the
``numpy.random.Generator`` it is given.
"""

from havln_mj.humans.motion.behaviours import (
    EXERCISE_KINDS,
    REACH_KINDS,
    SEAT_CLEARANCE,
    SIT_POSES,
    exercise,
    idle,
    pace,
    reach,
    sit,
    talk,
    walk_path,
)
from havln_mj.humans.motion.blend import blend, sequence
from havln_mj.humans.motion.gait import FPS, GaitStyle, cycle_time

RECIPES = {
    "idle": idle,
    "walk_path": walk_path,
    "pace": pace,
    "sit": sit,
    "reach": reach,
    "talk": talk,
    "exercise": exercise,
}
"""Recipe name → function, as named in the activity catalog."""

__all__ = [
    "EXERCISE_KINDS",
    "FPS",
    "REACH_KINDS",
    "RECIPES",
    "SEAT_CLEARANCE",
    "SIT_POSES",
    "GaitStyle",
    "blend",
    "cycle_time",
    "exercise",
    "idle",
    "pace",
    "reach",
    "sequence",
    "sit",
    "talk",
    "walk_path",
]
