"""Design tools for tactile objects (the paper's section 6), built on the engines: the surrogate
searches, the FEM verifies.

Modules: ``evaluation`` (the shared surrogate + FEM evaluator and JND arithmetic), ``tune``
(scale a texture to a target roughness), ``palette`` (distinguishable texture sets),
``tactile_image`` (pictures to textured plates), ``homogeneity`` (does a texture feel the same
everywhere). No CLI code here: the ``roughness`` subcommands are thin wrappers.
"""
