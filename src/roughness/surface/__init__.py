"""Surfaces: the heightmap type, its readers and writers, detrending and STL plates (lengths in mm).

Everything that turns a user's file into a ``Heightmap`` and back lives here; the engines
(``roughness.simulate``, the surrogate) only take a ``Heightmap``.
"""
