"""The CPU segmenter's configuration (pydantic, validated; stored inside every checkpoint as JSON).

Defaults are the settings chosen in ``experiments/fidelity-log.md``: 5 cm voxels, geometry-only input, a
4-level sparse residual U-Net with per-scene normalisation, foreground + centre-offset heads,
offset-shifted connected components for instances.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from ...config import Section, validate_config
from ...core.errors import ConfigError

Channels = Annotated[int, Field(ge=4, le=1024)]
Blocks = Annotated[int, Field(ge=1, le=8)]


class NetConfig(Section):
    """Backbone and heads."""

    voxel_size: float = Field(0.05, gt=0.005, le=0.5, description="voxel edge in metres")
    use_color: bool = Field(False, description="append RGB to the geometric input features")
    stem_channels: int = Field(16, ge=4, le=256, description="channels of the first convolution")
    enc_channels: tuple[Channels, Channels, Channels, Channels] = Field((16, 32, 64, 96), description="4 to 1024 each")
    enc_blocks: tuple[Blocks, Blocks, Blocks, Blocks] = Field((1, 1, 1, 1), description="1 to 8 each")
    dec_channels: tuple[Channels, Channels, Channels, Channels] = Field((96, 64, 48, 48), description="4 to 1024 each")
    dec_blocks: tuple[Blocks, Blocks, Blocks, Blocks] = Field((1, 1, 1, 1), description="1 to 8 each")
    norm: Literal["scene", "batch"] = Field("scene", description="scene: per-scene statistics; batch: BatchNorm")


class AugmentConfig(Section):
    """Training augmentations (applied to every training scene, generated or real, alike)."""

    crop_m: float = Field(6.0, ge=0.0, le=100.0, description="random square crop edge in metres (0 = whole scene)")
    keep_min: float = Field(0.35, gt=0.0, le=1.0, description="lowest fraction of points kept (density matching)")
    keep_max: float = Field(0.8, gt=0.0, le=1.0, description="highest fraction of points kept")
    scale: float = Field(0.1, ge=0.0, le=0.5, description="uniform scale jitter +-")
    tilt_deg: float = Field(1.0, ge=0.0, le=10.0, description="random tilt about x and y, +- degrees")
    floor_shift: tuple[float, float] = Field((-0.08, 0.05), description="random z translation range, metres")
    jitter: tuple[float, float] = Field((0.005, 0.02), description="Gaussian jitter sigma range, metres")
    color_jitter: float = Field(0.2, ge=0.0, le=1.0, description="brightness/contrast jitter (colour input only)")
    color_drop: float = Field(0.2, ge=0.0, le=1.0, description="probability of greying the colour (colour input only)")


class ClusterConfig(Section):
    """Instances from per-voxel predictions."""

    fg_threshold: float = Field(0.5, gt=0.0, lt=1.0, description="foreground probability threshold")
    radius: float = Field(0.07, gt=0.0, le=1.0, description="link radius on offset-shifted centres, metres")
    min_voxels: int = Field(6, ge=1, le=100_000, description="drop clusters with fewer voxels")


class OptimConfig(Section):
    """Loss weights and the optimiser (Adam; the loss is foreground BCE + weighted offset terms)."""

    lr: float = Field(2e-3, gt=0.0, le=1.0, description="Adam peak learning rate (cosine decay to 1 %)")
    weight_decay: float = Field(1e-4, ge=0.0, le=1.0, description="Adam's L2 weight decay")
    batch_size: int = Field(2, ge=1, le=64, description="scenes per step")
    offset_weight: float = Field(1.0, ge=0.0, description="weight of the L1 loss on centre offsets (object voxels)")
    direction_weight: float = Field(0.5, ge=0.0, description="weight of the offset direction loss (minus cosine)")
    ema_decay: float = Field(0.99, ge=0.0, lt=1.0, description="exponential moving average of the weights, kept "
                             "beside the trained ones and used as the final model (0 = off; experiments/fidelity-log.md "
                             "'Weight averaging')")
    precision: Literal["auto", "float32", "bfloat16"] = Field(
        "auto", description="arithmetic of the sparse convolutions in training: float32, or bfloat16 inputs "
        "with float32 accumulation (im2col blocks; several times faster where the CPU multiplies bfloat16 "
        "natively, AMX or AVX-512 BF16); auto = bfloat16 on such a CPU, else float32. Inference is float32")


class SegmenterConfig(Section):
    net: NetConfig = Field(default_factory=NetConfig)
    augment: AugmentConfig = Field(default_factory=AugmentConfig)
    cluster: ClusterConfig = Field(default_factory=ClusterConfig)
    optim: OptimConfig = Field(default_factory=OptimConfig)


# Keys added with a default other than the behaviour before them: (section, key) -> that behaviour.
# A key missing from a stored configuration otherwise takes today's default (pydantic), which is
# right for every key whose default reproduces what came before it.
BEFORE_ADDED: dict[tuple[str, str], Any] = {("optim", "ema_decay"): 0.0,  # no weight averaging
                                           ("optim", "precision"): "float32"}


# Options measured and not adopted, taken out of the schema: (section, key) -> the values that mean "off"
# (None: any value, for a setting that only mattered when another was on). A stored configuration holding one
# of them "off" reads as today's; one that was on was trained with a recipe this version no longer runs
# (experiments/fidelity-log.md names what each did and where it was measured).
RETIRED: dict[tuple[str, str], tuple[Any, ...] | None] = {
    ("augment", "elastic"): ((), []),  # smooth random warps
    ("augment", "top_cut_p"): (0, 0.0),  # removing everything above a random height
    ("augment", "top_cut_range"): None,
}


def legacy_config(data: Any, source: str = "stored config") -> Any:
    """A stored configuration (checkpoint, ``probe.json``) read as today's schema: completed with the
    values of :data:`BEFORE_ADDED` for the keys it lacks (a file written before such a key existed keeps
    its recipe and a resumed run stays what it was) and without the :data:`RETIRED` options it holds
    switched off; a :class:`ConfigError` naming ``source`` when one was switched on. Returned unchanged
    (the same object) when there is nothing to do."""
    if not isinstance(data, dict):
        return data
    missing = [(s, k) for s, k in BEFORE_ADDED if isinstance(data.get(s), dict) and k not in data[s]]
    retired = [(s, k) for s, k in RETIRED if isinstance(data.get(s), dict) and k in data[s]]
    if not missing and not retired:
        return data
    out = {s: dict(v) if isinstance(v, dict) else v for s, v in data.items()}
    for s, k in missing:
        out[s][k] = BEFORE_ADDED[(s, k)]
    for s, k in retired:
        off, value = RETIRED[(s, k)], out[s].pop(k)
        if off is not None and value not in off:
            raise ConfigError(f"{source}: {s}.{k} = {value!r} is an option that was measured, not adopted and "
                              "taken out of this version; train without it (its experiment folder keeps the figures)")
    return out


def parse_segmenter_config(data: dict | None, source: str = "<dict>") -> SegmenterConfig:
    return validate_config(SegmenterConfig, data, source=source, what="segmenter config")
