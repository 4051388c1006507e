"""What the figures and the animation are written as: formats, width and titles; the animation's format, frame
rate, speed and size (no matplotlib import, so a command can check ``--format`` before a flight without paying
for matplotlib's start-up)."""

from __future__ import annotations

import math
from dataclasses import dataclass

FORMATS = ("png", "pdf", "svg")
NO_ANALYSIS = "--no-analysis"  # fsr-fly's option for no figures and no metrics (its entry point reads it first)
ANIMATION_FORMATS = ("mp4", "gif")
MACRO_BLOCK_PX = 16  # H.264 macro block: frame sides a multiple of it are encoded without rescaling
GIF_FPS_MAX = 50.0  # GIF delays are whole 1/100 s and players stretch those under 2/100 s


@dataclass
class FigureOptions:
    """Formats to write, width override (``auto`` = each figure's own), titles inside figures."""

    formats: tuple[str, ...] = ("png",)
    width: str = "auto"  # auto | one | two
    titles: bool = False


@dataclass(frozen=True)
class AnimationOptions:
    """The flight's animation (``fsr-analyze --animate``): ``animation.<format>`` (:data:`ANIMATION_FORMATS`),
    ``fps`` frames per second of video, ``speed`` simulated seconds per second of video (1: real time, 2: twice
    as fast), ``size`` (width, height) [px], each a multiple of :data:`MACRO_BLOCK_PX`. ValueError naming the
    option for a bad value."""

    format: str = "mp4"
    fps: float = 30.0
    speed: float = 1.0
    size: tuple[int, int] = (640, 480)

    def __post_init__(self) -> None:
        if self.format not in ANIMATION_FORMATS:
            raise ValueError(f"--animate: expected one of {', '.join(ANIMATION_FORMATS)}; got '{self.format}'")
        for name in ("fps", "speed"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"--{name}: expected a number > 0; got {value!r}")
        if self.format == "gif" and self.fps > GIF_FPS_MAX:
            raise ValueError(f"--fps: a GIF plays at most {GIF_FPS_MAX:g} frames per second; got {self.fps:g}")
        if (len(self.size) != 2 or not all(isinstance(side, int) and side >= MACRO_BLOCK_PX
                                           and side % MACRO_BLOCK_PX == 0 for side in self.size)):
            raise ValueError(f"animation size: expected (width, height) in pixels, multiples of {MACRO_BLOCK_PX}; "
                             f"got {self.size!r}")

    @property
    def file_name(self) -> str:
        return f"animation.{self.format}"
