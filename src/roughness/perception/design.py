"""Balanced, randomised triplet trial lists for an experiment.

For each subject: references cycle through fresh random permutations of the stimuli (every stimulus
is a reference equally often, +-1); the two comparisons are the stimuli used least often as
comparisons so far (random tie-break; the second also avoids pairs already shown together, and a
trial (reference and pair) the subject has seen, unless every pair for that reference and first
comparison is used up), so comparison counts stay within 2 of each other; the side (left or right) goes to the comparison
shown less often on that side, so each stimulus is on the left as often as on the right (+-1).
The trial order is then shuffled. Everything follows from ``seed``.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import integer
from roughness.core.errors import InputError
from roughness.core.limits import MAX_TRIALS, check_size


@dataclass(frozen=True)
class Trial:
    subject: str
    trial: int  # 1-based position in the subject's list
    reference: str
    left: str
    right: str

    def row(self) -> dict[str, object]:
        """A trials-file row, ``answer`` left blank for the experimenter."""
        return {"subject": self.subject, "trial": self.trial, "reference": self.reference, "left": self.left,
                "right": self.right, "answer": ""}


FIELDNAMES = ("subject", "trial", "reference", "left", "right", "answer")


def balanced_design(stimuli: Sequence[str], trials: int, subjects: Sequence[str] = ("s1",),
                    seed: int = 0) -> list[Trial]:
    """``trials`` trials per subject over ``stimuli`` (at least 3 distinct ids)."""
    stimuli = list(stimuli)
    if len(stimuli) < 3 or len(set(stimuli)) != len(stimuli):
        raise InputError(f"a design needs at least 3 distinct stimuli, got {len(stimuli)}", parameter="stimuli")
    check_size("trials of all subjects together", integer("trials", trials, minimum=1) * len(subjects), MAX_TRIALS,
               "trials")
    if not subjects:
        raise InputError("at least one subject", parameter="subjects")
    rng = np.random.default_rng(seed)
    out: list[Trial] = []
    for subject in subjects:
        out.extend(_subject_trials(len(stimuli), trials, rng, subject, stimuli))
    return out


def _subject_trials(n: int, count: int, rng: np.random.Generator, subject: str, ids: list[str]) -> list[Trial]:
    as_comparison = np.zeros(n)
    on_left = np.zeros(n)
    on_right = np.zeros(n)
    together = np.zeros((n, n))
    shown: set[tuple[int, int, int]] = set()
    references = np.concatenate([rng.permutation(n) for _ in range(-(-count // n))])[:count]
    chosen = []
    for ref in references:
        noise = rng.uniform(0, 0.5, n)  # tie-break below one count
        score = as_comparison + noise
        score[ref] = np.inf
        a = int(np.argmin(score))
        score2 = as_comparison + together[a] / (together[a].max() + 1) * 0.5 + noise * 0.5
        seen_with = [k for k in range(n) if (int(ref), min(a, k), max(a, k)) in shown]
        score2[seen_with] += n + count  # repeat a trial only when no unseen one is left for (ref, a)
        score2[[ref, a]] = np.inf
        b = int(np.argmin(score2))
        shown.add((int(ref), min(a, b), max(a, b)))
        as_comparison[[a, b]] += 1
        together[a, b] += 1
        together[b, a] += 1
        left_first = (on_left[a] - on_right[a]) - (on_left[b] - on_right[b])
        if left_first > 0 or (left_first == 0 and rng.uniform() < 0.5):
            a, b = b, a
        on_left[a] += 1
        on_right[b] += 1
        chosen.append((int(ref), a, b))
    order = rng.permutation(len(chosen))
    return [Trial(subject, i + 1, ids[chosen[k][0]], ids[chosen[k][1]], ids[chosen[k][2]])
            for i, k in enumerate(order)]
