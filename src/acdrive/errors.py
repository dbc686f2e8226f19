"""Input errors: one line naming the field and the rule it breaks."""


class InputError(ValueError):
    """Invalid user input (parameter, scenario field or CLI argument).

    The message always has the form ``<field>: <rule>`` so the CLI can print it as one line.
    """

    def __init__(self, field: str, rule: str):
        self.field = field
        self.rule = rule
        super().__init__(f"{field}: {rule}")


def require_finite(field: str, value) -> float:
    """Return ``value`` as float, or raise InputError if it is not a finite real number."""
    import math

    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(field, f"must be a number, got {type(value).__name__}")
    value = float(value)
    if not math.isfinite(value):
        raise InputError(field, "must be finite (not NaN or infinite)")
    return value


def require_positive(field: str, value) -> float:
    """Return ``value`` as float, or raise InputError unless it is finite and > 0."""
    value = require_finite(field, value)
    if value <= 0.0:
        raise InputError(field, f"must be > 0, got {value:g}")
    return value


def require_nonnegative(field: str, value) -> float:
    """Return ``value`` as float, or raise InputError unless it is finite and >= 0."""
    value = require_finite(field, value)
    if value < 0.0:
        raise InputError(field, f"must be >= 0, got {value:g}")
    return value
