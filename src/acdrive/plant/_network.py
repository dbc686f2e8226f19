"""The stator-side network: a supply bus behind a shared series R-L, stator relays, a switch.

``SupplyBus``: a source v_g feeds a bus through a series resistance R and inductance L shared by
n machines (Bodson's transformer feeding several motors):

    v_bus = v_g - R sum(i_s,k) - L sum(di_s,k/dt).

Each connected machine gives di_s,k/dt = a_k v_bus + b_k (``DoublyFedMachine`` outputs a_k, b_k),
so the bus equation is linear in v_bus and solved exactly at every evaluation:

    v_bus = (v_g - R sum(i_s,k) - L sum(b_k)) / (1 + L sum(a_k)).

With R = L = 0 the bus is the source itself.

``StatorRelay``: the voltage at a machine's stator terminals: the bus voltage while the relay is
closed, the machine's open-circuit voltage while it is open.

``RelayCommand``: a sampled part that closes a relay at a given time (e.g. a stator switched onto
the grid at t = 0); drive controllers give the same output from their synchroniser.

``ForcedRelay``: a relay mis-operation between a command and the relay: the contact closes at a
given time whatever the command says (an operator's manual close, a welded contact), and stays
closed; before that it follows the command.
"""

from __future__ import annotations

from typing import ClassVar

from acdrive._jit import jit, jit_fast
from acdrive.core._describe import layout_text
from acdrive.core._parts import ContinuousPart, SampledPart
from acdrive.core._signals import Layout, cplx, real
from acdrive.errors import InputError

BUS_PARAMS = Layout(
    real("R", "ohm", "series resistance shared by the machines", "nonnegative"),
    real("L", "H", "series inductance shared by the machines", "nonnegative"),
)
BUS_OUTPUTS = Layout(cplx("v", "V", "bus voltage, stationary frame"))
_R, _L = BUS_PARAMS.slot("R"), BUS_PARAMS.slot("L")
#: input slots: the source, then per machine (i_s, a, b) in this many floats
_V_G, _FIRST_MACHINE, _PER_MACHINE = 0, 2, 5


def _bus_inputs(n: int) -> Layout:
    declared = [cplx("v_g", "V", "source voltage, stationary frame")]
    for k in range(n):
        declared += [
            cplx(f"i_s{k}", "A", f"stator current of machine {k}"),
            real(f"a{k}", "1/H", f"a of di_s/dt = a v_bus + b, machine {k}"),
            cplx(f"b{k}", "A/s", f"b of di_s/dt = a v_bus + b, machine {k}"),
        ]
    layout = Layout(*declared)
    if layout.slot("v_g") != _V_G or (n and layout.slot("i_s0") != _FIRST_MACHINE):
        raise ImportError("SupplyBus input layout no longer matches its kernel's slots")
    return layout


@jit_fast
def no_state_outputs(t, x, p, y):
    pass  # every output is a direct output


@jit_fast
def bus_direct_outputs(t, x, u, p, y):
    n = (u.shape[0] - _FIRST_MACHINE) // _PER_MACHINE
    sum_i_s = 0.0 + 0.0j
    sum_a = 0.0
    sum_b = 0.0 + 0.0j
    for k in range(n):
        o = _FIRST_MACHINE + _PER_MACHINE * k
        sum_i_s += complex(u[o], u[o + 1])
        sum_a += u[o + 2]
        sum_b += complex(u[o + 3], u[o + 4])
    v_g = complex(u[_V_G], u[_V_G + 1])
    v_bus = (v_g - p[_R] * sum_i_s - p[_L] * sum_b) * (1.0 / (1.0 + p[_L] * sum_a))
    y[0], y[1] = v_bus.real, v_bus.imag


@jit_fast
def no_rhs(t, x, u, p, y, dx):
    pass  # no states


class SupplyBus(ContinuousPart):
    """A bus fed from a source through a series R-L shared by ``n_machines`` machines, solved
    exactly (module docstring). Wire ``machine.out.i_s, bus_gain, bus_drive`` to the bus inputs
    ``i_s<k>, a<k>, b<k>`` with :meth:`wires_from`."""

    SOURCE = "supply bus behind a shared series R-L, solved exactly (plant._network)"

    PARAMS, OUTPUTS = BUS_PARAMS, BUS_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"R": 0.0, "L": 0.0}
    PER_INSTANCE: ClassVar[dict] = {
        "INPUTS": "set by n_machines (wires_from connects machine k); with one machine: "
        + layout_text(_bus_inputs(1)),
    }
    DIRECT_OUTPUTS = ("v",)
    state_outputs = no_state_outputs
    direct_outputs = bus_direct_outputs
    rhs = no_rhs

    def __init__(self, name: str, n_machines: int = 1, **params):
        if isinstance(n_machines, bool) or not isinstance(n_machines, int) or n_machines < 1:
            raise InputError(f"{name}.n_machines", "must be an integer >= 1")
        self.INPUTS = _bus_inputs(n_machines)
        self.DIRECT_FROM = tuple(v.name for v in self.INPUTS)
        self.n_machines = n_machines
        super().__init__(name, **params)

    def wires_from(self, k: int, machine) -> list:
        """The three wires from machine k's bus terms to this bus."""
        return [
            (machine.out.i_s, getattr(self.inp, f"i_s{k}")),
            (machine.out.bus_gain, getattr(self.inp, f"a{k}")),
            (machine.out.bus_drive, getattr(self.inp, f"b{k}")),
        ]


