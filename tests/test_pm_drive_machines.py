"""The published machine of the PM drive (``drives/pm/_machines.py``): its printed numbers belong
together (back-EMF constant and flux, rated current and torque), which also fixes the scaling
(peak phase current, peak flux per phase)."""

import math

import pytest

from acdrive.drives.pm import _machines as m


def test_bly171d_back_emf_constant_gives_its_flux_within_the_printed_rounding():
    w_e_per_krpm = 1000.0 * 2.0 * math.pi / 60.0 * m.BLY171D.n_p  # electrical rad/s at 1000 rpm
    psi_from_ke = m.BLY171D_KE / math.sqrt(3.0) / w_e_per_krpm  # phase peak V / (rad/s)
    assert psi_from_ke == pytest.approx(m.BLY171D.psi_m, abs=0.5e-4)  # printed to 4 decimals


def test_bly171d_rated_torque_is_its_peak_current_torque():
    tau = 1.5 * m.BLY171D.n_p * m.BLY171D.psi_m * m.BLY171D_I_RATED_PEAK
    assert tau == pytest.approx(m.BLY171D_T_RATED, rel=0.01)


# --- motulator's 2.2-kW interior PMSM: nominal values against the model ----------------------


def _ipmsm_mtpa_at_nominal_current():
    """(i_d, i_q) of the MTPA point at the nominal current, power-invariant (|i| = sqrt(3/2)
    times the phase peak sqrt(2) I_rms), and psi_f."""
    from acdrive._frames import K_PEAK
    from acdrive.drives.pm import _design as d

    p = m.IPMSM_2KW2
    psi_f = d.magnet_flux(p.psi_m)
    i_s = K_PEAK * math.sqrt(2.0) * m.IPMSM_2KW2_I_NOM
    return d.mtpa_point(psi_f, p.L_d, p.L_q, i_s), psi_f


def test_ipmsm_nominal_torque_is_its_power_at_nominal_speed():
    w_m = 2.0 * math.pi * m.IPMSM_2KW2_F_NOM / m.IPMSM_2KW2.n_p  # 1500 rpm
    assert m.IPMSM_2KW2_P_NOM / w_m == pytest.approx(m.IPMSM_2KW2_T_NOM, rel=1e-3)


def test_ipmsm_mtpa_torque_at_nominal_current_is_near_the_nominal_torque():
    from acdrive.drives.pm import _design as d

    p = m.IPMSM_2KW2
    (i_d, i_q), psi_f = _ipmsm_mtpa_at_nominal_current()
    tau = d.torque(p.n_p, psi_f, p.L_d, p.L_q, i_d, i_q)
    # 15.1 N m: the nominal current carries 8 % more than the nominal torque (``_machines``)
    assert m.IPMSM_2KW2_T_NOM < tau < 1.1 * m.IPMSM_2KW2_T_NOM
    # the same number in motulator's peak scaling: (3/2) n_p (psi_f' i_q' + (L_d - L_q) i_d' i_q')
    k = math.sqrt(1.5)
    peak = 1.5 * p.n_p * (p.psi_m * i_q / k + (p.L_d - p.L_q) * (i_d / k) * (i_q / k))
    assert peak == pytest.approx(tau, rel=1e-12)
    assert i_d < 0.0  # interior machine: MTPA uses the reluctance torque


def test_ipmsm_back_emf_and_nominal_voltage_at_75_hz():
    p = m.IPMSM_2KW2
    (i_d, i_q), psi_f = _ipmsm_mtpa_at_nominal_current()
    w_e = 2.0 * math.pi * m.IPMSM_2KW2_F_NOM
    # power-invariant |v| equals the line-to-line rms value: |v| = sqrt(3/2) sqrt(2) V_ph,rms
    emf = w_e * psi_f
    # the line rms of the phase peak w_e psi_m: sqrt(3) / sqrt(2) w_e psi_m = 314.5 V
    assert emf == pytest.approx(math.sqrt(1.5) * w_e * p.psi_m, rel=1e-12)
    assert emf < 0.9 * m.IPMSM_2KW2_U_NOM  # no load: 15 % below the nominal 370 V
    v = complex(p.R_s * i_d - w_e * p.L_q * i_q, p.R_s * i_q + w_e * (p.L_d * i_d + psi_f))
    assert abs(v) == pytest.approx(m.IPMSM_2KW2_U_NOM, rel=0.01)  # 368.4 V at nominal load
    # and the DC link's linear range V_dc / sqrt(2) = 381.8 V holds it
    assert abs(v) < m.IPMSM_2KW2_V_DC / math.sqrt(2.0)
