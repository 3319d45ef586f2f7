"""The library's exception type."""

from __future__ import annotations


class MeshRepairError(ValueError):
    """Raised for invalid input: the message says what is wrong and how to fix it."""
