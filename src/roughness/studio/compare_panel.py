"""Compare two or more textures: the JND matrix and, for each pair, the verdict of `roughness jnd A B` (its own
helpers: the distance on the standard scale with its uncertainty, and the words)."""
from __future__ import annotations

from collections.abc import Callable

from nicegui import ui

import roughness
from roughness.surface.heightmap import Heightmap


class ComparePanel:
    """A card collecting textures (``current()`` gives the page's (name, heightmap), or None if it has none)."""

    def __init__(self, current: Callable[[], tuple[str, Heightmap] | None]) -> None:
        self.current = current
        self.compared: list[tuple[str, Heightmap]] = []
        with ui.card().classes("w-full"):
            ui.label("Compare textures").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("gap-4"):
                ui.button("Add this texture", on_click=self.add).props(
                    'aria-label="Add the current texture to the comparison"').mark("compare-add")
                ui.button("Compare", on_click=self.compare).mark("compare")
                ui.button("Clear", on_click=self.clear).props('aria-label="Clear the comparison"')
            self.listing = ui.label("No textures to compare yet.")
            self.table = ui.table(columns=[], rows=[]).classes("w-full")
            self.table.set_visibility(False)
            self.verdicts = ui.column().props('role="status" aria-live="polite"').mark("verdicts")

    def add(self) -> None:
        texture = self.current()
        if texture is None:
            self.listing.set_text("Open or make a texture first.")
            return
        self.compared.append(texture)
        self.listing.set_text("To compare: " + "; ".join(n for n, _ in self.compared))

    def clear(self) -> None:
        self.compared.clear()
        self.listing.set_text("No textures to compare yet.")
        self.table.set_visibility(False)
        self.verdicts.clear()

    def compare(self) -> None:
        """The JND matrix (row texture against column texture, signed: positive, the row is rougher) and the
        verdict of each pair, as `roughness jnd A B` gives them."""
        from roughness.cli.jnd import distance_line, jnd_between, uncertainty_kinds

        if len(self.compared) < 2:
            self.listing.set_text("Add at least two textures to compare.")
            return
        names = [f"{i + 1}: {name}" for i, (name, _) in enumerate(self.compared)]
        predictions = roughness.predict({n: hm for n, (_, hm) in zip(names, self.compared)}, units_ok=True)
        columns = [{"name": "texture", "label": "texture", "field": "texture", "align": "left"},
                   {"name": "V", "label": "V", "field": "V"}]
        columns += [{"name": str(j), "label": f"JND vs {j + 1}", "field": str(j)} for j in range(len(names))]
        rows = []
        self.verdicts.clear()
        for i, pa in enumerate(predictions):
            se = pa.roughness_stderr if pa.roughness_stderr is not None else pa.roughness_std
            row = {"texture": names[i], "V": f"{pa.roughness:.4f}" + (f" ± {se:.4f}" if se is not None else "")}
            for j, pb in enumerate(predictions):
                d = jnd_between(pa, pb)
                row[str(j)] = "-" if i == j else "none" if d.jnd is None else f"{d.jnd:+.2f}"
                if j > i:
                    with self.verdicts:
                        ui.label(f"{i + 1} vs {j + 1}: " + distance_line(d, uncertainty_kinds(pa, pb)))
            rows.append(row)
        self.table.columns, self.table.rows = columns, rows
        self.table.set_visibility(True)
        self.table.update()
