"""The Texture page through NiceGUI's test client (no browser): every flow reads the library's own numbers."""
from __future__ import annotations

import subprocess
import sys

import pytest

from roughness.studio.pages.texture import example_path

pytestmark = pytest.mark.anyio


def cli_v(*args: str) -> str:
    """The V that `roughness predict` prints (its text line's "V = ..." to the comma)."""
    out = subprocess.run([sys.executable, "-m", "roughness.cli", "predict", *args], capture_output=True, text=True,
                         check=True).stdout
    return out.split("V = ", 1)[1].split(" ", 1)[0]


async def test_bundled_example_reads_the_v_the_cli_prints(studio):
    await studio.user.open("/texture")
    studio.user.find("Open the bundled example").click()
    await studio.user.should_see(f"V = {cli_v(str(example_path()), '--pixel-mm', '0.05', '--height-mm', '1')}")
