"""View encoders in plain torch: a small ResNet trained on our renders, or ResNet-152 weights.

HA3D's agents read ImageNet ResNet-152 pool features (2048-d) of 640×480 frames. Nothing is
downloaded, so the default encoder is :class:`~.ViewEncoder`, a ResNet-style CNN trained from
scratch on the simulator's own renders by multi-task prediction of simulator ground truth
(:func:`~.pretrain_encoder`): the viewpoint's region, the fraction of the view showing a person,
whether FORWARD would move, and a coarse depth grid. Users who hold ImageNet ResNet-152 weights
can load them with :func:`~.load_resnet152` instead.

The ResNet is written here in plain torch with torchvision's parameter names and shapes
(:mod:`havln_mj.agents.vision.resnet`): torchvision's wheels for the pinned CPU torch are
CUDA builds whose compiled operators do not load beside it.

Input conventions (:func:`~.prepare_views`): RGB ``uint8`` → ``x / 127.5 - 1`` in ``[-1, 1]``;
depth in metres clipped to ``[0, DEPTH_MAX]`` (no reading, NaN or negative → 0; +inf →
``DEPTH_MAX``) → ``2 · d / DEPTH_MAX - 1`` in ``[-1, 1]``, stacked as a fourth channel. The
ResNet-152 path uses ImageNet's per-channel mean and std instead (:func:`~.prepare_imagenet`).

Modules: :mod:`~.inputs` (input preparation), :mod:`~.encoder` (:class:`~.ViewEncoder`,
:func:`~.encode_views`), :mod:`~.heads` (pretraining read-outs and loss), :mod:`~.pretrain`
(the pretraining loop), :mod:`~.resnet` (ResNet-152 and user weights).
"""

from havln_mj.agents.vision.encoder import ViewEncoder, encode_views
from havln_mj.agents.vision.heads import (
    DEFAULT_LOSS_WEIGHTS,
    TARGET_KEYS,
    PretrainHeads,
    pretrain_loss,
)
from havln_mj.agents.vision.inputs import (
    DEPTH_MAX,
    IMAGENET_MEAN,
    IMAGENET_STD,
    prepare_imagenet,
    prepare_views,
)
from havln_mj.agents.vision.pretrain import pretrain_encoder
from havln_mj.agents.vision.resnet import (
    RESNET152_LAYERS,
    ResNet,
    ResNetFeatures,
    load_resnet152,
    resnet152,
)

__all__ = [
    "DEFAULT_LOSS_WEIGHTS",
    "DEPTH_MAX",
    "IMAGENET_MEAN",
    "IMAGENET_STD",
    "RESNET152_LAYERS",
    "TARGET_KEYS",
    "PretrainHeads",
    "ResNet",
    "ResNetFeatures",
    "ViewEncoder",
    "encode_views",
    "load_resnet152",
    "prepare_imagenet",
    "prepare_views",
    "pretrain_encoder",
    "pretrain_loss",
    "resnet152",
]
