"""What running one scenario gives, for every drive kind: ``Outcome``.

``acdrive.drives.run_scenario(setup)`` returns the outcome of the drive that owns ``setup``
(DFIM ``ScenarioOutcome``, cage IM ``IMOutcome``, PM ``PMOutcome``), each a subclass of
``Outcome`` with the same public members: the scenario's ``name`` and drive ``kind``, the
``results`` by run label (``main`` the first), the ``summary`` (what ``acdrive run`` writes to
summary.json; the command adds ``log``, the logging it chose, before writing), the
``headline()`` lines it prints after announcing the run, ``figures(folder)`` (the figures it draws)
and ``write(folder)`` (everything it writes). A drive's own members stay on its subclass.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from acdrive._arguments import Anything, Table, checked
from acdrive.drives._registry import Setup


@checked(setup=Setup(), results=Table(Anything()), summary=Table(empty=True))
@dataclass
class Outcome:
    """The runs of one scenario (label -> that drive's result) and its summary (summary.json).

    Every member below asks the drive that owns ``setup`` (``acdrive.drives.for_setup``), so an
    outcome reads, draws and writes exactly as ``acdrive run`` does for its scenario."""

    setup: object
    results: dict
    summary: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        """The scenario's name (its ``name`` field, or the file's stem)."""
        return self.setup.name

    @property
    def kind(self) -> str:
        """The drive kind (the scenario's ``drive`` value: ``"dfim"``, ``"cage-im"``, ``"pm"``)."""
        return self.drive.kind

    @property
    def drive(self):
        """The registered drive (``acdrive.drives.Drive``) that ran the scenario."""
        from acdrive.drives._registry import for_setup

        return for_setup(self.setup)

    @property
    def main(self):
        """The first run's result (the only one unless the scenario compares runs)."""
        return next(iter(self.results.values()))

    def headline(self) -> list[str]:
        """The lines ``acdrive run`` prints before naming the files it wrote: the first line,
        the aligned (label, value) rows, and the summary's finding, warnings and note."""
        from acdrive.columns import headline_lines

        first, rows = self.drive.headline(self, self.summary)
        return [first, *headline_lines(rows, self.summary)]

    def figures(self, folder) -> list[Path]:
        """Draw into ``folder`` the figures ``acdrive run`` draws (PNG, one sub-folder per run
        when the scenario compares runs); returns their paths."""
        return self.drive.figures(self, Path(folder))

    def write(self, folder, figures: bool = True, fmt: str = "parquet") -> dict:
        """Write what ``acdrive run`` writes into ``folder`` (data as ``fmt``, one of
        ``acdrive.columns.FORMATS``, with columns.md; figures unless ``figures`` is False;
        summary.json); returns the summary written, equal to ``summary``."""
        return self.drive.write(self, Path(folder), figures=figures, fmt=fmt)
