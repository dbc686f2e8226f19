"""Progress bars of the commands (on stderr, only when it is a terminal).

Kept below the CLI layer so that commands can draw a bar without importing ``acdrive.cli``;
``ACTIVE_BARS`` lets the CLI write a notice above a bar that is being drawn.
"""

from __future__ import annotations

import sys

#: the progress bars drawn now (a notice is written above them, not across)
ACTIVE_BARS: list = []


class Progress:
    """A progress bar on stderr over a command's phases (``with Progress(total, "run") as bar:
    bar.phase("simulate"); ...; bar.advance()``), redrawn twice a second so a long phase shows
    its elapsed time. Shown only when stderr is a terminal (tqdm's own rule): a log or a test
    capturing stderr gets no bar, only the one-line notices and errors."""

    def __init__(self, total: int, description: str):
        import threading

        self.bar = None
        self._stop = threading.Event()
        if not (hasattr(sys.stderr, "isatty") and sys.stderr.isatty()):
            return
        from tqdm import tqdm  # only when a bar is drawn: its import costs 0.1-0.2 s

        self.bar = tqdm(
            total=total, desc=description, file=sys.stderr, leave=False, dynamic_ncols=True,
            bar_format="{desc}: {n}/{total} |{bar}| {elapsed}{postfix}",
        )  # fmt: skip
        ACTIVE_BARS.append(self.bar)
        self._thread = threading.Thread(target=self._refresh, daemon=True)
        self._thread.start()

    def _refresh(self) -> None:
        while not self._stop.wait(0.5):
            self.bar.refresh()

    def phase(self, text: str) -> None:
        """Name what is being done now (shown after the bar)."""
        if self.bar is not None:
            self.bar.set_postfix_str(text, refresh=True)

    def advance(self, n: int = 1) -> None:
        if self.bar is not None:
            self.bar.update(n)

    def close(self) -> None:
        self._stop.set()
        if self.bar is not None:
            self._thread.join()
            ACTIVE_BARS.remove(self.bar)
            self.bar.close()
            self.bar = None

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close()
