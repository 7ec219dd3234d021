"""What the generator knows about object classes and rooms, shared by configuration, selection,
planning and metrics: class lists and name normalisation (:mod:`.classes`) and room-type
templates (:mod:`.roomtypes`). Depends on nothing else in the package but :mod:`assist3d.core.errors`."""
