"""View encoders: our ResNet, its pretraining on simulator ground truth, ResNet-152 weights."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from havln_mj.agents.vision import (  # noqa: E402
    DEPTH_MAX,
    PretrainHeads,
    ResNetFeatures,
    ViewEncoder,
    encode_views,
    load_resnet152,
    prepare_imagenet,
    prepare_views,
    pretrain_encoder,
    pretrain_loss,
    resnet152,
)
from havln_mj.agents.vision.pretrain import _split  # noqa: E402
from havln_mj.errors import (  # noqa: E402
    InvalidArgumentError,
    MalformedDataError,
    MissingDataError,
)

TINY = {"widths": (8, 16, 32, 32), "out_dim": 32}


def _rgb(n: int, h: int, w: int, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (n, h, w, 3), dtype=np.uint8)


def synthetic_views(n: int, seed: int = 0, size: int = 32, grid: tuple[int, int] = (2, 2)):
    """Views whose hue encodes the region, brightness the depth, a magenta stripe the person
    fraction and a white centre square FORWARD; every depth grid's top-left cell is unread."""
    rng = np.random.default_rng(seed)
    palette = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0]], np.float32)
    region = rng.integers(0, 4, n)
    dist = rng.uniform(1, 9, n).astype(np.float32)
    bright = 0.25 + 0.75 * (1 - dist / DEPTH_MAX)
    img = palette[region][:, None, None, :] * bright[:, None, None, None]
    img = np.broadcast_to(img, (n, size, size, 3)).copy()
    cols = np.round(rng.uniform(0, 0.5, n) * size).astype(int)
    forward = rng.random(n) < 0.5
    c = size // 2
    for i in range(n):
        img[i, :, : cols[i]] = (1, 0, 1)
        if forward[i]:
            img[i, c - 4 : c + 4, c - 4 : c + 4] = 1
    img += rng.normal(0, 0.03, img.shape)
    rgb = (np.clip(img, 0, 1) * 255).astype(np.uint8)
    depth = np.broadcast_to(dist[:, None, None], (n, size, size)).copy()
    depth_grid = np.broadcast_to(dist[:, None, None], (n, *grid)).copy()
    depth_grid[:, 0, 0] = 0
    targets = {
        "region": region.astype(np.int64),
        "person": (cols / size).astype(np.float32),
        "forward": forward.astype(np.float32),
        "depth": depth_grid.astype(np.float32),
    }
    return rgb, depth.astype(np.float32), targets


# ---------------------------------------------------------------------- ViewEncoder


@pytest.mark.parametrize("hw", [(48, 64), (32, 32), (37, 53), (96, 128)])
@pytest.mark.parametrize("channels", [3, 4])
def test_view_encoder_output_shapes(hw, channels):
    torch.manual_seed(0)
    enc = ViewEncoder(channels, **TINY)
    x = torch.randn(3, channels, *hw)
    assert enc(x).shape == (3, 32)
    enc.eval()
    with torch.no_grad():
        assert enc(x[:1]).shape == (1, 32)


def test_view_encoder_default_architecture():
    enc = ViewEncoder()
    assert enc.out_dim == 256 and enc.in_channels == 4
    blocks = [m for m in enc.modules() if type(m).__name__ == "_BasicBlock"]
    assert len(blocks) == 4 and all(isinstance(b.bn1, torch.nn.BatchNorm2d) for b in blocks)
    assert [b.conv1.stride for b in blocks] == [(1, 1), (2, 2), (2, 2), (2, 2)]
    with torch.no_grad():
        assert enc.eval()(torch.zeros(2, 4, 48, 64)).shape == (2, 256)
    with pytest.raises(InvalidArgumentError, match=r"\(N, 4, H, W\)"):
        enc(torch.zeros(2, 3, 48, 64))
    with pytest.raises(InvalidArgumentError, match="equal length"):
        ViewEncoder(widths=(8, 16), blocks=(1,))


def test_view_encoder_config_round_trip():
    torch.manual_seed(1)
    enc = ViewEncoder(3, widths=(8, 16), blocks=(2, 1), out_dim=12, stem_stride=1).eval()
    cfg = json.loads(json.dumps(enc.config()))
    clone = ViewEncoder.from_config(cfg)
    assert clone.config() == enc.config()
    clone.load_state_dict(enc.state_dict())
    clone.eval()
    x = torch.randn(2, 3, 32, 32)
    with torch.no_grad():
        assert torch.equal(clone(x), enc(x))


# ---------------------------------------------------------------------- inputs


