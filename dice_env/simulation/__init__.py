"""The simulation: a scene packed for the kernels, the one driver, the paper's listings."""
