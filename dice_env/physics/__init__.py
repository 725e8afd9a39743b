"""The numba kernels, importing nothing else from the package: one die, groups, SIMD, CUDA."""
