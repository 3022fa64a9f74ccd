"""Where a Matterport3D scan's files are in the user's copy of the dataset.

Matterport3D is licensed, so the data never ships with havln_mj: users point at their own
copy with ``--mp3d-dir`` or ``$HAVLN_MP3D_DIR``. Two layouts are accepted, and several roots
for each (users point at ``v1/scans``, ``v1`` or the download folder alike). Candidates, in
the order they are tried, for a scan ``<scan>`` and a root ``<root>``:

Raw release (``download_mp.py``, with ``matterport_mesh`` and ``house_segmentations``
unzipped), for ``<base>`` in ``<root>/v1/scans/<scan>``, ``<root>/scans/<scan>``,
``<root>/<scan>``:

- mesh: ``<base>/matterport_mesh/<mesh_id>/<mesh_id>.obj`` (+ ``.mtl`` and textures);
- house: ``<base>/house_segmentations/<scan>.house``; ply: ``…/<scan>.ply``.

Habitat (``mp3d`` scene dataset), for ``<base>`` in ``<root>/scene_datasets/mp3d/<scan>``,
``<root>/mp3d/<scan>``, ``<root>/<scan>``:

- mesh: ``<base>/<scan>.glb``; house: ``<base>/<scan>.house``; no ply.

The first candidate with both a mesh and a house file wins; failing that, the first with a
mesh. Both layouts store vertices z-up in Matterport's frame (habitat-sim reads its MP3D
``.glb`` files as "gravity −z" and rotates them itself), so both load with ``up="z"``.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

from havln_mj.errors import MissingDataError, UnknownSceneError

ENV_VAR = "HAVLN_MP3D_DIR"
"""Environment variable naming the Matterport3D root when ``--mp3d-dir`` is not given."""

HOW_TO_GET = (
    "Matterport3D is licensed: request access at https://niessner.github.io/Matterport/ "
    "(agree to the Terms of Use), download the scans (matterport_mesh, house_segmentations) "
    f"or the habitat mp3d scene dataset, and pass --mp3d-dir or set {ENV_VAR}"
)

LAYOUTS = ("raw", "habitat")

_SCAN_ID = re.compile(r"[A-Za-z0-9_-]+")
_RAW_BASES = (("v1", "scans"), ("scans",), ())
_HABITAT_BASES = (("scene_datasets", "mp3d"), ("mp3d",), ())


@dataclass(frozen=True)
class MatterportFiles:
    """A scan's files in the user's copy of Matterport3D.

    Attributes:
        scan_id: The scan id, e.g. ``"17DRP5sb8fy"``.
        layout: ``"raw"`` (release ``.obj``) or ``"habitat"`` (``.glb``).
        mesh: The textured mesh.
        house: The ``.house`` annotations, or None when absent.
        ply: The house-segmentation ``.ply`` (raw layout only), or None.
    """

    scan_id: str
    layout: str
    mesh: Path
    house: Path | None
    ply: Path | None

    @property
    def up(self) -> str:
        """The mesh file's up axis for :func:`havln_mj.scene.mesh.load_mesh_parts`."""
        return "z"  # Both layouts: see the module docstring.


def resolve_mp3d_root(arg: Path | str | None) -> Path | None:
    """The Matterport3D root: ``arg`` if given, else ``$HAVLN_MP3D_DIR``, else None.

    ``~`` is expanded; the folder is not checked here (:func:`find_matterport_files` says
    what is missing).
    """
    if arg is None or str(arg) == "":
        arg = os.environ.get(ENV_VAR) or None
    return None if arg is None else Path(arg).expanduser()


def _raw_mesh(base: Path) -> Path | None:
    """``matterport_mesh/<id>/<id>.obj`` (else the first ``.obj`` there), or None."""
    folder = base / "matterport_mesh"
    if not folder.is_dir():
        return None
    objs = sorted(p for p in folder.glob("*/*.obj") if p.is_file())
    named = [p for p in objs if p.stem == p.parent.name]
    return (named or objs or [None])[0]


def _candidates(root: Path, scan_id: str) -> list[tuple[str, Path, Path, Path | None, list[str]]]:
    """(layout, mesh, house, ply, paths described for messages) for every candidate."""
    out = []
    for parts in _RAW_BASES:
        base = root.joinpath(*parts, scan_id)
        seg = base / "house_segmentations"
        mesh = _raw_mesh(base) or base / "matterport_mesh" / "<mesh_id>" / "<mesh_id>.obj"
        looked = [str(mesh), str(seg / f"{scan_id}.house")]
        out.append(("raw", mesh, seg / f"{scan_id}.house", seg / f"{scan_id}.ply", looked))
    for parts in _HABITAT_BASES:
        base = root.joinpath(*parts, scan_id)
        mesh, house = base / f"{scan_id}.glb", base / f"{scan_id}.house"
        out.append(("habitat", mesh, house, None, [str(mesh), str(house)]))
    return out


