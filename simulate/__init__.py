"""FEM reference engine: skin block on a rigid texture, strain at receptor depth, variation V."""
from .config import SimConfig
from .heightmap import Heightmap, InputError
from .io import load_heightmap, save_heightmap
from .model import Result, SimulationError, Simulator, roughness

__all__ = ["Heightmap", "InputError", "Result", "SimConfig", "SimulationError", "Simulator",
           "load_heightmap", "roughness", "save_heightmap"]
