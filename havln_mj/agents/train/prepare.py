"""What a run trains and validates on: episodes, vocabulary, view encoder and features."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass

from havln_mj.agents.data import instructions_of, scans_of, split_episodes
from havln_mj.agents.features import FeatureStore
from havln_mj.agents.featurize import FeatureSpec, build_features, load_encoder, save_encoder
from havln_mj.agents.train.config import TrainConfig
from havln_mj.agents.vision import ViewEncoder
from havln_mj.paths import cache_dir
from havln_mj.tasks.episodes import Instruction
from havln_mj.tasks.vocab import Vocabulary


def _encoder_for(
    cfg: TrainConfig, spec: FeatureSpec, scenes: list[str], progress: bool
) -> tuple[ViewEncoder, FeatureStore]:
    """The view encoder (pretrained once per spec and scenes, cached) and the feature set."""
    render = {"connectivity_dir": cfg.connectivity_dir, "human_placements": cfg.human_placements}
    if spec.resnet152 is not None:
        return build_features(scenes, spec, progress=progress, **render)
    pretrain_on = scenes[: spec.pretrain_scenes]
    key = json.dumps({"spec": asdict(spec), "scenes": pretrain_on}, sort_keys=True, default=str)
    path = cache_dir("agents", "encoders") / f"{hashlib.sha1(key.encode()).hexdigest()[:16]}.pt"
    encoder = load_encoder(path) if path.is_file() else None
    encoder, store = build_features(
        scenes, spec, encoder=encoder, pretrain_on=pretrain_on, progress=progress, **render
    )
    if not path.is_file():
        save_encoder(encoder, path)
    return encoder, store


@dataclass
class RunData:
    """Everything a run trains and validates on."""

    train: list[Instruction]
    val: list[Instruction]
    vocab: Vocabulary
    encoder: ViewEncoder
    spec: FeatureSpec
    store: FeatureStore


def prepare_data(cfg: TrainConfig, progress: bool = True) -> RunData:
    """Episodes, vocabulary and features of a run."""
    where = {"connectivity_dir": cfg.connectivity_dir, "data_dir": cfg.data_dir}
    train_eps = split_episodes(cfg.train, cfg.people_seed, **where)
    val_eps = split_episodes(cfg.val, cfg.people_seed, **where) if cfg.val else []
    train = instructions_of(train_eps)
    val = instructions_of(val_eps)[: cfg.eval_instructions]
    vocab = Vocabulary.from_texts(i.text for i in train)
    spec = FeatureSpec.from_dict({**cfg.features, "seed": cfg.people_seed})
    scenes = scans_of(train_eps) + [s for s in scans_of(val_eps) if s not in scans_of(train_eps)]
    encoder, store = _encoder_for(cfg, spec, scenes, progress)
    return RunData(train, val, vocab, encoder, spec, store)
