"""The CPU-trainable class-agnostic segmenter (needs the ``[train]`` extra) and the geometric reference.

``features`` (voxels, density-independent input features), ``model`` (sparse U-Net + foreground and
centre-offset heads), ``data`` (augmented training examples), ``train`` (budgeted, resumable
training), ``cluster`` (instances from offsets), ``infer``, ``geometric`` (non-learned reference),
``checkpoint`` (safe, tensors-only files), ``probe`` (the data-quality benchmark), ``shipped``.
See ``experiments/fidelity-log.md``.
"""
