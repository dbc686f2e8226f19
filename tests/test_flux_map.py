"""2-D table parameters and the synchronous machine with a flux map (machines._flux_map_part).

* a 2-D table is packed with its axes and values checked (one line naming the field), read
  bilinearly and clamped at the grid's edges by the kernel helper, and its C gives numba's bits;
* a map of the linear model reproduces the linear machine to rounding (bilinear is exact on a
  linear map); a map of the algebraic saturation model on a grid reproduces its run within the
  bilinear interpolation bound of the grid's second differences;
* a map that does not increase along its axes is refused naming the point, a non-reciprocal one
  warns naming the worst node; a map written to CSV and read back runs the same, and SyR-e's
  .mat layout reads as the same map.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_synchronous_machine import SERVO, assert_fmu_pair_runs_as_the_loop, linear_from

from acdrive._frames import K_PEAK
from acdrive._jit import jit
from acdrive.control._open_loop import VoltageProgram
from acdrive.core import Layout, Table2D, real, table, table2d, table2d_at, table2d_offset
from acdrive.errors import InputError, Notice
from acdrive.machines import (
    SYRM_6_7KW,
    FluxMap,
    FluxMapSynchronousMachine,
    SynchronousMachine,
    read_flux_map_csv,
    read_syre_mat,
    write_flux_map_csv,
)
from acdrive.machines._flux_map import CSV_STAMP
from acdrive.machines._synchronous_part import magnetic_currents
from acdrive.plant._mechanics import Shaft
from acdrive.sim import System, _native

# --- the 2-D table kind -------------------------------------------------------------------------
LAYOUT = Layout(real("k", "", "a gain"), table("r", "", "a profile"),
                table2d("g", "A", "a map"), table2d("h", "A", "another map"))  # fmt: skip
GRID = Table2D([0.0, 1.0, 3.0], [-1.0, 2.0], [[1.0, 2.0], [3.0, 5.0], [4.0, 0.0]])


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ({"x": [0.0, 1.0], "y": [0.0, 1.0]}, r"^t\.g\.values: must be given"),
        (Table2D([0.0, 0.0], [0.0, 1.0], [[1, 2], [3, 4]]), r"^t\.g\.x: must be strictly incr"),
        (Table2D([0.0, 1.0], [0.0, np.nan], [[1, 2], [3, 4]]), r"^t\.g\.y: must be finite"),
        (Table2D([0.0], [0.0, 1.0], [[1, 2]]), r"^t\.g\.x: must be a list of at least 2"),
        (Table2D([0.0, 1.0], [0.0, 1.0], [[1, 2, 3], [3, 4, 5]]),
         r"^t\.g\.values: must have len\(x\) = 2 rows of len\(y\) = 2 values, got shape \(2, 3\)"),
        (Table2D([0.0, 1.0], [0.0, 1.0], [[1, 2], [np.inf, 4]]),
         r"^t\.g\.values: must be finite, got inf at row 1, column 0"),
        (3.0, r"^t\.g: must be Table2D\(x, y, values\)"),
    ],
)  # fmt: skip
def test_a_malformed_2d_table_is_refused_naming_the_field(value, message):
    with pytest.raises(InputError, match=message) as caught:
        LAYOUT.pack("t", {"k": 1.0, "r": 0.0, "g": value, "h": GRID})
    assert "\n" not in str(caught.value)


def test_a_2d_table_comes_after_every_table():
    with pytest.raises(ValueError, match="2-D tables must come after every table"):
        Layout(table2d("g", "", "a map"), table("r", "", "a profile"))


@jit
def _second_table_at(p, x, y):
    return table2d_at(p, table2d_offset(p, 8, 1), x, y)  # after k and a 3-point profile r


def test_the_kernel_reads_a_2d_table_bilinearly_and_clamps_it_at_the_edges():
    """A table of the linear function 2 + 3x - y + 0.5xy (bilinear reproduces it exactly),
    stored after a profile and another 2-D table, read by the kernel helper: the function inside
    the grid, the edge's value outside (each coordinate clamped to its axis)."""
    x, y = np.array([-1.0, 0.5, 2.0, 4.0]), np.array([0.0, 1.0, 3.0])
    f = lambda a, b: 2.0 + 3.0 * a - b + 0.5 * a * b  # noqa: E731
    p = LAYOUT.pack("t", {"k": 1.0, "r": [[0.0, 1.0], [1.0, 2.0], [2.0, 0.0]], "g": GRID,
                          "h": Table2D(x, y, f(x[:, None], y[None, :]))})  # fmt: skip
    assert LAYOUT.table_start + 1 + 2 * 3 == 8
    for a, b in [(0.0, 0.5), (-1.0, 3.0), (3.9, 2.2), (1.7, 0.0)]:
        assert _second_table_at(p, a, b) == pytest.approx(f(a, b), rel=1e-14, abs=1e-14)
    for (a, b), (ca, cb) in {(-5.0, 0.5): (-1.0, 0.5), (9.0, -2.0): (4.0, 0.0),
                             (1.0, 7.0): (1.0, 3.0)}.items():  # fmt: skip
        assert _second_table_at(p, a, b) == pytest.approx(f(ca, cb), rel=1e-14)


