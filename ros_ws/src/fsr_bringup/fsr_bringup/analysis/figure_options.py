"""What the figures are written as: formats, width and titles (no matplotlib import, so a command can check
``--format`` before a flight without paying for matplotlib's start-up)."""

from __future__ import annotations

from dataclasses import dataclass

FORMATS = ("png", "pdf", "svg")


@dataclass
class FigureOptions:
    """Formats to write, width override (``auto`` = each figure's own), titles inside figures."""

    formats: tuple[str, ...] = ("png",)
    width: str = "auto"  # auto | one | two
    titles: bool = False
