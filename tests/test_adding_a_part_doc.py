"""The guide page "Adding a part" (docs/guide/adding-a-part.md): its sampled part, written with
the public API only, runs as printed on the native tier from C generated from its kernel, and
does what the page says. The V/f controller's frequency follows its ramp, its event bits count
the samples on which the ramp and the voltage ceiling act, and the cage machine it feeds
settles at the speed where the steady-state equivalent circuit gives a torque equal to the load
(Amezquita-Brooks et al. (1)-(2) at steady state, the torque from the rotor's copper losses)."""

from __future__ import annotations

import re
import runpy
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from acdrive.sim import _native

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guide" / "adding-a-part.md"
EXAMPLE = ROOT / "examples" / "plot_vf_soft_start.py"
SECTION = "## A sampled part of your own: V/f control"

needs_cc = pytest.mark.skipif(_native.compiler() is None, reason="no C compiler on this machine")


def guide_blocks(language: str) -> list[str]:
    """The code blocks of one language in the guide's worked example, in order."""
    text = GUIDE.read_text()
    section = text[text.index(SECTION) :]
    section = section[: section.index("\n## ", 1)]
    return re.findall(rf"```{language}\n(.*?)```", section, re.DOTALL)


def steady_speed(machine, V_pk, f_s, T_s, tau_load, B):
    """The speed below synchronism at which the machine's steady-state torque, from the rotor
    copper losses n_p R_r |I_r|^2 / w_2 (w_2 = w_e - n_p w the slip frequency), balances
    ``tau_load + B w``; stator voltage sqrt(3/2) V_pk (Bodson (8)) times the fundamental of its
    sample-and-hold, sin(x)/x with x = w_e T_s / 2."""
    p, w_e = machine, 2.0 * np.pi * f_s
    x = 0.5 * w_e * T_s
    V_s = np.sqrt(1.5) * V_pk * np.sin(x) / x

    def margin(w):
        w_2 = w_e - p.n_p * w
        # rotor loop: I_r = -j w_2 L_m I_s / (R_r + j w_2 L_r); stator loop gives I_s
        rotor = -1j * w_2 * p.L_m / (p.R_r + 1j * w_2 * p.L_r)
        i_s = V_s / (p.R_s + 1j * w_e * p.L_s + 1j * w_e * p.L_m * rotor)
        i_r = rotor * i_s
        return p.n_p * p.R_r * abs(i_r) ** 2 / w_2 - tau_load - B * w

    synchronous = w_e / p.n_p
    return brentq(margin, 0.5 * synchronous, synchronous * (1.0 - 1e-12), xtol=1e-12)


@needs_cc
def test_the_guides_vf_part_runs_natively_and_settles_at_the_equivalent_circuit_speed(
    tmp_path, monkeypatch
):
    from acdrive.sim._ccode import _kinds

    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "auto")  # what a user's run chooses
    monkeypatch.setenv("ACDRIVE_BACKGROUND_COMPILE", "0")
    script = tmp_path / "vf_from_the_guide.py"  # a file: the translator reads the kernel's source
    script.write_text("\n".join(guide_blocks("python")))
    scope = runpy.run_path(str(script))
    result, vf, shaft, machine = (scope[k] for k in ("result", "vf", "shaft", "machine"))

    assert result.tier == "native"
    step = _kinds.c_step_of(vf)
    assert step.from_kernel and "VoltsPerHertz, generated from its kernels" in step.source

    t, f, w = result.t, result.signal(vf.out.f), result.signal(shaft.out.w)
    T_s = t[1] - t[0]
    slew, f_ref, V_per_Hz, V_max = (vf.values[k] for k in ("slew", "f_ref", "V_per_Hz", "V_max"))
    # the ramp: slew T_s per sample from zero, then the reference
    assert np.max(np.abs(f - np.minimum(slew * (t + T_s), f_ref))) < 1e-9
    # the events: the samples on which the ramp limited the change, and the ceiling the voltage
    assert result.events["vf"]["slewing"] == np.count_nonzero(f < f_ref) > 0
    assert result.events["vf"]["voltage_limit"] == np.count_nonzero(V_per_Hz * f > V_max) > 0
    # the steady state: the ceiling's voltage at the reference frequency against the load
    # after its step and the friction
    tau_load = shaft.values["load"][-1][1]
    expected = steady_speed(machine, min(V_per_Hz * f_ref, V_max), f_ref, T_s, tau_load,
                            shaft.values["B"])  # fmt: skip
    settled = t >= t[-1] - 0.5
    slip = 2.0 * np.pi * f_ref / machine.n_p - expected
    assert slip > 0.1 * expected  # loaded: a slip worth measuring
    assert abs(w[settled].mean() - expected) < 1e-4 * slip


def test_the_guides_c_excerpt_is_the_generated_c(tmp_path):
    """The lines of C the guide shows are in the C exported from the guide's part, and the
    header names its event bits (no compile: the export writes text)."""
    from acdrive.export import to_c

    script = tmp_path / "vf_part_from_the_guide.py"  # a file: the translator reads the source
    script.write_text(guide_blocks("python")[0])
    part = runpy.run_path(str(script))["VoltsPerHertz"]
    system = _system_with(part("vf", V_per_Hz=3.0, V_max=150.0, slew=120.0, f_ref=60.0))
    exported = to_c(system, 1e-4, open_loop=True)
    (excerpt,) = guide_blocks("c")
    for line in excerpt.strip().splitlines():
        assert line.strip() in exported.source, line
    assert "#define ACD_VOLTS_PER_HERTZ_SLEWING (1u << 0)" in exported.header
    assert "#define ACD_VOLTS_PER_HERTZ_VOLTAGE_LIMIT (1u << 1)" in exported.header


def _system_with(vf):
    from acdrive.machines import UGALDE_IM_300W, CageInductionMachine
    from acdrive.plant import AveragedConverter, Shaft
    from acdrive.sim import System

    converter = AveragedConverter("converter", V_dc=310.0)
    im = CageInductionMachine.from_params("im", UGALDE_IM_300W)
    shaft = Shaft("shaft", J=UGALDE_IM_300W.J)
    return System([vf, converter, im, shaft], [
        (vf.out.v_ref, converter.inp.v_ref), (converter.out.v, im.inp.v_s),
        (shaft.out.w, im.inp.w), (im.out.tau_e, shaft.inp.tau_e)])  # fmt: skip


def test_the_gallery_example_holds_the_guides_part():
    """The gallery example the guide points to runs the same part: the guide's part block is in
    it word for word (its run is the docs build's, tests/test_docs.py)."""
    part = guide_blocks("python")[0]
    example = EXAMPLE.read_text()
    start = part.index("PARAMS = Layout(")
    assert part[start:] in example
