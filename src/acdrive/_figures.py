"""Helpers of every figure acdrive writes (a drive's figures, the reports', the robustness maps): figures made without ``matplotlib.pyplot`` (its import and
figure manager cost time and nothing here needs them) and a min/max envelope of long time traces
so a figure draws a few thousand points instead of every sample.

``new_figure`` gives a ``matplotlib.figure.Figure`` on the Agg canvas, as ``pyplot.subplots``
would; ``save_figure`` gives it the tight layout and draws it once.
``plot_trace`` draws ``envelope(t, y)``: the trace cut into ``ENVELOPE_BINS`` runs of consecutive
samples, of which each keeps its first, smallest, largest and last sample in time order. Every
extreme of every run is a sample of the drawn line, so no peak or trough is lost or moved, and
consecutive runs are joined from the last sample of one to the first of the next, as in the full
trace (a line at 7 in and 90 dpi spans about 630 pixel columns: 1500 runs are more than two per
column, and at most 6000 samples are drawn).
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
    runs = -(-n // size)
    # pad the last run with its last sample: it can neither be a new extreme nor move one
    padded = np.concatenate([y, np.full(runs * size - n, y[-1])]).reshape(runs, size)
    start = np.arange(runs) * size
    keep = [start, np.minimum(start + size - 1, n - 1)]
    finite = np.isfinite(padded)
    if finite.all():
        keep += [start + np.argmin(padded, axis=1), start + np.argmax(padded, axis=1)]
    else:
        keep += [
            start + np.argmin(np.where(finite, padded, np.inf), axis=1),
            start + np.argmax(np.where(finite, padded, -np.inf), axis=1),
            start + np.argmin(finite, axis=1),  # the first non-finite sample (or the first)
        ]
    index = np.unique(np.minimum(np.concatenate(keep), n - 1))
    return t[index], y[index]


def plot_trace(ax, t, y, *style, **kwargs):
    """``ax.plot(t, y, *style, **kwargs)`` of the trace's ``envelope``; returns the Line2D."""
    (line,) = ax.plot(*envelope(t, y), *style, **kwargs)
    return line


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
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, **subplots_kwargs)
    if margins_in is not None:
        left, right, bottom, top = margins_in
        width, height = figsize
        fig.subplots_adjust(left=left / width, right=1.0 - right / width,
                            bottom=bottom / height, top=1.0 - top / height)  # fmt: skip
        fig._acdrive_fixed_margins = True
    return fig, axes


def save_figure(path: Path, fig) -> None:
    """Write ``fig`` to ``path`` at ``DPI`` and close it (a PNG at ``PNG_COMPRESS_LEVEL``).

    A figure with fixed margins (``new_figure(margins_in=...)``) is drawn as it is. Another
    figure without a layout engine (``pyplot.subplots``, ``new_figure``) gets the
    tight layout, after which its engine is dropped: ``savefig`` would otherwise draw it once more
    (without rendering) to lay it out again, and that pass costs as much as the layout itself. A
    figure made with an engine (e.g. ``layout="constrained"``) is laid out by ``savefig``."""
    if fig.get_layout_engine() is None and not getattr(fig, "_acdrive_fixed_margins", False):
        fig.tight_layout()
        fig.set_layout_engine(None)
    kwargs = {"pil_kwargs": {"compress_level": PNG_COMPRESS_LEVEL}}
    fig.savefig(path, dpi=DPI, **(kwargs if str(path).lower().endswith(".png") else {}))
    pyplot = sys.modules.get("matplotlib.pyplot")  # only pyplot's figures need closing
    if pyplot is not None:
        pyplot.close(fig)
