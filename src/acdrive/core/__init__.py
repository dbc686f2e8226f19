"""Building blocks of a part: declared quantities (``real``, ``cplx``, ``table``, ``table2d`` in a
``Layout``), the part kinds a system is made of (``ContinuousPart``, ``SampledPart``,
``Modulator``) with their ports, the time profiles a table parameter takes (``Profile``) and the
compiled lookups a kernel uses (``table_at``, ``table2d_at``)."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "Var": "._signals",
        "Layout": "._signals",
        "real": "._signals",
        "cplx": "._signals",
        "table": "._signals",
        "table2d": "._signals",
        "Table2D": "._signals",
        "Part": "._parts",
        "ContinuousPart": "._parts",
        "SampledPart": "._parts",
        "Modulator": "._parts",
        "Port": "._parts",
        "Profile": "._profile",
        "table_at": "._tables",
        "table_offset": "._tables",
        "table2d_at": "._tables",
        "table2d_offset": "._tables",
    },
)
