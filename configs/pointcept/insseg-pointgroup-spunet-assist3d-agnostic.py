# Class-agnostic PointGroup (SpUNet backbone) trained on a dataset written by `assist3d generate`.
#
# Copy this file into a Pointcept checkout as configs/assist3d/ (it inherits Pointcept's
# configs/_base_/default_runtime.py), make `assist3d.interop.pointcept` importable in Pointcept's
# environment (`pip install --no-deps /path/to/assist3d`; that module needs numpy only), point
# data_root at the dataset folder and run
#     sh scripts/train.sh -g 1 -d assist3d -c insseg-pointgroup-spunet-assist3d-agnostic -n agnostic
# docs/ecosystem.md ("Pointcept") says what each part is and what was checked against Pointcept.
#
# Semantic classes: wall, floor, object (segment20.npy folded by Assist3DAgnosticDataset); instances
# come from instance.npy; wall and floor are never instances (segment_ignore_index), as in
# Pointcept's ScanNet configurations. Splits: train.json / val.json in the dataset folder (every
# fifth scene is validation).

_base_ = ["../_base_/default_runtime.py"]
custom_imports = dict(imports=["assist3d.interop.pointcept"], allow_failed_imports=False)

batch_size = 8  # total over all GPUs
num_worker = 8
mix_prob = 0
empty_cache = False
enable_amp = True
enable_wandb = False
evaluate = True

data_root = "data/assist3d"  # the folder `assist3d generate --out` wrote
class_names = ["wall", "floor", "object"]
num_classes = 3
segment_ignore_index = (-1, 0, 1)  # unlabelled, wall, floor: not instances

model = dict(
    type="PG-v1m1",
    backbone=dict(
        type="SpUNet-v1m1",
        in_channels=6,  # colour + normal
        num_classes=0,
        channels=(32, 64, 128, 256, 256, 128, 96, 96),
        layers=(2, 3, 4, 6, 2, 2, 2, 2),
    ),
    backbone_out_channels=96,
    semantic_num_classes=num_classes,
    semantic_ignore_index=-1,
    segment_ignore_index=segment_ignore_index,
    instance_ignore_index=-1,
    cluster_thresh=1.5,
    cluster_closed_points=300,
    cluster_propose_points=100,
    cluster_min_points=50,
    voxel_size=0.02,
)

epoch = 200
optimizer = dict(type="SGD", lr=0.1, momentum=0.9, weight_decay=0.0001, nesterov=True)
scheduler = dict(type="PolyLR")

dataset_type = "Assist3DAgnosticDataset"
feat = dict(feat_keys=("color", "normal"))
instances = dict(type="InstanceParser", segment_ignore_index=segment_ignore_index, instance_ignore_index=-1)
eval_keys = ("coord", "grid_coord", "segment", "instance", "origin_coord", "origin_segment", "origin_instance",
             "instance_centroid", "bbox", "name")
eval_transform = [
    dict(type="CenterShift", apply_z=True),
    dict(type="Copy", keys_dict={"coord": "origin_coord", "segment": "origin_segment",
                                 "instance": "origin_instance"}),
    dict(type="GridSample", grid_size=0.02, hash_type="fnv", mode="train", return_grid_coord=True),
    dict(type="CenterShift", apply_z=False),
    dict(type="NormalizeColor"),
    instances,
    dict(type="ToTensor"),
    dict(type="Collect", keys=eval_keys, offset_keys_dict=dict(offset="coord", origin_offset="origin_coord"), **feat),
]

data = dict(
    num_classes=num_classes,
    ignore_index=-1,
    names=class_names,
    train=dict(
        type=dataset_type,
        split="train.json",
        data_root=data_root,
        transform=[
            dict(type="CenterShift", apply_z=True),
            dict(type="RandomDropout", dropout_ratio=0.2, dropout_application_ratio=0.5),
            dict(type="RandomRotate", angle=[-1, 1], axis="z", center=[0, 0, 0], p=0.5),
            dict(type="RandomRotate", angle=[-1 / 64, 1 / 64], axis="x", p=0.5),
            dict(type="RandomRotate", angle=[-1 / 64, 1 / 64], axis="y", p=0.5),
            dict(type="RandomScale", scale=[0.9, 1.1]),
            dict(type="RandomFlip", p=0.5),
            dict(type="RandomJitter", sigma=0.005, clip=0.02),
            dict(type="ChromaticAutoContrast", p=0.2, blend_factor=None),
            dict(type="ChromaticTranslation", p=0.95, ratio=0.1),
            dict(type="ChromaticJitter", p=0.95, std=0.05),
            dict(type="GridSample", grid_size=0.02, hash_type="fnv", mode="train", return_grid_coord=True),
            dict(type="SphereCrop", point_max=250000, mode="random"),
            dict(type="NormalizeColor"),
            instances,
            dict(type="ToTensor"),
            dict(type="Collect", keys=("coord", "grid_coord", "segment", "instance", "instance_centroid", "bbox"),
                 **feat),
        ],
        test_mode=False,
    ),
    val=dict(type=dataset_type, split="val.json", data_root=data_root, transform=eval_transform, test_mode=False),
    test=dict(type=dataset_type, split="val.json", data_root=data_root, transform=eval_transform, test_mode=False),
)

hooks = [
    dict(type="CheckpointLoader", keywords="module.", replacement="module."),
    dict(type="IterationTimer", warmup_iter=2),
    dict(type="InformationWriter"),
    dict(type="InsSegEvaluator", segment_ignore_index=segment_ignore_index, instance_ignore_index=-1),
    dict(type="CheckpointSaver", save_freq=None),
    dict(type="PreciseEvaluator", test_last=False),
]

test = dict(type="InsSegTester", segment_ignore_index=segment_ignore_index, instance_ignore_index=-1, verbose=False)
