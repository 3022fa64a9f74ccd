"""Loaders for user-supplied real motion files.

AMASS ``.npz``, HAPS ``*_smpl_params.npy`` and MDM ``results.npy`` are never shipped (licensed
data); each loader converts its source's frame and rate into a
:class:`~havln_mj.humans.clip.Clip` in our z-up frame. Rotation sources also carry the rest
offsets that make forward kinematics reproduce the source's joints (from the user's SMPL
model when given, see :mod:`havln_mj.humans.smpl_model`).
"""

from havln_mj.humans.loaders.amass import load_amass
from havln_mj.humans.loaders.haps import HAPS_FPS, haps_dir_name, load_haps, load_haps_folder
from havln_mj.humans.loaders.mdm import MDM_FPS, load_mdm
from havln_mj.humans.loaders.motion import LoadedMotion

__all__ = [
    "HAPS_FPS",
    "MDM_FPS",
    "LoadedMotion",
    "haps_dir_name",
    "load_amass",
    "load_haps",
    "load_haps_folder",
    "load_mdm",
]
