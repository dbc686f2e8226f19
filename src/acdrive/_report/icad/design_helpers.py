"""Report section 'acdrive's design helpers on the paper's problem' (not in the papers).

``check_controller`` on controller (20) and on the PI (360, 9000), and ``propose_controller``,
with the specifications of Amezquita-Brooks et al. sec. V-B, for both parameter sets; then the
worst cases of (20) over w_r from ``speed_sweep``.
"""

from __future__ import annotations

import numpy as np

from acdrive._report import icad_targets as targets
from acdrive._report.icad.common import W_R
from acdrive._report.markdown import Row, Section, fmt
from acdrive.analysis._design import PAPER_SPECS, check_controller, propose_controller
from acdrive.analysis._freqresp import LTI
from acdrive.analysis._robustness import speed_sweep
from acdrive.control._lti import PAPER_PI


def section_design_helpers(k20: LTI) -> Section:
    """The design-helper section (``k20`` = controller (20)); no figures."""
    s = Section("acdrive's design helpers on the paper's problem")
    s.text = (
        "Not in the papers: `check_controller` and `propose_controller` (acdrive.analysis._design) "
        f"with the specifications of sec. V-B ({targets.SPEC_BANDWIDTH.text}, {targets.SPEC_GM.text}, "
        f"{targets.SPEC_PM.text}, {targets.SPEC_COUPLING.text}; acdrive checks the bandwidth as the crossover "
        "of c_i and the margins on both c_i and k_i g_ii, w_r in [0, 375] at 7 speeds); and the "
        "worst cases of `speed_sweep` over 0 ... 375 rad/s."
    )
    for label, machine in (("(13)", "delorenzo-im-13"), ("App.", "delorenzo-im")):
        chk = check_controller(machine, k20, k20, PAPER_SPECS)
        s.rows.append(
            Row(
                f"(20) against the specs, {label}",
                "sec. V-B",
                "all met",
                "all met" if chk.met_all else "unmet: " + ", ".join(chk.unmet),
                "",
            )
        )
        pi = PAPER_PI
        chk = check_controller(machine, pi, pi, PAPER_SPECS)
        s.rows.append(
            Row(
                f"PI 360/9000 against the specs, {label}",
                "sec. VI-D",
                "-",
                "all met" if chk.met_all else "unmet: " + ", ".join(chk.unmet),
                "",
            )
        )
        prop = propose_controller(machine, None, PAPER_SPECS)
        c = prop.candidate
        desc = f"{c.structure}: {fmt(c.gain)} (s + {fmt(c.pi_zero)})/s" + (
            ""
            if c.lag_zero is None
            else f" x (s + {fmt(c.lag_zero)})^2/(s^2 + {fmt(2 * c.lag_zeta * c.lag_w0)} s + "
            f"{fmt(c.lag_w0**2)})"
        )
        chk = prop.check
        s.rows.append(
            Row(
                f"propose_controller, {label}",
                "cf. (20)",
                "(20)",
                desc,
                ("meets all specs" if chk.met_all else "unmet: " + ", ".join(chk.unmet))
                + f"; crossover {fmt(chk.get('bandwidth (crossover of c_i)').worst)} rad/s,"
                f" PM {fmt(chk.get('phase margin of c_i').worst, 3)} deg, coupling "
                f"{fmt(chk.get('coupling peak').worst, 3)} dB",
            )
        )
    sw = speed_sweep("delorenzo-im-13", k20, k20, np.linspace(0, W_R, 7))
    s.after = (
        "Worst cases of (20) over w_r in [0, 375] (`speed_sweep`, delorenzo-im-13):\n\n"
        "| figure | worst | at w_r [rad/s] |\n|---|---|---|\n"
        + "\n".join(
            f"| {v.figure} | {fmt(v.value)} {v.unit} | {fmt(v.speed)} |"
            for v in sw.worst.values()
            if v.figure != "gm_min"
        )
    )
    return s
