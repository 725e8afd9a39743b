"""The simulation: a scene packed for the kernels, the one driver, the paper's listings.

Many throws in seeded chunks, here or on Ray: :mod:`.runner` (run folders: :mod:`.chunks`).
"""
