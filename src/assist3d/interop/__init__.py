"""Our datasets in other projects' formats: :mod:`.scannet` writes a generated dataset as ScanNet v2
scans (what Mask3D's, Pointcept's and most other ScanNet preprocessing scripts read), :mod:`.s3dis`
as S3DIS rooms (``Annotations/<class>_<k>.txt``);
:mod:`.pointcept` is the small dataset class a Pointcept configuration imports for class-agnostic
training. Sits above the generation and learning sides: it reads the writer's folders and cuts
scans into the learning side's superpoints; nothing in the package imports it but the command line."""