def _zips(root: Path, scan_id: str) -> list[Path]:
    """Still-zipped raw downloads of the scan (``matterport_mesh.zip`` etc.)."""
    found = []
    for parts in _RAW_BASES:
        base = root.joinpath(*parts, scan_id)
        for name in ("matterport_mesh.zip", "house_segmentations.zip"):
            if (base / name).is_file():
                found.append(base / name)
    return found


def label_files(mesh: Path, scan_id: str, layout: str) -> tuple[Path, Path]:
    """Where a scan's per-face object labels and ``.house`` file sit beside its mesh.

    Raw layout: ``<base>/house_segmentations/<scan>.ply`` (faces carry ``face_segment``, the
    object index) for a mesh at ``<base>/matterport_mesh/<id>/<id>.obj``. Habitat layout:
    ``<scan>_semantic.ply`` (faces carry ``object_id``) beside ``<scan>.glb``. The paths are
    not checked.

    Returns:
        (ply, house).
    """
    if layout == "raw":
        folder = mesh.parent.parent.parent / "house_segmentations"
        return folder / f"{scan_id}.ply", folder / f"{scan_id}.house"
    return mesh.parent / f"{scan_id}_semantic.ply", mesh.parent / f"{scan_id}.house"


SKYBOX_FOLDER = "matterport_skybox_images"


def skybox_folders(scan_id: str, root: Path | str) -> list[Path]:
    """Where a scan's ``matterport_skybox_images`` folder may be, in the order tried."""
    root = Path(root).expanduser()
    return [root.joinpath(*parts, scan_id, SKYBOX_FOLDER) for parts in _RAW_BASES]


def find_house_file(scan_id: str, root: Path | str | None) -> Path | None:
    """A scan's ``.house`` file in either layout under ``root``, even without its mesh."""
    if root is None:
        return None
    for _, _, house, _, _ in _candidates(Path(root).expanduser(), scan_id):
        if house.is_file():
            return house
    return None


def find_matterport_files(scan_id: str, root: Path | str | None) -> MatterportFiles:
    """Finds a scan's mesh and annotations under a Matterport3D root.

    Args:
        scan_id: The scan id (e.g. ``"17DRP5sb8fy"``).
        root: The user's Matterport3D folder; None reads ``$HAVLN_MP3D_DIR``.

    Returns:
        The files of the first candidate location that has them (see the module docstring).

    Raises:
        UnknownSceneError: ``scan_id`` is not a plain name (letters, digits, ``_``, ``-``).
        MissingDataError: No root was given, or no candidate holds the scan's mesh; the
            message lists every path looked at and how to get the data.
    """
    if not isinstance(scan_id, str) or not _SCAN_ID.fullmatch(scan_id):
        raise UnknownSceneError(
            f"Matterport3D scan id {scan_id!r} is not a plain name (letters, digits, _ and -), "
            "e.g. '17DRP5sb8fy'"
        )
    resolved = resolve_mp3d_root(root)
    if resolved is None:
        raise MissingDataError(
            f"scan {scan_id!r} needs Matterport3D data, but no folder was given "
            f"(--mp3d-dir not passed, {ENV_VAR} not set). {HOW_TO_GET}."
        )
    if not resolved.is_dir():
        raise MissingDataError(
            f"Matterport3D folder {resolved} does not exist or is not a folder "
            f"(looking for scan {scan_id!r}). {HOW_TO_GET}."
        )
    candidates = _candidates(resolved, scan_id)
    with_mesh = [c for c in candidates if c[1].is_file()]
    best = next((c for c in with_mesh if c[2].is_file()), with_mesh[0] if with_mesh else None)
    if best is not None:
        layout, mesh, house, ply, _ = best
        return MatterportFiles(
            scan_id=scan_id,
            layout=layout,
            mesh=mesh,
            house=house if house.is_file() else None,
            ply=ply if ply is not None and ply.is_file() else None,
        )
    looked = "\n".join(f"  {p}" for c in candidates for p in c[4])
    zipped = _zips(resolved, scan_id)
    unzip = (
        "\nFound still-zipped downloads (unzip them so that the paths above exist): "
        + ", ".join(str(z) for z in zipped)
        if zipped
        else ""
    )
    raise MissingDataError(
        f"Matterport3D scan {scan_id!r} not found under {resolved}. Looked for:\n"
        f"{looked}{unzip}\n{HOW_TO_GET}."
    )