def test_describe_shows_a_2d_table():
    part = FluxMapSynchronousMachine("fm", R_s=1.0, n_p=2, i_d=GRID, i_q=GRID)
    text = str(part.describe())
    assert "2-D table, 3 x 2 points, x 0..3, y -1..2" in text


# --- flux maps of the built-in models ---------------------------------------------------------
def flux_map_of(machine: SynchronousMachine, i_d, i_q) -> FluxMap:
    """The flux map of ``machine``'s magnetic model on the current grid i_d x i_q."""
    return FluxMap.of_currents(lambda a, b: magnetic_currents(machine.p, a, b), i_d, i_q)


def vf_run(machine, J, duration=0.06):
    """An open-loop V/f program into ``machine`` on a free shaft (test_synchronous_machine's)."""
    shaft = Shaft("shaft", J=J, B=1e-4)
    program = VoltageProgram("program", V_pk=[[0.0, 5.0], [0.05, 60.0]],
                             f=[[0.0, 1.0], [0.05, 20.0]])  # fmt: skip
    wires = [(program.out.v_ref, machine.inp.v_s), (shaft.out.w, machine.inp.w),
             (machine.out.tau_e, shaft.inp.tau_e)]  # fmt: skip
    return System([machine, shaft, program], wires)


def run_of(machine, J):
    return vf_run(machine, J).compile().run(
        0.06, 1e-4, 2, log=[machine.out.i_dq, machine.out.psi_dq, machine.out.tau_e]
    )


def test_a_map_of_the_linear_model_runs_as_the_linear_model():
    """Bilinear interpolation is exact on a linear map and Newton's inversion of it is exact:
    currents, fluxes and torque of the run agree to rounding."""
    linear = linear_from(SERVO)
    grid = np.linspace(-150.0, 150.0, 7)
    machine = FluxMapSynchronousMachine.from_flux_map(
        "sm", flux_map_of(linear, grid, grid), R_s=SERVO.R_s, n_p=SERVO.n_p
    )
    reference, run = run_of(linear, 2e-4), run_of(machine, 2e-4)
    i_dq = reference.signal(linear.out.i_dq)
    assert np.max(np.abs(i_dq)) > 10.0
    assert np.max(np.abs(i_dq)) < 150.0  # the run stays inside the map
    for name in ("i_dq", "psi_dq", "tau_e"):
        a = reference.signal(getattr(linear.out, name))
        b = run.signal(getattr(machine.out, name))
        assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(a)), name


