"""A user-supplied SMPL body model: shaped joints and numpy linear blend skinning.

The SMPL model files are licensed (non-commercial, no redistribution), so the project never
ships one; a user may point to theirs. Readable are ``.npz`` files and ``.pkl`` files whose
arrays are plain numpy or scipy-sparse (SMPL's original v1.x pickles hold ``chumpy`` objects
and must be converted to ``.npz`` once, see :func:`load_smpl_model`).

The model lives in SMPL's frame (y up, facing +z, +x = the body's left); the methods that
take or return poses work in our body frame (:mod:`havln_mj.humans.skeleton`), converting
with :data:`~havln_mj.humans.skeleton.SMPL_TO_BODY`. Nothing here assumes 6890 vertices.
"""

from __future__ import annotations

import pickle
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from havln_mj.errors import MalformedDataError, MissingDataError
from havln_mj.humans import rotations as rot
from havln_mj.humans.skeleton import (
    NUM_JOINTS,
    PARENTS,
    SMPL_TO_BODY,
    forward_kinematics,
    offsets_from_positions,
)

_REQUIRED = ("v_template", "shapedirs", "J_regressor", "weights", "kintree_table", "f")
_POSE_FEATURES = 9 * (NUM_JOINTS - 1)  # (R_j − I) of the 23 non-root joints, row-major

CONVERT_HINT = (
    "convert it once to .npz in an environment that has chumpy installed: "
    "python -c \"import pickle, numpy as np; d = pickle.load(open('MODEL.pkl', 'rb'), "
    "encoding='latin1'); keys = ('v_template', 'shapedirs', 'posedirs', 'J_regressor', "
    "'weights', 'kintree_table', 'f'); np.savez('MODEL.npz', **{k: np.asarray(getattr(d[k], "
    "'r', d[k].toarray() if hasattr(d[k], 'toarray') else d[k])) for k in keys})\""
)


