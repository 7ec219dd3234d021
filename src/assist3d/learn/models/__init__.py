"""The class-agnostic Mask3D-style model (needs the ``[train]`` extra; torch is imported by the submodules).

``sparse`` (pure-PyTorch sparse convolution), ``spconv_backend`` (optional), ``unet`` (Res16UNet34C-like
backbone), ``fourier`` and ``decoder`` (Mask3D transformer decoder), ``mask3d`` (the full model).
See ``docs/model.md``.
"""
