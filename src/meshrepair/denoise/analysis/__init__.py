"""The analysis of a denoising input: one immutable reading of the noise (``spectrum``).

May import ``meshrepair.mesh`` and the base modules; never a stage of the run.
"""
