"""assist3d: synthesise fully annotated indoor scenes for class-agnostic 3D instance segmentation.

The core package needs only numpy to import; heavy parts (torch, the ray caster, the LLM client)
are imported lazily by the stages that use them.
"""

__version__ = "0.1.0"