RELAY_INPUTS = Layout(
    cplx("v_bus", "V", "bus voltage"),
    cplx("v_open", "V", "the machine's open-stator voltage"),
    real("closed", "", "relay command: 1 closed, 0 open"),
)
RELAY_OUTPUTS = Layout(
    cplx("v", "V", "stator terminal voltage, stationary frame"),
    real("closed", "", "relay state: 1 closed, 0 open"),
)
_IN_BUS, _IN_OPEN, _IN_CLOSED = (RELAY_INPUTS.slot(n) for n in ("v_bus", "v_open", "closed"))
_OUT_V, _OUT_CLOSED = RELAY_OUTPUTS.slot("v"), RELAY_OUTPUTS.slot("closed")


@jit_fast
def relay_direct_outputs(t, x, u, p, y):
    # the relay as a switching function c in {0, 1}: v = c v_bus + (1 - c) v_open. Written as
    # arithmetic, not as a choice: LLVM turns a choice between two inputs into a load from a
    # chosen slot, which keeps the lockstep lane loop scalar (sim._lockstep_source). Exact for
    # finite voltages (one of the products is a zero); the sign of a zero may differ.
    c = 1.0 if u[_IN_CLOSED] != 0.0 else 0.0
    y[_OUT_V] = c * u[_IN_BUS] + (1.0 - c) * u[_IN_OPEN]
    y[_OUT_V + 1] = c * u[_IN_BUS + 1] + (1.0 - c) * u[_IN_OPEN + 1]
    y[_OUT_CLOSED] = c


class StatorRelay(ContinuousPart):
    """Relay between the bus and one stator: its terminal voltage is the bus voltage while closed,
    the machine's open-circuit voltage while open (the machine's ``connected`` input takes the
    same command)."""

    SOURCE = (
        "stator relay: the bus voltage while closed, the open stator's voltage while open "
        "(plant._network)"
    )

    INPUTS, OUTPUTS = RELAY_INPUTS, RELAY_OUTPUTS
    DIRECT_FROM = ("v_bus", "v_open", "closed")
    DIRECT_OUTPUTS = ("v", "closed")
    state_outputs = no_state_outputs
    direct_outputs = relay_direct_outputs
    rhs = no_rhs


COMMAND_PARAMS = Layout(real("close_at", "s", "time at which the relay closes", "nonnegative"))
COMMAND_OUTPUTS = Layout(real("closed", "", "relay command: 1 closed, 0 open"))


@jit
def relay_command_step(t, T_s, u, p, s, y):
    y[0] = 1.0 if t >= p[0] else 0.0
    return 0


class RelayCommand(SampledPart):
    """Close a relay at ``close_at`` (held from the sample at or after it; closed before the
    first sample if ``close_at`` is 0)."""

    SOURCE = "relay command at a set time (plant._network.relay_command_step)"

    PARAMS, OUTPUTS = COMMAND_PARAMS, COMMAND_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"close_at": 0.0}
    step = relay_command_step

    def held_outputs(self) -> dict:
        return {"closed": 1.0 if self.values["close_at"] == 0.0 else 0.0}


FORCED_PARAMS = Layout(
    real("close_at", "s", "time from which the relay is closed whatever its command", "nonnegative")
)
FORCED_INPUTS = Layout(real("command", "", "relay command: 1 closed, 0 open"))
FORCED_OUTPUTS = Layout(real("closed", "", "relay state: 1 closed, 0 open"))
EVENT_FORCED = 1


@jit
def forced_relay_step(t, T_s, u, p, s, y):
    if u[0] != 0.0:
        y[0] = 1.0
        return 0
    if t >= p[0]:
        y[0] = 1.0
        return EVENT_FORCED
    y[0] = 0.0
    return 0


class ForcedRelay(SampledPart):
    """A relay closed at ``close_at`` whatever its ``command`` (module docstring): closed =
    command or t >= close_at, from the sample at or after ``close_at`` (from the start if it is
    0); event ``forced`` on every sample it holds the relay closed against an open command."""

    SOURCE = "a relay closed from close_at whatever its command (plant._network)"

    PARAMS, INPUTS, OUTPUTS = FORCED_PARAMS, FORCED_INPUTS, FORCED_OUTPUTS
    EVENTS = ("forced",)
    step = forced_relay_step

    def held_outputs(self) -> dict:
        return {"closed": 1.0 if self.values["close_at"] == 0.0 else 0.0}
