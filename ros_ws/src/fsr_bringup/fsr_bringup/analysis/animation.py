"""The flight's animation (``fsr-analyze RUN --animate [mp4|gif]``): a 3D view of the vehicle, its trail, the
thrust arrow of each rotor and the external force (true and estimated) with the simulated time, written as
``animation.mp4`` (H.264 by the ffmpeg that the imageio-ffmpeg wheel ships) or ``animation.gif`` (Pillow).

What is drawn, and in which frame: :mod:`fsr_bringup.analysis.animation_scene` (world NED shown as east, north,
up, so the vehicle is upright; frame ``k`` at simulated time ``t_0 + k speed / fps``). The camera is fixed and
orthographic, the box holds the whole flight at one scale on every axis.

Speed: the figure is drawn once without the moving artists (axes, labels, planned path, legend) and kept; each
frame restores that background and draws only the moving artists, created once and given new data (blitting on
the Agg canvas).

The file is written under a temporary name in the output folder and renamed once complete: an interrupted run
(Ctrl-C; SIGTERM where the command turns it into KeyboardInterrupt) or a failure leaves no animation, never a
broken one.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator
from mpl_toolkits.mplot3d import proj3d
from mpl_toolkits.mplot3d.art3d import Line3DCollection

from fsr_bringup.analysis.animation_scene import Arrows, Scene, arrow_lines, build_scene
from fsr_bringup.analysis.figure_options import MACRO_BLOCK_PX, AnimationOptions
from fsr_bringup.analysis.figures import OKABE_ITO, RC
from fsr_bringup.analysis.load import RecordedFlight

DPI = 100
ELEVATION_DEG = 25.0
AZIMUTH_DEG = -60.0  # seen from the south-south-east, above
AXES_RECT = (0.25, 0.03, 0.72, 0.95)  # figure fractions: the text (scenario, time, legend) on the left
BOX_ZOOM = 0.86  # the box a little smaller than its axes: room for the axis labels
FIT_SHRINK, FIT_TRIES = 0.92, 8  # the box shrunk by this until its axis labels fit in the figure (at most so often)
TICKS = 5  # at most this many ticks per axis
LEGEND_PT = 7.0
MP4_QUALITY = 7  # imageio-ffmpeg's 0..10 (H.264 CRF 15): sharp lines, a few MB for 30 s at 640 x 480
CENTRE_COLOUR = OKABE_ITO["reddish_purple"]  # used by nothing else: the centre of mass can be found in a frame
TRAIL = {"color": OKABE_ITO["blue"], "lw": 1.2}
PLANNED = {"color": "0.6", "ls": "--", "lw": 0.8}
ARMS = {"colors": OKABE_ITO["black"], "linewidths": 1.6}
DISCS = {"colors": "0.45", "linewidths": 0.8}
THRUST = {"colors": OKABE_ITO["orange"], "linewidths": 1.4}
TRUE_FORCE = {"colors": OKABE_ITO["black"], "linewidths": 1.2, "linestyles": "--"}
ESTIMATED_FORCE = {"colors": OKABE_ITO["vermillion"], "linewidths": 2.2}
GIF_BLENDS = 16  # levels of each colour towards white in the GIF's palette (half as many towards black)
GIF_GREYS = 32

Progress = Callable[[int, int], None]  # (frames done, frames in all)


@dataclass
class WrittenAnimation:
    path: Path
    frames: int
    notes: list[str] = field(default_factory=list)


class FlightAnimation:
    """The figure of a :class:`Scene` at ``size`` (width, height) [px]; :meth:`render` draws frame ``k``."""

    def __init__(self, scene: Scene, size: tuple[int, int] = (640, 480), title: str = "", speed: float = 1.0) -> None:
        self.scene = scene
        self.size = size
        self.speed = speed
        with matplotlib.rc_context(RC):
            self.figure = Figure(figsize=(size[0] / DPI, size[1] / DPI), dpi=DPI)
            self.canvas = FigureCanvasAgg(self.figure)
            ax = self.axes = self.figure.add_axes(AXES_RECT, projection="3d", proj_type="ortho",
                                                  computed_zorder=False)
            ax.view_init(elev=ELEVATION_DEG, azim=AZIMUTH_DEG)
            for set_limits, (low, high) in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), scene.bounds, strict=True):
                set_limits(low, high)
            ax.set_box_aspect(np.ptp(scene.bounds, axis=1), zoom=BOX_ZOOM)  # one scale on every axis
            self.box_zoom = BOX_ZOOM
            for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
                axis.set_major_locator(MaxNLocator(TICKS))
            ax.set_xlabel("east [m]")
            ax.set_ylabel("north [m]")
            ax.set_zlabel("up [m]")
            self._fit_axis_labels(np.ptp(scene.bounds, axis=1))
            handles = self._static_artists(title)
            self._moving = self._moving_artists()
            handles += self._legend_handles()
            self.figure.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, 0.86), borderaxespad=0.3,
                               handlelength=1.6, fontsize=LEGEND_PT)
        elevation, azimuth = np.radians(ELEVATION_DEG), np.radians(AZIMUTH_DEG)
        self.towards_viewer = np.array([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                                        np.sin(elevation)])
        self.canvas.draw()  # the moving artists are animated: left out of this, the background
        self._background = self.canvas.copy_from_bbox(self.figure.bbox)

    def _fit_axis_labels(self, sides: np.ndarray) -> None:
        """Shrink the box until the three axis labels lie within the figure (a wide, flat box puts "up [m]" past
        its right edge)."""
        renderer = self.canvas.get_renderer()
        frame = self.figure.bbox
        for _ in range(FIT_TRIES):
            self.canvas.draw()
            extents = [axis.label.get_window_extent(renderer) for axis in (self.axes.xaxis, self.axes.yaxis,
                                                                            self.axes.zaxis)]
            if all(e.x0 >= frame.x0 and e.x1 <= frame.x1 and e.y0 >= frame.y0 and e.y1 <= frame.y1 for e in extents):
                return
            self.box_zoom *= FIT_SHRINK
            self.axes.set_box_aspect(sides, zoom=self.box_zoom)

    @property
    def frame_count(self) -> int:
        return self.scene.frame_count

    def _static_artists(self, title: str) -> list[Line2D]:
        handles = []
        if self.scene.reference is not None:
            (planned,) = self.axes.plot(*self.scene.reference.T, **PLANNED, label="planned path")
            handles.append(planned)
        pace = "real time" if self.speed == 1 else f"{self.speed:g}x real time"
        self.figure.text(0.01, 0.97, f"{title} ({pace})" if title else pace, va="top", ha="left")
        return handles

    def _moving_artists(self) -> list:
        ax = self.axes
        (self.trail,) = ax.plot([], [], [], **TRAIL, label="flown path")
        self.arms = self.discs = self.thrust = self.true_force = self.estimated_force = None
        if self.scene.rotors is not None:
            self.arms = Line3DCollection([], **ARMS)
            self.discs = Line3DCollection([], **DISCS)
        arrows = (self.scene.thrust, THRUST), (self.scene.external_estimate, ESTIMATED_FORCE), \
            (self.scene.external_truth, TRUE_FORCE)
        collections = [None if a is None else Line3DCollection([], **style) for a, style in arrows]
        self.thrust, self.estimated_force, self.true_force = collections
        (self.centre,) = ax.plot([], [], [], "o", color=CENTRE_COLOUR, ms=7, mec="none", label="centre of mass")
        self.clock = self.figure.text(0.01, 0.93, "", va="top", ha="left", family="DejaVu Sans Mono")
        moving = [self.trail, self.discs, self.arms, self.thrust, self.estimated_force, self.true_force, self.centre]
        moving = [artist for artist in moving if artist is not None]
        for artist in moving:
            if isinstance(artist, Line3DCollection):
                ax.add_collection3d(artist, autolim=False)  # the limits are the scene's bounds
        for artist in [*moving, self.clock]:
            artist.set_animated(True)
        return moving

    def _legend_handles(self) -> list[Line2D]:
        """Proxies for the legend (the animated artists are empty when the legend is made)."""
        handles = [Line2D([], [], **TRAIL, label="flown path"),
                   Line2D([], [], marker="o", ls="none", color=CENTRE_COLOUR, ms=7, mec="none", label="centre of mass")]
        for arrows, style in ((self.scene.thrust, THRUST), (self.scene.external_truth, TRUE_FORCE),
                              (self.scene.external_estimate, ESTIMATED_FORCE)):
            if arrows is not None:
                handles.append(Line2D([], [], color=style["colors"], lw=style["linewidths"],
                                      ls=style.get("linestyles", "-"), label=arrows.label))
        return handles

    def _arrows(self, collection: Line3DCollection | None, arrows: Arrows | None, k: int) -> None:
        if collection is not None:
            collection.set_segments(arrow_lines(arrows.tails[k], arrows.vectors[k], self.towards_viewer)
                                    .reshape(-1, 2, 3))

    def render(self, k: int) -> memoryview:
        """Draw frame ``k``; its RGBA pixels (height, width, 4), valid until the next call."""
        s = self.scene
        trail = np.vstack((s.trail[: s.trail_counts[k]], s.centre[k]))
        self.trail.set_data_3d(trail[:, 0], trail[:, 1], trail[:, 2])
        self.centre.set_data_3d(s.centre[k, :1], s.centre[k, 1:2], s.centre[k, 2:])
        if self.arms is not None:
            self.arms.set_segments(np.stack(np.broadcast_arrays(s.centre[k][None, :], s.rotors[k]), axis=1))
            self.discs.set_segments(s.discs[k])
        self._arrows(self.thrust, s.thrust, k)
        self._arrows(self.true_force, s.external_truth, k)
        self._arrows(self.estimated_force, s.external_estimate, k)
        self.clock.set_text(f"t = {s.times[k]:6.2f} s")  # short: the text is a good part of a frame's drawing
        self.canvas.restore_region(self._background)
        for artist in self._moving:
            if isinstance(artist, Line3DCollection):
                artist.do_3d_projection()  # Axes3D.draw does this for a full draw; the camera is fixed
            self.axes.draw_artist(artist)
        self.figure.draw_artist(self.clock)
        return self.canvas.buffer_rgba()

    def pixels(self, points: np.ndarray) -> np.ndarray:
        """Image coordinates (column, row from the top) [px] (n, 2) of view-frame points (n, 3)."""
        points = np.atleast_2d(points)
        x, y, _ = proj3d.proj_transform(points[:, 0], points[:, 1], points[:, 2], self.axes.M)
        return self._image(np.column_stack((x, y)))

    def centre_pixel(self, k: int) -> np.ndarray:
        """Where frame ``k`` draws the centre of mass: (column, row) [px] of the scene's centre, projected."""
        return self.pixels(self.scene.centre[k])[0]

    def marker_pixel(self) -> np.ndarray:
        """(column, row) [px] at which the last :meth:`render` drew the centre-of-mass marker."""
        x, y = self.centre.get_data()
        return self._image(np.column_stack((x, y)))[0]

    def _image(self, data_2d: np.ndarray) -> np.ndarray:
        display = self.axes.transData.transform(data_2d)
        return np.column_stack((display[:, 0], self.size[1] - display[:, 1]))


