"""The studio's latency in a real browser (Playwright on Debian's chromium): slider to answer, and page load,
beside the command line's time for the same answer.

Slider to answer: the height slider of the Texture page (the bundled example loaded) moved by the keyboard (one
step, alternately up and down) and dragged with the mouse (released after a 0.4 s drag); timed in the page, from the
key press or the mouse release (the slider stops) to the moment the answer with the new factor is on screen (a
MutationObserver on the answer). Target: 150 ms. Page load: from navigation to the Texture page's first control
visible, each in a fresh tab. The CLI: `roughness predict` on the same example, the wall time of the whole command
(a fresh process) and the engine time it reports.

    python benchmarks/studio_latency.py [--presses 40] [--drags 10] [--loads 5]
    # writes benchmarks/results/studio_latency.md
"""
from __future__ import annotations

import argparse
import os
import platform
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the studio's server and browser helpers (tests/studio_helpers.py)

from roughness.studio.texture_source import example_path  # noqa: E402
from studio_helpers import README_UNITS, find_chromium, served_studio  # noqa: E402

TARGET_MS = 150.0
WATCH = """() => {
  const answer = [...document.querySelectorAll('[role=status]')].find(e => e.innerText.includes('V = '));
  window.__changes = [];
  new MutationObserver(() => window.__changes.push([performance.now(), answer.innerText]))
    .observe(answer, {childList: true, characterData: true, subtree: true});
  window.__stops = [];
  for (const kind of ['keydown', 'pointerup']) document.addEventListener(kind, () => window.__stops.push(performance.now()), true);
}"""


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def answered_ms(page, expected: str, timeout_s: float = 10.0) -> float | None:
    """Milliseconds from the last stop of the slider to the first answer that shows ``expected`` (0 if the answer
    on screen when it stopped already did: a drag's live answers can reach its last value before the release)."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        stop, changes = page.evaluate("() => [window.__stops.at(-1), window.__changes]")
        shown = [text for t, text in changes if t <= stop]
        if shown and expected in shown[-1]:
            return 0.0
        hit = [t for t, text in changes if t > stop and expected in text]
        if hit:
            return hit[0] - stop
        time.sleep(0.01)
    return None  # counted as a miss


def factor(page) -> str:
    return f"height x {float(page.get_by_role('slider', name='Height factor').get_attribute('aria-valuenow')):.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--presses", type=int, default=40)
    parser.add_argument("--drags", type=int, default=10)
    parser.add_argument("--loads", type=int, default=5)
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    chromium = find_chromium()
    if chromium is None:
        sys.exit("no Chromium found (Debian: apt-get install chromium)")
    keys, drags, loads = [], [], []
    load_before = os.getloadavg()[0]
    with served_studio() as url, sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium)
        for _ in range(args.loads + 1):  # the first load warms the server (imports, the model): reported apart
            tab = browser.new_page(viewport={"width": 1280, "height": 900})
            start = time.perf_counter()
            tab.goto(f"{url}/texture")
            tab.get_by_role("button", name="Open the bundled example").wait_for()
            loads.append(time.perf_counter() - start)
            tab.close()
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        page.goto(f"{url}/texture")
        page.get_by_role("button", name="Open the bundled example").click()
        page.locator("[role=status]", has_text="V = ").first.wait_for()
        page.evaluate(WATCH)
        slider = page.get_by_role("slider", name="Height factor")
        track = slider.locator('[tabindex="0"]')
        track.focus()
        for i in range(args.presses):
            track.press("ArrowRight" if i % 2 == 0 else "ArrowLeft")
            keys.append(answered_ms(page, "height x 1.01" if i % 2 == 0 else "standard-1.0mm.png: V"))
            time.sleep(0.2)
        track.scroll_into_view_if_needed()
        box = track.bounding_box()
        for i in range(args.drags):
            y = box["y"] + box["height"] / 2
            x0 = box["x"] + box["width"] * 0.3
            x1 = box["x"] + box["width"] * (0.45 + 0.02 * i)
            page.mouse.move(x0, y)
            page.mouse.down()
            for step in range(1, 9):
                page.mouse.move(x0 + (x1 - x0) * step / 8, y)
                time.sleep(0.05)
            page.mouse.up()
            page.wait_for_timeout(300)  # the slider's value settled
            drags.append(answered_ms(page, factor(page)))
            time.sleep(0.2)
        browser.close()
    cli_wall, cli_engine = [], []
    for _ in range(5):
        start = time.perf_counter()
        out = subprocess.run([sys.executable, "-m", "roughness.cli", "predict", str(example_path()), *README_UNITS],
                             capture_output=True, text=True, check=True).stdout
        cli_wall.append(time.perf_counter() - start)
        cli_engine.append(float(re.search(r", ([\d.]+) ms\)", out).group(1)))
    misses = {"keyboard": keys.count(None), "drag": drags.count(None)}
    keys, drags = [v for v in keys if v is not None], [v for v in drags if v is not None]
    rows = [("slider to answer, keyboard step", keys), ("slider to answer, mouse drag released", drags)]
    lines = ["# Studio latency in the browser", "",
             f"Measured by `python benchmarks/studio_latency.py` ({platform.machine()}, {os.cpu_count()} cores, shared "
             f"with other work: load average {load_before:.1f} before, {os.getloadavg()[0]:.1f} after; Chromium "
             f"headless {chromium}). Target: the answer on screen within {TARGET_MS:.0f} ms of the slider stopping.",
             "",
             "| what | n | median | p95 | max |", "|---|---|---|---|---|"]
    lines += [f"| {name} | {len(v)} | {statistics.median(v):.0f} ms | {percentile(v, 0.95):.0f} ms | {max(v):.0f} ms |"
              for name, v in rows]
    lines += [f"| page load, Texture page (fresh tab) | {len(loads) - 1} | {1e3 * statistics.median(loads[1:]):.0f} ms "
              f"| {1e3 * percentile(loads[1:], 0.95):.0f} ms | {1e3 * max(loads[1:]):.0f} ms |",
              f"| first page load after the server started | 1 | {1e3 * loads[0]:.0f} ms | | |",
              f"| CLI: `roughness predict` the example, whole command | {len(cli_wall)} | "
              f"{1e3 * statistics.median(cli_wall):.0f} ms | {1e3 * percentile(cli_wall, 0.95):.0f} ms | "
              f"{1e3 * max(cli_wall):.0f} ms |",
              f"| CLI: the engine time it reports | {len(cli_engine)} | {statistics.median(cli_engine):.1f} ms | "
              f"{percentile(cli_engine, 0.95):.1f} ms | {max(cli_engine):.1f} ms |", "",
              f"Slider answers within {TARGET_MS:.0f} ms: keyboard {sum(v <= TARGET_MS for v in keys)}/{len(keys)}, "
              f"drag {sum(v <= TARGET_MS for v in drags)}/{len(drags)}; no answer with the slider's value within 10 s: "
              f"keyboard {misses['keyboard']}, drag {misses['drag']}. The studio answers in its running server (model "
              "loaded once), so a slider's answer costs the surrogate and the round trip, not a process start."]
    text = "\n".join(lines) + "\n"
    (ROOT / "benchmarks" / "results" / "studio_latency.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
