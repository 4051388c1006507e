"""The panels of a figure and where they go: a grid of time-axis panels, an optional zoom on the first seconds
beside each, the legend (and an optional title) above them, placed from one measurement of the labels.

No layout engine: constrained layout measures every artist twice per saved format and took ~40 % of the
drawing time. Here each panel's axes and what was drawn in it are kept in a :class:`Panel`; :func:`arrange`
measures the y tick labels and labels of the left-most axes of each column group, the bottom row's x axes,
the legend and the title once, and sets every axes' position. Geometry (inches): group ``g`` (a column of
panels: the force, the torque) has a left margin that fits its y labels; with a zoom, the zoom takes
:data:`ZOOM_SHARE` of the group's plot width, left of the panel, and shares its y axis (the zoom's tick labels
and label stand for both).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.legend import Legend
from matplotlib.ticker import FormatStrFormatter, MaxNLocator

PNG_DPI = 300  # PNG resolution, and the figures' own (measured at it)
PLOT_BUCKETS = 1500  # longer series are drawn as per-bucket min and max (same picture, far fewer points)
ZOOM_SHARE = 0.24  # of a group's plot width
ZOOM_GAP_IN = 0.1  # between a zoom and its panel (room for its last and the panel's first time label)
GROUP_GAP_IN = 0.08  # between a group's panels and the next group's labels
PAD_IN = 0.04  # around the measured labels
EXTRA_HEIGHT_IN = 0.55  # a figure is rows x row height plus this (legend, time axis)
# The axes' own labels (never drawn) say what each axes is: "panel 0,1", "zoom 0,1", "twin".
PANEL_LABEL, ZOOM_LABEL, TWIN_LABEL = "panel", "zoom", "twin"


def envelope(t: np.ndarray, y: np.ndarray, buckets: int = PLOT_BUCKETS) -> tuple[np.ndarray, np.ndarray]:
    """Min-max decimation of a 1-D series for drawing: each of ``buckets`` equal slices keeps its minimum and
    maximum in time order, so peaks (saturation spikes) survive. Short series are returned as they are."""
    n = len(t)
    size = n // buckets
    if size < 4:
        return t, y
    head = buckets * size
    block = y[:head].reshape(buckets, size)
    i_min = np.argmin(np.where(np.isnan(block), np.inf, block), axis=1)
    i_max = np.argmax(np.where(np.isnan(block), -np.inf, block), axis=1)
    index = np.sort(np.stack((i_min, i_max), axis=1), axis=1) + (np.arange(buckets) * size)[:, None]
    index = np.concatenate((index.ravel(), np.arange(head, n)))
    return t[index], y[index]


@dataclass(eq=False)
class Panel:
    """One panel: its axes over the whole time axis, the series drawn in it (every sample, for the zoom, the
    floors and the rules) and its zoom axes once :func:`add_zoom` made one."""

    ax: Axes
    unit: str | None = None  # selects the panel's floor
    series: list[tuple[np.ndarray, np.ndarray, dict]] = field(default_factory=list)
    hlines: list[tuple[float, dict]] = field(default_factory=list)
    zoom: Axes | None = None

    def plot(self, t: np.ndarray, y: np.ndarray, **style: object) -> None:
        """Draw ``y(t)`` (decimated by :func:`envelope`) and keep every sample."""
        self.ax.plot(*envelope(t, y), **style)
        self.series.append((t, y, style))

    def hline(self, y: float, **style: object) -> None:
        self.ax.axhline(y, **style)
        self.hlines.append((y, style))

    def label(self, text: str, unit: str, frame: str = "") -> None:
        """Axis label ``text [unit]`` with the frame on a second line; the unit also selects the floor (a
        ``rotor `` prefix selects the rotor floor and is not shown)."""
        shown = unit.removeprefix("rotor ")
        self.ax.set_ylabel(f"{text} [{shown}]" + (f"\n{frame}" if frame else ""))
        self.unit = unit

    def data_range(self) -> tuple[float, float] | None:
        """(min, max) of the finite samples drawn, None without any."""
        values = [np.asarray(y, dtype=float) for _, y, _ in self.series]
        values = [v[np.isfinite(v)] for v in values]
        values = [v for v in values if v.size]
        if not values:
            return None
        return min(float(v.min()) for v in values), max(float(v.max()) for v in values)

    @property
    def lead(self) -> Axes:
        """The left-most axes of the panel (the zoom when there is one): it carries the y labels."""
        return self.zoom if self.zoom is not None else self.ax


@dataclass
class Margins:
    """Inches: left of each group's plot area, right of the last, above the top row, below the bottom row, and
    between rows."""

    left: list[float]
    right: float = 0.12
    top: float = 0.35
    bottom: float = 0.42
    row_gap: float = 0.1

    @classmethod
    def guess(cls, groups: int) -> Margins:
        return cls([0.62] * groups)


@dataclass(eq=False)
class Panels:
    """A figure's panels, ``cells[row, group]``, and the axes drawn over them with their own y axis on the right
    (``twins``)."""

    fig: Figure
    cells: np.ndarray
    twins: list[Axes] = field(default_factory=list)
    zoom_end: float | None = None  # length [s] of the zoom on the first seconds

    def __getitem__(self, index: tuple[int, int]) -> Panel:
        return self.cells[index]

    @property
    def flat(self) -> list[Panel]:
        return list(self.cells.flat)

    @property
    def rows(self) -> int:
        return self.cells.shape[0]

    @property
    def groups(self) -> int:
        return self.cells.shape[1]

    def twin(self, panel: Panel) -> Axes:
        """An axes over ``panel`` with its y axis on the right (its own scale)."""
        twin = panel.ax.twinx()
        twin.set_label(TWIN_LABEL)
        self.twins.append(twin)
        return twin


def panel_grid(rows: int, groups: int, width: float, row_height: float = 1.15, dpi: float = PNG_DPI) -> Panels:
    """A ``width`` x ``rows * row_height + EXTRA_HEIGHT_IN`` figure (inches) of ``rows`` x ``groups`` panels
    sharing their time axis, placed as a first guess (:func:`arrange` places them for good). ``dpi``: the PNG's,
    so that the renderer :func:`arrange` measures with, and the text it lays out, serve the PNG again."""
    fig = Figure(figsize=(width, row_height * rows + EXTRA_HEIGHT_IN), dpi=dpi)
    FigureCanvasAgg(fig)
    cells = np.empty((rows, groups), dtype=object)
    first = None
    for row in range(rows):
        for group in range(groups):
            ax = fig.add_axes((0.0, 0.0, 1.0, 1.0), sharex=first, label=f"{PANEL_LABEL} {row},{group}")
            first = first or ax
            if row < rows - 1:
                ax.tick_params(labelbottom=False)
            cells[row, group] = Panel(ax)
    panels = Panels(fig, cells)
    _place(panels, Margins.guess(groups))
    return panels


def add_zoom(panels: Panels, t_start: float, span: float, title: str) -> None:
    """A zoom on ``[t_start, t_start + span]`` [s] left of every panel, sharing its y axis: the panel's series
    and lines drawn again over that interval (every sample), the y labels moved to the zoom, ``title`` above
    the top row's zooms."""
    end = t_start + span
    first = None
    for row, group in np.ndindex(panels.cells.shape):
        panel = panels[row, group]
        zoom = panels.fig.add_axes(panel.ax.get_position(), sharey=panel.ax, sharex=first,
                                   label=f"{ZOOM_LABEL} {row},{group}")
        first = first or zoom
        for t, y, style in panel.series:
            stop = int(np.searchsorted(t, end, side="right")) + 1  # one sample past the end: no gap at the edge
            zoom.plot(*envelope(t[:stop], y[:stop]), **{**style, "label": "_nolegend_"})
        for y, style in panel.hlines:
            zoom.axhline(y, **{**style, "label": "_nolegend_"})
        zoom.set_xlim(t_start, end)
        zoom.xaxis.set_major_locator(MaxNLocator(nbins=2, steps=[1, 2, 5, 10]))
        zoom.xaxis.set_major_formatter(FormatStrFormatter("%g"))  # "1", not "1.0": short next to the panel's "0"
        zoom.set_ylabel(panel.ax.get_ylabel())
        panel.ax.set_ylabel("")
        panel.ax.tick_params(labelleft=False)
        if row < panels.rows - 1:
            zoom.tick_params(labelbottom=False)
        if row == 0 and title:
            zoom.set_title(title, pad=3)
        panel.zoom = zoom
    panels.zoom_end = span