def test_prepare_views_normalises_rgb_and_depth():
    rgb = np.zeros((2, 4, 5, 3), np.uint8)
    rgb[0] = 255
    rgb[1, 0, 0] = (0, 128, 255)
    depth = np.zeros((2, 4, 5), np.float16)
    depth[0, 0, :5] = [0.0, 5.0, 10.0, 25.0, np.inf]
    depth[0, 1, 0] = np.nan
    depth[0, 1, 1] = -3.0
    rgb.setflags(write=False)  # cache arrays may be read-only
    x = prepare_views(rgb, depth)
    assert x.dtype == torch.float32 and x.shape == (2, 4, 4, 5)
    assert torch.all(x[0, :3] == 1.0) and torch.all(x[1, :3, 1:] == -1.0)
    assert torch.allclose(x[1, :3, 0, 0], torch.tensor([-1.0, 128 / 127.5 - 1, 1.0]), atol=1e-6)
    # metres → [-1, 1] over [0, DEPTH_MAX]; no reading / NaN / negative → -1; far / inf → 1
    assert x[0, 3, 0].tolist() == [-1.0, 0.0, 1.0, 1.0, 1.0]
    assert x[0, 3, 1, :2].tolist() == [-1.0, -1.0]
    assert float(x.min()) >= -1.0 and float(x.max()) <= 1.0
    rgb_only = prepare_views(rgb, None)
    assert rgb_only.shape == (2, 3, 4, 5) and torch.equal(rgb_only, x[:, :3])


def test_prepare_views_rejects_bad_input():
    with pytest.raises(InvalidArgumentError, match="uint8"):
        prepare_views(np.zeros((1, 4, 4, 3), np.float32), None)
    with pytest.raises(InvalidArgumentError, match="uint8"):
        prepare_views(np.zeros((4, 4, 3), np.uint8), None)
    with pytest.raises(InvalidArgumentError, match="depth"):
        prepare_views(np.zeros((1, 4, 4, 3), np.uint8), np.zeros((1, 4, 5)))
    with pytest.raises(InvalidArgumentError, match="RGB-D"):
        ViewEncoder(4, **TINY).prepare(np.zeros((1, 4, 4, 3), np.uint8), None)


def test_prepare_imagenet_uses_imagenet_statistics():
    rgb = np.empty((1, 6, 8, 3), np.uint8)
    rgb[...] = (124, 116, 104)  # ≈ ImageNet's mean colour
    x = prepare_imagenet(rgb)
    assert x.dtype == torch.float32 and x.shape == (1, 3, 6, 8)
    assert float(x.abs().max()) < 0.01
    white = prepare_imagenet(np.full((1, 6, 8, 3), 255, np.uint8))
    assert torch.allclose(white[0, :, 0, 0], torch.tensor([2.2489, 2.4286, 2.6400]), atol=1e-3)
    assert prepare_imagenet(rgb, size=(12, 16)).shape == (1, 3, 12, 16)


# ---------------------------------------------------------------------- pretraining


def test_pretrain_loss_ignores_unknown_regions_and_unread_depth():
    torch.manual_seed(0)
    heads = PretrainHeads(8, n_regions=3, depth_grid=(2, 2))
    pred = heads(torch.randn(4, 8))
    targets = {
        "region": torch.tensor([0, -1, 2, -1]),
        "depth": torch.tensor([[[0.0, 2.0], [3.0, 4.0]]] * 4),
    }
    loss, parts = pretrain_loss(pred, targets)
    known = torch.tensor([0, 2])
    ce = torch.nn.functional.cross_entropy(pred["region"][known], targets["region"][known])
    assert parts["region"] == pytest.approx(ce.item(), rel=1e-6)
    # Changing predictions where the target is unknown / unread changes nothing.
    moved = {k: v.detach().clone() for k, v in pred.items()}
    moved["region"][[1, 3]] += torch.tensor([50.0, -50.0, 9.0])
    moved["depth"][:, 0, 0] = 7.5
    loss2, parts2 = pretrain_loss(moved, targets)
    assert loss2.item() == pytest.approx(loss.item(), rel=1e-6)
    assert parts2 == pytest.approx(parts, rel=1e-6)
    # Nothing known: the term is dropped and the loss stays finite.
    loss3, parts3 = pretrain_loss(
        pred, {"region": torch.full((4,), -1), "depth": torch.zeros(4, 2, 2)}
    )
    assert "region" not in parts3 and "depth" not in parts3 and loss3.item() == 0.0
    loss3.backward()  # still differentiable
    with pytest.raises(InvalidArgumentError, match="unknown pretraining targets"):
        pretrain_loss(pred, {"regions": targets["region"]})


