"""``Profile(times, values)``: a quantity that changes with time, given to a part parameter declared
as a ``table`` (a supply voltage ramp, a load step, a speed reference).

Interpolation (the one rule, applied by the compiled lookup ``core.table_at``): linear between
points, held before the first and after the last point; two points at the same time make a
vertical step there (the later point holds after it; at the instant itself too, unless the step
is at the first time, where the first point's value is returned for that one instant).

A table parameter accepts three forms, each with one meaning:

* a number: a constant;
* ``Profile(times, values)``: two sequences of the same length;
* a list of ``[time_s, value]`` points, as in the scenario files (``[[0, 0], [1, 180]]`` is a
  ramp from 0 at t = 0 s to 180 at t = 1 s).

A bare tuple ``(times, values)`` is refused: ``([0, 1], [0, 180])`` would read as the ramp above
while ``[[0, 1], [0, 180]]`` is a step to 180 at t = 0, and the two look alike.
"""

from __future__ import annotations

import numpy as np

from acdrive.errors import InputError

#: the accepted forms, as an error message ends
ACCEPTED = (
    "a number, Profile(times, values) or a list of [time_s, value] points "
    "(linear between points, a repeated time is a step)"
)


class Profile(tuple):
    """``Profile(times, values)``: values [the parameter's unit] at times [s], linear between
    points, held outside them, a step where a time repeats (module docstring).

    It is the pair ``(times, values)`` of float arrays (``times, values = profile`` works);
    ``Profile.constant(v)``, ``Profile.step(at, before, after)`` and
    ``Profile.from_points([[t, v], ...])`` build the common ones. The values are checked against
    the parameter's rule, and the times (>= 0, non-decreasing), when a part receives it."""

    __slots__ = ()

    def __new__(cls, times, values):
        arrays = []
        for what, data in (("times", times), ("values", values)):
            try:
                array = np.array(data, dtype=float, ndmin=1)
            except (TypeError, ValueError):
                raise InputError(f"Profile {what}", "must be a sequence of numbers") from None
            if array.ndim != 1:
                raise InputError(f"Profile {what}", "must be a flat sequence of numbers")
            arrays.append(array)
        return super().__new__(cls, arrays)

    def __getnewargs__(self):  # pickling (batches send setups to worker processes)
        return self[0], self[1]

    @property
    def times(self) -> np.ndarray:
        return self[0]

    @property
    def values(self) -> np.ndarray:
        return self[1]

    @classmethod
    def constant(cls, value: float) -> Profile:
        return cls([0.0], [value])

    @classmethod
    def step(cls, at: float, before: float, after: float) -> Profile:
        """``before`` until ``at`` [s], ``after`` from then on."""
        return cls([0.0, at, at], [before, before, after])

    @classmethod
    def from_points(cls, points) -> Profile:
        """From ``[[time_s, value], ...]``."""
        array = np.asarray(points, dtype=float)
        if array.ndim != 2 or array.shape[1] != 2:
            raise InputError("Profile points", "must be a list of [time_s, value] points")
        return cls(array[:, 0], array[:, 1])

    def __eq__(self, other) -> bool:
        if not isinstance(other, Profile):
            return NotImplemented
        return all(np.array_equal(a, b) for a, b in zip(self, other, strict=True))

    def __ne__(self, other) -> bool:
        equal = self.__eq__(other)
        return equal if equal is NotImplemented else not equal

    __hash__ = None  # arrays inside

    def __repr__(self) -> str:
        return f"Profile(times={self[0].tolist()!r}, values={self[1].tolist()!r})"
