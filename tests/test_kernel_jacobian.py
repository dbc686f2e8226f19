"""The linear models the analysis uses are the Jacobians of the simulated machines' kernels.

Every current-subsystem plant of ``analysis._plants.plant_from_params`` (the cage IM's
``stator_current_ss``, the PM machine's ``dq_current_ss``, the DFIM's ``dfim_rotor_current_ss``),
the DFIM's impedances and Delta Z of Bodson (11), (13) (``machines._dfim``), and the first-order
current loops the drives are designed and checked on (the DFIM's rotor current after the
decoupling of Bodson (45)-(46), the PM drive's axes after its feed-forward) are compared, entry
by entry, with the Jacobian of the machine part's compiled kernels
(``analysis._kernel_jacobian``), carried into the model's coordinates
(``analysis._kernel_plants``), at several operating points: speeds of either sign and zero,
nonzero currents, fluxes and voltages, rotor angles away from zero. The tolerance is twice the
rounding bound of ``_kernel_jacobian`` (the kernel's and the model's own rounding, both within it;
the central differences are exact for these kernels); :func:`assert_model_is_kernel` also checks
that the bound is below one part in 10^9 of the matrix's largest entry, so that a changed model
term cannot hide in it.
"""

import dataclasses
import math

import numpy as np
import pytest

from acdrive._frames import K_PEAK
from acdrive.analysis._kernel_jacobian import OPERATIONS, gamma, kernel_jacobian
from acdrive.analysis._kernel_plants import (
    cage_current_subsystem,
    dfim_rotor_current_subsystem,
    leakage_condition,
    pm_current_subsystem,
)
from acdrive.analysis._plants import MACHINES, plant_from_params
from acdrive.machines import BODSON_DFIM, DELORENZO_IM, DFIMParams, IMParams, PMSGParams
from acdrive.machines._cage_part import CageInductionMachine
from acdrive.machines._dfim import (
    delta_z_coefficients,
    impedances,
    machine_vector,
    shifted_delta_z_coefficients,
)

#: the largest part of a matrix's largest entry the rounding bound may be (module docstring)
SENSITIVITY = 1e-9

IM_MACHINES = {
    **{name: p for name, p in MACHINES.items() if isinstance(p, IMParams)},
    # two pole pairs: the part's speed input is mechanical, the model's speed electrical
    "delorenzo-im, n_p = 2": dataclasses.replace(DELORENZO_IM, n_p=2),
}
PM_MACHINES = {
    **{name: p for name, p in MACHINES.items() if isinstance(p, PMSGParams)},
    # salient (L_q = 1.6 L_d) with three pole pairs, test values: the (L_d - L_q) terms count
    "salient, n_p = 3": PMSGParams(R_s=0.02, L_d=1.1e-3, L_q=1.76e-3, psi_m=0.5, n_p=3),
}
DFIM_MACHINES = {
    **{name: p for name, p in MACHINES.items() if isinstance(p, DFIMParams)},
    "bodson-dfim, n_p = 3": dataclasses.replace(BODSON_DFIM, n_p=3),
}
W_60HZ, W_50HZ = 2.0 * math.pi * 60.0, 2.0 * math.pi * 50.0


def assert_model_is_kernel(model, kernel) -> None:
    """Each of A, B, C, D of ``model`` within twice ``kernel``'s rounding bound of the kernel's,
    the bound below ``SENSITIVITY`` of the matrix's largest entry (module docstring)."""
    for name, ours, theirs in zip("ABCD", model, (kernel.A, kernel.B, kernel.C, kernel.D),
                                  strict=True):  # fmt: skip
        bound = 2.0 * kernel.bounds[name]
        scale = max(np.max(np.abs(ours)), np.max(np.abs(theirs)))
        assert np.all(bound <= SENSITIVITY * scale) or scale == 0.0, (name, bound.max(), scale)
        miss = np.abs(ours - theirs) > bound
        assert not miss.any(), (
            f"{name} differs from the kernel's Jacobian at {np.argwhere(miss).tolist()}:\n"
            f"model\n{ours}\nkernel\n{theirs}\nbound\n{bound}"
        )