def test_pretrain_loss_person_term_is_zero_when_exact():
    frac = torch.tensor([0.0, 0.1, 0.5, 0.9])
    pred = {"person": torch.logit(frac, eps=1e-7), "region": torch.zeros(4, 2)}
    _, parts = pretrain_loss(pred, {"person": frac})
    assert parts["person"] == pytest.approx(0.0, abs=1e-5)
    _, worse = pretrain_loss({**pred, "person": torch.zeros(4)}, {"person": frac})
    assert worse["person"] > 0.05


def test_pretraining_learns_synthetic_ground_truth():
    rgb, _, targets = synthetic_views(384)
    torch.manual_seed(0)
    enc = ViewEncoder(3, **TINY)
    history = pretrain_encoder(
        enc, rgb, None, targets, n_regions=4, epochs=8, batch_size=32, lr=1e-2,
        progress=False, val_fraction=0.25,
    )  # fmt: skip
    assert [h["epoch"] for h in history] == list(range(1, 9))
    first, last = history[0], history[-1]
    assert last["train_total"] < 0.5 * first["train_total"]
    for part in ("region", "person", "forward", "depth"):
        assert last[f"train_{part}"] < first[f"train_{part}"], part
    # Chance / constant predictions: region 0.25 (4 balanced classes), person MAE 0.125
    # (fractions uniform in [0, 0.5]), forward 0.5, depth MAE 2 m (uniform in [1, 9] m).
    assert last["val_region_acc"] > 0.8
    assert last["val_person_mae"] < 0.08
    assert last["val_forward_acc"] > 0.75
    assert last["val_depth_mae"] < 1.0
    assert not enc.training


def test_pretraining_is_deterministic_given_the_seed():
    rgb, depth, targets = synthetic_views(48, seed=3, size=16)
    torch.manual_seed(0)
    base = ViewEncoder(4, widths=(4, 8), blocks=(1, 1), out_dim=8)

    def run(seed: int):
        enc = copy.deepcopy(base)
        hist = pretrain_encoder(
            enc, rgb, depth, targets, n_regions=4, epochs=2, batch_size=16, seed=seed,
            progress=False,
        )  # fmt: skip
        return enc.state_dict(), hist

    rng_before = torch.get_rng_state()
    (a, ha), (b, hb) = run(0), run(0)
    assert torch.equal(torch.get_rng_state(), rng_before)  # the caller's RNG is left alone
    assert all(torch.equal(a[k], b[k]) for k in a)
    assert [{k: v for k, v in h.items() if k != "seconds"} for h in ha] == [
        {k: v for k, v in h.items() if k != "seconds"} for h in hb
    ]
    c, _ = run(1)
    assert not all(torch.equal(a[k], c[k]) for k in a)


def test_pretraining_validates_targets():
    rgb, _, targets = synthetic_views(8, size=8)
    enc = ViewEncoder(3, widths=(4,), blocks=(1,), out_dim=4)
    with pytest.raises(InvalidArgumentError, match="'person' must have 8 rows"):
        pretrain_encoder(enc, rgb, None, {"person": targets["person"][:5]}, n_regions=4)
    with pytest.raises(InvalidArgumentError, match="region target 4"):
        pretrain_encoder(enc, rgb, None, {"region": targets["region"] * 0 + 4}, n_regions=4)
    with pytest.raises(InvalidArgumentError, match="valid"):
        pretrain_encoder(enc, rgb, None, {"colour": targets["person"]}, n_regions=4)


def test_validation_split_keeps_groups_whole():
    groups = np.repeat(np.arange(10), 5)
    train, val = _split(50, 0.2, np.random.default_rng(0), groups)
    assert len(train) + len(val) == 50 and len(val) == 10
    assert not set(groups[train]) & set(groups[val])
    train, val = _split(50, 0.0, np.random.default_rng(0), None)
    assert len(val) == 0 and len(train) == 50


def test_encode_views_batches_in_eval_mode():
    torch.manual_seed(0)
    enc = ViewEncoder(4, **TINY)
    enc.train()
    with torch.no_grad():  # give BatchNorm non-trivial running statistics
        enc(prepare_views(_rgb(8, 24, 32, seed=1), np.full((8, 24, 32), 3.0)))
    rgb, depth = _rgb(5, 24, 32), np.random.default_rng(2).uniform(0, 12, (5, 24, 32))
    big = encode_views(enc, rgb, depth)
    small = encode_views(enc, rgb, depth, batch_size=2)
    assert big.dtype == np.float32 and big.shape == (5, 32)
    np.testing.assert_allclose(big, small, rtol=1e-5, atol=1e-5)
    assert enc.training  # mode restored
    assert encode_views(enc, rgb[:0], depth[:0]).shape == (0, 32)
    with pytest.raises(InvalidArgumentError, match="RGB-D"):
        encode_views(enc, rgb, None)


