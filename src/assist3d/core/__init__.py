"""The light core every stage builds on: typed contracts between stages (:mod:`.contracts`), keyed
seed streams (:mod:`.rng`), the error kinds (:mod:`.errors`), atomic files (:mod:`.fileio`), plugin
registries (:mod:`.registry`), memory bounds, interrupt handling, user paths, the class / room
taxonomy (:mod:`.taxonomy`) and the planar and box geometry that placement, assembly and the checks
share (:mod:`.geometry`). Imports nothing heavier than numpy, except shapely in :mod:`.geometry`."""
