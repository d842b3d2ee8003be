"""The stated limits on sizes that inputs and options imply, checked before anything is allocated.

Each limit is sized so that the work it bounds fits a 24 GB machine comfortably (a few GB at most)
and finishes in minutes, while leaving room for every real use (a 100 x 100 mm map at 0.05 mm
pixels is 4 Mpx). ``check_size`` refuses a count above its limit with an InputError that names
the quantity, the limit and the parameter that implied it. The bounds on physical quantities
(``Bound``: lengths, forces, factors) are the upper ends of the command-line options' domains
(roughness.cli.common.Number), each what a touchable texture or object can need. The precisions
at the end say when two stored numbers are the same number.
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


class Bound(float):
    """A limit on a physical quantity (mm, N, a factor) that knows its name (for messages)."""

    name: str

    def __new__(cls, value: float, name: str) -> Bound:
        bound = super().__new__(cls, value)
        bound.name = name
        return bound


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
"""Layers of a printed texture (--printer): 100,000 layers of 0.01 mm are a 1 m tall relief."""
MAX_LAYER_PIXELS = Limit(1_000_000_000, "MAX_LAYER_PIXELS")
"""Distinct print layers x map pixels (--printer): a resin print's light bleed and a filament print's bead ends
filter the whole map once per distinct layer (a Gaussian or a distance transform: 0.05-0.15 s per Mpx, so about
2 minutes at the limit). A 100 mm plate at 0.05 mm (4 Mpx) may have 250 layers; a 12 mm map, 17,000."""
MAX_FILTER_TAPS = Limit(20_000_000_000, "MAX_FILTER_TAPS")
"""Map pixels x kernel taps of a print's lateral filters (--printer): a bead's disk (one 1-D pass per row of the
disk, about 10 ns per pixel each, for its erosion and its dilation) and, per distinct layer, the light bleed's
Gaussian (its two 1-D kernels): minutes at most. A 9 mm bead (181 rows at 0.05 mm) on a 100 mm plate is 1.4e9."""
MAX_MODEL_FILE_BYTES = Limit(2**31, "MAX_MODEL_FILE_BYTES")
"""Bytes of an ONNX surrogate file read (--model; checked before it is read): 2 GiB, protobuf's limit on one ONNX
file (larger models keep their weights in external files, which are not read). The shipped models are 2 MB."""
MAX_HEIGHT_MM = Bound(1000.0, "MAX_HEIGHT_MM")
"""|height| (mm) a heightmap may hold: a texture's relief is millimetres; 1 m is no texture. Also the upper end of
--height-mm and --outline-height-mm."""
MIN_PIXEL_MM = Bound(1e-9, "MIN_PIXEL_MM")
"""Smallest pixel (mm) of a heightmap: 1 pm, below any instrument; coordinates / pixel stay within int64."""
MAX_PIXEL_MM = Bound(1000.0, "MAX_PIXEL_MM")
"""Largest pixel (mm) of a heightmap (--pixel-mm): 1 m, 100 times the 10 mm footprint, so a map of a pixel or two
(refused by the engines with their reason) is the coarsest; the unit check already refuses pixels above 1 mm
unless --units-ok."""
MAX_COORDINATE_MM = Bound(1e6, "MAX_COORDINATE_MM")
"""|x|, |y| (mm) of a footprint centre: 1 km, far beyond any object (a tiled map repeats without end)."""
MAX_LENGTH_MM = Bound(1000.0, "MAX_LENGTH_MM")
"""Any length an option gives for a texture, plate, object or their sampling (mm: --size-mm, --base-mm, --step-mm,
--window-mm, --edge-mm, --radius-mm, ...): 1 m, beyond any printer's build volume (desktop printers: 0.2-0.5 m)."""
MAX_RADIUS_MM = Bound(1e6, "MAX_RADIUS_MM")
"""|radius| (mm) of a curved base (--curvature-mm): at 1 km the base sags 1e-5 mm under the 10 mm footprint, flat
for every engine."""
MAX_FORCE_N = Bound(1000.0, "MAX_FORCE_N")
"""Normal force (N) of the skin model (--force, --forces): 100 kg on one fingertip; people explore textures with
0.1-5 N, and the FEM refuses indentations beyond its small-strain regime far below this."""
MAX_WAVELENGTH_MM = Bound(10.0, "MAX_WAVELENGTH_MM")
"""Target equivalent wavelength (mm) of the design tools (--target-lambda): the 10 mm footprint; the standard
scale's textures span 0.625-1.625 mm and the power law beyond them reaches V 7.5 here."""
MAX_JND = Bound(30.0, "MAX_JND")
"""JND distance an option asks for (--jnd, --min-jnd, --tolerance-jnd): a factor 184 in equivalent wavelength, more
than the 22 JND from the standard scale's floor (0.2 mm) to the footprint (10 mm)."""
MAX_SCALE_FACTOR = Bound(100.0, "MAX_SCALE_FACTOR")
"""Height or lateral scale factor a tune search may reach (--min-factor, --max-factor): a hundredfold; the default
ranges are 0.1-3 (height) and 0.4-2.5 (lateral), and 100 times a texture is another texture."""
MAX_MESH_TRIANGLES = Limit(40_000_000, "MAX_MESH_TRIANGLES")
"""Triangles of a mesh read or made (a textured object: a 60 mm ball at 0.05 mm is about 10 million; 40 million
are 1.4 GB of vertices and faces)."""
MAX_MESH_FILE_BYTES = 4_000_000_000
"""Bytes of a mesh file read (a binary STL of 80 million triangles; checked before the file is opened)."""
PIXEL_RTOL = 1e-5
"""Relative precision of a pixel size: files and people state it to 6 significant digits (float32 holds 7; %g
prints 6), so sizes within one unit of the 6th digit are one size: 0.0499999987 (0.05 mm as float32 metres) and
0.0499999 are 0.05 mm. Decisions on the pixel grid (how many samples per patch pixel, whether a footprint fits)
use it."""
SQUARE_RTOL = 1e-3
"""Relative difference below which a file's pixel sizes along x and y are one square pixel (their mean, with a note):
instrument round-off (real optical scans state sizes differing by 0.008-0.06%). The mean is off by at most half of
it along either axis, so lengths along one axis are stretched by at most 0.05%: an equivalent wavelength off by
ln(1.0005) / ln(1.19) = 0.003 JND at most, and points at the edge of the 10 mm footprint moved by 0.0025 mm, a
twentieth of the 0.05 mm pixel (tests/test_scans.py measures the effect on V with the spectral engine)."""
HEIGHT_RTOL = 2.0**-23
"""Relative precision of stored heights: float32 (1.2e-7), the coarsest floats the formats read hold; differences
below this times the largest |height| are round-off, not relief."""


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
