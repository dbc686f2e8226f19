"""The background compile (``sim._tier.start_background``): ``python -m acdrive.sim._background
JOB`` compiles, into the on-disk cache, the part kinds' kernels, the generic loop and a
specialised loop that a foreground run did not wait for, so that later runs load them.

Numba writes each cache file under a temporary name and renames it when complete, and the
generated modules are written the same way (``sim._codegen``), so an interrupted compile leaves no
broken entry: the next run finds nothing and compiles again. Failures are silent here (the
foreground falls back to compiling what it needs); the compile times measured are recorded for
the notices (``sim._codegen.record_time``).
"""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path


def main(argv: list[str]) -> int:
    job = json.loads(argv[0])
    from acdrive.sim import _codegen as codegen
    from acdrive.sim import _kernels as kernels
    from acdrive.sim import _tier as tier

    failures = 0
    for module_name, qualname in job.get("kinds", []):
        try:
            kind = importlib.import_module(module_name)
            for name in qualname.split("."):
                kind = getattr(kind, name)
            _, seconds = kernels.addresses(kind)
            if seconds:
                codegen.record_time("kernels", 1, seconds)
        except Exception:  # noqa: BLE001 - a kind that cannot compile stays on the fallback
            failures += 1
    if job.get("generic"):
        try:
            from acdrive.sim import _generic

            seconds, compiled = codegen.compile_for(_generic.run, tier.GENERIC_RUN_ARGS)
            if compiled:
                codegen.record_time("generic", 1, seconds)
        except Exception:  # noqa: BLE001
            failures += 1
    if job.get("specialised"):
        try:
            path = Path(job["specialised"])
            # a loop may import kernels generated beside it (a stats reducer's step), which the
            # foreground process had loaded by name: here they are found in that folder
            sys.path.append(str(path.parent))
            module = codegen.load_module(path.read_text())
            seconds, compiled = codegen.compile_for(module.run, tier.RUN_ARGS)
            if compiled:
                codegen.record_time("specialised", int(job.get("size", 1)), seconds)
        except Exception:  # noqa: BLE001
            failures += 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
