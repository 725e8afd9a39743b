"""Many throws in seeded chunks, here or on Ray (:mod:`.distributed`), kept in run folders.

Run folders: :mod:`.chunks`. The studies that write ``docs/`` are the repository's top-level
``studies/`` (run from a checkout); this package imports nothing from them.
"""
