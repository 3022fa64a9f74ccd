"""Building feature sets: pretrain the view encoder on renders, then encode every scan.

``python -m havln_mj.agents.featurize --scenes proc-0 proc-1 ... [--encoder FILE]`` renders the
36 × slots views of every viewpoint (:mod:`havln_mj.agents.views`), encodes them and caches
the result per scan (:mod:`havln_mj.agents.features`). Without ``--encoder`` a
:class:`~.ViewEncoder` is first trained from scratch on renders of the
first scenes, on what the simulator knows about each view: the room type, how much of it
shows people, whether FORWARD would move, and a coarse depth map.
"""

from __future__ import annotations

import argparse
import hashlib
import io
import pickle
import sys
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from havln_mj import argchecks
from havln_mj.agents.features import FeatureStore
from havln_mj.agents.views import REGION_CODES, ViewConfig, ViewpointViews, ViewRenderer
from havln_mj.agents.vision import ViewEncoder, encode_views, load_resnet152, pretrain_encoder
from havln_mj.cache import atomic_write_bytes
from havln_mj.errors import HavlnError, InvalidArgumentError, MalformedDataError, MissingDataError

DEPTH_GRID = (6, 8)  # coarse depth target: rows × columns of cells


@dataclass
class FeatureSpec:
    """Everything that decides a feature set.

    Attributes:
        view: How views are rendered.
        encoder: :class:`~.ViewEncoder` arguments.
        pretrain_scenes: How many of the first scenes the encoder is pretrained on.
        pretrain_viewpoints: Viewpoints drawn per pretraining scene.
        pretrain_epochs: Pretraining epochs.
        seed: People seed of the renders (the dataset's) and pretraining seed.
        resnet152: A user-supplied ImageNet ResNet-152 weights file: its 2048-d pooled RGB
            features replace the encoder trained here (HA3D's features; nothing is pretrained).
        resnet_input: ``(height, width)`` views are resized to for ResNet-152 (None: as
            rendered; ImageNet models expect about 224 × 224).
    """

    view: ViewConfig = field(default_factory=ViewConfig)
    encoder: dict = field(default_factory=dict)
    pretrain_scenes: int = 12
    pretrain_viewpoints: int = 16
    pretrain_epochs: int = 4
    seed: int = 0
    resnet152: str | None = None
    resnet_input: tuple[int, int] | None = None

    def fixed_encoder(self) -> torch.nn.Module | None:
        """The user's ResNet-152 when :attr:`resnet152` names one, else None.

        Raises:
            MissingDataError: The weights file does not exist.
            MalformedDataError: It is not a ResNet-152 state_dict.
        """
        if self.resnet152 is None:
            return None
        size = None if self.resnet_input is None else tuple(self.resnet_input)
        return load_resnet152(self.resnet152, input_size=size)

    @classmethod
    def from_dict(cls, d: dict) -> FeatureSpec:
        """From a config section (``view`` as a dict)."""
        d = dict(d)
        unknown = set(d) - set(cls.__dataclass_fields__)
        if unknown:
            raise InvalidArgumentError(
                f"unknown feature settings {sorted(unknown)}; valid: "
                f"{sorted(cls.__dataclass_fields__)}"
            )
        view = ViewConfig(**d.pop("view", {}))
        return cls(view=view, **d)


def encoder_digest(encoder: torch.nn.Module) -> str:
    """12 hex digits naming the encoder's weights."""
    h = hashlib.sha1()
    for name, tensor in sorted(encoder.state_dict().items()):
        h.update(name.encode())
        h.update(tensor.detach().cpu().numpy().tobytes())
    return h.hexdigest()[:12]


def feature_store(encoder: torch.nn.Module, spec: FeatureSpec) -> FeatureStore:
    """The cached feature set of ``encoder`` under ``spec``'s views and people seed."""
    name = f"{encoder_digest(encoder)}-{spec.view.key()}-seed{spec.seed}"
    return FeatureStore.named(name, spec.view, encoder.out_dim)