def _place(panels: Panels, margins: Margins) -> None:
    """Set every axes' position from ``margins`` (module docstring's geometry)."""
    fig = panels.fig
    width, height = fig.get_size_inches()
    rows, groups = panels.rows, panels.groups
    plot_h = (height - margins.top - margins.bottom - (rows - 1) * margins.row_gap) / rows
    plot_w = (width - sum(margins.left) - margins.right - (groups - 1) * GROUP_GAP_IN) / groups
    x = 0.0
    for group in range(groups):
        x += margins.left[group]
        for row in range(rows):
            panel = panels[row, group]
            y = height - margins.top - row * (plot_h + margins.row_gap) - plot_h
            main_x, main_w = x, plot_w
            if panel.zoom is not None:
                zoom_w = ZOOM_SHARE * plot_w
                panel.zoom.set_position((x / width, y / height, zoom_w / width, plot_h / height))
                main_x, main_w = x + zoom_w + ZOOM_GAP_IN, plot_w - zoom_w - ZOOM_GAP_IN
            panel.ax.set_position((main_x / width, y / height, main_w / width, plot_h / height))  # twins follow
        x += plot_w + GROUP_GAP_IN


def arrange(panels: Panels, legend: Legend | None, title: str | None) -> None:
    """Measure the labels once and place the panels, the legend and the title (module docstring)."""
    fig = panels.fig
    renderer = fig.canvas.get_renderer()
    dpi = fig.dpi
    _, height = fig.get_size_inches()
    top = PAD_IN
    if title:
        text = fig.suptitle(title, y=1.0 - PAD_IN / height, va="top")
        top += text.get_window_extent(renderer).height / dpi + PAD_IN
    if legend is not None:  # its box sits below the anchor by the legend's own border pad
        legend.set_bbox_to_anchor((0.5, 1.0 - top / height), transform=fig.transFigure)
        top = height - legend.get_window_extent(renderer).y0 / dpi
    left = [0.0] * panels.groups
    above = [0.0] * panels.rows  # labels reaching above a row's plot area (offset text, the zoom's title)
    bottom = right = 0.0
    for (row, group), panel in np.ndenumerate(panels.cells):
        lead = panel.lead
        frame = lead.get_window_extent(renderer)
        ybox = lead.yaxis.get_tightbbox(renderer)
        if ybox is not None:
            left[group] = max(left[group], (frame.x0 - ybox.x0) / dpi)
            above[row] = max(above[row], (ybox.y1 - frame.y1) / dpi)
        if lead.get_title():
            above[row] = max(above[row], (lead.title.get_window_extent(renderer).y1 - frame.y1) / dpi)
        if row == panels.rows - 1:
            for ax in dict.fromkeys((lead, panel.ax)):
                xbox = ax.xaxis.get_tightbbox(renderer)
                if xbox is not None:
                    bottom = max(bottom, (frame.y0 - xbox.y0) / dpi)
                    if group == panels.groups - 1 and ax is panel.ax:
                        right = max(right, (xbox.x1 - ax.get_window_extent(renderer).x1) / dpi)
    for twin in panels.twins:
        ybox = twin.yaxis.get_tightbbox(renderer)
        if ybox is not None:
            right = max(right, (ybox.x1 - twin.get_window_extent(renderer).x1) / dpi)
    margins = Margins(
        left=[value + PAD_IN for value in left],
        right=max(right, 0.0) + PAD_IN,
        top=top + max(above[0], 0.0) + PAD_IN,
        bottom=bottom + PAD_IN,
        row_gap=max([0.0, *above[1:]]) + 2 * PAD_IN,
    )
    _place(panels, margins)
