"""A system with its compiled loop: one run or a batch of variants, the size bounds of a run, and
the held-input right-hand side the slow path and the linearisation use.

The loop is one of two tiers (``sim._tier``): the native loop (the system's generated C) or
numba's specialised loop of this topology. ``System.compile()`` compiles or loads the chosen
loop at once; the seconds that took are reported by the next run's result
(``compile_time``, ``tier``, ``compiled_now``) apart from its simulation time (``wall_time``).
"""

from __future__ import annotations

import time

import numpy as np

from acdrive.errors import InputError, SimulationDiverged, call_interruptible
from acdrive.sim import _codegen as codegen
from acdrive.sim import _tier
from acdrive.sim._loop_source import STATUS_OK
from acdrive.sim._result import SystemResult

#: Size bounds of one run (also applied by the scenario loader): substeps per segment, memory
#: for the logs, and RK4 steps (samples x substeps x variants; about 2 us each: half an hour).
MAX_SUBSTEPS = 1000
LOG_BUDGET_BYTES = 2 * 1024**3
MAX_WORK = 1e9
#: integrator steps (variants x samples x substeps) from which a batch of a system the native
#: loop runs goes to numba's lockstep loop instead of the native loop per variant: the lockstep
#: loop's compile (about 40 s) is paid back at about 0.7 us saved per step (3.5x the per-variant
#: speed per CPU-second; docs/speed.md, "The batch loops")
LOCKSTEP_PAYS_STEPS = 5e7