def write_animation(flight: RecordedFlight, out_dir: str | Path, options: AnimationOptions | None = None,
                    progress: Progress | None = None) -> WrittenAnimation:
    """Write ``out_dir/animation.<format>`` of ``flight`` (ValueError without odometry; OSError if it cannot be
    written). ``progress(done, total)`` is called after each frame."""
    options = options or AnimationOptions()
    scene = build_scene(flight, options.fps, options.speed)
    animation = FlightAnimation(scene, options.size, flight.scenario_name, options.speed)
    target = Path(out_dir) / options.file_name
    partial = target.with_name(f".{target.stem}.partial{target.suffix}")  # the suffix tells ffmpeg the format
    try:
        WRITERS[options.format](animation, partial, options.fps, progress or (lambda done, total: None))
        os.replace(partial, target)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise
    return WrittenAnimation(target, animation.frame_count, scene.notes)


def _write_mp4(animation: FlightAnimation, path: Path, fps: float, progress: Progress) -> None:
    import imageio_ffmpeg

    writer = imageio_ffmpeg.write_frames(str(path), animation.size, pix_fmt_in="rgba", fps=fps, quality=MP4_QUALITY,
                                         macro_block_size=MACRO_BLOCK_PX, ffmpeg_log_level="error")
    writer.send(None)  # starts ffmpeg
    try:
        for k in range(animation.frame_count):
            writer.send(animation.render(k))
            progress(k + 1, animation.frame_count)
    finally:
        writer.close()  # ffmpeg finishes the file (then removed if this is an interruption)


