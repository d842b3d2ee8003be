"""Shipped surrogate models, their model cards and the standard-scale calibration table (data only)."""
from pathlib import Path

MODELS_DIR = Path(__file__).resolve().parent