def save_encoder(encoder: ViewEncoder, path: Path, history: list | None = None) -> None:
    """Writes the encoder's configuration and weights (atomically)."""
    buf = io.BytesIO()
    torch.save(
        {"config": encoder.config(), "state_dict": encoder.state_dict(), "history": history}, buf
    )
    atomic_write_bytes(Path(path), buf.getvalue())


def load_encoder(path: str | Path) -> ViewEncoder:
    """Reads an encoder written by :func:`save_encoder`.

    Raises:
        MissingDataError: No such file.
        MalformedDataError: The file is not such an encoder.
    """
    path = Path(path).expanduser()
    if not path.is_file():
        raise MissingDataError(f"view encoder file {path} does not exist")
    try:
        blob = torch.load(path, map_location="cpu", weights_only=False)
        encoder = ViewEncoder.from_config(blob["config"])
        encoder.load_state_dict(blob["state_dict"])
    except (KeyError, TypeError, RuntimeError, EOFError, pickle.UnpicklingError) as exc:
        raise MalformedDataError(f"{path} is not a view encoder file: {exc}") from None
    return encoder.eval()


def _depth_cells(depth: np.ndarray) -> np.ndarray:
    """``(N, H, W)`` metres → ``(N, gh, gw)`` mean over the valid pixels of each cell."""
    n, h, w = depth.shape
    gh, gw = DEPTH_GRID
    d = depth[:, : h - h % gh, : w - w % gw].astype(np.float32)
    d = d.reshape(n, gh, d.shape[1] // gh, gw, d.shape[2] // gw)
    valid = (d > 0).sum(axis=(2, 4))
    return np.where(valid > 0, d.sum(axis=(2, 4)) / np.maximum(valid, 1), 0.0).astype(np.float32)


def _images(views: Sequence[ViewpointViews], cfg: ViewConfig) -> tuple[np.ndarray, ...]:
    """RGB ``(N, H, W, 3)`` and depth ``(N, H, W)`` (or None), one row per view and slot."""
    rgb = np.concatenate([v.rgb.reshape(-1, cfg.height, cfg.width, 3) for v in views])
    depth = None
    if cfg.depth:
        depth = np.concatenate([v.depth.reshape(-1, cfg.height, cfg.width) for v in views])
    return rgb, depth


def _targets(views: Sequence[ViewpointViews], cfg: ViewConfig) -> dict[str, np.ndarray]:
    """The pretraining targets of :func:`_images`' rows (depth cells added by the caller)."""
    slots = cfg.slots
    return {
        "region": np.concatenate([np.full(v.rgb.shape[0] * slots, v.region) for v in views]),
        "person": np.concatenate([v.person.reshape(-1) for v in views]),
        "forward": np.concatenate([np.repeat(v.forward, slots) for v in views]).astype(np.float32),
    }


def pretrain(
    renderer: ViewRenderer, scenes: Sequence[str], spec: FeatureSpec, progress: bool = True
) -> tuple[ViewEncoder, list[dict]]:
    """Trains a fresh encoder on renders of ``spec.pretrain_viewpoints`` per scene."""
    rng = np.random.default_rng([spec.seed, 7])
    views: list[ViewpointViews] = []
    for scene in tqdm(scenes, desc="pretraining renders", unit="scene", disable=not progress):
        vps = renderer.viewpoints(scene)
        pick = rng.permutation(len(vps))[: spec.pretrain_viewpoints]
        views += list(renderer.render(scene, [vps[i] for i in sorted(pick)]))
    rgb, depth = _images(views, spec.view)
    # Validation rows come from viewpoints the encoder never trained on.
    per_vp = views[0].rgb.shape[0] * spec.view.slots
    groups = np.repeat(np.arange(len(views)), per_vp)
    targets = _targets(views, spec.view)
    if depth is not None:
        targets["depth"] = _depth_cells(depth)
    torch.manual_seed(spec.seed)
    encoder = ViewEncoder(in_channels=4 if spec.view.depth else 3, **spec.encoder)
    history = pretrain_encoder(
        encoder,
        rgb,
        depth,
        targets,
        n_regions=len(REGION_CODES),
        epochs=spec.pretrain_epochs,
        seed=spec.seed,
        progress=progress,
        groups=groups,
    )
    return encoder.eval(), history


def encode_scans(
    renderer: ViewRenderer,
    encoder: ViewEncoder,
    store: FeatureStore,
    scenes: Sequence[str],
    progress: bool = True,
) -> None:
    """Renders and encodes every scene not yet in ``store`` (one file per scene)."""
    missing = [s for s in scenes if not store.has(s)]
    for scene in tqdm(missing, desc="features", unit="scene", disable=not progress):
        store.put(scene, *encode_viewpoints(encoder, renderer.render(scene), store.config))


def encode_viewpoints(
    encoder: ViewEncoder, views: Iterable[ViewpointViews], cfg: ViewConfig
) -> tuple[list[str], np.ndarray]:
    """The viewpoint ids of ``views`` and their ``(V, 36, S, D)`` features."""
    vps, feats = [], []
    for v in views:
        rgb, depth = _images([v], cfg)
        feats.append(encode_views(encoder, rgb, depth).reshape(-1, cfg.slots, encoder.out_dim))
        vps.append(v.viewpoint)
    return vps, np.stack(feats)


def build_features(
    scenes: Sequence[str],
    spec: FeatureSpec,
    *,
    encoder: ViewEncoder | None = None,
    pretrain_on: Sequence[str] | None = None,
    connectivity_dir: str | Path | None = None,
    human_placements: str | Path | None = None,
    progress: bool = True,
) -> tuple[ViewEncoder, FeatureStore]:
    """The encoder (pretrained when not given) and its feature set, covering ``scenes``.

    Args:
        scenes: Scans whose features are needed.
        spec: Views, encoder sizes, pretraining and seed.
        encoder: A trained encoder; None pretrains one on ``pretrain_on``.
        pretrain_on: Scenes to pretrain on (default: the first ``spec.pretrain_scenes``).
        connectivity_dir: Navigation graphs of real scans.
        human_placements: HA3D placement file for real scans.
        progress: Show progress bars.
    """
    with ViewRenderer(
        spec.view,
        seed=spec.seed,
        connectivity_dir=connectivity_dir,
        human_placements=human_placements,
    ) as renderer:
        history = None
        encoder = encoder or spec.fixed_encoder()
        if encoder is None:
            chosen = list(pretrain_on or scenes[: spec.pretrain_scenes])
            encoder, history = pretrain(renderer, chosen, spec, progress)
        store = feature_store(encoder, spec)
        if not (store.folder / "features.json").is_file():
            if isinstance(encoder, ViewEncoder):
                save_encoder(encoder, store.folder / "encoder.pt", history)
            store.write_meta({"spec": {**asdict(spec), "view": asdict(spec.view)}})
        encode_scans(renderer, encoder, store, scenes, progress)
    return encoder, store


PROG = "python -m havln_mj.agents.featurize"


def parser(prog: str = PROG) -> argparse.ArgumentParser:
    """The command's argument parser."""
    p = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    p.add_argument("--scenes", nargs="+", required=True, help="scene ids (proc-<seed>, scan ids)")
    p.add_argument("--encoder", type=Path, default=None, help="trained encoder file (.pt)")
    p.add_argument(
        "--resnet152", type=Path, default=None, help="ImageNet ResNet-152 weights (instead)"
    )
    p.add_argument("--seed", type=int, default=0, help="people seed (the dataset's)")
    argchecks.add_data_flags(p, "--connectivity-dir", "--human-placements")
    return p


def main(argv: Sequence[str] | None = None, prog: str = PROG) -> int:
    """``havln_mj featurize``; returns the exit code."""
    p = parser(prog)
    args = p.parse_args(argv)
    if args.seed < 0:
        p.error(f"--seed must be ≥ 0, got {args.seed}")
    try:
        encoder = load_encoder(args.encoder) if args.encoder else None
        _, store = build_features(
            args.scenes,
            FeatureSpec(
                seed=args.seed,
                resnet152=None if args.resnet152 is None else str(args.resnet152),
                resnet_input=None if args.resnet152 is None else (224, 224),
            ),
            encoder=encoder,
            connectivity_dir=args.connectivity_dir,
            human_placements=args.human_placements,
        )
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(store.folder)
    return 0


if __name__ == "__main__":
    sys.exit(main())
