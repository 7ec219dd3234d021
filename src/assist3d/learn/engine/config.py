"""Training configuration schema (pydantic). Defaults are the paper's / Mask3D's ScanNet settings.

Presets live in ``configs/`` (``paper.yaml``, ``small-cpu.yaml``); :func:`load_train_config` reads one
and validates it, and :func:`dump_train_config` writes the resolved copy next to the outputs.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Literal

import yaml
from pydantic import Field

from ...config import Section, read_yaml_mapping, validate_config
from ...core.errors import ConfigError


class ModelConfig(Section):
    """Sizes of the backbone and decoder (defaults: Mask3D with Res16UNet34C)."""

    stem_channels: int = Field(32, description="stem conv output channels (paper 32)")
    stem_kernel: int = Field(5, description="stem conv kernel (paper 5)")
    enc_channels: tuple[int, int, int, int] = Field((32, 64, 128, 256), description="encoder stage channels")
    enc_blocks: tuple[int, int, int, int] = Field((2, 3, 4, 6), description="BasicBlocks per encoder stage")
    dec_channels: tuple[int, int, int, int] = Field((256, 128, 96, 96), description="decoder stage channels")
    dec_blocks: tuple[int, int, int, int] = Field((2, 2, 2, 2), description="BasicBlocks per decoder stage")
    bn_momentum: float = Field(0.02, description="BatchNorm momentum (paper 0.02)")
    hidden: int = Field(128, description="transformer width (paper 128)")
    heads: int = Field(8, description="attention heads (paper 8)")
    ffn: int = Field(1024, description="FFN width (paper 1024)")
    dropout: float = Field(0.0, description="dropout (paper 0)")
    num_passes: int = Field(3, description="passes over the 4 levels (paper 3 -> 12 layers)")
    shared: bool = Field(True, description="share layer weights across passes (paper true)")
    sample_sizes: tuple[int, int, int, int] = Field((200, 800, 3200, 12800),
                                                    description="keys sampled per level in training")
    num_queries: int = Field(100, ge=1, le=10_000, description="queries in training, at most 10,000 (paper 100)")
    num_queries_eval: int = Field(150, ge=1, le=10_000, description="queries at inference, at most 10,000 (paper 150 "
                                                                    "on ScanNet)")
    backend: Literal["torch", "spconv"] = Field("torch", description="sparse conv backend")


class DataSpec(Section):
    """One training set: a reader spec ``FORMAT:PATH`` tagged real or synthetic."""

    spec: str
    kind: Literal["real", "synthetic"] | None = Field(None, description="default: synthetic for assist3d:, else real")

    def resolved_kind(self) -> str:
        if self.kind is not None:
            return self.kind
        return "synthetic" if self.spec.split(":", 1)[0] == "assist3d" else "real"


class DataConfig(Section):
    train: list[DataSpec] = Field(default_factory=list, description="training sets")
    voxel_size: float = Field(0.02, ge=0.005, le=1, description="voxel edge in metres, 0.005..1 (paper 0.02)")
    synthetic_alpha: float = Field(0.5, description="weight of the synthetic loss (paper 0.5)")
    max_points: int = Field(0, ge=0, le=100_000_000, description="random crop to this many points per scene "
                                                                 "(0 = no crop; at most 100,000,000)")
    cache_scenes: bool = Field(False, description="keep every loaded scene in memory (small datasets)")
    workers: int = Field(0, ge=0, le=64, description="processes that prepare the coming batches (crop, augment, "
                                                     "voxelise) while the model trains; 0 = in the training "
                                                     "process. The batches are the same for any number.")


class AugmentConfig(Section):
    enabled: bool = Field(True, description="apply training augmentations")
    offset_m: float = Field(0.5, description="random translation after centring, metres")
    mirror: bool = Field(True, description="mirror x and y with p 0.5 each (Mask3D)")
    elastic: list[tuple[float, float]] = Field([(0.2, 0.4), (0.8, 1.6)],
                                               description="(granularity m, magnitude) pairs (Mask3D)")
    elastic_p: float = Field(0.95, description="probability of elastic distortion (Mask3D 0.95)")
    scale: float = Field(0.1, description="per-axis scale jitter +- (Mask3D 0.1)")
    rotate_z_rad: float = Field(math.pi, description="rotation about z, +- radians (Mask3D pi)")
    rotate_xy_rad: float = Field(math.pi / 24, description="rotation about x and y, +- radians (Mask3D pi/24)")
    color_jitter: float = Field(0.2, description="brightness/contrast +- (Mask3D 0.2)")
    rgb_shift: float = Field(20.0, description="per-channel RGB shift +- (Mask3D 20)")


class LossConfig(Section):
    objectness_weight: float = Field(2.0, description="objectness loss and matching weight (paper 2)")
    mask_weight: float = Field(5.0, description="mask BCE weight (paper 5)")
    dice_weight: float = Field(2.0, description="dice weight (paper 2)")
    no_object_weight: float = Field(0.1, description="weight of unmatched queries in objectness BCE (paper 0.1)")
    aux: bool = Field(True, description="auxiliary losses after every decoder layer")
    num_points: int = Field(0, ge=0, le=100_000_000, description="voxels sampled per scene for matching/losses "
                                                                 "(0 = all; at most 100,000,000)")


class OptimConfig(Section):
    lr: float = Field(1e-4, description="AdamW peak learning rate (paper 1e-4)")
    weight_decay: float = Field(0.01, description="AdamW weight decay")
    epochs: int = Field(600, ge=1, le=100_000, description="epochs, at most 100,000 (paper 600)")
    batch_size: int = Field(5, ge=1, le=1024, description="scenes per step per process, at most 1024 (Mask3D 5)")
    pct_start: float = Field(0.3, description="OneCycleLR warm-up fraction")
    grad_clip: float = Field(0.0, description="gradient norm clip (0 = off)")
    amp: bool = Field(True, description="mixed precision on CUDA (ignored on CPU)")


class PredictConfig(Section):
    top_k: int = Field(100, ge=1, le=10_000, description="masks kept per scene (at most 10,000)")
    dbscan: bool = Field(False, description="split masks into DBSCAN clusters")
    dbscan_eps: float = Field(0.95, description="DBSCAN radius in metres (Mask3D ScanNet 0.95)")
    dbscan_min_points: int = Field(1, description="DBSCAN core point neighbour count")
    min_points: int = Field(1, description="drop masks with fewer points")


class TrainConfig(Section):
    seed: int = Field(0, ge=0, le=2**32 - 1, description="global seed, 0..2^32-1")
    device: str = Field("auto", description="auto, cpu or cuda")
    checkpoint_every: int = Field(10, ge=1, le=100_000, description="epochs between numbered checkpoints (last.pt "
                                                                    "every epoch)")
    threads: int = Field(0, ge=0, le=256, description="torch CPU threads (0 = torch default; at most 256)")
    model: ModelConfig = Field(default_factory=ModelConfig)
    data: DataConfig = Field(default_factory=DataConfig)
    augment: AugmentConfig = Field(default_factory=AugmentConfig)
    loss: LossConfig = Field(default_factory=LossConfig)
    optim: OptimConfig = Field(default_factory=OptimConfig)
    predict: PredictConfig = Field(default_factory=PredictConfig)


def parse_train_config(data: dict, source: str = "<dict>") -> TrainConfig:
    return validate_config(TrainConfig, data, source=source, what="training config")


def load_train_config(path: str | Path) -> TrainConfig:
    data = read_yaml_mapping(path, missing="training config not found (presets: configs/small-cpu.yaml, "
                                          "configs/paper.yaml)")
    return parse_train_config(data, str(path))


def dump_train_config(cfg: TrainConfig) -> str:
    return yaml.safe_dump(cfg.model_dump(mode="json"), sort_keys=False)


def parse_data_arg(item: str) -> DataSpec:
    """``[real=|synthetic=]FORMAT:PATH`` -> :class:`DataSpec`."""
    kind = None
    for prefix in ("real=", "synthetic="):
        if item.startswith(prefix):
            kind, item = prefix[:-1], item[len(prefix):]
    if ":" not in item:
        raise ConfigError(f"--data {item!r}: expected FORMAT:PATH, e.g. pointcept:/data/scannet/train")
    return DataSpec(spec=item, kind=kind)  # type: ignore[arg-type]
