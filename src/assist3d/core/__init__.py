"""The light core every stage builds on: typed contracts between stages (:mod:`.contracts`), keyed
seed streams (:mod:`.rng`), the error kinds (:mod:`.errors`), atomic files (:mod:`.fileio`), plugin
registries (:mod:`.registry`), memory bounds, interrupt handling, user paths and the class / room
taxonomy (:mod:`.taxonomy`). Imports nothing heavier than numpy."""
