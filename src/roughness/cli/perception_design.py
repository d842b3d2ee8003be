"""`roughness perception design --stimuli TABLE --trials N --out CSV`: a balanced, randomised triplet trial list."""
from __future__ import annotations

import argparse
import re

from roughness.core.limits import MAX_TRIALS

from .common import LENGTH, SEED, add_overwrite, count, finish
from .perception_common import check_trials


def add_parser(sub) -> None:
    des = sub.add_parser("design", help="a balanced, randomised triplet trial list for an experiment")
    des.add_argument("--stimuli", required=True, metavar="TABLE", help="stimuli table (its ids are used)")
    des.add_argument("--trials", required=True, type=count(MAX_TRIALS), help="trials per subject")
    des.add_argument("--subjects", type=count(MAX_TRIALS), default=1, help="number of subjects s1..sN (default 1)")
    des.add_argument("--seed", type=SEED, default=0, help="seed of the trial order (default: %(default)s)")
    des.add_argument("--out", required=True, metavar="CSV", help="trial list (answer column left blank)")
    des.add_argument("--plates", metavar="DIR", help="also write every stimulus as a printable plate DIR/<id>.stl "
                                                     "(default: none)")
    des.add_argument("--plate-mm", type=LENGTH, default=25.0, help="side of the plates in mm (default: %(default)s, "
                                                                     "as in the paper)")
    des.add_argument("--base-mm", type=LENGTH, default=2.0, help="plate thickness below the texture in mm "
                                                                   "(default: %(default)s)")
    add_overwrite(des)
    finish(des, run_design)


def run_design(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct, check_output, check_output_folder
    from roughness.perception.design import FIELDNAMES, balanced_design
    from roughness.perception.stimuli import read_stimuli
    from roughness.perception.trials import write_trials
    from roughness.surface.io import save_heightmap

    check_distinct({"--out": args.out, "--plates": args.plates}, {"--stimuli": args.stimuli})
    check_trials(args)
    stimuli = read_stimuli(args.stimuli)
    ids = [s.stimulus for s in stimuli]
    out = check_output(args.out, args.overwrite, "out")
    plates = check_output_folder(args.plates, args.overwrite, "plates") if args.plates else None
    subjects = [f"s{i}" for i in range(1, args.subjects + 1)]
    trials = balanced_design(ids, args.trials, subjects, args.seed)
    if plates is not None:
        names = {s.stimulus: _file_name(s.stimulus) for s in stimuli}
        if len(set(names.values())) < len(names):
            raise InputError("stimulus ids that differ only in characters other than letters, digits, '.', '-' "
                             "and '_' would share a plate file name", parameter="plates")
        maps = {s.stimulus: s.plate_heightmap(args.plate_mm) for s in stimuli}  # every map, before writing any
        plates.mkdir(exist_ok=True)
        for stimulus, hm in maps.items():
            save_heightmap(hm, plates / f"{names[stimulus]}.stl", base_mm=args.base_mm, overwrite=args.overwrite)
    write_trials(out, (t.row() for t in trials), FIELDNAMES, args.overwrite)
    print(f"wrote {out}: {len(trials)} trials ({args.trials} per subject, {len(subjects)} subject(s)) over "
          f"{len(ids)} stimuli; fill the answer column with left or right"
          + (f"; {len(ids)} plates of {args.plate_mm:g} mm in {plates}" if plates is not None else ""))
    return 0


def _file_name(stimulus: str) -> str:
    """A stimulus id as a file name: characters other than letters, digits, '.', '-' and '_' become '_'."""
    return re.sub(r"[^\w.-]", "_", stimulus)