def rest_bound(kernel, x: list[complex], u: list[complex], kappa: float, constant=0.0):
    """Twice the rounding bound of ``kernel.rest`` = f(x0, u0) - A x0 - B u0 (module docstring of
    ``_kernel_jacobian``): the terms |A| |x0| + |B| |u0| + |constant|, times gamma (kappa + 1)."""
    x = np.abs([c for v in x for c in (v.real, v.imag)])
    u = np.abs([c for v in u for c in (v.real, v.imag)])
    terms = np.abs(kernel.A) @ x + np.abs(kernel.B) @ u + np.abs(constant)
    return 2.0 * gamma(OPERATIONS) * (kappa + 1.0) * terms


# --- the helper on a kernel with a known Jacobian ----------------------------------------------
def test_torque_row_is_exact_with_a_step_as_large_as_the_point():
    """tau_e = n_p (L_m / L_r) (psi_re i_im - psi_im i_re) (Amezquita-Brooks et al. (2)) is
    bilinear: the central difference with h = |z_j| is its gradient up to rounding alone."""
    p = dataclasses.replace(DELORENZO_IM, n_p=2)
    part = CageInductionMachine.from_params("machine", p)
    i_s, psi_r = 3.0 - 4.0j, 0.9 + 0.2j
    jac = kernel_jacobian(part, {"i_s": i_s, "psi_r": psi_r}, {"v_s": 50.0 + 1.0j, "w": 70.0})
    k = p.n_p * p.L_m / p.L_r
    expected = k * np.array([-psi_r.imag, psi_r.real, i_s.imag, -i_s.real])
    m, bounds, _ = jac.subsystem(("i_s", "psi_r"), ("v_s", "w"), ("tau_e",))
    np.testing.assert_allclose(m["C"][0], expected, rtol=0, atol=2.0 * bounds["C"][0].max())
    assert np.all(m["D"] == 0.0)  # the torque reads no input


# --- cage induction machine -------------------------------------------------------------------
@pytest.mark.parametrize("name", IM_MACHINES)
@pytest.mark.parametrize("w_r", [0.0, 150.0, -375.0])
@pytest.mark.parametrize(
    "point", [(1.5 - 0.7j, 0.8 + 0.3j, 120.0 - 40.0j), (-4.0 + 9.0j, -0.05 - 1.2j, -30.0 + 300.0j)]
)
def test_cage_im_plant_is_its_kernels_jacobian(name, w_r, point):
    """``plant_from_params`` of a cage IM (Amezquita-Brooks et al. (1), stationary frame) is the
    Jacobian of ``CageInductionMachine``'s kernels, and (1) has no constant term."""
    params = IM_MACHINES[name]
    kernel = cage_current_subsystem(params, w_r, *point)
    plant = plant_from_params(params, w_r)
    assert_model_is_kernel((plant.A, plant.B, plant.C, plant.D), kernel)
    i_s, psi_r, v_s = point
    kappa = leakage_condition(params.L_s, params.L_r, params.L_m)
    assert np.all(np.abs(kernel.rest) <= rest_bound(kernel, [i_s, psi_r], [v_s], kappa))


# --- permanent-magnet machine -----------------------------------------------------------------
@pytest.mark.parametrize("name", PM_MACHINES)
@pytest.mark.parametrize("w_r", [0.0, 0.37 * 2.0 * math.pi * 50.0, -2.0 * math.pi * 50.0])
@pytest.mark.parametrize(
    "point", [(1200.0 - 800.0j, 300.0 + 150.0j, 0.7), (-5.0 + 40.0j, -60.0 - 8.0j, -2.1)]
)
def test_pm_plant_is_its_kernels_jacobian(name, w_r, point):
    """``plant_from_params`` of a PM machine (Ugalde-Loo et al. (9)-(11), rotor coordinates) is
    the Jacobian of ``PermanentMagnetMachine``'s kernels fed from the stationary frame
    (v_s = v_dq e_r), and the rest is the magnet's back EMF of (7), -w_r psi_pm / L_q on the q
    axis with psi_pm = sqrt(3/2) psi_m (power-invariant scaling)."""
    params = PM_MACHINES[name]
    i_dq, v_dq, theta = point
    kernel = pm_current_subsystem(params, w_r, i_dq, v_dq, theta)
    plant = plant_from_params(params, w_r)
    assert_model_is_kernel((plant.A, plant.B, plant.C, plant.D), kernel)
    magnet = np.array([0.0, -K_PEAK * params.psi_m * w_r / params.L_q])
    bound = rest_bound(kernel, [i_dq], [v_dq], 1.0, magnet)
    assert np.all(np.abs(kernel.rest - magnet) <= bound), (kernel.rest, magnet)