@dataclass(frozen=True)
class SmplModel:
    """The arrays of an SMPL model (SMPL frame, metres).

    Attributes:
        v_template: Rest vertices ``(V, 3)`` of the mean shape.
        shapedirs: Shape blend shapes ``(V, 3, B)``.
        j_regressor: Joint regressor ``(24, V)`` (dense).
        weights: Skinning weights ``(V, 24)``.
        faces: Triangles ``(F, 3)`` (vertex indices).
        posedirs: Pose blend shapes ``(V, 3, 207)``, or None to skin without them.
        path: The file the model came from ("" when built in memory).
    """

    v_template: np.ndarray
    shapedirs: np.ndarray
    j_regressor: np.ndarray
    weights: np.ndarray
    faces: np.ndarray
    posedirs: np.ndarray | None = None
    path: str = ""

    def __post_init__(self) -> None:
        v = len(self.v_template)
        where = self.path or "SMPL model"
        expect = {
            "v_template": (self.v_template, (v, 3)),
            "J_regressor": (self.j_regressor, (NUM_JOINTS, v)),
            "weights": (self.weights, (v, NUM_JOINTS)),
        }
        for key, (arr, shape) in expect.items():
            if arr.shape != shape:
                raise MalformedDataError(
                    f"{where}: {key!r} has shape {arr.shape}, expected {shape} "
                    f"(a 24-joint SMPL model with {v} vertices)"
                )
        if self.shapedirs.ndim != 3 or self.shapedirs.shape[:2] != (v, 3):
            raise MalformedDataError(
                f"{where}: 'shapedirs' has shape {self.shapedirs.shape}, expected ({v}, 3, B)"
            )
        if self.faces.ndim != 2 or self.faces.shape[1] != 3 or self.faces.size == 0:
            raise MalformedDataError(f"{where}: 'f' has shape {self.faces.shape}, expected (F, 3)")
        if self.faces.min() < 0 or self.faces.max() >= v:
            raise MalformedDataError(f"{where}: 'f' indexes vertices outside 0..{v - 1}")
        if self.posedirs is not None and self.posedirs.shape != (v, 3, _POSE_FEATURES):
            raise MalformedDataError(
                f"{where}: 'posedirs' has shape {self.posedirs.shape}, "
                f"expected ({v}, 3, {_POSE_FEATURES})"
            )

    @property
    def num_vertices(self) -> int:
        """Number of mesh vertices."""
        return len(self.v_template)

    @property
    def num_betas(self) -> int:
        """Number of shape coefficients the model has."""
        return self.shapedirs.shape[2]

    def shaped(self, betas: np.ndarray | None = None) -> np.ndarray:
        """Rest vertices ``(V, 3)`` of shape ``betas`` in the SMPL frame.

        Extra betas beyond the model's are ignored (AMASS stores 16, SMPL has 10); missing
        ones are zero.
        """
        b = self._betas(betas)
        return self.v_template + self.shapedirs @ b

    def joints(self, betas: np.ndarray | None = None) -> np.ndarray:
        """Rest joint positions ``(24, 3)`` in the SMPL frame: J_regressor · shaped vertices."""
        return self.j_regressor @ self.shaped(betas)

    def rest_offsets(self, betas: np.ndarray | None = None) -> np.ndarray:
        """Parent-relative rest offsets ``(24, 3)`` in our body frame.

        Row 0, as in :func:`~havln_mj.humans.skeleton.rest_offsets`, is the pelvis's height
        above the soles (the lowest rest vertex).
        """
        shaped = self.shaped(betas) @ SMPL_TO_BODY.T
        joints = self.j_regressor @ shaped
        off = offsets_from_positions(joints)
        off[0] = (0.0, 0.0, joints[0, 2] - shaped[:, 2].min())
        return off

    def skin(self, betas: np.ndarray | None, local: np.ndarray, root: np.ndarray) -> np.ndarray:
        """Posed mesh vertices by linear blend skinning, in our body/world frame.

        Args:
            betas: Shape coefficients (None: mean shape).
            local: Local joint rotations ``(..., 24, 4)`` in our body frame (a clip's poses).
            root: Pelvis positions ``(..., 3)``.

        Returns:
            Vertices ``(..., V, 3)``. Pose blend shapes are applied when the model has them.
        """
        local = np.asarray(local, float)
        root = np.asarray(root, float)
        verts = self.shaped(betas) @ SMPL_TO_BODY.T  # (V, 3), body frame
        joints = self.j_regressor @ verts
        if self.posedirs is not None:
            # SMPL's pose features are its own local matrices: C⁻¹ R_body C per joint.
            r_body = rot.to_matrix(local[..., 1:, :])
            r_smpl = np.einsum("ba,...bc,cd->...ad", SMPL_TO_BODY, r_body, SMPL_TO_BODY)
            feat = (r_smpl - np.eye(3)).reshape(*local.shape[:-2], _POSE_FEATURES)
            verts = verts + np.einsum("...k,vck->...vc", feat, self.posedirs) @ SMPL_TO_BODY.T
        pos, quat = forward_kinematics(offsets_from_positions(joints), local, root)
        mats = rot.to_matrix(quat)  # (..., 24, 3, 3)
        trans = pos - np.einsum("...jab,jb->...ja", mats, joints)
        # Blend the 24 rigid transforms per vertex, then apply each blended one.
        m_v = np.einsum("vj,...jab->...vab", self.weights, mats)
        t_v = np.einsum("vj,...ja->...va", self.weights, trans)
        return np.einsum("...vab,...vb->...va", m_v, verts) + t_v

    def _betas(self, betas: np.ndarray | None) -> np.ndarray:
        b = np.zeros(self.num_betas)
        if betas is not None:
            betas = np.asarray(betas, float).ravel()[: self.num_betas]
            b[: len(betas)] = betas
        return b


