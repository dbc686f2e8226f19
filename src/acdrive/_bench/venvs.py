"""The peers' virtual environments: made by the suite, kept in a cache folder, never in the repo.

Each peer runs in its own virtualenv under ``peers_dir`` (default ``$XDG_CACHE_HOME/acdrive/peers``
or ``~/.cache/acdrive/peers``, outside the repository and outside any output folder, overridable
with ``acdrive bench --peers-dir``), one folder per peer and pinned version, e.g.
``motulator-0.18``. A venv that already imports the pinned version is reused; otherwise it is made
with a Python the peer supports (``PeerSpec.pythons``: motulator 0.18 and motulator-export 0.11
need 3.12; GEM 3.0.3 runs on the suite's own Python) and the pinned requirement is installed from
the package index with pip. Every failure is returned as a reason, never raised: the suite still measures acdrive and the
JSON says why the peer is missing (``available: false``).
"""

from __future__ import annotations

import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

PEER_SCRIPTS = Path(__file__).resolve().parent / "peers"


def default_peers_dir() -> Path:
    """``$XDG_CACHE_HOME/acdrive/peers``, else ``~/.cache/acdrive/peers``."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "acdrive" / "peers"


def _pythons_named(minor: str) -> list[str]:
    """Existing interpreters called ``python<minor>``: PATH, pyenv's versions, /usr(/local)/bin."""
    found = [shutil.which(f"python{minor}")]
    found += sorted(glob.glob(os.path.expanduser(f"~/.pyenv/versions/{minor}*/bin/python{minor}")))
    found += [f"/usr/bin/python{minor}", f"/usr/local/bin/python{minor}"]
    out = []
    for c in found:
        if c and os.path.exists(c) and c not in out:
            out.append(c)
    return out


def python312() -> list[str]:
    """Candidates for motulator 0.18, which needs Python >= 3.12."""
    return _pythons_named("3.12")


def running_python() -> list[str]:
    """The suite's own interpreter (a venv's python makes a venv from its base), then 3.11."""
    return [sys.executable, *_pythons_named("3.11")]


@dataclass(frozen=True)
class PeerSpec:
    """A peer: its distribution, pinned requirement and version prefix, its venv folder name,
    the interpreters to try (a function returning paths) and the Python versions it accepts."""

    name: str
    distribution: str
    requirement: str
    version_prefix: str
    folder: str
    pythons: Callable[[], list[str]]
    accepts: tuple[tuple[int, int], ...]


MOTULATOR = PeerSpec(
    "motulator",
    "motulator",
    "motulator==0.18.*",
    "0.18",
    "motulator-0.18",
    python312,
    ((3, 12), (3, 13)),
)
#: motulator's control ported to C with a native simulation; installs motulator 0.18 beside it
MOTULATOR_EXPORT = PeerSpec(
    "motulator-export",
    "motulator-export",
    "motulator-export==0.11.*",
    "0.11",
    "motulator-export-0.11",
    python312,
    ((3, 12), (3, 13)),
)
GEM = PeerSpec(
    "gym-electric-motor",
    "gym-electric-motor",
    "gym-electric-motor==3.0.3",
    "3.0.3",
    "gem-3.0.3",
    running_python,
    ((3, 9), (3, 10), (3, 11), (3, 12)),
)