def test_a_map_of_the_algebraic_model_runs_as_it_within_the_interpolation_bound():
    """The 6.7-kW SyRM's saturation model as a map on a 41 x 41 current grid, inverted onto a
    41 x 41 flux grid: the run's currents stay within twice the bilinear interpolation bound
    (h_x^2 max|f_xx| + h_y^2 max|f_yy|) / 8 of the flux tables, estimated by their second
    differences (two interpolations: of the current-grid map, inverted, and of the flux tables)."""
    syrm = SynchronousMachine.from_params("sm", SYRM_6_7KW)
    grid = np.linspace(-80.0, 80.0, 41)
    machine = FluxMapSynchronousMachine.from_flux_map(
        "sm", flux_map_of(syrm, grid, grid), R_s=SYRM_6_7KW.R_s, n_p=SYRM_6_7KW.n_p
    )
    bound = 0.0
    for t in machine.tables():
        along_d = np.abs(np.diff(t.values, 2, axis=0)).max()
        along_q = np.abs(np.diff(t.values, 2, axis=1)).max()
        bound = max(bound, (along_d + along_q) / 8.0)
    reference, run = run_of(syrm, SYRM_6_7KW.J), run_of(machine, SYRM_6_7KW.J)
    i_ref = reference.signal(syrm.out.i_dq)
    assert 30.0 < np.max(np.abs(i_ref)) < 80.0  # saturating, inside the map
    error = np.max(np.abs(run.signal(machine.out.i_dq) - i_ref))
    assert error <= 2.0 * bound, (error, bound)
    assert bound < 0.02 * np.max(np.abs(i_ref))


@pytest.mark.skipif(_native.compiler() is None, reason="no C compiler on this machine")
def test_native_loop_equals_numba_bit_for_bit(monkeypatch):
    """The C of the flux-map machine (its 2-D tables read by acd_table2d_at) runs the loop to
    numba's bits."""
    syrm = SynchronousMachine.from_params("sm", SYRM_6_7KW)
    grid = np.linspace(-30.0, 30.0, 9)  # the run leaves this grid: the clamped edges count too
    machine = FluxMapSynchronousMachine.from_flux_map(
        "sm", flux_map_of(syrm, grid, grid), R_s=SYRM_6_7KW.R_s, n_p=SYRM_6_7KW.n_p
    )
    system = vf_run(machine, SYRM_6_7KW.J)
    runs = {}
    for tier in ("native", "specialised"):
        monkeypatch.setenv("ACDRIVE_LOOP_TIER", tier)
        compiled = system.compile()
        assert compiled.tier == tier
        runs[tier] = compiled.run(0.06, 1e-4, 2, log=[machine.out.i_dq, machine.out.psi_dq])
    psi = runs["native"].signal(machine.out.psi_dq)
    t_d, _ = machine.tables()
    assert np.max(np.abs(psi.imag)) > t_d.y[-1]  # the clamped region is visited
    assert np.array_equal(runs["native"].data, runs["specialised"].data)


# --- checks ---------------------------------------------------------------------------------
def linear_map(i_d, i_q, L_d=5e-3, L_q=2e-3, psi_pm=0.1):
    d, q = np.meshgrid(i_d, i_q, indexing="ij")
    return d, q, L_d * d + psi_pm, L_q * q


def test_a_map_that_does_not_increase_is_refused_naming_the_point():
    grid = np.linspace(-10.0, 10.0, 11)
    _, _, psi_d, psi_q = linear_map(grid, grid)
    psi_d[6, 3] = psi_d[5, 3] - 0.01
    with pytest.raises(InputError, match=(
            r"^flux_map\.psi_d: must increase with i_d .* between \(i_d, i_q\) = \(0, -4\) A "
            r"and \(2, -4\) A$")):  # fmt: skip
        FluxMap(grid, grid, psi_d, psi_q)


