"""Printed numbers of the two ICAD papers: the targets of the reproduction report.

Every value here is a fact read from a paper (with its location), never a number acdrive
computed. ``acdrive reproduce icad`` sets each one beside the value acdrive computes from the
paper's own equations and parameters, and states why they differ where they do.

Seed 001: C. E. Ugalde-Loo et al., "Structural robustness assessment of electric machine
applications using individual channel analysis and design" ("Ugalde-Loo").
Seed 002: L. A. Amezquita-Brooks et al., "Induction motor control: multivariable analysis and
effective decentralized control of stator currents for high-performance applications"
("Amezquita-Brooks").
"""

from __future__ import annotations

from dataclasses import dataclass

UGALDE = "Ugalde-Loo"
AMEZQUITA = "Amezquita-Brooks"


@dataclass(frozen=True)
class Printed:
    """One number as printed in a paper: ``value`` [``unit``] at ``where`` (section, eq., fig.);
    ``digits``: the number as printed where its last digit is not that of ``value`` written
    out (e.g. "0.31e4": two significant digits), for the half-unit reading tolerance."""

    paper: str
    where: str
    value: float
    unit: str = ""
    text: str = ""
    digits: str = ""

    @property
    def as_printed(self) -> str:
        return self.digits or printed_text(self.value)


def printed_text(value: float) -> str:
    """A printed number written back as the paper prints it (six significant digits at most)."""
    return f"{value:.6g}"


# --- machine parameters as printed ---------------------------------------------------------

#: 2 MW PMSG, Ugalde-Loo section 3.5 (J printed as "416, 633"; read as 416 633 kg m^2).
PMSG_2MW_PRINTED = {
    "J": Printed(UGALDE, "sec. 3.5", 416633.0, "kg m^2", "printed '416, 633'; read as 416 633"),
    "n_p": Printed(UGALDE, "sec. 3.5", 2, ""),
    "f": Printed(UGALDE, "sec. 3.5", 50.0, "Hz"),
    "R_s": Printed(UGALDE, "sec. 3.5", 4.523e-3, "ohm"),
    "L_d": Printed(UGALDE, "sec. 3.5", 322e-6, "H"),
    "L_q": Printed(UGALDE, "sec. 3.5", 322e-6, "H"),
    "psi_m": Printed(UGALDE, "sec. 3.5", 1.79, "V s"),
}

#: 300 W IM, Ugalde-Loo section 4.5.
UGALDE_IM_PRINTED = {
    "J": Printed(UGALDE, "sec. 4.5", 0.000711, "kg m^2"),
    "n_p": Printed(UGALDE, "sec. 4.5", 1, ""),
    "R_s": Printed(UGALDE, "sec. 4.5", 16.19, "ohm"),
    "R_r": Printed(UGALDE, "sec. 4.5", 24.0, "ohm"),
    "L_s": Printed(UGALDE, "sec. 4.5", 1.45, "H"),
    "L_r": Printed(UGALDE, "sec. 4.5", 1.56, "H"),
    "L_m": Printed(UGALDE, "sec. 4.5", 1.45, "H"),
}

#: DeLorenzo DL10115A1 IM, Amezquita-Brooks Appendix (P = 2 poles).
DELORENZO_APPENDIX_PRINTED = {
    "R_s": Printed(AMEZQUITA, "Appendix", 16.2, "ohm"),
    "R_r": Printed(AMEZQUITA, "Appendix", 23.2, "ohm"),
    "L_s": Printed(AMEZQUITA, "Appendix", 1.44, "H"),
    "L_r": Printed(AMEZQUITA, "Appendix", 1.5, "H"),
    "L_m": Printed(AMEZQUITA, "Appendix", 1.42, "H"),
    "P": Printed(AMEZQUITA, "Appendix", 2, "poles"),
}

# --- state matrices as printed (speed-dependent entries split into constant and w slope) ----
# Each entry is (constant part, coefficient of the speed); B is diagonal-in-first-two-rows.


@dataclass(frozen=True)
class PrintedIMMatrix:
    """Printed A, B of the stationary-frame IM model: A = A0 + w_r A1 (entries by name).

    Names follow the structure of Ugalde-Loo (41) / Amezquita-Brooks (1): a11 = a22,
    a13 = a24 (L_m R_r / (sigma L_s L_r^2)), a14 = -a23 (L_m / (sigma L_s L_r), times w_r),
    a31 = a42 (L_m R_r / L_r), a33 = a44 (-R_r / L_r), a34 = -a43 (-1, times w_r),
    b (1 / (sigma L_s)).
    """

    paper: str
    where: str
    a11: float
    a13: float
    a14_per_w: float
    a31: float
    a33: float
    b: float


