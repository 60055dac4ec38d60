"""Parametric testbed geometry and solids (trimesh). Knows nothing of finite elements."""
