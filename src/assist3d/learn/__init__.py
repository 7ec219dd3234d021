"""The learning side (needs the ``[train]`` extra, torch): :mod:`.segmenter`, the CPU-trainable
class-agnostic segmenter behind ``assist3d probe`` and ``assist3d segment``; :mod:`.engine` and
:mod:`.models`, the Mask3D-style model and its trainer for GPUs."""
