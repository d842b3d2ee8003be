"""Braille labels: cell geometry against ADA 2010 Table 703.3.1 and words against their known cells."""
from __future__ import annotations

import numpy as np
import pytest

from roughness.core.errors import InputError
from roughness.design.braille import BrailleStyle, braille_relief, cells_of, grade1

ADA_MM = {"dot_diameter_mm": (1.5, 1.6), "dot_spacing_mm": (2.3, 2.5), "cell_spacing_mm": (6.1, 7.6),
          "dot_height_mm": (0.6, 0.9), "line_spacing_mm": (10.0, 10.2)}  # Table 703.3.1, centre to centre


def test_the_default_cell_is_within_the_ada_ranges():
    style = BrailleStyle()
    for name, (low, high) in ADA_MM.items():
        assert low <= getattr(style, name) <= high, name


def test_dots_as_relief_have_the_cited_diameter_height_and_spacing():
    """A full cell then 'a': dots 1.5 mm at the base, 0.7 mm high, 2.5 mm apart in a cell, cells 6.2 mm apart
    (measured on 0.02 mm pixels: within a pixel or two)."""
    pixel = 0.02
    relief = braille_relief([(1, 2, 3, 4, 5, 6), (1,)], pixel)
    assert relief.max() == pytest.approx(0.7, abs=1e-3)
    row = relief[round(0.75 / pixel)]  # through the centres of dots 1 and 4 (and the next cell's dot 1)
    peaks = [i for i in range(1, len(row) - 1) if row[i] > 0.69 and row[i] >= row[i - 1] and row[i] >= row[i + 1]]
    centres = np.array([np.mean(g) for g in np.split(np.array(peaks), np.where(np.diff(peaks) > 5)[0] + 1)]) * pixel
    assert np.diff(centres) == pytest.approx([2.5, 6.2 - 2.5], abs=2 * pixel)
    foot = np.flatnonzero(row[: round(2 / pixel)] > 0)
    assert len(foot) * pixel == pytest.approx(1.5, abs=2 * pixel)
    column = relief[:, round(0.75 / pixel)]  # dots 1, 2, 3 of the first cell: 2.5 mm apart down
    assert np.count_nonzero(column > 0.69) >= 3 and relief.shape[0] * pixel == pytest.approx(6.5, abs=pixel)


@pytest.mark.parametrize("text, cells", [
    ("cat", [(1, 4), (1,), (2, 3, 4, 5)]),
    ("Key", [(6,), (1, 3), (1, 5), (1, 3, 4, 5, 6)]),
    ("12", [(3, 4, 5, 6), (1,), (1, 2)]),
    ("3b", [(3, 4, 5, 6), (1, 4), (5, 6), (1, 2)]),  # a letter a-j after digits: the grade 1 indicator first
    ("sun.", [(2, 3, 4), (1, 3, 6), (1, 3, 4, 5), (2, 5, 6)]),
    ("a z", [(1,), (), (1, 3, 5, 6)]),
])
def test_words_have_their_known_cells(text, cells):
    assert grade1(text) == cells


def test_characters_outside_grade_1_and_a_missing_liblouis_are_refused_clearly():
    with pytest.raises(InputError, match="not in the built-in grade 1"):
        grade1("café")
    try:
        import louis  # noqa: F401
    except ImportError:
        with pytest.raises(InputError, match="needs liblouis, which is not installed"):
            cells_of("cat", "en-ueb-g2.ctb")
    else:
        assert cells_of("cat", "en-ueb-g1.ctb") == grade1("cat")


def test_the_key_strip_places_samples_and_labels_and_wraps():
    from roughness.dataset.textures import standard_texture
    from roughness.design.key import KEY_GAP_MM, LABEL_GAP_MM, SWATCH_MM, key_entries, key_strip

    textures = [None, standard_texture(1.0, seed=1), standard_texture(1.625, seed=1)]
    entries = key_entries([1, 2], {2: "sea"}, None)
    assert [(r, label) for r, label, _ in entries] == [(1, "a"), (2, "sea")]
    style = BrailleStyle()
    relief, labels, placed = key_strip(entries, textures, 120.0, 50.0, 0.1, 0, style)
    assert relief.shape[0] * 0.1 == pytest.approx(SWATCH_MM + 2 * KEY_GAP_MM, abs=0.1)  # one row
    first, second = placed
    assert first.swatch_mm == pytest.approx((5, 55, 20, 70)) and second.swatch_mm[1] == pytest.approx(55)
    assert (labels[60:190, 60:190] == 1).all() and (labels[60:190, 60:190] != 0).all()  # the sample
    left = round((5 + SWATCH_MM + LABEL_GAP_MM) / 0.1)  # the 'a' beside the first sample: one dot, 0.7 mm high
    assert relief[50:100, left:left + 16].max() == pytest.approx(0.7, abs=0.01)
    assert relief[50:100, left + 16:left + 40].max() == 0  # and nothing else (dot 1 only)
    narrow = key_strip(entries, textures, 45.0, 50.0, 0.1, 0, style)[2]  # one entry per row
    assert narrow[1].swatch_mm[1] == pytest.approx(55 + SWATCH_MM + KEY_GAP_MM)
    with pytest.raises(InputError, match="does not fit across"):
        key_strip(key_entries([1], {1: "a long label"}, None), textures, 45.0, 0.0, 0.1, 0, style)
