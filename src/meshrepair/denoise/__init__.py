"""The denoising task: ``meshrepair.denoise(V, F)`` (in ``api``) reads the noise from the input,
runs a
robust probe, the robust and feature stages of the shared ADMM solver (``run``), and finishes
the result (``finish``). docs/parameters.md describes every default.

May import: ``meshrepair.model``, ``meshrepair.mesh``, ``meshrepair.io``, ``meshrepair._kernels``
and the base modules; never another task.
"""
