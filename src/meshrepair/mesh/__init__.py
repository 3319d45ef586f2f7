"""Mesh-level pieces shared by the tasks (below them in the data flow)."""