# ---------------------------------------------------------------------- ResNet-152


@pytest.fixture(scope="module")
def resnet():
    torch.manual_seed(0)
    return resnet152().eval()


@pytest.fixture
def flush_denormals():
    """A randomly initialised ResNet-152 produces denormal floats that make CPU convs ~40×
    slower; real weights do not. Flush them for these tests only."""
    torch.set_flush_denormal(True)
    yield
    torch.set_flush_denormal(False)


def test_resnet152_has_torchvision_names_and_shapes(resnet):
    sd = resnet.state_dict()
    assert sum(p.numel() for p in resnet.parameters()) == 60_192_808
    assert len(sd) == 932  # 467 parameters + 3 BatchNorm buffers × 155
    expected = {
        "conv1.weight": (64, 3, 7, 7),
        "bn1.running_var": (64,),
        "layer1.0.conv1.weight": (64, 64, 1, 1),
        "layer1.0.conv3.weight": (256, 64, 1, 1),
        "layer1.0.downsample.0.weight": (256, 64, 1, 1),
        "layer1.0.downsample.1.running_mean": (256,),
        "layer2.0.conv2.weight": (128, 128, 3, 3),
        "layer2.7.bn3.weight": (512,),
        "layer3.35.conv3.weight": (1024, 256, 1, 1),
        "layer4.0.downsample.0.weight": (2048, 1024, 1, 1),
        "layer4.2.bn3.num_batches_tracked": (),
        "fc.weight": (1000, 2048),
        "fc.bias": (1000,),
    }
    for key, shape in expected.items():
        assert tuple(sd[key].shape) == shape, key
    assert "layer1.1.downsample.0.weight" not in sd and "layer3.36.conv1.weight" not in sd
    assert [k for k in sd if "downsample.0.weight" in k] == [
        f"layer{i}.0.downsample.0.weight" for i in range(1, 5)
    ]
    assert resnet.layer2[0].conv2.stride == (2, 2) and resnet.layer2[0].conv1.stride == (1, 1)


def test_resnet152_save_load_round_trip(resnet, tmp_path, flush_denormals):
    rgb = _rgb(1, 64, 64)
    x = prepare_imagenet(rgb)
    with torch.no_grad():
        want = resnet.features(x).numpy()
        logits = resnet(x)
    assert want.shape == (1, 2048) and logits.shape == (1, 1000)
    plain = tmp_path / "plain.pth"
    torch.save(resnet.state_dict(), plain)
    loaded = load_resnet152(plain)
    assert isinstance(loaded, ResNetFeatures) and loaded.out_dim == 2048
    assert not loaded.training and not any(p.requires_grad for p in loaded.parameters())
    assert set(loaded.state_dict()) == set(resnet.state_dict())
    np.testing.assert_array_equal(encode_views(loaded, rgb, None), want)

    # A training checkpoint: wrapped, saved from DataParallel, from an old torchvision
    # without num_batches_tracked, and head-less.
    sd = {f"module.{k}": v for k, v in resnet.state_dict().items()}
    sd = {k: v for k, v in sd.items() if "num_batches_tracked" not in k and ".fc." not in k}
    wrapped = tmp_path / "wrapped.pth"
    torch.save({"epoch": 90, "state_dict": sd}, wrapped)
    with torch.no_grad():
        np.testing.assert_array_equal(load_resnet152(wrapped)(x).numpy(), want)


def test_load_resnet152_errors(resnet, tmp_path):
    missing = tmp_path / "nowhere" / "resnet152.pth"
    with pytest.raises(MissingDataError, match="IMAGENET1K_V1") as info:
        load_resnet152(missing)
    assert str(missing) in str(info.value)

    sd = dict(resnet.state_dict())
    del sd["layer1.0.conv1.weight"]
    sd["head.weight"] = torch.zeros(3)
    sd["fc.weight"] = torch.zeros(10, 2048)
    broken = tmp_path / "broken.pth"
    torch.save({"model": sd}, broken)
    with pytest.raises(MalformedDataError) as info:
        load_resnet152(broken)
    msg = str(info.value)
    assert "missing keys: layer1.0.conv1.weight" in msg
    assert "unexpected keys: head.weight" in msg
    assert "fc.weight (10, 2048) (want (1000, 2048))" in msg

    junk = tmp_path / "junk.pth"
    junk.write_text("not a checkpoint")
    with pytest.raises(MalformedDataError, match=r"junk\.pth"):
        load_resnet152(junk)
    torch.save([1, 2, 3], junk)
    with pytest.raises(MalformedDataError, match="not a ResNet-152 state_dict"):
        load_resnet152(junk)