def load_smpl_model(path: str | Path) -> SmplModel:
    """Reads a user's SMPL model file (``.npz``, or ``.pkl`` without chumpy objects).

    Expected arrays (SMPL's own names): ``v_template`` (V, 3), ``shapedirs`` (V, 3, ≥10),
    ``J_regressor`` (24, V) dense or scipy-sparse, ``weights`` (V, 24), ``kintree_table``
    (2, 24) with SMPL's parents, ``f`` (F, 3); optional ``posedirs`` (V, 3, 207).

    Raises:
        MissingDataError: The file does not exist.
        MalformedDataError: The file is unreadable, lacks an array or has a wrong shape, or
            is a pickle that needs ``chumpy`` (the message says how to convert it).
    """
    path = Path(path)
    if not path.is_file():
        raise MissingDataError(f"SMPL model file not found: {path}")
    if path.suffix == ".pkl":
        data = _read_pickle(path)
    else:
        try:
            with np.load(path, allow_pickle=True) as npz:  # a sparse J_regressor is an object
                data = {k: npz[k] for k in npz.files}
        except (OSError, ValueError, pickle.UnpicklingError) as exc:
            raise MalformedDataError(f"{path}: not a readable .npz SMPL model ({exc})") from exc
    missing = [k for k in _REQUIRED if k not in data]
    if missing:
        raise MalformedDataError(
            f"{path}: SMPL model lacks {missing}; expected keys {list(_REQUIRED)} "
            "(+ optional 'posedirs')"
        )
    arrays = {k: _dense(data[k], path, k) for k in (*_REQUIRED, "posedirs") if k in data}
    _check_tree(arrays["kintree_table"], path)
    return SmplModel(
        v_template=arrays["v_template"],
        shapedirs=arrays["shapedirs"],
        j_regressor=arrays["J_regressor"],
        weights=arrays["weights"],
        faces=arrays["f"].astype(np.int64),
        posedirs=arrays.get("posedirs"),
        path=str(path),
    )


def _read_pickle(path: Path) -> dict:
    try:
        with path.open("rb") as fh:
            data = pickle.load(fh, encoding="latin1")  # SMPL's pickles come from Python 2
    except ModuleNotFoundError as exc:
        if (exc.name or "").split(".")[0] == "chumpy":
            raise MalformedDataError(
                f"{path}: this SMPL .pkl holds chumpy objects, which havln_mj does not read; "
                + CONVERT_HINT
            ) from exc
        raise MalformedDataError(f"{path}: unpickling needs module {exc.name!r}") from exc
    except (OSError, EOFError, pickle.UnpicklingError, ValueError) as exc:
        raise MalformedDataError(f"{path}: not a readable SMPL .pkl ({exc})") from exc
    if not isinstance(data, dict):
        raise MalformedDataError(f"{path}: expected a pickled dict, got {type(data).__name__}")
    return data


def _dense(value: object, path: Path, key: str) -> np.ndarray:
    if isinstance(value, np.ndarray) and value.dtype == object and value.ndim == 0:
        value = value.item()  # np.savez wraps a scipy sparse matrix in a 0-d object array
    if hasattr(value, "toarray"):
        value = value.toarray()
    arr = np.asarray(value)
    if arr.dtype == object or not np.issubdtype(arr.dtype, np.number):
        raise MalformedDataError(f"{path}: {key!r} is not a numeric array (dtype {arr.dtype})")
    return arr.astype(np.int64 if key in ("f", "kintree_table") else float)


def _check_tree(kintree: np.ndarray, path: Path) -> None:
    if kintree.shape != (2, NUM_JOINTS):
        raise MalformedDataError(
            f"{path}: 'kintree_table' has shape {kintree.shape}, expected (2, 24) (SMPL, not "
            "SMPL-H/SMPL-X)"
        )
    order = np.argsort(kintree[1])
    parents = kintree[0][order]
    if not np.array_equal(kintree[1][order], np.arange(NUM_JOINTS)) or not np.array_equal(
        parents[1:], PARENTS[1:]
    ):
        raise MalformedDataError(
            f"{path}: 'kintree_table' parents {parents.tolist()} differ from SMPL's "
            f"{PARENTS.tolist()}"
        )