# --- doubly-fed induction machine -------------------------------------------------------------
DFIM_POINTS = [
    (3.0 - 2.0j, -2.5 + 1.0j, 20.0 + 5.0j, 0.4, 0.0),
    (-0.5 + 7.0j, 4.0 + 0.3j, -3.0 - 40.0j, -1.3, 120.0 - 15.0j),
]


@pytest.mark.parametrize("name", DFIM_MACHINES)
@pytest.mark.parametrize("w_r", [0.0, 188.5, 0.9 * W_60HZ, 1.2 * W_60HZ, -300.0])
@pytest.mark.parametrize("w_e", [W_60HZ, W_50HZ])
@pytest.mark.parametrize("point", DFIM_POINTS)
def test_dfim_plant_is_its_kernels_jacobian(name, w_r, w_e, point):
    """``plant_from_params`` of a DFIM (Bodson (9)-(11): rotor currents, frame at w_e) is the
    Jacobian of ``DoublyFedMachine``'s kernels (flux linkages, stationary frame, rotor voltage in
    rotor coordinates) carried into currents in that frame, and the stator voltage, the model's
    disturbance, enters as L^-1 (v_S, 0)."""
    params = DFIM_MACHINES[name]
    i_S, i_R, v_R, theta, v_S = point
    kernel = dfim_rotor_current_subsystem(params, w_r, w_e, i_S, i_R, v_R, theta, v_S)
    plant = plant_from_params(params, w_r, w_e=w_e)
    assert_model_is_kernel((plant.A, plant.B, plant.C, plant.D), kernel)
    L = np.array([[params.L_s, params.M], [params.M, params.L_r]])
    disturbance = np.linalg.solve(L, [v_S, 0.0])
    expected = np.array([c for v in disturbance for c in (v.real, v.imag)])
    kappa = leakage_condition(params.L_s, params.L_r, params.M)
    bound = rest_bound(kernel, [i_S, i_R], [v_R], kappa, expected)
    assert np.all(np.abs(kernel.rest - expected) <= bound), (kernel.rest, expected)


def complex_matrix(real_form: np.ndarray) -> np.ndarray:
    """The complex n x n matrix of a complex-linear real 2n x 2n one ([[a, -b], [b, a]] blocks)."""
    return real_form[0::2, 0::2] + 1j * real_form[1::2, 0::2]


@pytest.mark.parametrize("name", DFIM_MACHINES)
@pytest.mark.parametrize("w_m", [0.0, 60.0, -150.0, 250.0])
@pytest.mark.parametrize("w_e", [W_60HZ, W_50HZ])
def test_dfim_impedances_and_delta_z_are_the_kernels(name, w_m, w_e):
    """Bodson (9)-(11) in the frame at w_e: L di/dt = v - Z i, so Z = -L A of the kernel's
    Jacobian, and Delta Z(s) = det(s L + Z) (13): ``impedances``, ``delta_z_coefficients`` and,
    in the stationary frame, ``shifted_delta_z_coefficients`` (15)-(16) against the kernel, at
    shaft speed ``w_m`` (so w_r = n_p w_m)."""
    params = DFIM_MACHINES[name]
    i_S, i_R, v_R, theta, v_S = DFIM_POINTS[1]
    kernel = dfim_rotor_current_subsystem(params, params.n_p * w_m, w_e, i_S, i_R, v_R, theta, v_S)
    A = kernel.A
    # complex-linear: the real form is made of [[a, -b], [b, a]] blocks
    np.testing.assert_array_less(np.abs(A[0::2, 0::2] - A[1::2, 1::2]),
                                 2.0 * kernel.bounds["A"][0::2, 0::2] + 1e-300)  # fmt: skip
    np.testing.assert_array_less(np.abs(A[1::2, 0::2] + A[0::2, 1::2]),
                                 2.0 * kernel.bounds["A"][1::2, 0::2] + 1e-300)  # fmt: skip
    L = np.array([[params.L_s, params.M], [params.M, params.L_r]])
    Z_kernel = -L @ complex_matrix(A)
    Z_bound = L @ (kernel.bounds["A"][0::2, 0::2] + kernel.bounds["A"][1::2, 0::2])
    Z_bound += gamma(OPERATIONS) * L @ np.abs(complex_matrix(A))
    Z_S, Z_MS, Z_R, Z_MR = impedances(machine_vector(params), w_e, w_m)
    Z_model = np.array([[Z_S, Z_MS], [Z_MR, Z_R]])
    assert np.all(Z_bound <= SENSITIVITY * np.abs(Z_model).max())
    assert np.all(np.abs(Z_model - Z_kernel) <= 2.0 * Z_bound), (Z_model, Z_kernel)
    coefficients, bounds = delta_z_from(params, Z_kernel, Z_bound)
    model = delta_z_coefficients(params, w_e, w_m)
    assert np.all(np.abs(model - coefficients) <= 2.0 * bounds), (model, coefficients)
    # the stationary frame (Bodson (15)-(16)): Delta Z(s - j w_e) = det(s L + Z - j w_e L)
    Z_stationary = Z_kernel - 1j * w_e * L
    Z_bound += gamma(OPERATIONS) * np.abs(Z_stationary)
    coefficients, bounds = delta_z_from(params, Z_stationary, Z_bound)
    model = shifted_delta_z_coefficients(params, w_m)
    assert np.all(np.abs(model - coefficients) <= 2.0 * bounds), (model, coefficients)


