"""Parameter sweeps: many variants of one scenario, run in chunks into a Parquet dataset.

``load_sweep`` reads and validates a sweep file into a ``SweepSpec`` (its variants: a grid or
seeded random, computed on demand); ``run_sweep`` runs the chunks (locally or on a Dask
cluster), writes each atomically, resumes after an interruption and refuses a sweep too large
for the limits (``estimate`` says how large); ``read_table`` reads the results back and
``write_report`` writes the markdown report and its figures. The simulation itself is
``acdrive.batch.simulate_batch``.
"""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "SweepSpec": "._spec",
        "load_sweep": "._spec",
        "builtin_sweeps": "._spec",
        "estimate": "._engine",
        "run_sweep": "._engine",
        "read_table": "._engine",
        "write_report": "._report",
    },
)