def _output(cmd: list[str], timeout: float = 120.0) -> str | None:
    """stdout of ``cmd`` if it succeeds, else None."""
    try:
        r = subprocess.run(
            cmd, check=False, capture_output=True, text=True, timeout=timeout, env=clean_env()
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    return r.stdout.strip() if r.returncode == 0 else None


def clean_env() -> dict:
    """The environment for a peer's process: without acdrive's venv or path settings."""
    return {
        k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")
    }


def installed_version(python: str, distribution: str) -> str | None:
    """The version of ``distribution`` importable by ``python``, or None."""
    code = f"import importlib.metadata as m; print(m.version({distribution!r}))"
    return _output([python, "-c", code])


def ensure_venv(spec: PeerSpec, peers_dir: Path, log=None) -> dict:
    """``{"available": True, "python": ..., "venv": ..., "version": ...}`` once ``spec``'s venv
    imports the pinned version (made or repaired here if needed), else ``{"available": False,
    "reason": ...}``. ``log`` receives progress lines."""
    say = log or (lambda _msg: None)
    venv = Path(peers_dir) / spec.folder
    python = venv / "bin" / "python"
    info = {"venv": str(venv), "requirement": spec.requirement}
    if python.exists():
        got = installed_version(str(python), spec.distribution) or ""
        if got.startswith(spec.version_prefix):
            return {"available": True, "python": str(python), "version": got, **info}
    else:
        base = None
        tried = spec.pythons()
        for candidate in tried:
            v = _output([candidate, "-c", "import sys; print(*sys.version_info[:2])"])
            if v and tuple(int(x) for x in v.split()) in spec.accepts:
                base = candidate
                break
        if base is None:
            versions = ", ".join(f"{a}.{b}" for a, b in spec.accepts)
            return {
                "available": False,
                **info,
                "reason": (
                    f"no Python that {spec.name} supports ({versions}) was found (tried: "
                    f"{', '.join(tried) or 'none'})"
                ),
            }
        say(f"making {venv} with {base}")
        try:
            venv.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            return {"available": False, **info, "reason": f"cannot create {venv.parent}: {exc}"}
        failed = _run_step([base, "-m", "venv", str(venv)])
        if failed:
            return {"available": False, **info, "reason": failed}
    say(f"installing {spec.requirement} in {venv}")
    failed = _run_step(
        [str(python), "-m", "pip", "install", "--quiet", spec.requirement], timeout=1800
    )
    if failed:
        return {"available": False, **info, "reason": failed}
    got = installed_version(str(python), spec.distribution) or ""
    if not got.startswith(spec.version_prefix):
        return {
            "available": False,
            **info,
            "reason": f"{spec.requirement} not importable in {venv} after install (got {got!r})",
        }
    return {"available": True, "python": str(python), "version": got, **info}


def _run_step(cmd: list[str], timeout: float = 600.0) -> str | None:
    """None if ``cmd`` succeeds, else a one-line reason with the end of its output."""
    try:
        r = subprocess.run(
            cmd, check=False, capture_output=True, text=True, timeout=timeout, env=clean_env()
        )
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"{' '.join(cmd[:4])} failed: {exc}"
    if r.returncode != 0:
        tail = (r.stderr or r.stdout).strip().splitlines()[-3:]
        return f"{' '.join(cmd[:4])} failed: {' | '.join(tail)}"
    return None


class PeerFailed(RuntimeError):
    """The peer's process ended, answered with an error or could not be started."""


class PeerProcess:
    """A peer script running with ``--serve`` in the peer's virtualenv (``peers/_serve.py``):
    ``ask(cmd, **args)`` sends one command and returns its JSON answer; ``close()`` ends it.
    Its stderr goes to a temporary file (a pipe nobody reads could fill and block it) whose end
    is quoted when it fails."""

    REPLY_PREFIX = "ACDRIVE-BENCH "

    def __init__(self, python: str, script: str, cwd: str | None = None):
        self.script = script
        self._stderr = tempfile.TemporaryFile(mode="w+", encoding="utf-8")  # noqa: SIM115 - closed by close()
        try:
            self._proc = subprocess.Popen(
                [python, str(PEER_SCRIPTS / script), "--serve"],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=self._stderr,
                text=True,
                bufsize=1,
                env=clean_env(),
                cwd=cwd,
            )
        except OSError as exc:
            self._stderr.close()
            raise PeerFailed(f"{script} could not start: {exc}") from exc

    def _tail(self) -> str:
        self._stderr.seek(0)
        lines = self._stderr.read().strip().splitlines()[-5:]
        return " | ".join(lines) or "no message"

    def ask(self, cmd: str, **args) -> dict:
        try:
            self._proc.stdin.write(json.dumps({"cmd": cmd, "args": args}) + "\n")
            self._proc.stdin.flush()
        except OSError as exc:
            raise PeerFailed(f"{self.script} ended: {self._tail()}") from exc
        for line in self._proc.stdout:
            if line.startswith(self.REPLY_PREFIX):
                answer = json.loads(line[len(self.REPLY_PREFIX) :])
                if "error" in answer:
                    raise PeerFailed(f"{self.script} {cmd}: {answer['error']}")
                return answer
        self._proc.wait()
        raise PeerFailed(f"{self.script} ended (exit {self._proc.returncode}): {self._tail()}")

    def close(self) -> None:
        try:
            if self._proc.poll() is None:
                self._proc.stdin.write(json.dumps({"cmd": "quit"}) + "\n")
                self._proc.stdin.flush()
            self._proc.wait(timeout=30)
        except (OSError, subprocess.TimeoutExpired):
            self._proc.kill()
            self._proc.wait()
        finally:
            for stream in (self._proc.stdin, self._proc.stdout):
                if stream is not None:
                    stream.close()
            self._stderr.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
