"""Training and inference of the model (needs the ``[train]`` extra; torch is imported by the submodules).

``config`` (training config schema), ``voxelize``, ``augment``, ``scenes``, ``matcher``, ``losses``,
``train`` (``train(cfg, out_dir)``), ``predict`` (``predict_dataset``), ``bench`` (``run_model_bench``),
``dist`` (DDP helpers), ``toy`` (box-room scenes). See ``docs/model.md``.
"""