def test_a_map_that_folds_is_refused_naming_the_point():
    """Each flux increases along its own axis but the cross-coupling turns the map over:
    in the cell from (i_d, i_q) = (8, 8) A to (10, 10) A, d psi_d/d i_d d psi_q/d i_q =
    5e-3 * 2e-3 < d psi_d/d i_q d psi_q/d i_d = 4e-3 * 4e-3: det(d psi / d i) < 0 at each of its
    corners, the first one, (8, 8) A, named."""
    grid = np.linspace(0.0, 10.0, 6)
    d, q, psi_d, psi_q = linear_map(grid, grid)
    psi_d = psi_d + 4e-3 * q * (d >= 8.0)  # d psi_d/d i_q = 4e-3 only in the last column
    psi_q = psi_q + 4e-3 * d * (q >= 8.0)
    with pytest.raises(InputError, match=(r"^flux_map: is not invertible at \(i_d, i_q\) = "
                                          r"\(8, 8\) A: .* determinant -6e-06")):  # fmt: skip
        FluxMap(grid, grid, psi_d, psi_q)


def test_a_non_reciprocal_map_warns_naming_the_worst_node():
    """psi_d = L_d i_d + psi_pm + M i_q i_d^2 / 100, psi_q = L_q i_q: d psi_d/d i_q = M i_d^2 / 100
    against d psi_q/d i_d = 0, relative to d psi_d/d i_d = L_d + 2 M i_q i_d / 100, largest at
    (i_d, i_q) = (-10, 10)."""
    i_d, i_q = np.linspace(-10.0, 10.0, 21), np.linspace(0.0, 10.0, 11)
    d, q, psi_d, psi_q = linear_map(i_d, i_q)
    with pytest.warns(Notice, match=r"at \(i_d, i_q\) = \(-10, 10\) A, the worst node"):
        FluxMap(i_d, i_q, psi_d + 1e-3 * q * d**2 / 100.0, psi_q)


def test_a_reciprocal_map_does_not_warn(recwarn):
    grid = np.linspace(-10.0, 10.0, 5)
    FluxMap(grid, grid, *linear_map(grid, grid)[2:])
    assert not [w for w in recwarn if issubclass(w.category, Notice)]


# --- files ------------------------------------------------------------------------------------
@pytest.mark.parametrize("scaling", ["power-invariant", "peak"])
def test_a_map_written_to_csv_and_read_back_runs_the_same(tmp_path, scaling):
    syrm = SynchronousMachine.from_params("sm", SYRM_6_7KW)
    grid = np.linspace(-60.0, 60.0, 9)
    flux_map = flux_map_of(syrm, grid, grid)
    path = write_flux_map_csv(flux_map, tmp_path / "map.csv", scaling=scaling)
    assert path.read_text().splitlines()[:3] == [
        f"# scaling: {scaling}", CSV_STAMP, "i_d [A],i_q [A],psi_d [Wb],psi_q [Wb]"]  # fmt: skip
    back = read_flux_map_csv(path)
    for name in ("i_d", "i_q", "psi_d", "psi_q"):
        assert np.allclose(getattr(back, name), getattr(flux_map, name), rtol=1e-15, atol=0), name
    machines = [FluxMapSynchronousMachine.from_flux_map("sm", m, R_s=0.54, n_p=2)
                for m in (flux_map, back)]  # fmt: skip
    runs = [run_of(m, SYRM_6_7KW.J) for m in machines]
    a, b = (r.signal(m.out.i_dq) for r, m in zip(runs, machines, strict=True))
    if scaling == "power-invariant":
        assert np.array_equal(a, b)
    else:  # / K on writing and * K on reading may each round the last bit
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(a))


