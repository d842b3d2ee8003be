"""The Printed page through NiceGUI's test client: digital and printed side by side, as `roughness predict
--printer` reports them."""
from __future__ import annotations

import subprocess
import sys

import pytest

from roughness.studio.texture_source import example_path
from studio_helpers import README_UNITS, text_of

pytestmark = pytest.mark.anyio


def cli_printer_line(printer: str) -> str:
    """The "printer ...: V digital ..., printed ..." line of `roughness predict --printer`."""
    out = subprocess.run([sys.executable, "-m", "roughness.cli", "predict", str(example_path()), *README_UNITS,
                          "--printer", printer], capture_output=True, text=True, check=True).stdout
    return next(line.strip() for line in out.splitlines() if line.strip().startswith("printer "))


async def test_digital_and_printed_side_by_side_for_each_printer(studio):
    await studio.user.open("/printed")
    studio.user.find(marker="open-example").click()
    await studio.user.should_see(marker="difference", content="V digital")
    assert text_of(studio.user, "difference") == cli_printer_line("fdm-0.4-0.2")
    assert "as printed: V = " in text_of(studio.user, "printed-answer")
    assert text_of(studio.user, "digital-answer").startswith("standard-1.0mm.png: V = ")
    assert "layer quantisation" in text_of(studio.user, "print-steps")
    studio.user.find(marker="printer").elements.pop().value = "msla-35um"
    await studio.user.should_see(marker="difference", content="msla-35um")
    assert text_of(studio.user, "difference") == cli_printer_line("msla-35um")
