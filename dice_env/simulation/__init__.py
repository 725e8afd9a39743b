"""The simulation: a scene packed for the kernels, the one driver and its backends.

``simulate`` (one die) and ``simulate_group`` (several), the paper's listings, the
calibration against the simulator and the precompile.
"""
