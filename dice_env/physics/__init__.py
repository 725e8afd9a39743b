"""The physics: numba kernels only, importing nothing else from the package.

Contact laws, one die's step, the flight, and the single, group, SIMD and CUDA loops.
"""
