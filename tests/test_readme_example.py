"""The README is a front page: short, its links lead somewhere, and its own-PMSM scenario runs
with ``acdrive run FILE`` and from Python as printed, and does what a speed drive must."""

import json
import re
import tomllib
from pathlib import Path

import pytest

from acdrive.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
#: the README's own bound: a front page, the reference material in docs/
MAX_LINES = 130


def _section(title: str) -> str:
    text = README.read_text()
    start = text.index(f"## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start : end if end > 0 else None]


def _block(title: str, language: str) -> str:
    return re.search(rf"```{language}\n(.*?)```", _section(title), re.DOTALL).group(1)


def test_readme_stays_a_front_page():
    assert len(README.read_text().splitlines()) <= MAX_LINES


def test_every_relative_link_and_picture_of_the_readme_exists():
    targets = re.findall(r"\]\(([^)#\s]+)\)", README.read_text())
    local = [t for t in targets if "://" not in t]
    assert len(local) >= 10  # the links are really read
    missing = [t for t in local if not (ROOT / t).exists()]
    assert not missing, missing


def test_the_pmsm_example_is_the_datasheet_machine_it_names():
    """The README says its numbers are the Anaheim BLY171D's: the catalog's record (its source
    and checks in acdrive.machines._pm_catalog)."""
    from acdrive.machines._pm_catalog import BLY171D, BLY171D_I_RATED_PEAK, BLY171D_V_DC

    scenario = tomllib.loads(_block("Your own PMSM", "toml"))
    params = scenario["machine"]["params"]
    assert {k: params[k] for k in ("R_s", "L_d", "L_q", "psi_m", "n_p", "J")} == {
        "R_s": BLY171D.R_s, "L_d": BLY171D.L_d, "L_q": BLY171D.L_q, "psi_m": BLY171D.psi_m,
        "n_p": BLY171D.n_p, "J": BLY171D.J,
    }  # fmt: skip
    assert scenario["control"]["current_limit_pk_a"] == BLY171D_I_RATED_PEAK
    assert scenario["converter"]["dc_link_voltage"] == BLY171D_V_DC


def test_the_pmsm_example_runs_and_holds_its_speed_against_its_load(tmp_path, monkeypatch,
                                                                    capsys):
    """``acdrive run my-pmsm.toml`` as the README says, then the README's Python call on the same
    file. At the end the speed is the reference and the electrical torque carries the load
    (no friction given: the shaft's balance at constant speed), within the current limit."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my-pmsm.toml").write_text(_block("Your own PMSM", "toml"))
    scenario = tomllib.loads((tmp_path / "my-pmsm.toml").read_text())
    assert main(["run", "my-pmsm.toml", "--no-figures"]) == 0
    summary = json.loads((tmp_path / "acdrive-out" / "my-pmsm" / "summary.json").read_text())
    reference = scenario["reference"]["speed_rad_s"]
    load = scenario["machine"]["load_torque"]
    limit = scenario["control"]["current_limit_pk_a"]
    assert summary["speed_final_rad_s"] == pytest.approx(reference, rel=1e-3)
    assert summary["torque_final_n_m"] == pytest.approx(load, rel=1e-2)
    assert summary["current_peak_a"] <= limit * 1.001
    assert "base speed" in capsys.readouterr().out  # the headline the README describes

    scope: dict = {}
    code = _block("Your own PMSM", "python")
    exec(compile(code, "README.md", "exec"), scope)  # noqa: S102  (the README example itself)
    assert scope["outcome"].summary["speed_final_rad_s"] == summary["speed_final_rad_s"]


def test_a_broken_datasheet_value_is_refused_naming_its_field(tmp_path, monkeypatch, capsys):
    """As the README says: one line naming ``machine.params.L_d``, exit code 2, nothing written."""
    monkeypatch.chdir(tmp_path)
    text = _block("Your own PMSM", "toml").replace("L_d = 1.0e-3", "L_d = -1.0e-3")
    (tmp_path / "my-pmsm.toml").write_text(text)
    assert main(["run", "my-pmsm.toml"]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith("acdrive: error: machine.params.L_d:")
    assert not (tmp_path / "acdrive-out").exists()
