"""The cage-IM current controllers acdrive designs from machine parameters (``controller =
"imc-pi"`` and ``controller = "icad-proposed"``), as opposed to the built-in published transfer functions (``control._lti.BUILTIN``:
Amezquita-Brooks et al.'s (20), the PI of their sec. VI-D, the PI family of Fig. 17), which are
fixed numbers and are never re-derived.

Internal-model design on the stator's transient model: seen from the stator terminals, over
times short against the rotor time constant, the machine's stator current obeys
sigma L_s di_s/dt = v_s - (R_s + R_R) i_s - (rotor-flux back-EMF), with R_R = R_r (L_m / L_r)^2
the inverse-Gamma rotor resistance (the rotor-flux term is left to the loop as a disturbance).
The stationary-frame PI K_P = alpha sigma L_s, K_I = alpha (R_s + R_R) cancels that pole and
makes the closed loop alpha / (s + alpha) for the transient model. It is designed on the
scenario's design machine (the nominal machine, or a ``[design]`` table's estimates).

``"icad-proposed"``: the diagonal controller k_1 = k_2 that ``analysis.propose_controller``
(Ugalde-Loo et al.'s ICAD as applied by Amezquita-Brooks et al., their sec. V: a PI, else a
PI x lag of the form of their (22)) finds for the ICAD plant of the design machine
(``analysis._plants.plant_from_params``), with its full ICAD check against the specifications
(``analysis._design.Specifications``; defaults ``PAPER_SPECS``, their sec. V-B). Only the
design machine enters: with a ``[design]`` table the proposal is re-derived from the estimates,
the simulated plant stays the truth.
"""

from __future__ import annotations

import dataclasses
import functools

from acdrive.analysis._design import PAPER_SPECS, Proposal, Specifications, propose_controller
from acdrive.errors import InputError, require_positive
from acdrive.machines._induction import IMParams

#: the name of the designed controller in ``[current_control] controller``
DESIGNED = "imc-pi"
#: the name of the ICAD-proposed controller in ``[current_control] controller``
PROPOSED = "icad-proposed"
#: the fields of ``[current_control.specs]`` (with ``controller = "icad-proposed"``): those of
#: ``analysis._design.Specifications``, defaults ``PAPER_SPECS``
SPEC_FIELDS = tuple(f.name for f in dataclasses.fields(Specifications))


def specifications(values: dict, where: str) -> Specifications:
    """``PAPER_SPECS`` with ``values`` (a ``[current_control.specs]`` table) replacing fields; an
    unknown field or a value out of its range raises ``InputError("<where>.<field>", rule)``."""
    for key in values:
        if key not in SPEC_FIELDS:
            raise InputError(f"{where}.{key}", f"unknown specification (known: {', '.join(SPEC_FIELDS)})")  # fmt: skip
    try:
        return dataclasses.replace(PAPER_SPECS, **values)
    except InputError as exc:
        raise InputError(f"{where}.{exc.field}", exc.rule) from None
    except TypeError as exc:  # a value of the wrong type reaching a comparison
        raise InputError(where, f"a specification has a value of the wrong type ({exc})") from None


@functools.lru_cache(maxsize=32)
def icad_proposal(machine: IMParams, specs: Specifications = PAPER_SPECS) -> Proposal:
    """``analysis.propose_controller`` on the ICAD plant of ``machine`` over the speeds of
    ``specs`` (module docstring); cached, as a scenario is built more than once per run."""
    return propose_controller(machine, None, specs)


def imc_current_pi(machine: IMParams, bandwidth: float) -> tuple[float, float]:
    """(K_P [V/A = ohm], K_I [ohm/s]) of the internal-model PI of the module docstring for
    ``machine`` at closed-loop bandwidth ``bandwidth`` [rad/s]."""
    a = require_positive("current_control.bandwidth_rad_s", bandwidth)
    r_rotor = machine.R_r * (machine.L_m / machine.L_r) ** 2
    return a * machine.sigma * machine.L_s, a * (machine.R_s + r_rotor)
