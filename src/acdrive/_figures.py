"""Helpers of every figure acdrive writes (a drive's figures, the reports', the robustness maps): figures made without ``matplotlib.pyplot`` (its import and
figure manager cost time and nothing here needs them) and long time traces drawn as their min/max
envelope per pixel column, so a figure draws a few thousand points instead of every sample.

``new_figure`` gives a ``matplotlib.figure.Figure`` on the Agg canvas at ``DPI``, as
``pyplot.subplots`` would; ``save_figure`` gives it the tight layout and draws it once.
``plot_trace`` draws a trace whole and marks it; ``save_figure``, once the layout and the axis
limits are final, replaces each marked trace by ``column_envelope``: the samples cut into runs of
consecutive samples that fall in one pixel column of the written image, of which each keeps its
first, smallest, largest and last sample in time order. Every column's highest and lowest sample
is a sample of the drawn line, at its time, so no peak or trough is lost or moved, and
consecutive columns are joined from the last sample of one to the first of the next, as in the
full trace (a line across a 7 in axes at 90 dpi spans about 560 columns: at most four samples
each).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

#: Resolution of the figures acdrive writes [dots per inch].
DPI = 90

#: Runs of samples a long trace is cut into by ``envelope`` (each keeps at most four samples).
ENVELOPE_BINS = 1500


def _kept_in_runs(y, run_start: np.ndarray) -> np.ndarray:
    """Indices (sorted, unique) of the first, smallest, largest and last sample of each run of
    ``y``; ``run_start`` holds the first index of every run, ascending, starting at 0. A run with
    non-finite values keeps its first one too (the gap stays a gap) and its extremes are those
    of its finite values."""
    import numpy as np

    n = y.shape[0]
    run_end = np.append(run_start[1:], n) - 1
    finite = np.isfinite(y)
    keep = [run_start, run_end]
    if finite.all():
        keep += [run_start + _argextreme(y, run_start, np.minimum),
                 run_start + _argextreme(y, run_start, np.maximum)]  # fmt: skip
    else:
        keep += [
            run_start + _argextreme(np.where(finite, y, np.inf), run_start, np.minimum),
            run_start + _argextreme(np.where(finite, y, -np.inf), run_start, np.maximum),
            run_start + _argextreme(finite.astype(np.int8), run_start, np.minimum),
        ]  # the last: the first non-finite sample of the run (or its first sample)
    return np.unique(np.concatenate(keep))


def _argextreme(y, run_start, extreme) -> np.ndarray:
    """Offset in its run of the first sample of each run equal to the run's ``extreme``
    (``np.minimum`` or ``np.maximum``)."""
    import numpy as np

    n = y.shape[0]
    run = np.repeat(np.arange(run_start.size), np.diff(np.append(run_start, n)))
    best = extreme.reduceat(y, run_start)
    hit = np.flatnonzero(y == best[run])
    first = np.unique(run[hit], return_index=True)[1]  # hits are in time order
    return hit[first] - run_start


def envelope(t, y, bins: int = ENVELOPE_BINS) -> tuple[np.ndarray, np.ndarray]:
    """(t, y) reduced to the first, smallest, largest and last sample of each of ``bins`` runs of
    consecutive samples, in time order; a trace of at most ``4 * bins`` samples is returned as
    given. A run with non-finite values keeps its first one too (the gap stays a gap) and its
    extremes are those of its finite values."""
    import numpy as np  # here: the command line imports this module before it needs numpy

    t, y = np.asarray(t), np.asarray(y)
    n = y.shape[0]
    if n <= 4 * bins or t.shape != y.shape or y.ndim != 1:
        return t, y
    size = -(-n // bins)  # samples per run; the last run may be shorter
    index = _kept_in_runs(y, np.arange(0, n, size))
    return t[index], y[index]


def column_envelope(t, y, column) -> tuple[np.ndarray, np.ndarray]:
    """(t, y) reduced to the first, smallest, largest and last sample of each run of consecutive
    samples with one ``column`` (the pixel column each sample falls in), in time order. A trace
    with at most four samples per run is returned as given."""
    import numpy as np

    t, y, column = np.asarray(t), np.asarray(y), np.asarray(column)
    n = y.shape[0]
    if n == 0 or t.shape != y.shape or y.ndim != 1 or column.shape != y.shape:
        return t, y
    run_start = np.flatnonzero(np.concatenate([[True], column[1:] != column[:-1]]))
    if n <= 4 * run_start.size:
        return t, y
    index = _kept_in_runs(y, run_start)
    return t[index], y[index]


def pixel_columns(ax, t) -> np.ndarray:
    """The pixel column of the written image (at the figure's dpi) each time ``t`` falls in on
    the x axis of ``ax``, with the axes' current limits."""
    import numpy as np

    t = np.asarray(t, dtype=float)
    x = ax.transData.transform(np.column_stack([t, np.zeros_like(t)]))[:, 0]
    return np.floor(x)


#: the attribute that marks a line drawn by ``plot_trace``: its full (t, y)
_TRACE = "_acdrive_trace"


def plot_trace(ax, t, y, *style, **kwargs):
    """``ax.plot(t, y, *style, **kwargs)`` of the whole trace, marked so that ``save_figure``
    draws it as its ``column_envelope`` once the axes are laid out; returns the Line2D."""
    (line,) = ax.plot(t, y, *style, **kwargs)
    setattr(line, _TRACE, (t, y))
    return line


def fit_traces(fig) -> None:
    """Replace the data of every ``plot_trace`` line of ``fig`` by its ``column_envelope`` at the
    figure's current layout, limits and dpi (``save_figure`` calls it just before drawing). A
    figure with a layout engine is laid out first."""
    engine = fig.get_layout_engine()
    lines = [line for ax in fig.axes for line in ax.get_lines()]
    if engine is not None and any(getattr(line, _TRACE, None) is not None for line in lines):
        engine.execute(fig)
    for ax in fig.axes:
        traces = [line for line in ax.get_lines() if getattr(line, _TRACE, None) is not None]
        if not traces:
            continue
        ax.get_xlim(), ax.get_ylim()  # settles the autoscaled limits on the full traces
        for line in traces:
            t, y = getattr(line, _TRACE)
            line.set_data(*column_envelope(t, y, pixel_columns(ax, t)))
            setattr(line, _TRACE, None)


#: margins [in] (left, right, bottom, top) of a single-axes time plot: room for five-digit tick
#: labels and the axis label on the left, the tick labels and the axis label below, the title
#: above (10 pt text)
TIME_PLOT_MARGINS_IN = (0.8, 0.2, 0.55, 0.35)

#: PNG compression level of the figures written (zlib 1: a third of the default's encoding time
#: for a slightly larger file)
PNG_COMPRESS_LEVEL = 1


#: whether this process is an ``acdrive`` command (``acdrive.cli.main`` sets it): nothing in it
#: reads matplotlib's docstrings, so ``_figure_classes`` imports matplotlib without building them
COMMAND_PROCESS = False


def _figure_classes():
    """(Figure, FigureCanvasAgg). In an ``acdrive`` command whose process has not imported
    matplotlib's figure module yet, the import skips one thing: matplotlib gives every artist
    class a ``set()`` docstring listing its properties, built by inspecting the class when the
    class is defined (``matplotlib.artist.kwdoc``); measured on matplotlib 3.11 it is 0.13 of the
    import's 0.51 CPU-s, a quarter of a warm ``acdrive run``'s figures. While ``acdrive`` imports
    the figure modules, ``kwdoc`` gives a one-line pointer instead, and it is put back before
    any figure is drawn. Signatures, behaviour and drawing are untouched; in a Python session
    (``COMMAND_PROCESS`` false) matplotlib is imported as it is."""
    built = None
    if COMMAND_PROCESS and "matplotlib.figure" not in sys.modules:
        from matplotlib import artist

        built = getattr(artist, "kwdoc", None)
        if built is not None:
            artist.kwdoc = lambda _artist: "Properties: see the class's set_* methods."
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    finally:
        if built is not None:
            artist.kwdoc = built
    return Figure, FigureCanvasAgg


def new_figure(figsize, nrows: int = 1, ncols: int = 1, margins_in=None, **subplots_kwargs):
    """(figure, axes) as ``pyplot.subplots`` gives them, without pyplot: a figure of ``figsize``
    inches on the Agg canvas, laid out by ``save_figure`` (tight layout), or with fixed
    ``margins_in`` (left, right, bottom, top, inches; e.g. ``TIME_PLOT_MARGINS_IN``), which spares
    the layout its extra drawing pass. matplotlib is imported here, when a figure is drawn
    (0.4 CPU-s): not by a run without figures."""
    Figure, FigureCanvasAgg = _figure_classes()
    fig = Figure(figsize=figsize, dpi=DPI)  # the written image's pixels (``fit_traces``)
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, **subplots_kwargs)
    if margins_in is not None:
        left, right, bottom, top = margins_in
        width, height = figsize
        fig.subplots_adjust(left=left / width, right=1.0 - right / width,
                            bottom=bottom / height, top=1.0 - top / height)  # fmt: skip
        fig._acdrive_fixed_margins = True
    return fig, axes