def gif_durations_ms(frames: int, fps: float) -> list[int]:
    """Per-frame GIF delays [ms], whole 1/100 s (the format's unit) whose sums follow ``k / fps``: the GIF plays
    at ``fps`` on average although 1 / fps is rarely a whole number of 1/100 s."""
    ends = np.round(np.arange(1, frames + 1) * 100.0 / fps)
    return [int(v) * 10 for v in np.diff(ends, prepend=0.0)]


def gif_palette() -> np.ndarray:
    """The GIF's one palette (n, 3) uint8: :data:`GIF_GREYS` greys, and every colour drawn blended with white
    (antialiased edges on the white background) and with black (where a black arm crosses it). One fixed palette,
    each frame mapped to it without dithering: steady colours, and ten times faster than Pillow's palette per
    frame. Pillow maps colours through bins 8 levels wide: greys 8 apart keep white white."""
    colours = {to_rgb(style[key]) for style in (TRAIL, PLANNED, ARMS, DISCS, THRUST, TRUE_FORCE, ESTIMATED_FORCE)
               for key in ("color", "colors") if key in style} | {to_rgb(CENTRE_COLOUR)}
    colours = np.array(sorted(c for c in colours if len(set(c)) > 1))  # the greys are in the grey ramp
    white = np.linspace(0.0, 1.0, GIF_BLENDS + 1)[1:, None, None]
    black = np.linspace(0.0, 1.0, GIF_BLENDS // 2 + 1)[1:-1, None, None]
    entries = np.concatenate([np.repeat(np.linspace(0.0, 1.0, GIF_GREYS)[:, None], 3, axis=1),
                              (white * colours + (1.0 - white)).reshape(-1, 3),
                              (black * colours).reshape(-1, 3)])
    return np.round(entries * 255).astype(np.uint8)


def _write_gif(animation: FlightAnimation, path: Path, fps: float, progress: Progress) -> None:
    from PIL import Image

    palette = Image.new("P", (1, 1))
    palette.putpalette(gif_palette().ravel().tolist())

    def frames() -> Iterator[Image.Image]:
        for k in range(animation.frame_count):
            rgb = Image.frombuffer("RGBA", animation.size, animation.render(k), "raw", "RGBA", 0, 1).convert("RGB")
            yield rgb.quantize(palette=palette, dither=Image.Dither.NONE)
            progress(k + 1, animation.frame_count)

    sequence = frames()
    first = next(sequence)
    first.save(path, format="GIF", save_all=True, append_images=sequence, loop=0,
               duration=gif_durations_ms(animation.frame_count, fps))


WRITERS = {"mp4": _write_mp4, "gif": _write_gif}
