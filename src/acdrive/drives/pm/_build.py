"""The PM speed drive as a system of parts: ``build(setup)`` (``_entry.run`` simulates it).

Parts (plant and sensors are acdrive's existing parts; the controller is ``drives.pm._control``):

    speed_reference -> speed_pi -> torque_reference -> current -> converter -> machine <-> shaft
                          ^              ^               ^  ^                    |          |
                        speed <------- encoder <---------+--|--------------------+----------+
                                                            i_s (machine output, sampled)

``converter`` is ``plant.AveragedConverter`` (V_dc fixed) or ``plant.Inverter`` fed by a
``plant.DCSource``. The run starts at standstill with zero currents; the controller's
integrators start at zero.
"""

from __future__ import annotations

from typing import NamedTuple

from acdrive.control._bodson import SpeedEstimator
from acdrive.control._speed import SpeedPIGains, SpeedReference
from acdrive.drives.pm._control import (
    PMSpeedPI,
    PMTorqueReference,
    RotorFrameCurrentController,
)
from acdrive.drives.pm._design import CurrentPIGains
from acdrive.drives.pm._setup import PMDriveSetup
from acdrive.errors import InputError
from acdrive.machines._pmsm_part import PermanentMagnetMachine
from acdrive.plant._converter import AveragedConverter
from acdrive.plant._inverter import Inverter
from acdrive.plant._mechanics import Shaft
from acdrive.plant._sensors import Encoder
from acdrive.plant._sources import DCSource
from acdrive.sim._system import System


class Built(NamedTuple):
    """What ``build`` returns: the system, initial states and held outputs (``System.run``'s
    ``initial`` and ``held``), and the logged ports by name."""

    system: System
    initial: dict
    held: dict
    log: dict


def _estimates(setup: PMDriveSetup) -> dict:
    m = setup.controller_machine
    return {"R_s": m.R_s, "L_d": m.L_d, "L_q": m.L_q, "psi_m": m.psi_m, "n_p": m.n_p}


def _limits(setup: PMDriveSetup) -> dict:
    return {"i_max": setup.i_max, "V_dc": setup.V_dc, "margin": setup.voltage_margin}


def controller_parts(setup: PMDriveSetup) -> dict:
    """The three controller parts, designed from the estimates and the setup's bandwidths
    (``_design.CurrentPIGains.design``, ``control.SpeedPIGains.design``)."""
    est, lim = _estimates(setup), _limits(setup)
    cur = CurrentPIGains.design(est["R_s"], est["L_d"], est["L_q"], setup.current_bandwidth)
    spd = SpeedPIGains.design(setup.speed_design_J, setup.speed_bandwidth, K_F=setup.K_F)
    return {
        "speed_pi": PMSpeedPI(
            "speed_pi",
            K_P=spd.K_P,
            K_I=spd.K_I,
            K_F=spd.K_F,
            tau_max=setup.torque_limit,
            **est,
            **lim,
        ),
        "torque_reference": PMTorqueReference("torque_reference", **est, **lim),
        "current": RotorFrameCurrentController(
            "current",
            K_P_d=cur.K_P_d,
            K_P_q=cur.K_P_q,
            K_I_d=cur.K_I_d,
            K_I_q=cur.K_I_q,
            V_dc=setup.V_dc,
            advance=0.5 * setup.carrier_samples,
            **est,
        ),
    }


def build(setup: PMDriveSetup) -> Built:
    """Parts, wires, initial state and logged ports of one run (module docstring)."""
    if not isinstance(setup, PMDriveSetup):
        raise InputError("setup", "must be a drives.pm.PMDriveSetup")
    p = {
        "machine": PermanentMagnetMachine.from_params("machine", setup.machine),
        "shaft": Shaft("shaft", J=setup.J, B=setup.B, load=setup.load),
        "encoder": Encoder(
            "encoder", offset=setup.encoder_offset, counts_per_rev=setup.encoder_counts
        ),
        "speed": SpeedEstimator("speed"),
        "speed_reference": SpeedReference("speed_reference", w=setup.speed_reference),
        **controller_parts(setup),
    }
    machine, shaft, enc, speed = p["machine"], p["shaft"], p["encoder"], p["speed"]
    spi, tref, cur = p["speed_pi"], p["torque_reference"], p["current"]
    wires = [
        (shaft.out.w, machine.inp.w),
        (machine.out.tau_e, shaft.inp.tau_e),
        (shaft.out.theta, enc.inp.theta),
        (enc.out.theta, speed.inp.theta),
        (p["speed_reference"].out.w_ref, spi.inp.w_ref),
        (speed.out.w, spi.inp.w),
        (spi.out.tau_ref, tref.inp.tau_ref),
        (speed.out.w, tref.inp.w),
        (tref.out.i_dq_ref, cur.inp.i_dq_ref),
        (machine.out.i_s, cur.inp.i_s),
        (enc.out.theta, cur.inp.theta),
        (speed.out.w, cur.inp.w),
    ]
    if setup.converter == "switching":
        p["dc"] = DCSource("dc", V=setup.V_dc)
        p["converter"] = Inverter("converter", f_pwm=setup.f_pwm)
        wires += [
            (p["dc"].out.v_dc, p["converter"].inp.v_dc),
            (machine.out.i_s, p["converter"].inp.i_s),
        ]
    else:
        p["converter"] = AveragedConverter("converter", V_dc=setup.V_dc)
    wires += [
        (cur.out.v_ref, p["converter"].inp.v_ref),
        (p["converter"].out.v, machine.inp.v_s),
    ]
    system = System(list(p.values()), wires)
    log = {
        "w_ref": p["speed_reference"].out.w_ref,
        "w": shaft.out.w,
        "theta": shaft.out.theta,
        "w_meas": speed.out.w,
        "tau_ref": spi.out.tau_ref,
        "tau_avail": spi.out.tau_avail,
        "i_dq_ref": tref.out.i_dq_ref,
        "tau_lim": tref.out.tau_lim,
        "psi_max": tref.out.psi_max,
        "v_dq_ref": cur.out.v_dq_ref,
        "v_dq_wanted": cur.out.v_dq_wanted,
        "v_ref": cur.out.v_ref,
        "v_s": p["converter"].out.v,
        "i_s": machine.out.i_s,
        "i_dq": machine.out.i_dq,
        "tau_e": machine.out.tau_e,
    }
    return Built(system, {}, {}, log)
