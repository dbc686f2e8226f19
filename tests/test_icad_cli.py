"""``acdrive icad``: JSON report, sweep figures, exit code 2 on bad input."""

import json
import math

import pytest

from acdrive.analysis import gm_min, plant_for
from acdrive.analysis._icad import analyse, controller_for
from acdrive.cli import main
from acdrive.machines import DELORENZO_IM

KEYS = {
    "conditions",
    "gm_min_db",
    "crossover_rad_s",
    "pm_deg",
    "gm_db",
    "structural_gm_db",
    "coupling_peak_db",
}


def run_json(capsys, *argv):
    code = main(["icad", *argv, "--json"])
    out = capsys.readouterr().out
    return code, json.loads(out)


@pytest.mark.slow
def test_single_speed_json_keys_and_values(capsys):
    code, report = run_json(capsys, "delorenzo-im", "--speed", "375")
    assert code == 0
    assert KEYS <= set(report)
    assert set(report["conditions"]) == {"i", "ii", "iii", "iv"}
    assert all(isinstance(v, bool) for v in report["conditions"].values())
    assert report["controller"] == "paper-20"  # default for an IM
    assert report["gm_min_db"] == pytest.approx(20 * math.log10(gm_min(DELORENZO_IM)))
    k = controller_for("paper-20")
    a = analyse(plant_for("delorenzo-im", 375.0), k, k)
    assert report["pm_deg"] == pytest.approx(min(ch.margins.pm_deg for ch in a.channels))
    assert report["structural_gm_db"] == pytest.approx(a.structural.gm_db)


def test_pmsg_defaults_to_imc_pi_and_has_no_gm_min(capsys):
    code, report = run_json(capsys, "pmsg-2mw", "--speed", "100", "--controller", "imc-pi")
    assert code == 0 and report["controller"] == "imc-pi"
    assert report["gm_min_db"] is None  # (19) is an IM result
    assert report["conditions"] == {"i": True, "ii": True, "iii": True, "iv": True}


@pytest.mark.parametrize(
    "argv",
    [
        ["icad", "delorenzo-im", "--speed", "nan"],
        ["icad", "no-such-machine", "--speed", "1"],
        ["icad", "delorenzo-im", "--speed", "1", "--controller", "nope"],
        ["icad", "delorenzo-im"],  # neither --speed nor --sweep
        ["icad", "pmsg-2mw", "--speed", "1", "--controller", "imc-pi", "--bandwidth", "-5"],
        ["icad", "delorenzo-im", "--sweep", "--speeds", "0", "375", "0"],
    ],
)
def test_bad_input_exits_2(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        raise SystemExit(main(argv))
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("acdrive: error:") and err.count("\n") == 1


@pytest.mark.slow
def test_sweep_writes_figures(tmp_path, capsys):
    out = tmp_path / "figs"
    code, report = run_json(
        capsys,
        "ugalde-im-300w",
        "--sweep",
        "--speeds",
        "0",
        "375",
        "2",
        "--out",
        str(out),
        "--no-verify",
    )
    assert code == 0
    names = {p.split("/")[-1] for p in report["figures"]}
    assert {
        "nyquist_gamma.png",
        "nyquist_gamma_h.png",
        "bode_channels.png",
        "pole_map.png",
    } <= names
    for path in report["figures"]:
        assert (out / path.split("/")[-1]).stat().st_size > 1000
    assert report["all_conditions"] is True
