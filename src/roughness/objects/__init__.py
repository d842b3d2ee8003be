"""Textured 3D objects: put a texture on a mesh (``texturing``) and map how each part of it feels (``feel``).

Meshes are read and written with trimesh (the ``roughness[objects]`` extra); lengths in mm.
"""
