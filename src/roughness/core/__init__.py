"""Shared primitives of every layer: errors, number checks, atomic files, content hashes.

The lowest layer: it imports nothing else of the project.
"""
