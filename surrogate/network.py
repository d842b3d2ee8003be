"""The surrogate CNN: footprint heights (mm, max 0) -> log(V + offset), plus a shape embedding.

Strided convolutions down to a ~1 mm grid, then a global mean: V is a mean over the
footprint of a local strain statistic, so the network averages local features the same way.
The pooled features (the embedding) also feed the learned domain score.

A multi-fidelity network (``spacing_input``) also takes the FEM contact spacing h of a label,
as log(h / 0.2 mm) beside the embedding in the dense head, so it learns V at every mesh level
from labels of mixed levels; called without h it answers at its ``query`` spacing (a buffer,
so the exported graph keeps the one-input interface). With ``engine_input`` it also learns from
spectral labels (h nan): the head takes [is FEM, is FEM x log(h / 0.2 mm)], so the spectral rows
teach the shared features and the FEM rows the finite block's and the mesh's departures from them;
it answers as the FEM at the query spacing.
"""
from __future__ import annotations

import torch
from torch import nn


def conv_bn(cin: int, cout: int, kernel: int = 3, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(nn.Conv2d(cin, cout, kernel, stride, kernel // 2, bias=False), nn.BatchNorm2d(cout),
                         nn.ReLU(inplace=True))


SPACING_REF_MM = 0.2  # the spacing input is log(h / SPACING_REF_MM)


class RoughnessNet(nn.Module):
    """Input (B, 1, P, P) heights in mm; outputs (B,) log(V + offset) and (B, widths[-1]) embedding.

    ``query_h_mm``: make it a multi-fidelity network that answers at this contact spacing (mm)
    unless ``forward`` is given each row's spacing.
    """

    def __init__(self, widths: tuple[int, ...] = (16, 32, 64, 96), hidden: int = 64,
                 query_h_mm: float | None = None, engine_input: bool = False) -> None:
        super().__init__()
        layers = [conv_bn(1, widths[0], kernel=5, stride=2)]
        for cin, cout in zip(widths[:-1], widths[1:]):
            layers += [conv_bn(cin, cout, stride=2), conv_bn(cout, cout)]
        self.features = nn.Sequential(*layers)
        self.spacing_input = query_h_mm is not None
        self.engine_input = engine_input and self.spacing_input
        inputs = widths[-1] + self.spacing_input + self.engine_input
        self.head = nn.Sequential(nn.Linear(inputs, hidden), nn.ReLU(inplace=True), nn.Linear(hidden, 1))
        if self.spacing_input:
            query = torch.tensor([query_h_mm], dtype=torch.float32)
            self.register_buffer("query", fidelity_features(query, self.engine_input).reshape(-1))

    def forward(self, heights: torch.Tensor, h_mm: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        """``h_mm`` (B,): each row's contact spacing (nan: a spectral label); None: the query spacing."""
        embedding = self.features(heights).mean(dim=(2, 3))
        features = embedding
        if self.spacing_input:
            # (B, k) from the batch's own shape, so the exported graph keeps a dynamic batch axis
            fidelity = self.query.reshape(1, -1) if h_mm is None else fidelity_features(h_mm, self.engine_input)
            features = torch.cat([embedding, torch.zeros_like(embedding[:, :1]) + fidelity], dim=1)
        return self.head(features).squeeze(1), embedding


def fidelity_features(h_mm: torch.Tensor, engine_input: bool) -> torch.Tensor:
    """The head's fidelity inputs (n, 1 or 2) for contact spacings ``h_mm`` (n,) in mm: log(h / SPACING_REF_MM),
    and with ``engine_input`` [is FEM, is FEM x log(h / SPACING_REF_MM)], where nan means a spectral label."""
    if not engine_input:
        return torch.log(h_mm / SPACING_REF_MM)[:, None]
    fem = torch.isfinite(h_mm)
    spacing = torch.where(fem, torch.log(torch.where(fem, h_mm, SPACING_REF_MM) / SPACING_REF_MM), 0.0)
    return torch.stack([fem.to(h_mm.dtype), spacing], dim=1)


def parameter_count(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