def delta_z_from(params, Z: np.ndarray, Z_bound: np.ndarray):
    """(coefficients, bounds) of det(s L + Z) = det L s^2 + (L_s Z_22 + L_r Z_11 - M (Z_21 +
    Z_12)) s + det Z (Bodson (13)), highest power first, from the impedance matrix Z with
    entrywise bounds ``Z_bound``: the bounds carried through, plus their own rounding."""
    (z11, z12), (z21, z22) = Z
    (b11, b12), (b21, b22) = Z_bound
    L_s, L_r, M = params.L_s, params.L_r, params.M
    coefficients = np.array(
        [L_s * L_r - M * M, L_s * z22 + L_r * z11 - M * (z21 + z12), z11 * z22 - z21 * z12]
    )
    carried = np.array([
        0.0,
        L_s * b22 + L_r * b11 + M * (b21 + b12),
        b11 * abs(z22) + abs(z11) * b22 + b21 * abs(z12) + abs(z21) * b12,
    ])  # fmt: skip
    terms = np.array([
        L_s * L_r + M * M,
        L_s * abs(z22) + L_r * abs(z11) + M * (abs(z21) + abs(z12)),
        abs(z11 * z22) + abs(z21 * z12),
    ])  # fmt: skip
    kappa = leakage_condition(L_s, L_r, M)
    return coefficients, carried + gamma(OPERATIONS) * (kappa + 1.0) * terms


@pytest.mark.parametrize("name", DFIM_MACHINES)
@pytest.mark.parametrize("w_m", [0.0, 60.0, -150.0, 250.0])
@pytest.mark.parametrize("point", DFIM_POINTS)
def test_dfim_rotor_current_decoupling_is_the_kernels_rotor_row(name, w_m, point):
    """Bodson (45): sigma L_R di_R/dt = v_R - u_R with u_R = Z_R i_R + Z_MR i_S + (M / L_S)
    (v_S - Z_S i_S - Z_MS i_R), sigma L_R = L_R - M^2 / L_S: the plant the rotor current PI (47)
    sees after the decoupling (46), and the first-order loop of the DFIM drive's period check
    (``drives.dfim._period``). The controller's own u_R (``control._bodson.rotor_current_loop``
    with zero PI gains and virtual resistance) against the kernel's di_R/dt in the frame at w_e."""
    from acdrive.control._bodson import SpeedController, rotor_current_loop

    params, w_e = DFIM_MACHINES[name], W_60HZ
    i_S, i_R, v_R, theta, v_S = point
    v_S = v_S or 90.0 + 25.0j  # the decoupling's stator-voltage term counts
    kernel = dfim_rotor_current_subsystem(params, params.n_p * w_m, w_e, i_S, i_R, v_R, theta, v_S)
    currents, voltage = np.array([i_S.real, i_S.imag, i_R.real, i_R.imag]), [v_R.real, v_R.imag]
    di_R = (kernel.A @ currents + kernel.B @ voltage + kernel.rest)[2:]
    windings = {n: getattr(params, n) for n in ("R_s", "R_r", "L_s", "L_r", "M", "n_p")}
    controller = SpeedController("controller", **windings, K_P=1.0, K_I=1.0, i_s_max=1e6,
                                 i_r_max=1e6, v_r_max=1e12)  # fmt: skip
    s = controller.initial_state()
    u_R, saturated = rotor_current_loop(controller.p, s, 1e-4, w_e, w_m, v_S, i_S, i_R, i_R)
    assert not saturated
    sigma_L_r = params.L_r - params.M**2 / params.L_s
    expected = (v_R - u_R) / sigma_L_r
    # rounding: the kernel's rotor row (its terms) and u_R's terms, over sigma L_R
    kappa = leakage_condition(params.L_s, params.L_r, params.M)
    Z_S, Z_MS, Z_R, Z_MR = impedances(machine_vector(params), w_e, w_m)
    u_terms = abs(Z_R * i_R) + abs(Z_MR * i_S) + params.M / params.L_s * (
        abs(v_S) + abs(Z_S * i_S) + abs(Z_MS * i_R))  # fmt: skip
    bound = rest_bound(kernel, [i_S, i_R], [v_R], kappa, kernel.rest)[2:]
    bound += 2.0 * gamma(OPERATIONS) * (kappa + 1.0) * (abs(v_R) + u_terms) / sigma_L_r
    assert np.all(np.abs(di_R - [expected.real, expected.imag]) <= bound), (di_R, expected)


