"""The one result type of a run: ``Result``.

Every run, from the engine's ``SystemResult`` to a drive's view of it (``drives.dfim.DriveResult``,
``drives.cage_im.IMDriveResult``), is a ``Result``; what a run holds is told by its *signals*:
``"part.name"`` keys with a unit and a one-line description taken from the declaring part's
declaration (or, for a signal a drive computes from several outputs, from the drive's table).

Reaching a signal
-----------------
* ``result.signal("dfim0.i_s")``, ``result.signal(port)`` or ``result.signal("i_s", part)``:
  complex where the part declares a space vector.
* ``result.dfim0.i_s``: attribute access through a part view (``result.part("dfim0")``). A part
  named ``<kind><index>`` (``dfim0``, ``dfim1``, ``shaft0``) is also reached by its kind alone
  when it is the only one of that kind: ``result.dfim.i_s`` in a single-motor run. With several
  motors the kind alone is ambiguous and the error names the parts to choose from.
* A bare name (``result.signal("w")``) is accepted when one part declares it (or when a view
  names a default part, as the DFIM view does for motor 0).

What every result offers once, here: ``signal``, ``parts``, ``unit``, ``description``,
``to_dataframe`` (units and descriptions in ``frame.attrs``), ``save`` (parquet, csv or mat with
``columns.md``, ``acdrive.columns``), ``plot`` (a min/max envelope per time bin on one shared
time axis, one axis per unit), ``summary`` (the drive's metrics, computed once when first read;
a drive may attach its own) and a one-line ``repr``. A view supplies four hooks: ``_declare``
(signal key -> unit, description), ``_values`` (key -> array), ``table_columns`` (the layout of
its result files) and, optionally, ``_compute_summary`` and ``_headline``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from acdrive.columns import DEFAULT_FORMAT, Column, write_table
from acdrive.core._parts import Port
from acdrive.errors import InputError
from acdrive.sim._timing import simulated_in

__all__ = ["PLOT_BINS", "PartView", "Result", "SystemResult", "envelope"]

#: time bins of ``Result.plot``: a longer signal is drawn as its min/max in each bin
PLOT_BINS = 2000

_KIND = re.compile(r"^(?P<kind>.*?[A-Za-z_])\d+$")


def envelope(t: np.ndarray, y: np.ndarray, bins: int = PLOT_BINS) -> tuple[np.ndarray, np.ndarray]:
    """(times, values) drawing ``y`` against ``t`` as its min/max envelope: with more than
    ``2 bins`` samples, the samples are cut into ``bins`` consecutive bins of (nearly) equal
    count and each bin is drawn by its minimum and its maximum, at the times they occur, in time
    order; shorter signals are returned whole. Every extreme of the data is drawn (a decimated
    plot that drops peaks would hide the limit events a drive engineer looks for)."""
    t, y = np.asarray(t), np.asarray(y)
    if bins < 1:
        raise InputError("bins", "must be an integer >= 1")
    if y.size <= 2 * bins:
        return t, y
    edges = np.linspace(0, y.size, bins + 1).astype(np.int64)
    starts, ends = edges[:-1], edges[1:]
    # all bins at once: row k holds bin k, padded after its end with a value that is never its
    # first minimum (+inf) or first maximum (-inf); argmin / argmax take the first occurrence,
    # as on the bin alone (a NaN, too, is found where it is first)
    index = starts[:, None] + np.arange(int((ends - starts).max()))[None, :]
    inside = index < ends[:, None]
    values = y[np.minimum(index, y.size - 1)]
    i_min = starts + np.argmin(np.where(inside, values, np.inf), axis=1)
    i_max = starts + np.argmax(np.where(inside, values, -np.inf), axis=1)
    pairs = np.sort(np.stack([i_min, i_max], axis=1), axis=1).ravel()
    return t[pairs], y[pairs]


class PartView:
    """The logged signals of one part of a result: ``view.i_s`` is ``result.signal("part.i_s")``;
    ``view.signals`` lists the names, ``view.units`` and ``view.descriptions`` their
    declarations."""

    def __init__(self, result: Result, part: str):
        self._result = result
        self._part = part

    @property
    def signals(self) -> list[str]:
        prefix = self._part + "."
        return [k[len(prefix) :] for k in self._result._declared() if k.startswith(prefix)]

    @property
    def units(self) -> dict[str, str]:
        return {n: self._result.unit(f"{self._part}.{n}") for n in self.signals}

    @property
    def descriptions(self) -> dict[str, str]:
        return {n: self._result.description(f"{self._part}.{n}") for n in self.signals}

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        key = f"{self._part}.{name}"
        if key not in self._result._declared():
            raise AttributeError(
                f"part {self._part} logged no signal {name!r} (logged: {', '.join(self.signals)})"
            )
        return self._result._values(key)

    def __dir__(self):
        return [*super().__dir__(), *self.signals]

    def __repr__(self) -> str:
        items = ", ".join(f"{n} [{u or '-'}]" for n, u in self.units.items())
        return f"<part {self._part}: {items}>"


class Result:
    """Base of every run's result (module docstring): ``t`` (the logged times) plus the hooks
    of a view. Not instantiated itself."""

    t: np.ndarray
    #: how a bare name resolves when several parts declare it: a part index or name, or None
    _default_part = None
    #: the signals ``plot()`` draws when none are named (None: every signal)
    plot_signals: tuple[str, ...] | None = None

    # -- hooks of a view ------------------------------------------------------------------------
    def _declare(self) -> dict[str, tuple[str, str]]:
        """``"part.name"`` -> (unit, description) of every signal, in table order."""
        raise NotImplementedError

    def _values(self, key: str) -> np.ndarray:
        """The values of the signal ``key`` (a key of ``_declare``), complex where declared."""
        raise NotImplementedError

    def table_columns(self, separator: str = ".") -> list[Column]:
        """The result table: ``t`` then every signal (``.re`` / ``.im`` for the two parts of a
        complex one), names with ``separator`` between part and signal."""
        out = [Column("t", self.t, "s", "time of the logged sample")]
        for key, (unit, text) in self._declared().items():
            values, name = self._values(key), key.replace(".", separator)
            if np.iscomplexobj(values):
                out.append(Column(f"{name}{separator}re", values.real, unit, f"{text} (real part)"))
                out.append(Column(f"{name}{separator}im", values.imag, unit, f"{text} (imaginary part)"))  # fmt: skip
            else:
                out.append(Column(name, values, unit, text))
        return out

    def _compute_summary(self) -> dict:
        """The drive's metrics of this run (a view overrides this); the engine's result has
        none until a drive attaches them."""
        return {}

    def _headline(self) -> list[str]:
        """The headline figures ``repr`` shows (a view overrides this)."""
        figures = [(k, v) for k, v in self.summary.items()
                   if isinstance(v, (int, float)) and not isinstance(v, bool)]  # fmt: skip
        return [f"{k} {v:.4g}" for k, v in figures[:3]]

    @property
    def title(self) -> str:
        """The first line of ``columns.md``."""
        return "Result columns"

    # -- one implementation for every result --------------------------------------------------
    def _declared(self) -> dict[str, tuple[str, str]]:
        cached = self.__dict__.get("_declared_cache")
        if cached is None:
            cached = self.__dict__["_declared_cache"] = self._declare()
        return cached

    @property
    def parts(self) -> list[str]:
        """The parts with logged signals, in table order."""
        return list(dict.fromkeys(k.split(".", 1)[0] for k in self._declared()))

    def _part_name(self, part) -> str:
        parts = self.parts
        if isinstance(part, (int, np.integer)) and not isinstance(part, bool):
            if not 0 <= part < len(parts):
                raise KeyError(f"part index {part} out of range (parts: {', '.join(parts)})")
            return parts[part]
        if part in parts:
            return part
        same_kind = [p for p in parts if (m := _KIND.match(p)) and m["kind"] == part]
        if len(same_kind) == 1:
            return same_kind[0]
        if same_kind:
            raise KeyError(f"{part} is ambiguous: name one of {', '.join(same_kind)}")
        raise KeyError(f"no part {part} (parts: {', '.join(parts)})")

    def part(self, name) -> PartView:
        """The view of one part (its name, its kind when it is the only one, or its index)."""
        return PartView(self, self._part_name(name))

    def __getattr__(self, name: str):
        if name.startswith("_") or "t" not in self.__dict__:
            raise AttributeError(name)
        try:
            return self.part(name)
        except KeyError as exc:
            why = exc.args[0]
            if not why.startswith("no part"):  # an ambiguous kind: the error names the parts
                raise AttributeError(why) from None
            raise AttributeError(
                f"{type(self).__name__} has no attribute or part {name!r} "
                f"(parts: {', '.join(self.parts)})"
            ) from None

    def __dir__(self):
        return [*super().__dir__(), *self.parts]

    def _key(self, name, part=None) -> str:
        declared = self._declared()
        if isinstance(name, Port):
            name = name.path
        name = str(name)
        if part is not None:
            key = f"{self._part_name(part)}.{name}"
        elif name in declared:
            key = name
        else:
            owners = [k for k in declared if k.split(".", 1)[1] == name]
            if len(owners) == 1:
                key = owners[0]
            elif owners and self._default_part is not None:
                key = f"{self._part_name(self._default_part)}.{name}"
            elif owners:
                raise KeyError(f"{name} is logged by several parts: name one ({', '.join(owners)})")
            else:
                key = name
        if key not in declared:
            raise KeyError(f"{key} was not logged (logged: {', '.join(declared)})")
        return key

    def signal(self, name, part=None) -> np.ndarray:
        """A logged signal: ``"part.name"``, a port, or ``name`` of ``part`` (a part name, kind
        or index; a bare name when one part logs it). Complex where declared."""
        return self._values(self._key(name, part))

    def unit(self, name, part=None) -> str:
        """The SI unit of a signal ("" if dimensionless), from its declaration."""
        return self._declared()[self._key(name, part)][0]

    def description(self, name, part=None) -> str:
        """The one-line description of a signal, from its declaration."""
        return self._declared()[self._key(name, part)][1]

    @cached_property
    def summary(self) -> dict:
        """The drive's summary of this run: computed once when first read (``_compute_summary``),
        or attached by the drive that ran it (``result.summary = {...}``)."""
        return self._compute_summary()

    @property
    def duration(self) -> float:
        """Logged span [s]: last logged time minus the first, plus one logging interval."""
        if self.t.size < 2:
            return 0.0
        return float(self.t[-1] - self.t[0] + (self.t[1] - self.t[0]))

    def to_dataframe(self):
        """A pandas DataFrame of :meth:`table_columns` (the result files' table); units in
        ``frame.attrs["units"]``, one-line descriptions in ``frame.attrs["descriptions"]``."""
        import pandas as pd

        columns = self.table_columns()
        frame = pd.DataFrame({c.name: c.values for c in columns})
        frame.attrs["units"] = {c.name: c.unit for c in columns}
        frame.attrs["descriptions"] = {c.name: c.description for c in columns}
        return frame

    def save(self, folder, fmt: str = DEFAULT_FORMAT) -> list:
        """Write the table as ``fmt`` (``acdrive.columns.FORMATS``: parquet, csv or mat) with
        ``columns.md`` into ``folder`` (created if needed); return the paths written. The
        engine's table names its columns ``part.signal``; MATLAB names cannot hold dots, so the
        ``.mat`` file names them ``part_signal`` (listed in ``columns.md``)."""
        from pathlib import Path

        columns = self.table_columns("_" if fmt == "mat" else ".")
        return write_table(Path(folder), columns, fmt, self.title)

    def plot(self, signals=None, axes=None, bins: int = PLOT_BINS, pyplot: bool = True):
        """The ``signals`` (keys, bare names or ports; default ``plot_signals``, else every
        signal) against time on one shared time axis: one stacked axis per unit (real and
        imaginary parts of a complex signal on the same axis), or on the ``axes`` given (one
        per unit, in order of first appearance). A signal longer than ``2 bins`` samples is
        drawn as its min/max envelope per time bin (``envelope``). Returns the Figure: a
        ``pyplot`` figure (shown in a notebook), or with ``pyplot=False`` one on the Agg canvas
        that pyplot does not know (``_figures.new_figure``: for writing a file)."""
        if signals is None:
            signals = self.plot_signals or list(self._declared())
        groups: dict[str, list[tuple[str, np.ndarray]]] = {}
        for name in signals:
            key = self._key(name)  # an unlogged signal is named here, before any drawing
            groups.setdefault(self._declared()[key][0], []).append((key, self._values(key)))
        if axes is None:
            if pyplot:
                from matplotlib.pyplot import subplots
            else:
                from acdrive._figures import new_figure as subplots
            fig, axes = subplots(nrows=len(groups), ncols=1, sharex=True, squeeze=False,
                                 figsize=(8, 1.2 + 2.0 * len(groups)))  # fmt: skip
            axes = axes[:, 0]
        else:
            axes = list(np.atleast_1d(axes))
            if len(axes) != len(groups):
                raise InputError(
                    "axes", f"must be {len(groups)} axes (one per unit), got {len(axes)}"
                )
            fig = axes[0].figure
            for ax in axes[1:]:
                ax.sharex(axes[0])
        for ax, (unit, members) in zip(axes, groups.items(), strict=True):
            for key, y in members:
                parts = [(" (re)", y.real), (" (im)", y.imag)] if np.iscomplexobj(y) else [("", y)]
                for suffix, values in parts:
                    ax.plot(*envelope(self.t, values, bins), lw=0.8, label=key + suffix)
            ax.set_ylabel(f"[{unit}]" if unit else "[-]")
            ax.legend(loc="best", fontsize="small")
        axes[-1].set_xlabel("time [s]")
        fig.tight_layout()
        return fig

    def __repr__(self) -> str:
        """One line for a notebook or a log: what it holds (span, samples, parts) and the
        summary's headline figures."""
        parts = self.parts
        shown = ", ".join(parts[:5]) + (", ..." if len(parts) > 5 else "")
        head = (
            f"<{type(self).__name__} {self.title.split(':')[0]!r}: {self.duration:g} s, "
            f"{self.t.size} samples; {len(self._declared())} signals of {len(parts)} parts "
            f"({shown})"
        )
        figures = self._headline()
        return head + (f"; {', '.join(figures)}>" if figures else ">")


@dataclass(eq=False, repr=False)
class SystemResult(Result):
    """Logged outputs of one run of a compiled system: ``data[i, j]`` is column j at time
    ``t[i]`` (``part.output``, or ``part.output.re`` / ``.im`` for a complex one)."""

    t: np.ndarray
    data: np.ndarray
    columns: list[str]
    units: dict[str, str]
    events: dict[str, dict[str, int]]  # part -> event name -> samples on which it was raised
    event_log: np.ndarray
    final_state: np.ndarray
    wall_time: float = 0.0
    steps: int = 0
    extra: dict = field(default_factory=dict)
    descriptions: dict[str, str] = field(default_factory=dict)
    #: seconds spent compiling or loading the loop before this run (not in ``wall_time``)
    compile_time: float = 0.0
    #: the loop that ran (``sim._tier``): "native" or "specialised"
    tier: str = ""
    #: whether ``compile_time`` was a compile (else a load from the cache)
    compiled_now: bool = False

    @property
    def title(self) -> str:
        return "System run: result columns"

    def _declare(self) -> dict[str, tuple[str, str]]:
        out = {}
        for name in self.columns:
            if name.endswith(".im"):
                continue
            key = name.removesuffix(".re")
            text = self.descriptions.get(name, key)
            out[key] = (self.units.get(name, ""), text.removesuffix(" (real part)"))
        return out

    def _values(self, key: str) -> np.ndarray:
        if key in self.columns:
            return self.data[:, self.columns.index(key)]
        return (
            self.data[:, self.columns.index(f"{key}.re")]
            + 1j * self.data[:, self.columns.index(f"{key}.im")]
        )

    def table_columns(self, separator: str = ".") -> list[Column]:
        """``t`` then every logged column with its unit and the declaring part's one-line
        description, in the order logged."""
        out = [Column("t", self.t, "s", "time of the logged sample")]
        for j, name in enumerate(self.columns):
            out.append(Column(name.replace(".", separator), self.data[:, j],
                              self.units.get(name, ""), self.descriptions.get(name, name)))  # fmt: skip
        return out

    def raised_events(self) -> dict[str, int]:
        """``"part.event"`` -> samples on which it was raised, for the events raised at all."""
        return {f"{part}.{name}": n for part, names in self.events.items()
                for name, n in names.items() if n}  # fmt: skip

    def _headline(self) -> list[str]:
        events = self.raised_events()
        raised = ", ".join(f"{k} {v}" for k, v in events.items()) if events else "none"
        return [*super()._headline(), f"events raised: {raised}",
                f"{self.steps} steps {simulated_in([self])}"]  # fmt: skip
