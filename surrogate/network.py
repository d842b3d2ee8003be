"""The surrogate CNN: footprint heights (mm, max 0) -> log(V + offset), plus a shape embedding.

Strided convolutions down to a ~1 mm grid, then a global mean: V is a mean over the
footprint of a local strain statistic, so the network averages local features the same way.
The pooled features (the embedding) also feed the learned domain score.

A multi-fidelity network (``spacing_input``) also takes the FEM contact spacing h of a label,
as log(h / 0.2 mm) beside the embedding in the dense head, so it learns V at every mesh level
from labels of mixed levels; called without h it answers at its ``query`` spacing (a buffer,
so the exported graph keeps the one-input interface).
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
                 query_h_mm: float | None = None) -> None:
        super().__init__()
        layers = [conv_bn(1, widths[0], kernel=5, stride=2)]
        for cin, cout in zip(widths[:-1], widths[1:]):
            layers += [conv_bn(cin, cout, stride=2), conv_bn(cout, cout)]
        self.features = nn.Sequential(*layers)
        self.spacing_input = query_h_mm is not None
        self.head = nn.Sequential(nn.Linear(widths[-1] + self.spacing_input, hidden), nn.ReLU(inplace=True),
                                  nn.Linear(hidden, 1))
        if self.spacing_input:
            self.register_buffer("query", spacing_feature(torch.tensor([query_h_mm], dtype=torch.float32)))

    def forward(self, heights: torch.Tensor, h_mm: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        embedding = self.features(heights).mean(dim=(2, 3))
        features = embedding
        if self.spacing_input:
            # (B, 1) from the batch's own shape, so the exported graph keeps a dynamic batch axis
            spacing = torch.zeros_like(embedding[:, :1]) + (self.query if h_mm is None else spacing_feature(h_mm)[:, None])
            features = torch.cat([embedding, spacing], dim=1)
        return self.head(features).squeeze(1), embedding


def spacing_feature(h_mm: torch.Tensor) -> torch.Tensor:
    """The network's spacing input for contact spacings ``h_mm`` (mm)."""
    return torch.log(h_mm / SPACING_REF_MM)


def parameter_count(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
