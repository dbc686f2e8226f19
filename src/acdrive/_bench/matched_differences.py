"""What accounts for the remaining difference between acdrive's and motulator's runs of the
matched cage-IM case (``_bench.motulator_im``): acdrive's run against motulator's runs of the
case's variants, the speed PI's law exchanged between them (``benchmarks/bench_matched_im.py``;
docs/speed.md, "The benchmark suite")."""

from __future__ import annotations

import os
import shutil
import tempfile

import numpy as np

from acdrive._bench.motulator_im import (
    DURATION,
    T_S,
    TAU_MAX,
    acdrive_states,
    motulator_states,
    prepare_acdrive,
    speed_difference,
    state_difference,
)

#: motulator's variants of the case (peers/motulator_im.py VARIANTS): the example, with acdrive's
#: speed PI law in place of its own, and with its own held to acdrive's fixed torque limit
MOTULATOR_VARIANTS = ("example", "clamping_speed_pi", "fixed_limit_speed_pi")


def remaining_differences(peer: dict, duration: float = DURATION, converter: str = "averaged",
                          log=None) -> dict:  # fmt: skip
    """acdrive's run of the matched case against motulator's runs of its ``MOTULATOR_VARIANTS``
    (each recorded by the peer process in motulator's venv, ``peer``: ``ensure_venv``'s answer):
    per variant the largest speed and current differences relative to motulator's peaks
    (``state_difference``), the speed difference per phase (``speed_difference``), and the
    variant's own distance from motulator's example (``vs_motulators_example``). The step
    between the variants is what the speed PI's anti-windup accounts for; what the last variant
    leaves is the current controller, the computational delay and the flux model
    (``MATCHED["control"]["differences"]``)."""
    from acdrive._bench.venvs import PeerProcess

    say = log or (lambda _m: None)
    say(f"acdrive {converter}: one run of {duration:g} s")
    acd = prepare_acdrive(converter, duration)
    primary = acd["variants"][acd["primary"]]
    a_states = acdrive_states(primary, acd["_ports"], acd["_system"])
    out: dict = {"converter": converter, "duration_s": duration, "tau_max_n_m": TAU_MAX,
                 "variants": {}}  # fmt: skip
    tmp = tempfile.mkdtemp(prefix="acdrive_bench_")
    try:
        example = None  # motulator's example run, the first variant
        with PeerProcess(peer["python"], "motulator_im.py", cwd=tmp) as proc:
            for variant in MOTULATOR_VARIANTS:
                say(f"motulator {converter}: recording the {variant} variant")
                path = os.path.join(tmp, f"{variant}.npz")
                proc.ask("record", converter=converter, seconds=duration, out=path,
                         variant=variant, tau_max=TAU_MAX)  # fmt: skip
                m_states, _ = motulator_states(dict(np.load(path)))
                example = m_states if variant == "example" else example
                n = min(a_states.shape[0], m_states.shape[0]) - 1
                out["variants"][variant] = {
                    **state_difference(a_states, m_states),
                    "vs_motulators_example": state_difference(m_states, example),
                    "speed_by_phase": speed_difference(
                        a_states[:n, 4], m_states[:n, 4], np.arange(n) * T_S
                    ),
                    "peak_speed_rad_s": {
                        "acdrive": float(np.max(a_states[:n, 4])),
                        "motulator": float(np.max(m_states[:n, 4])),
                    },
                }
    finally:
        shutil.rmtree(tmp, ignore_errors=True)  # this measurement's own folder (mkdtemp)
    return out