def test_a_csv_with_a_missing_point_is_refused_naming_it(tmp_path):
    grid = np.linspace(-10.0, 10.0, 3)
    path = write_flux_map_csv(FluxMap(grid, grid, *linear_map(grid, grid)[2:]), tmp_path / "m.csv")
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines[:-1]) + "\n")
    with pytest.raises(InputError, match=(r"every grid point once: \(i_d, i_q\) = \(10, 10\) "
                                          r"A is there not at all")):  # fmt: skip
        read_flux_map_csv(path)
    path.write_text("\n".join(["# scaling: rms", *lines[1:]]))
    with pytest.raises(InputError, match=r"m\.csv:1: must be '# scaling: peak or power-invariant'"):
        read_flux_map_csv(path)


def test_syre_mat_layout_reads_as_the_peak_valued_map(tmp_path):
    """SyR-e's fdfq_idiq file: Id, Iq, Fd, Fq on meshgrid(id, iq) (rows along i_q), peak-valued."""
    from scipy.io import savemat

    i_d, i_q = np.linspace(-10.0, 10.0, 5), np.linspace(0.0, 20.0, 3)
    Id, Iq = np.meshgrid(i_d, i_q)
    savemat(tmp_path / "fdfq_idiq_n256.mat",
            {"Id": Id, "Iq": Iq, "Fd": 5e-3 * Id + 0.1, "Fq": 2e-3 * Iq})  # fmt: skip
    flux_map = read_syre_mat(tmp_path / "fdfq_idiq_n256.mat")
    assert np.allclose(flux_map.i_d, K_PEAK * i_d) and np.allclose(flux_map.i_q, K_PEAK * i_q)
    d, q = np.meshgrid(flux_map.i_d, flux_map.i_q, indexing="ij")
    assert np.allclose(flux_map.psi_d, 5e-3 * d + K_PEAK * 0.1)
    assert np.allclose(flux_map.psi_q, 2e-3 * q)


# --- FMUs ---------------------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.skipif(_native.compiler() is None, reason="no C compiler on this machine")
def test_the_flux_map_machine_runs_in_a_plant_fmu_as_in_the_loop(monkeypatch, tmp_path):
    """The V/f program as a controller FMU and the flux-map SyRM (its 2-D tables written into
    the plant's C) with its shaft as a plant FMU, stepped by a Gauss-Seidel master: the loop's
    run to 1e-9."""
    T_s, duration = 1e-4, 0.06
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "native")
    grid = np.linspace(-80.0, 80.0, 9)
    syrm = FluxMapSynchronousMachine.from_flux_map(
        "syrm", flux_map_of(SynchronousMachine.from_params("sm", SYRM_6_7KW), grid, grid),
        R_s=SYRM_6_7KW.R_s, n_p=SYRM_6_7KW.n_p,
    )
    system = vf_run(syrm, SYRM_6_7KW.J)
    shaft = next(p for p in system.parts if p.name == "shaft")
    assert_fmu_pair_runs_as_the_loop(system, syrm, shaft, T_s, duration, tmp_path,
                                     "flux-map SyRM")  # fmt: skip


def test_writing_a_map_replaces_only_a_map_acdrive_wrote(tmp_path):
    """A user's file at the path is refused naming ``path`` and left as it was; a map file the
    writer wrote is replaced; the written file reads back with its stamp line as a comment."""
    grid = np.linspace(-10.0, 10.0, 3)
    flux_map = FluxMap(grid, grid, *linear_map(grid, grid)[2:])
    users = tmp_path / "mine.csv"
    users.write_text("my own measurements\n")
    with pytest.raises(InputError, match="^path: .*acdrive did not write it"):
        write_flux_map_csv(flux_map, users)
    assert users.read_text() == "my own measurements\n"
    ours = write_flux_map_csv(flux_map, tmp_path / "map.csv")
    write_flux_map_csv(flux_map, ours, scaling="peak")
    assert ours.read_text().startswith("# scaling: peak\n# Generated by acdrive")
    back = read_flux_map_csv(ours)
    assert np.allclose(back.psi_d, flux_map.psi_d, rtol=1e-15, atol=0)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.csv", "mine.csv"]
