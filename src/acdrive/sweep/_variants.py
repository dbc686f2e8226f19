"""The variants of a sweep: index -> overrides, computed on demand (nothing is materialised).

* **grid**: every combination of the varied fields' values; variant i is i written in the mixed
  radix of the value counts, the first ``[[vary]]`` varying slowest.
* **random**: variant i draws each field from its own generator
  ``numpy.random.default_rng([seed, i])`` (uniform within the bounds, log-uniform with
  ``log = true``, a uniform pick among ``values``): a variant does not depend on the chunk size,
  on the other variants or on the order in which chunks run.

A variant's id is its zero-padded index and a hash of its overrides
(``0000042-3f2a9c1d``): stable across runs and resumes, and it changes if the variant does.
"""

from __future__ import annotations

import hashlib
import json
import math

import numpy as np

from acdrive.sweep._spec import SweepSpec, Vary


def grid_values(v: Vary) -> list:
    """The values of one field on a grid."""
    if v.values is not None:
        return list(v.values)
    if v.log:
        return [float(x) for x in np.geomspace(v.low, v.high, v.points)]
    return [float(x) for x in np.linspace(v.low, v.high, v.points)]


def count(spec: SweepSpec) -> int:
    """Number of variants (a Python int: a grid's product may be huge)."""
    if spec.method == "random":
        return spec.samples
    return math.prod(v.length for v in spec.vary)


def _draw(v: Vary, rng: np.random.Generator):
    if v.values is not None:
        return v.values[int(rng.integers(len(v.values)))]
    if v.log:
        return float(math.exp(rng.uniform(math.log(v.low), math.log(v.high))))
    return float(rng.uniform(v.low, v.high))


def variant(spec: SweepSpec, i: int, grids: list | None = None) -> dict:
    """The varied fields of variant ``i`` (field -> value)."""
    if spec.method == "random":
        rng = np.random.default_rng([spec.seed, i])
        return {v.field: _draw(v, rng) for v in spec.vary}
    grids = grids or [grid_values(v) for v in spec.vary]
    out, rest = {}, i
    for v, values in reversed(list(zip(spec.vary, grids, strict=True))):
        rest, j = divmod(rest, len(values))
        out[v.field] = values[j]
    return {v.field: out[v.field] for v in spec.vary}


def variant_id(i: int, varied: dict) -> str:
    text = json.dumps(varied, sort_keys=True)
    return f"{i:07d}-{hashlib.sha256(text.encode()).hexdigest()[:8]}"


def chunk_range(spec: SweepSpec, c: int, n: int | None = None) -> range:
    n = count(spec) if n is None else n
    return range(c * spec.chunk, min((c + 1) * spec.chunk, n))
