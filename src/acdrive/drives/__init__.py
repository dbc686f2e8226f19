"""Drives: one folder per drive kind (``dfim``, ``cage_im``, ``pm``) on the engine of
``acdrive.sim``, and the registry the command line, batches and sweeps ask (``Drive``,
``register``, ``get``, ``for_setup``, ``kinds``; docs/design.md, "Drives as plug-ins").

``run_scenario(setup)`` runs the setup of any drive (``acdrive.scenarios.load_scenario``) and
returns that drive's ``Outcome`` (the same members for every drive: ``name``, ``kind``,
``results``, ``summary``, ``headline()``, ``figures(folder)``, ``write(folder)``). The other
names are one drive's own and take that drive's setups only: ``simulate``, ``simulate_slow``, ``DFIMDrive`` the DFIM's (``DriveSetup``),
``run_im_scenario`` and ``IMDrive`` the cage IM's (``IMDriveSetup``)."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "Drive": "._registry",
        "register": "._registry",
        "unregister": "._registry",
        "get": "._registry",
        "kinds": "._registry",
        "for_data": "._registry",
        "for_setup": "._registry",
        "is_setup": "._registry",
        "DriveSetup": ".dfim._setup",
        "simulate": ".dfim._setup",
        "DFIMDrive": ".dfim._drive",
        "simulate_slow": ".dfim._drive",
        "DriveResult": ".dfim._result",
        "ScenarioOutcome": ".dfim._outcome",
        "run_scenario": "._registry",
        "Outcome": "._outcome",
        "IMDrive": ".cage_im._drive",
        "IMDriveSetup": ".cage_im._setup",
        "IMDriveResult": ".cage_im._result",
        "IMOutcome": ".cage_im._outcome",
        "run_im_scenario": ".cage_im._outcome",
    },
)