@pytest.mark.parametrize("name", PM_MACHINES)
@pytest.mark.parametrize("w_r", [0.0, 0.37 * 2.0 * math.pi * 50.0, -2.0 * math.pi * 50.0])
def test_pm_drive_decoupled_axes_are_the_kernels(name, w_r):
    """The PM drive's current loop model (``drives.pm._period``, ``_design.CurrentPIGains``): with
    the cross terms and the back EMF fed forward by its controller
    (``drives.pm._control.rotor_current_step``, v_dq = v' - w_r L_q i_q + j w_r (L_d i_d +
    psi_pm)), each axis is L di/dt = v' - R_s i. The controller with zero gains and its integral
    state at v' against the kernel's di_dq/dt."""
    from acdrive.drives.pm._control import RotorFrameCurrentController

    params = PM_MACHINES[name]
    i_dq, v_axes, theta = -35.0 + 120.0j, 14.0 - 6.0j, 0.9
    estimates = {n: getattr(params, n) for n in ("R_s", "L_d", "L_q", "psi_m", "n_p")}
    controller = RotorFrameCurrentController("current", K_P_d=0.0, K_P_q=0.0, K_I_d=0.0,
                                             K_I_q=0.0, **estimates, V_dc=1e9)  # fmt: skip
    s = controller.initial_state(x=v_axes)
    i_s = i_dq * np.exp(1j * params.n_p * theta)
    u = controller.INPUTS.pack("u", {"i_dq_ref": i_dq, "i_s": i_s, "theta": theta,
                                     "w": w_r / params.n_p})  # fmt: skip
    y = np.zeros(controller.OUTPUTS.size())
    assert type(controller).step(0.0, 1e-4, u, controller.p, s, y) == 0  # within the limit
    at = controller.OUTPUTS.slot("v_dq_wanted")
    v_dq = complex(y[at], y[at + 1])
    kernel = pm_current_subsystem(params, w_r, i_dq, v_dq, theta)
    di = kernel.A @ [i_dq.real, i_dq.imag] + kernel.B @ [v_dq.real, v_dq.imag] + kernel.rest
    expected = [(v_axes.real - params.R_s * i_dq.real) / params.L_d,
                (v_axes.imag - params.R_s * i_dq.imag) / params.L_q]  # fmt: skip
    # rounding: the kernel's terms and the feed-forward's, over the inductance of each axis
    feed_forward = np.abs([w_r * params.L_q * i_dq.imag,
                           w_r * (params.L_d * i_dq.real + K_PEAK * params.psi_m)])  # fmt: skip
    bound = rest_bound(kernel, [i_dq], [v_dq], 1.0, kernel.rest)
    axes = feed_forward + np.abs([v_axes.real, v_axes.imag])
    bound += 2.0 * gamma(OPERATIONS) * 2.0 * axes / [params.L_d, params.L_q]
    assert np.all(np.abs(di - expected) <= bound), (di, expected)