UGALDE_IM_MATRIX_80 = PrintedIMMatrix(UGALDE, "(80)", -359.2, 139.4, 9.0, 22.3, -15.4, 9.7)
#: C of Ugalde-Loo (80) row by row as printed: three rows, the first with three entries.
UGALDE_IM_C_80_ROWS = ((1, 0, 0), (0, 1, 0, 0), (0, 1, 0, 0))
DELORENZO_MATRIX_13 = PrintedIMMatrix(AMEZQUITA, "(13)", -359.2, 141.8, 9.2, 21.9, -15.4, 9.7)

#: PMSG A, B of Ugalde-Loo sec. 3.5: A = [[-14.0466, 2 w_gen], [-2 w_gen, -14.0466]],
#: B = 3105.59 I (speed is the *mechanical* w_gen; n_p = 2).
PMSG_A_DIAG = Printed(UGALDE, "sec. 3.5 A", -14.0466, "1/s")
PMSG_A_OFFDIAG_PER_WGEN = Printed(UGALDE, "sec. 3.5 A", 2.0, "")
PMSG_B = Printed(UGALDE, "sec. 3.5 B", 3105.59, "1/H")
#: Ugalde-Loo (34): G = 1e4 [[0.31 s + 4.36, 0.62 w], [-0.62 w, 0.31 s + 4.36]] / d(s).
PMSG_G34 = {
    "n11_s": Printed(UGALDE, "(34)", 0.31e4, digits="0.31e4"),
    "n11_0": Printed(UGALDE, "(34)", 4.36e4, digits="4.36e4"),
    "n12_per_wgen": Printed(UGALDE, "(34)", 0.62e4, digits="0.62e4"),
}
#: Ugalde-Loo (35): d(s) = s^2 + 28.0932 s + 197.31 + 4 w_gen^2.
PMSG_D35 = {
    "d_s": Printed(UGALDE, "(35)", 28.0932),
    "d_0": Printed(UGALDE, "(35)", 197.31),
    "d_wgen2": Printed(UGALDE, "(35)", 4.0),
}
#: Ugalde-Loo (36): gamma(s) = -4.14736e-7 w_gen^2 / (322 s + 4523)^2.
PMSG_MSF36 = {
    "numerator_per_wgen2": Printed(UGALDE, "(36)", -4.14736e-7),
    "den_root_s": Printed(UGALDE, "(36)", 322.0),
    "den_root_0": Printed(UGALDE, "(36)", 4523.0),
    "double_pole": Printed(UGALDE, "sec. 3.5", -14.05, "1/s"),
}

# --- closed forms and analysis figures -----------------------------------------------------

#: Amezquita-Brooks after (20): G_M,min of (19) "approx 0.75 (-2.47 dB)".
GM_MIN_PRINTED = Printed(AMEZQUITA, "(19) / text after (20)", 0.75, "", "approx 0.75 (-2.47 dB)")
GM_MIN_DB_PRINTED = Printed(AMEZQUITA, "text after (20)", -2.47, "dB")

#: Maximum speed of the design study (Amezquita-Brooks sec. V-B) [rad/s, electrical].
W_R_MAX = 375.0

#: Specifications, Amezquita-Brooks sec. V-B.
SPEC_BANDWIDTH = Printed(AMEZQUITA, "sec. V-B", 3300.0, "rad/s", "bandwidth of at least 3300 rad/s")
SPEC_GM = Printed(AMEZQUITA, "sec. V-B", 12.0, "dB", "gain margin over 12 dB")
SPEC_PM = Printed(AMEZQUITA, "sec. V-B", 50.0, "deg", "phase margin over 50 deg")
SPEC_COUPLING = Printed(AMEZQUITA, "sec. V-B", -15.0, "dB", "cross coupling below -15 dB")

#: Controller (20) = (22): 326.5 (s + 1000)/s * (s + 400)^2 / (s^2 + 100 s + 42500).
CONTROLLER_20 = {
    "gain": 326.5,
    "pi_zero": -1000.0,
    "lag_zeros": (-400.0, -400.0),
    "lag_den": (1.0, 100.0, 42500.0),  # poles -50 +/- j200
}

