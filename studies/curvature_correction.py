"""Condense the curvature study's committed results into ``models/curvature_correction.json``.

The table ``roughness.curvature_correction`` reads (the flat V's measured correction for a curved base), from
``studies/results/curvature_default.json`` (cylinders) and ``curvature_sphere.json`` (spheres), with their digests::

    python studies/curvature_correction.py
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from roughness.curvature_correction import STUDY_RESULTS, TABLE_PATH, table_from_study


def write_table(root: Path, path: Path = TABLE_PATH) -> dict:
    """Condense the study's committed results under ``root`` into ``path`` (with their digests)."""
    from roughness.core.files import atomic_write
    from roughness.core.hashing import file_sha256

    bases = {}
    for base, relative in STUDY_RESULTS.items():
        results = json.loads((root / relative).read_text())
        table = table_from_study(results)
        bases[base] = {"curvature_per_mm": list(table.curvature_per_mm), "difference": list(table.difference),
                       "error": list(table.error), "results": relative,
                       "results_sha256": file_sha256(root / relative), "command": results["command"]}
    data = {"meaning": "relative difference of V on a curved base from the flat V (mean over the studied textures "
                       "and realisations, heights along the normal) by signed curvature 1/R (1/mm, convex > 0), and "
                       "its error: the largest distance of any texture's measured min or max from that mean",
            "bases": bases}
    atomic_write(path, lambda tmp: Path(tmp).write_text(json.dumps(data, indent=1) + "\n"), True)
    return data


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.parse_args(argv)
    write_table(Path(__file__).resolve().parents[1])
    print(f"wrote {TABLE_PATH}")


if __name__ == "__main__":
    main()
