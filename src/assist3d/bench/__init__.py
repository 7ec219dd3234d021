"""The benchmarking side: :mod:`.data`, readers that turn ``FORMAT:PATH`` into point samples
(ScanNet, ScanNet++, S3DIS, Pointcept, arrays, PLY, our own format); :mod:`.evaluation`,
ScanNet-protocol AP / AR of predicted instance masks; :mod:`.metrics`, data-quality metrics of a
generated or real dataset (diversity, context, physical plausibility, layout realism)."""
