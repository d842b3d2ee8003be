"""The surrogate CNN: footprint heights (mm, max 0) -> log(V + offset), plus a shape embedding.

Strided convolutions down to a ~1 mm grid, then a global mean: V is a mean over the
footprint of a local strain statistic, so the network averages local features the same way.
The pooled features (the embedding) also feed the learned domain score.
"""
from __future__ import annotations

import torch
from torch import nn


def conv_bn(cin: int, cout: int, kernel: int = 3, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(nn.Conv2d(cin, cout, kernel, stride, kernel // 2, bias=False), nn.BatchNorm2d(cout),
                         nn.ReLU(inplace=True))


class RoughnessNet(nn.Module):
    """Input (B, 1, P, P) heights in mm; outputs (B,) log(V + offset) and (B, widths[-1]) embedding."""

    def __init__(self, widths: tuple[int, ...] = (16, 32, 64, 96), hidden: int = 64) -> None:
        super().__init__()
        layers = [conv_bn(1, widths[0], kernel=5, stride=2)]
        for cin, cout in zip(widths[:-1], widths[1:]):
            layers += [conv_bn(cin, cout, stride=2), conv_bn(cout, cout)]
        self.features = nn.Sequential(*layers)
        self.head = nn.Sequential(nn.Linear(widths[-1], hidden), nn.ReLU(inplace=True), nn.Linear(hidden, 1))

    def forward(self, heights: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        embedding = self.features(heights).mean(dim=(2, 3))
        return self.head(embedding).squeeze(1), embedding


def parameter_count(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
