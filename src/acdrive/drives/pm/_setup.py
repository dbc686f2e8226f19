"""The setup of one PM speed-drive run: machine, converter, controller design, profiles, run.

Every field is checked on construction (``InputError`` naming the field and the rule), before any
part is built, and so is the current loop against the control period (``drives.pm._period``). Currents are given as phase PEAK amperes (what a datasheet gives); the parts work
with space vectors, |i| = sqrt(3/2) I_pk (``acdrive._frames.K_PEAK``).
"""

from __future__ import annotations

from dataclasses import dataclass

from acdrive._frames import K_PEAK
from acdrive.core._signals import pack_table
from acdrive.drives.pm._design import (
    base_speed,
    magnet_flux,
    mtpa_torque,
    require_salient_or_round,
    voltage_bound_speed,
)
from acdrive.drives.pm._period import check_current_period
from acdrive.drives.pm._size import check_run_size
from acdrive.errors import InputError, require_between, require_nonnegative, require_positive
from acdrive.machines._pmsm import PMSGParams
from acdrive.plant._inverter import _N_TOLERANCE as CARRIER_RTOL
from acdrive.plant._sensors import check_counts_per_rev

CONVERTERS = ("averaged", "switching")


@dataclass(frozen=True)
class PMDriveSetup:
    """One PM speed-drive run.

    machine: the plant (``machines.PMSGParams``; its J is the rotor's); estimates: the
    controller's values (default: the plant's); J: inertia of rotor and load [kg m^2] (default
    machine.J); B: viscous friction [N m s/rad]; converter: "averaged" (the command held over the
    sample, ``plant.AveragedConverter``) or "switching" (``plant.Inverter``, centred SVPWM at
    f_pwm, the sample time dividing its period); V_dc [V]; i_max_peak: current limit, phase peak
    [A]; tau_max: the speed controller's torque limit [N m] (default: the MTPA torque at
    i_max_peak); voltage_margin: fraction of V_dc / sqrt(2) the references may use;
    current_bandwidth, speed_bandwidth [rad/s]: the design bandwidths (``_design``); K_F: the
    speed PI's reference weight (Bodson (25)); speed_reference [rad/s] and load [N m]: profiles
    (a number, or a list of [time_s, value] points); encoder_counts (0: ideal), encoder_offset
    [rad]; duration, sample_time [s], substeps per segment, log_every; design_J: the inertia the
    speed PI is designed on (``control.SpeedPIGains.design``) [kg m^2] (default J: the design
    on the simulated shaft; a ``[design]`` table's or a perturbed shaft's nominal J otherwise).
    """

    machine: PMSGParams
    V_dc: float
    i_max_peak: float
    speed_reference: object
    duration: float
    sample_time: float
    current_bandwidth: float
    speed_bandwidth: float
    name: str = "pm-speed"
    estimates: PMSGParams | None = None
    J: float | None = None
    B: float = 0.0
    load: object = 0.0
    converter: str = "averaged"
    f_pwm: float | None = None
    tau_max: float | None = None
    voltage_margin: float = 0.9
    K_F: float = 1.0
    encoder_counts: float = 0.0
    encoder_offset: float = 0.0
    substeps: int = 4
    log_every: int = 1
    design_J: float | None = None

    def __post_init__(self):
        if not isinstance(self.machine, PMSGParams):
            raise InputError("machine", "must be a machines.PMSGParams")
        if self.estimates is not None and not isinstance(self.estimates, PMSGParams):
            raise InputError("estimates", "must be a machines.PMSGParams or None")
        est = self.controller_machine
        require_salient_or_round("estimates.L_q", est.L_d, est.L_q)
        for name in ("V_dc", "i_max_peak", "duration", "sample_time", "current_bandwidth",
                     "speed_bandwidth"):  # fmt: skip
            object.__setattr__(self, name, require_positive(name, getattr(self, name)))
        J = self.J if self.J is not None else self.machine.J
        if J is None:
            raise InputError("J", "must be given (the machine record has no J)")
        object.__setattr__(self, "J", require_positive("J", J))
        object.__setattr__(self, "B", require_nonnegative("B", self.B))
        if self.design_J is not None:
            object.__setattr__(self, "design_J", require_positive("design_J", self.design_J))
        if self.converter not in CONVERTERS:
            raise InputError("converter", f"must be one of {', '.join(CONVERTERS)}")
        if self.converter == "switching":
            if self.f_pwm is None:
                raise InputError("f_pwm", "must be given for the switching converter")
            object.__setattr__(self, "f_pwm", require_positive("f_pwm", self.f_pwm))
            self._check_carrier()
        if self.tau_max is not None:
            object.__setattr__(self, "tau_max", require_positive("tau_max", self.tau_max))
        object.__setattr__(
            self, "voltage_margin", require_between("voltage_margin", self.voltage_margin, 0.0, 1.0)
        )
        if self.voltage_margin == 0.0:
            raise InputError("voltage_margin", "must be > 0")
        object.__setattr__(self, "K_F", require_between("K_F", self.K_F, 0.0, 1.0))
        object.__setattr__(
            self, "encoder_counts", check_counts_per_rev("encoder_counts", self.encoder_counts)
        )
        pack_table("speed_reference", self.speed_reference)
        pack_table("load", self.load)
        for name in ("substeps", "log_every"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InputError(name, "must be an integer >= 1")
        check_run_size(self.duration, self.sample_time, self.substeps, self.log_every)
        budget = self.voltage_margin * self.V_dc / 2**0.5 - est.R_s * self.i_max
        if budget <= 0.0:
            raise InputError(
                "voltage_margin", "voltage_margin V_dc / sqrt(2) must exceed R_s times the "
                f"current limit (the resistive drop at full current, {est.R_s * self.i_max:g} V)"
            )  # fmt: skip
        check_current_period(self)

    def _check_carrier(self) -> None:
        """The switching converter's carrier period 1 / f_pwm is the sample time times a whole
        number N >= 1 (``plant.Inverter.check_sample_time``, the same tolerance), checked here
        on ``f_pwm`` before any part is built."""
        ratio = 1.0 / (self.f_pwm * self.sample_time)
        n = round(ratio)
        if n < 1 or abs(ratio - n) > CARRIER_RTOL * ratio:
            raise InputError(
                "f_pwm", f"the carrier period 1 / f = {1.0 / self.f_pwm:g} s must be the "
                f"sample time {self.sample_time:g} s times a whole number >= 1, got "
                f"{ratio:.6g} (at most {1.0 / self.sample_time:g} Hz at this sample time)"
            )  # fmt: skip

    @property
    def controller_machine(self) -> PMSGParams:
        """The machine the controller is designed for (``estimates``, else the plant)."""
        return self.estimates if self.estimates is not None else self.machine

    @property
    def speed_design_J(self) -> float:
        """The inertia the speed PI is designed on [kg m^2]: design_J, else J."""
        return self.design_J if self.design_J is not None else self.J

    @property
    def i_max(self) -> float:
        """Current limit as a space-vector magnitude [A]: sqrt(3/2) i_max_peak."""
        return K_PEAK * self.i_max_peak

    @property
    def torque_limit(self) -> float:
        """The speed controller's torque limit [N m]: tau_max, else the MTPA torque at i_max."""
        if self.tau_max is not None:
            return self.tau_max
        m = self.controller_machine
        return float(mtpa_torque(m.n_p, magnet_flux(m.psi_m), m.L_d, m.L_q, self.i_max))

    @property
    def base_speed(self) -> float:
        """The machine's base speed [rad/s, mechanical] for the controller's machine at this
        current limit, DC link and voltage margin: ``_design.base_speed`` (the steady-state voltage
        of the MTPA point of full current reaches margin V_dc / sqrt(2))."""
        return self._at_full_current(base_speed)

    @property
    def voltage_bound_speed(self) -> float:
        """Speed [rad/s, mechanical] above which the references leave MTPA at full current:
        ``_design.voltage_bound_speed``, the drive's conservative voltage bound (V), a little
        below ``base_speed``."""
        return self._at_full_current(voltage_bound_speed)

    def _at_full_current(self, speed_of) -> float:
        m = self.controller_machine
        v_max = self.V_dc / 2**0.5
        return speed_of(m.R_s, m.L_d, m.L_q, magnet_flux(m.psi_m), m.n_p, self.i_max, v_max,
                        self.voltage_margin)  # fmt: skip

    @property
    def carrier_samples(self) -> int:
        """Control samples per carrier period (1 for the averaged converter)."""
        if self.converter != "switching":
            return 1
        return max(1, round(1.0 / (self.f_pwm * self.sample_time)))
