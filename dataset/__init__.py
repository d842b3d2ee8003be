"""Parametric texture datasets (heightmaps in mm)."""
