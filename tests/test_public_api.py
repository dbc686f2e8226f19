"""The public namespaces: every name in a subpackage's ``__all__`` resolves to the object defined
in its module, unknown names raise AttributeError, and importing a subpackage stays light."""

from __future__ import annotations

import importlib

import pytest

PACKAGES = (
    "acdrive.machines",
    "acdrive.control",
    "acdrive.plant",
    "acdrive.analysis",
    "acdrive.sim",
    "acdrive.drives",
    "acdrive.drives.dfim",
    "acdrive.drives.cage_im",
    "acdrive.drives.pm",
    "acdrive.scenarios",
    "acdrive.core",
    "acdrive.sweep",
    "acdrive.identify",
    "acdrive.robustness",
    "acdrive.export",
)


@pytest.mark.parametrize("package", PACKAGES)
def test_every_public_name_resolves_and_is_listed(package):
    module = importlib.import_module(package)
    assert module.__all__ == sorted(module.__all__) and module.__all__
    for name in module.__all__:
        obj = getattr(module, name)
        assert obj is not None
        assert name in dir(module)
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        module.no_such_name  # noqa: B018


def test_public_names_are_the_defining_modules_objects():
    from acdrive.analysis import analyse
    from acdrive.analysis._icad import analyse as analyse_def
    from acdrive.control import LTI, PAPER_20
    from acdrive.control._lti import LTI as LTI_def
    from acdrive.control._lti import PAPER_20 as PAPER_20_def
    from acdrive.machines import BODSON_DFIM
    from acdrive.machines._dfim import BODSON_DFIM as BODSON_def

    assert analyse is analyse_def and LTI is LTI_def and PAPER_20 is PAPER_20_def
    assert BODSON_DFIM is BODSON_def


def test_importing_the_namespaces_does_not_import_numba():
    """``import acdrive.machines`` (and the analysis namespace) stays light: no numba until a
    compiled function is needed."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR",)}
    code = "import sys, acdrive.machines, acdrive.analysis; print('numba' in sys.modules)"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
    )
    assert out.stdout.strip() == "False"


#: the modules a user imports; every other module has a name component starting with "_"
PUBLIC_MODULES = {"acdrive", *PACKAGES, "acdrive.batch", "acdrive.cli", "acdrive.columns",
                  "acdrive.errors"}  # fmt: skip


def test_every_other_module_is_private_by_name():
    import pkgutil

    import acdrive

    found = {"acdrive"}
    for info in pkgutil.walk_packages(acdrive.__path__, "acdrive."):
        found.add(info.name)
        if info.name not in PUBLIC_MODULES:
            private = any(p.startswith("_") for p in info.name.split(".")[1:])
            assert private, f"{info.name} is neither a public module nor private by name"
    assert found >= PUBLIC_MODULES  # every listed public module exists


@pytest.mark.parametrize("module_name", ["acdrive.batch", "acdrive.columns", "acdrive.errors"])
def test_the_flat_public_modules_export_what_they_list(module_name):
    module = importlib.import_module(module_name)
    assert module.__all__
    for name in module.__all__:
        assert getattr(module, name) is not None