#: Results printed for controller (20) on the nominal machine at w_r = 375 rad/s.
NOMINAL_20 = {
    "bandwidth": Printed(AMEZQUITA, "sec. V-C", 3350.0, "rad/s", "control system bandwidth"),
    "gm_gamma_h": Printed(AMEZQUITA, "sec. V-C, Table I", 3.4, "dB", "gain margin of gamma h_j"),
    "kg_at_375": Printed(AMEZQUITA, "sec. V-C, Fig. 6", 20.0, "dB", "|k g_ii| > 20 dB near 375"),
    "coupling_peak": Printed(AMEZQUITA, "sec. V-D, Fig. 8", -20.0, "dB", "coupling at most -20 dB"),
    "pm_full": Printed(AMEZQUITA, "sec. VII, Fig. 19", 67.0, "deg", "PM of c_i with (20)"),
    "pm_inner_pi": Printed(
        AMEZQUITA, "sec. VII, Fig. 19", 80.0, "deg", "PM of c_i with PI of (22)"
    ),
    "lag_gain_at_peak": Printed(AMEZQUITA, "sec. VII", 20.0, "dB", "open-loop gain at resonance"),
}

#: Perturbed plant of Amezquita-Brooks sec. VIII: factors on the nominal parameters.
PERTURBATION_FACTORS = {"R_s": 2.0, "R_r": 2.0, "L_s": 0.6, "L_r": 0.6, "L_m": 0.59}

#: Results printed for controller (20) on the perturbed machine at w_r = 375 rad/s (Fig. 22).
PERTURBED_20 = {
    "bandwidth": Printed(AMEZQUITA, "sec. VIII, Fig. 22", 3700.0, "rad/s"),
    "pm_channel": Printed(AMEZQUITA, "sec. VIII, Fig. 22", 77.0, "deg"),
    "gm_channel": Printed(AMEZQUITA, "sec. VIII, Fig. 22", 20.0, "dB"),
    "pm_kg": Printed(AMEZQUITA, "sec. VIII, Fig. 22", 77.0, "deg"),
    "gm_kg": Printed(AMEZQUITA, "sec. VIII, Fig. 22", 27.0, "dB"),
}

#: PI comparison of Amezquita-Brooks sec. VI-D and VII.
PI_KP = 360.0
PI_KI = 9000.0
PI_PM_MIN = Printed(AMEZQUITA, "sec. VI-D", 45.0, "deg", "minimum phase margin for the PI")
PI_FAMILY_TOP_GAIN = Printed(
    AMEZQUITA, "sec. VII, Fig. 17", 20.0, "dB", "highest-gain PI reaches 20 dB around 300 rad/s"
)

#: Design-model comparison, Amezquita-Brooks sec. V-A / Fig. 4: speed for models A and B and
#: the frequency of the phase lag model B misses.
DESIGN_MODEL_SPEED = 375.0
DESIGN_MODEL_LAG_FREQ = Printed(AMEZQUITA, "sec. V-A, Fig. 4", 370.0, "rad/s")

#: Figures of the papers that the report regenerates (number -> what it shows).
FIGURES = {
    (UGALDE, "Fig. 4"): "Nyquist of gamma for the 2 MW PMSG over w_gen",
    (UGALDE, "Fig. 6"): "poles of G (eigenvalues of A) of the 300 W IM over w_r",
    (UGALDE, "Fig. 7"): "poles of gamma of the 300 W IM over w_r",
    (UGALDE, "Fig. 8"): "Nyquist of gamma of the 300 W IM over w_r",
    (AMEZQUITA, "Fig. 3"): "Nyquist of gamma of the DeLorenzo IM over w_r",
    (AMEZQUITA, "Fig. 4"): "Bode of design models A-D at w_r = 375",
    (AMEZQUITA, "Fig. 5"): "Bode of channels c_i with (20) over w_r",
    (AMEZQUITA, "Fig. 6"): "Bode of k_i g_ii with (20) over w_r",
    (AMEZQUITA, "Fig. 7"): "Nyquist of gamma and gamma h_j over w_r",
    (AMEZQUITA, "Fig. 8"): "Bode of the coupling (10) over w_r",
    (AMEZQUITA, "Fig. 9"): "Nyquist of gamma h_j under parameter perturbations at w_r = 375",
    (AMEZQUITA, "Fig. 15"): "Bode of c_i with (20) and with the PI (360, 9000) at w_r = 375",
    (AMEZQUITA, "Fig. 17"): "Bode of c_i for the PI family of equal crossover at w_r = 375",
    (AMEZQUITA, "Fig. 19"): "Bode of c_i with (20) and with its inner PI at w_r = 375",
    (AMEZQUITA, "Fig. 21"): "Nyquist of gamma of the perturbed IM over w_r",
    (AMEZQUITA, "Fig. 22"): "Bode of c_i and k_i g_ii of the perturbed IM at w_r = 375",
}
