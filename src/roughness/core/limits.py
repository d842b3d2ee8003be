"""The stated limits on sizes that inputs and options imply, checked before anything is allocated.

Each limit is sized so that the work it bounds fits a 24 GB machine comfortably (a few GB at most)
and finishes in minutes, while leaving room for every real use (a 100 x 100 mm map at 0.05 mm
pixels is 4 Mpx). ``check_size`` refuses a count above its limit with an InputError that names
the quantity, the limit and the parameter that implied it.
"""
from __future__ import annotations

from .errors import InputError


class Limit(int):
    """An integer limit that knows its name (for messages)."""

    name: str

    def __new__(cls, value: int, name: str) -> Limit:
        limit = super().__new__(cls, value)
        limit.name = name
        return limit


MAX_HEIGHTMAP_PIXELS = Limit(100_000_000, "MAX_HEIGHTMAP_PIXELS")
"""Pixels of one heightmap, read from a file or made (800 MB as float64; 10,000 x 10,000 pixels: a 500 mm
plate at 0.05 mm). Also the samples taken of a map to cut out one batch of footprints."""
MAX_WORKING_VALUES = Limit(400_000_000, "MAX_WORKING_VALUES")
"""Values (float64: 3.2 GB) one step may hold at once, e.g. homogeneity's mirrored windows together."""
MAX_IMAGE_PIXELS = Limit(50_000_000, "MAX_IMAGE_PIXELS")
"""Pixels of a tactile-image picture (a 48 Mpx photo fits); the plate itself has at most MAX_PLATE_PIXELS."""
MAX_PLATE_PIXELS = Limit(4_000_000, "MAX_PLATE_PIXELS")
"""Pixels of a tactile-image plate (60 x 60 mm at 0.03 mm)."""
MAX_MAP_POSITIONS = Limit(1_000_000, "MAX_MAP_POSITIONS")
"""Footprint positions of a roughness map (predict --map, tactile-image --step-mm)."""
MAX_WINDOWS = Limit(10_000, "MAX_WINDOWS")
"""Windows of a homogeneity test (the statistics settle within a few hundred)."""
MAX_TRIALS = Limit(100_000, "MAX_TRIALS")
"""Trials of a perception design or simulation, all subjects together (an experiment has thousands)."""
MAX_DATASET_SAMPLES = Limit(100_000, "MAX_DATASET_SAMPLES")
"""Samples of one dataset build (the shipped training sets have 3,000; each takes seconds of FEM)."""
MAX_BATCH = Limit(16_384, "MAX_BATCH")
"""Inputs or footprints per surrogate batch (predict --batch-size): 16,384 patches are 650 MB as float32."""
MAX_PARALLEL = Limit(256, "MAX_PARALLEL")
"""Threads or worker processes of one run (--threads, --workers); more start slowly or not at all."""
MAX_CHANNELS = Limit(4096, "MAX_CHANNELS")
"""Channels of one surrogate layer (train --widths; the shipped networks have at most 96)."""
MAX_FILL_PIXELS = Limit(4_000_000, "MAX_FILL_PIXELS")
"""Missing points one --fill interpolates (a sparse solve over them: about 1 GB at this size)."""
MAX_PRINT_LAYERS = Limit(100_000, "MAX_PRINT_LAYERS")
"""Layers of a printed texture (--printer): a resin print's layers are each filtered once; 100,000 layers of
0.01 mm are a 1 m tall relief."""
MAX_HEIGHT_MM = 1000.0
"""|height| (mm) a heightmap may hold: a texture's relief is millimetres; 1 m is no texture."""
MIN_PIXEL_MM = 1e-9
"""Smallest pixel (mm) of a heightmap: 1 pm, below any instrument; coordinates / pixel stay within int64."""
MAX_COORDINATE_MM = 1e6
"""|x|, |y| (mm) of a footprint centre: 1 km, far beyond any object (a tiled map repeats without end)."""


def check_size(what: str, count: float, limit: Limit, parameter: str | None = None) -> int:
    """``count`` (an int), or InputError if it exceeds ``limit``; ``what`` names what is counted (a noun).

    ``count`` may be a float (an arithmetic estimate, possibly inf) so that nothing is allocated to
    find it; the message names the limit and the parameter (the CLI turns it into its flag).
    """
    if not count <= limit:  # also refuses nan
        raise InputError(f"{what}: {_shown(count)}, above the limit of {limit:,} ({limit.name})", parameter=parameter)
    return int(count)


def _shown(count: float) -> str:
    """A count for messages: with thousands separators, or as 1.23e+45 if that is long (ints of any size)."""
    if not isinstance(count, int):
        return f"{count:.3g}"
    if count < 10**15:
        return f"{count:,}"
    digits = str(count)
    return f"{digits[0]}.{digits[1:3]}e+{len(digits) - 1}"
MAX_MESH_TRIANGLES = Limit(40_000_000, "MAX_MESH_TRIANGLES")
"""Triangles of a mesh read or made (a textured object: a 60 mm ball at 0.05 mm is about 10 million; 40 million
are 1.4 GB of vertices and faces)."""
MAX_MESH_FILE_BYTES = 4_000_000_000
"""Bytes of a mesh file read (a binary STL of 80 million triangles; checked before the file is opened)."""
