"""p3d: exact mass properties, bounds and constraint solves for meshes and shapes."""

__version__ = "0.1.0"