class TimePlots:
    """Single-axes time plots of one size drawn in turn on one figure with fixed margins:
    ``next()`` gives (figure, axes) emptied of the previous plot's lines, texts, patches,
    collections and legend, with no title or axis labels, the colour cycle restarted and the
    limits left to the next plot's data. The figure, its axes and their ticks are made once
    for all the plots (about a fifth of the cost of each plot on a figure of its own); each
    written image is the one a figure of its own gives (``save_figure`` the figure after each
    plot)."""

    def __init__(self, figsize, margins_in=TIME_PLOT_MARGINS_IN):
        self.figsize, self.margins_in = figsize, margins_in
        self.fig = self.ax = None

    def next(self):
        if self.fig is None:
            self.fig, self.ax = new_figure(self.figsize, margins_in=self.margins_in)
            return self.fig, self.ax
        ax = self.ax
        for artist in [*ax.lines, *ax.texts, *ax.patches, *ax.collections, *ax.images]:
            artist.remove()
        if ax.get_legend() is not None:
            ax.get_legend().remove()
        ax.set_prop_cycle(None)
        ax.set(title="", xlabel="", ylabel="")
        ax.relim()
        ax.autoscale()
        return self.fig, ax


def save_figure(path: Path, fig) -> None:
    """Write ``fig`` to ``path`` at ``DPI`` and close it (a PNG at ``PNG_COMPRESS_LEVEL``).

    A figure with fixed margins (``new_figure(margins_in=...)``) is drawn as it is. Another
    figure without a layout engine (``pyplot.subplots``, ``new_figure``) gets the
    tight layout, after which its engine is dropped: ``savefig`` would otherwise draw it once more
    (without rendering) to lay it out again, and that pass costs as much as the layout itself. A
    figure made with an engine (e.g. ``layout="constrained"``) is laid out by ``savefig``. The
    traces of ``plot_trace`` are then drawn as their envelope per pixel column (``fit_traces``)."""
    if fig.get_layout_engine() is None and not getattr(fig, "_acdrive_fixed_margins", False):
        fig.tight_layout()
        fig.set_layout_engine(None)
    fig.set_dpi(DPI)
    fit_traces(fig)
    kwargs = {"pil_kwargs": {"compress_level": PNG_COMPRESS_LEVEL}}
    fig.savefig(path, dpi=DPI, **(kwargs if str(path).lower().endswith(".png") else {}))
    pyplot = sys.modules.get("matplotlib.pyplot")  # only pyplot's figures need closing
    if pyplot is not None:
        pyplot.close(fig)