class CompiledSystem:
    """A system with its compiled loop: run once or over a batch of variants.

    ``tier`` is the loop that runs it (``"native"`` or ``"specialised"``, ``sim._tier``);
    ``compile_time`` the seconds spent compiling or loading it that no run has reported yet
    (``compiled_now``: whether that was a compile rather than a load from the cache).
    """

    def __init__(self, system):
        """``system``: the ``sim.System`` to compile (``System.compile()`` calls this)."""
        self.system = system
        self.source = system.source()
        self._module = None
        self.tier = ""
        self.compile_time = 0.0
        self.compiled_now = False
        #: the batch loop the last batch ran in: "lockstep" or "per-variant" (None: no batch yet)
        self.last_batch_loop = None
        self._choose()

    @property
    def module(self):
        """The specialised loop's generated module (its functions compile on their first call,
        or load from the cache)."""
        if self._module is None:
            self._module = codegen.load_module(self.source)
        return self._module

    # --- the tier ---------------------------------------------------------------------------
    def _spent(self, seconds: float, compiled: bool) -> None:
        self.compile_time += seconds
        self.compiled_now = self.compiled_now or compiled

    def _choose(self) -> None:
        """Compile or load the loop ``sim._tier`` describes for this system now."""
        asked = _tier.chosen()
        self._native = None
        self._native_obstacle = None
        if asked in ("auto", "native") and self._nativise(required=asked == "native"):
            return
        if asked == "specialised":
            self._specialise("ACDRIVE_LOOP_TIER=specialised")
            return
        no_c = (f"the native loop cannot run it ({self._native_obstacle})"
                if self._native_obstacle else "")  # fmt: skip
        self._specialise(no_c or None)

    def _nativise(self, required: bool) -> bool:
        """Build or load the native loop (``sim._native``) if it can run this system; else
        keep the reason (``required``: ACDRIVE_LOOP_TIER=native, an error naming it)."""
        from acdrive.sim import _native

        obstacle = _native.native_obstacle(self.system)
        if obstacle is None:
            try:
                self._native, seconds, compiled = _native.build(
                    _native.native_source(self.system), notice=codegen.notice
                )
            except RuntimeError as error:  # the compiler refused: numba's tiers still run it
                obstacle = str(error)
        if obstacle is not None:
            if required:
                raise InputError("ACDRIVE_LOOP_TIER", f"native cannot run this system: {obstacle}")
            self._native_obstacle = obstacle
            return False
        self._spent(seconds, compiled)
        self._native_offsets = self.system.pack_params()[1]
        self.tier = "native"
        return True

    def _specialise(self, why: str | None, switch: bool = True) -> None:
        """Compile (notice: ``why``) or load the specialised loop's ``run`` now (``switch``:
        it becomes the tier of the single runs)."""
        run = self.module.run
        if why is not None and not codegen.is_cached(run):
            codegen.notice(_tier.describe_compile(self.system, why))
        seconds, compiled = codegen.compile_for(run, _tier.RUN_ARGS)
        if compiled:
            codegen.record_time("specialised", len(self.system.parts), seconds)
        self._spent(seconds, compiled)
        if switch:
            self.tier = "specialised"

    def _loop_for(self):
        """The run function of this system's tier."""
        if self.tier == "native":
            return self._native_run
        return self.module.run

    def _native_run(self, X, P, PO, S, Y, U, t0, T_s, n_sub, n_steps, log_every, idx, LOG, ELOG,
                    ECOUNT):  # fmt: skip
        """The native loop with the numba loops' arguments (``U`` is the loop's own inside)."""
        return self._native.run(P, PO, X, S, Y, t0, T_s, n_sub, n_steps, log_every, idx, LOG,
                                ELOG, ECOUNT)  # fmt: skip

    def _reported(self) -> tuple[float, bool]:
        """(compile or load seconds, compiled) not yet reported, now handed to a result."""
        out = (self.compile_time, self.compiled_now)
        self.compile_time, self.compiled_now = 0.0, False
        return out

    def _log_setup(self, log, n_steps, log_every):
        if isinstance(log_every, bool) or not isinstance(log_every, int) or log_every < 1:
            raise InputError("log_every", "must be an integer >= 1")
        if log_every > n_steps:
            raise InputError(
                "log_every", f"must not exceed the number of samples in the run ({n_steps})"
            )
        columns = self.system.log_columns(log)
        rows = n_steps // log_every + (n_steps % log_every > 0)
        return columns, rows

    def _steps(self, duration, sample_time, substeps):
        for field_name, value in (("duration", duration), ("sample_time", sample_time)):
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not np.isfinite(value)
                or value <= 0
            ):
                raise InputError(field_name, "must be a finite number > 0")
        if (
            isinstance(substeps, bool)
            or not isinstance(substeps, int)
            or not 1 <= substeps <= MAX_SUBSTEPS
        ):
            raise InputError("substeps", f"must be an integer from 1 to {MAX_SUBSTEPS}")
        n = round(duration / sample_time)
        if n < 1:
            raise InputError("duration", "must be at least one sample time")
        for part in self.system.parts:
            part.check_run(sample_time)
        return n

    def _check_size(self, n_steps, substeps, rows, n_columns, variants=1) -> None:
        """Refuse, before anything is allocated, a run beyond the bounds of this module."""
        n_values = variants * rows * (n_columns + len(self.system.event_names()))
        if n_values * 8 > LOG_BUDGET_BYTES:
            raise InputError(
                "log_every",
                f"the log would take {n_values * 8 / 1024**3:.3g} GB (limit "
                f"{LOG_BUDGET_BYTES / 1024**3:g} GB): log fewer signals, raise log_every or split "
                "the batch",
            )
        work = float(n_steps) * substeps * variants
        if work > MAX_WORK:
            raise InputError(
                "duration",
                f"needs {work:.3g} RK4 steps per segment (limit {MAX_WORK:.0e}): shorten the run, "
                "lengthen sample_time or use fewer substeps",
            )

    def run(self, duration: float, sample_time: float, substeps: int = 4, initial=None,
            log=None, log_every: int = 1, t0: float = 0.0, parts=None,
            held=None) -> SystemResult:  # fmt: skip
        """Simulate ``duration`` seconds; ``initial[part] = {state: value}``; ``held[part] =
        {output: value}`` for the outputs of sampled parts and modulators held before the first
        sample; ``log`` lists the output ports to record (default: all); ``parts`` replaces parts
        by re-parametrised copies of the same shape (``part.with_params``)."""
        sys_ = self.system
        n_steps = self._steps(duration, sample_time, substeps)
        columns, rows = self._log_setup(log, n_steps, log_every)
        self._check_size(n_steps, substeps, rows, len(columns))
        P, PO = sys_.pack_params(parts)
        X, S = sys_.pack_initial(initial)
        Y, U = sys_.pack_held(held), np.zeros(sys_.sizes["u"])
        LOG = np.zeros((rows, len(columns)))
        n_ev = len(sys_.event_names())
        ELOG = np.zeros((rows, n_ev), dtype=np.int64)
        ECOUNT = np.zeros((n_ev, 64), dtype=np.int64)
        idx = np.array([c[2] for c in columns], dtype=np.int64)
        tier = self.tier
        if tier == "native" and not np.array_equal(PO, self._native_offsets):
            # tables of other lengths than the library's structs hold
            self._specialise("a run with tables of other lengths runs the specialised loop", False)
            loop, tier = self.module.run, "specialised"
        else:
            loop = self._loop_for()
        start = time.perf_counter()
        done, status = loop(X, P, PO, S, Y, U, float(t0), float(sample_time), substeps, n_steps,
                            log_every, idx, LOG, ELOG, ECOUNT)  # fmt: skip
        wall = time.perf_counter() - start
        if status != STATUS_OK:
            bad = [
                name
                for name, _, _ in self._state_columns()
                if not np.isfinite(X[self._state_index(name)])
            ]
            raise SimulationDiverged(
                t0 + done * sample_time,
                f"state {', '.join(bad[:3]) or '?'} not finite; use a shorter sample_time or more "
                "substeps",
            )
        result = self._result(
            t0, sample_time, log_every, rows, columns, LOG, ELOG, ECOUNT, X, wall, n_steps
        )
        result.tier = tier
        result.compile_time, result.compiled_now = self._reported()
        return result

    def _state_columns(self):
        out = []
        for p in self.system.continuous:
            a, _ = self.system.slots[p.name].x
            for name, unit, _, s in p.STATES.columns(f"{p.name}."):
                out.append((name, unit, a + s))
        return out

    def _state_index(self, name):
        for n, _, i in self._state_columns():
            if n == name:
                return i
        raise KeyError(name)

    def _result(self, t0, T_s, log_every, rows, columns, LOG, ELOG, ECOUNT, X, wall, n_steps):
        events = {}
        for i, (part, names) in enumerate(self.system.event_names()):
            events[part] = {name: int(ECOUNT[i, b]) for b, name in enumerate(names)}
        return SystemResult(
            t=t0 + (np.arange(rows) * log_every) * T_s,  # sample k at k T_s, whatever log_every
            data=LOG,
            columns=[c[0] for c in columns],
            units={c[0]: c[1] for c in columns},
            descriptions=self.system.log_descriptions(columns),
            events=events,
            event_log=ELOG,
            final_state=X.copy(),
            wall_time=wall,
            steps=n_steps,
            tier=self.tier,
        )

    def run_batch(self, variants, duration, sample_time, substeps=4, initial=None, log=None,
                  log_every=1, t0=0.0, held=None, lockstep=None) -> list[SystemResult]:  # fmt: skip
        """Run many variants at once on all cores. ``variants`` is a list of dicts
        ``{part name: {parameter: value}}``; each variant's result equals running it alone (to
        the rounding stated in ``sim._lockstep_source`` when the variants run in lockstep;
        ``lockstep``: None chooses, True requires it, False runs one variant at a time)."""
        sys_ = self.system
        if not isinstance(variants, (list, tuple)):
            raise InputError(
                "variants", "must be a list of dicts {part name: {parameter: value}}, one per "
                f"variant, got {type(variants).__name__}"
            )  # fmt: skip
        for b, changes in enumerate(variants):
            if not isinstance(changes, dict) or not all(
                isinstance(params, dict) for params in changes.values()
            ):
                raise InputError(f"variants[{b}]", "must be a dict {part name: {parameter: value}}")
        n_steps = self._steps(duration, sample_time, substeps)
        columns, rows = self._log_setup(log, n_steps, log_every)
        B = len(variants)
        if B < 1:
            raise InputError("variants", "must hold at least one variant")
        self._check_size(n_steps, substeps, rows, len(columns), variants=B)
        packed = []
        for b, changes in enumerate(variants):
            parts = [sys_.part(name).with_params(**params) for name, params in changes.items()]
            packed.append(sys_.pack_params(parts))
        PO = packed[0][1]
        for b, (_, offsets) in enumerate(packed):
            if not np.array_equal(offsets, PO):
                raise InputError(
                    f"variants[{b}]", "tables of one batch must have the same number of points"
                )
        P = np.stack([params for params, _ in packed])
        X0, S0 = sys_.pack_initial(initial)
        X, S = np.tile(X0, (B, 1)), np.tile(S0, (B, 1))
        Y = np.tile(sys_.pack_held(held), (B, 1))
        LOG, ELOG, ECOUNT, DONE, STATUS, wall = self._batch_loop(
            P, PO, X, S, Y, t0, sample_time, substeps, n_steps, log_every, columns, rows, lockstep
        )
        results = []
        spent, compiled = self._reported()
        for b in range(B):
            r = self._result(
                t0,
                sample_time,
                log_every,
                rows,
                columns,
                LOG[b],
                ELOG[b],
                ECOUNT[b],
                X[b],
                wall / B,
                n_steps,
            )
            if b == 0:  # the batch's compile or load time, once
                r.compile_time, r.compiled_now = spent, compiled
            r.extra["status"] = (
                "ok"
                if STATUS[b] == STATUS_OK
                else f"diverged at t = {t0 + DONE[b] * sample_time:.6g} s"
            )
            results.append(r)
        return results

    def run_packed(self, P, PO, X, S, Y, duration, sample_time, substeps=4, log=None,
                   log_every=None, t0=0.0, lockstep=None):  # fmt: skip
        """The batch loop on arrays packed per variant, row b being variant b: ``P[b]`` (with the
        common offsets ``PO``), ``X[b]``, ``S[b]``, ``Y[b]`` as each variant's own system gives
        them (``pack_params``, ``pack_initial``, ``pack_held``). This is ``run_batch`` for
        variants that differ in more than parameters (initial states, held outputs, whole parts
        of the same shape); each row's result equals running that variant alone.

        ``X`` and ``S`` hold the final states on return (a sampled part that accumulates a
        metric in its state, ``acdrive.batch``, leaves it there). ``log`` lists output ports
        (default: none) logged every ``log_every`` samples (default: only the first sample, so
        nothing is kept per sample). Returns ``(LOG, ELOG, ECOUNT, DONE, STATUS, wall time)``.
        """
        n_steps = self._steps(duration, sample_time, substeps)
        log = [] if log is None else log
        log_every = n_steps if log_every is None else log_every
        columns, rows = self._log_setup(log, n_steps, log_every)
        B = X.shape[0]
        sizes = self.system.sizes
        if B < 1:
            raise InputError("variants", "must hold at least one variant")
        for name, array, width in (("X", X, sizes["x"]), ("S", S, sizes["s"]),
                                   ("Y", Y, sizes["y"]), ("P", P, int(PO[-1]))):  # fmt: skip
            if array.ndim != 2 or array.shape != (B, width) or array.dtype != np.float64:
                raise InputError(name, f"must be a float64 array of shape ({B}, {width})")
        self._check_size(n_steps, substeps, rows, len(columns), variants=B)
        PO = np.asarray(PO, dtype=np.int64)
        return self._batch_loop(
            P, PO, X, S, Y, t0, sample_time, substeps, n_steps, log_every, columns, rows, lockstep
        )

    def _batch_loop(self, P, PO, X, S, Y, t0, sample_time, substeps, n_steps, log_every,
                    columns, rows, lockstep=None):  # fmt: skip
        """The compiled batch loop over rows of packed arrays (states updated in place): the
        logs, event counts, samples done and status of every variant, and the wall time. The
        variants run in lockstep where ``lockstep_plan`` chooses it (``sim._lockstep_source``);
        ``self.last_batch_loop`` names the loop that ran."""
        B = X.shape[0]
        U = np.zeros((B, self.system.sizes["u"]))
        n_ev = len(self.system.event_names())
        LOG = np.zeros((B, rows, len(columns)))
        ELOG = np.zeros((B, rows, n_ev), dtype=np.int64)
        ECOUNT = np.zeros((B, n_ev, 64), dtype=np.int64)
        DONE = np.zeros(B, dtype=np.int64)
        STATUS = np.zeros(B, dtype=np.int64)
        idx = np.array([c[2] for c in columns], dtype=np.int64)
        if self._native_batch_pays(PO, B * n_steps * substeps, lockstep):
            start = time.perf_counter()
            self._native_batch(P, PO, X, S, Y, float(t0), float(sample_time), substeps, n_steps,
                               log_every, idx, LOG, ELOG, ECOUNT, DONE, STATUS)  # fmt: skip
            self.last_batch_loop = "native"
            return LOG, ELOG, ECOUNT, DONE, STATUS, time.perf_counter() - start
        import numba

        from acdrive.sim._lockstep_source import lockstep_broken, lockstep_plan

        lanes = lockstep_plan(self.system, PO, B, lockstep, P=P)
        if lanes is not None:
            lane_args = (X, P, S, Y, float(t0), float(sample_time), substeps, n_steps, log_every,
                         idx, LOG, ELOG, ECOUNT, DONE, STATUS)  # fmt: skip
            # compiled (or loaded) before the clock starts: its seconds are compile time
            seconds, compiled = codegen.compile_for(
                lanes.run, tuple(numba.typeof(a) for a in lane_args)
            )
            self._spent(seconds, compiled)
            start = time.perf_counter()
            before = X.copy(), S.copy(), Y.copy()
            broken = call_interruptible(lanes.run, *lane_args)
            if not broken:
                self.last_batch_loop = "lockstep"
                return LOG, ELOG, ECOUNT, DONE, STATUS, time.perf_counter() - start
            lockstep_broken(before, (X, S, Y), (LOG, ELOG, ECOUNT))
        self.last_batch_loop = "per-variant"
        args = (X, P, PO, S, Y, U, float(t0), float(sample_time), substeps, n_steps, log_every,
                idx, LOG, ELOG, ECOUNT, DONE, STATUS)  # fmt: skip
        if self.tier == "native":  # single runs stay native; the batch loads its own loop
            self._specialise("batches run the specialised loop", switch=False)
        seconds, compiled = codegen.compile_for(
            self.module.run_batch, tuple(numba.typeof(a) for a in args)
        )
        self._spent(seconds, compiled)
        start = time.perf_counter()
        call_interruptible(self.module.run_batch, *args)
        return LOG, ELOG, ECOUNT, DONE, STATUS, time.perf_counter() - start

    def _native_batch_pays(self, PO, steps: float, lockstep) -> bool:
        """Whether a batch runs in the native loop, variant by variant: the system's tier is
        native, the variants' tables have the library's lengths, and lockstep is neither asked
        for nor paid back (``LOCKSTEP_PAYS_STEPS``; ``lockstep=False`` refuses it)."""
        if lockstep not in (None, True, False):
            raise InputError("lockstep", f"must be None, True or False, got {lockstep!r}")
        if self.tier != "native" or lockstep is True:
            return False
        if not np.array_equal(PO, self._native_offsets):
            return False
        return lockstep is False or steps < LOCKSTEP_PAYS_STEPS

    def _native_batch(self, P, PO, X, S, Y, t0, T_s, n_sub, n_steps, log_every, idx, LOG, ELOG,
                      ECOUNT, DONE, STATUS):  # fmt: skip
        """Each row in the native loop as a single run of it (the same bits), the rows spread
        over the cores this process may use: ctypes lets go of the interpreter during the call,
        and the library keeps its run's context per thread."""

        def one(b: int) -> None:
            DONE[b], STATUS[b] = self._native.run(P[b], PO, X[b], S[b], Y[b], t0, T_s, n_sub,
                                                  n_steps, log_every, idx, LOG[b], ELOG[b],
                                                  ECOUNT[b])  # fmt: skip

        from acdrive._threads import usable_cores

        workers = min(X.shape[0], usable_cores())
        if workers <= 1:
            for b in range(X.shape[0]):
                one(b)
            return
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(one, range(X.shape[0])))

    # --- pieces for the slow path and the linearisation -------------------------------------
    def derivatives(self, t: float, X: np.ndarray, held: np.ndarray, parts=None) -> np.ndarray:
        """dX/dt with every non-plant output held at ``held`` (a Y vector): the right-hand side a
        Radau reference or a linearisation uses between two samples."""
        return self.evaluate(t, X, held, parts)[1]

    def evaluate(self, t: float, X: np.ndarray, held: np.ndarray, parts=None):
        """(Y, dX/dt): every output (plant outputs computed at ``X``, the rest as ``held``) and
        the right-hand side, at time ``t``."""
        P, PO = self.system.pack_params(parts)
        Y = np.array(held, dtype=float)
        U = np.zeros(self.system.sizes["u"])
        dX = np.empty_like(X)
        self.module.derivatives(t, X, P, PO, Y, U, dX)
        return Y, dX

    def output(self, Y: np.ndarray, port) -> complex | float:
        """The value of output ``port`` in an output vector ``Y``."""
        i = self.system.output_slot(port)
        return complex(Y[i], Y[i + 1]) if port.var.kind == "complex" else float(Y[i])
