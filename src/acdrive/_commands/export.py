"""``acdrive export``: a scenario's controller chains as C99 (``export c``), that C run in
acdrive's loop against acdrive's own run (``export sil``), its float build's size and
instructions per step on a Cortex-M4F board model (``export m4``), the controller and the plant as
FMI 2.0 co-simulation FMUs (``export fmu``) and those checked with fmpy (``export fmu-check``);
docs/guide/export.md, docs/guide/fmu.md."""

from __future__ import annotations


def register(subparsers):
    p = subparsers.add_parser(
        "export",
        help="a scenario's controller chains as C99 (export c), run in acdrive's loop (export "
        "sil), their cost on a Cortex-M4F (export m4), controller and plant as FMI 2.0 FMUs "
        "(export fmu)",
    )
    sub = p.add_subparsers(dest="what", required=True, metavar="{c,sil,m4,fmu,fmu-check}")
    c = sub.add_parser("c", help="write the C99 header and source of a scenario's controller")
    c.add_argument("scenario", help="built-in scenario name or TOML file")
    c.add_argument("--out", default="export", help="output folder (default: export/)")
    c.add_argument("--name", default=None, help="C prefix of the chain (default: the scenario's)")
    c.set_defaults(handler=run_c)
    s = sub.add_parser(
        "sil", help="run the exported C in acdrive's loop and compare it with acdrive's run"
    )
    s.add_argument("scenario", help="built-in scenario name or TOML file")
    s.add_argument("--duration", type=float, default=None, help="shorten the run (s)")
    s.add_argument("--real", choices=("double", "float"), default="double", help="C build")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(handler=run_sil)
    m = sub.add_parser(
        "m4",
        help="the float build on a Cortex-M4F: code and data size, instructions per control "
        "step on QEMU's mps2-an386 (needs scripts/install-cross-tools.sh)",
    )
    m.add_argument(
        "targets", nargs="*", metavar="TARGET",
        help="a case (dfim-voltage, dfim-current, ifoc-20, ifoc-pi, pm-foc) or a scenario of "
        "one run; default: the five cases",
    )  # fmt: skip
    m.add_argument("--duration", type=float, default=None, help="seconds replayed (s)")
    m.add_argument("--out", default=None, help="keep the built files (sources, ELF) here")
    m.add_argument("--json", action="store_true", help="print JSON")
    m.set_defaults(handler=run_m4)
    f = sub.add_parser(
        "fmu", help="write FMI 2.0 (or 3.0) co-simulation FMUs of a scenario's controller "
        "and plant"
    )
    f.add_argument("scenario", help="built-in scenario name or TOML file")
    f.add_argument("--part", choices=("controller", "plant", "both"), default="both",
                   help="which FMU (default: both)")  # fmt: skip
    f.add_argument("--out", default="export", help="output folder (default: export/)")
    f.add_argument("--name", default=None, help="C prefix (default: the scenario's)")
    f.add_argument("--fmi", type=int, choices=(2, 3), default=2,
                   help="FMI version of the FMUs (default: 2)")  # fmt: skip
    f.set_defaults(handler=run_fmu)
    k = sub.add_parser(
        "fmu-check", help="build both FMUs and compare them with acdrive's run (fmpy)"
    )
    k.add_argument("scenario", help="built-in scenario name or TOML file")
    k.add_argument("--part", choices=("controller", "plant", "both"), default="both",
                   help="which FMU (default: both, and the closed loop)")  # fmt: skip
    k.add_argument("--duration", type=float, default=None, help="shorten the run (s)")
    k.add_argument("--json", action="store_true", help="print JSON")
    k.set_defaults(handler=run_fmu_check)


def run_c(args) -> int:
    from acdrive._output import OutputFolder
    from acdrive.export._scenario import export_setup
    from acdrive.scenarios._loader import load_scenario
    from acdrive.sim._ccode._c_source import require_c_name

    setup = load_scenario(args.scenario)
    if args.name is not None:
        require_c_name("--name", args.name)
    export = export_setup(setup, args.name)  # every error before anything is written
    with OutputFolder(args.out, setup.name) as output:
        (output.staging / export.header_name).write_text(export.header)
        (output.staging / export.source_name).write_text(export.source)
        target = output.publish()
    chains = ", ".join(m.chain.name for m in export.chains)
    print(f"wrote {target / export.header_name} and {export.source_name} (chains: {chains})")
    return 0


def run_sil(args) -> int:
    from acdrive._output import strict_json
    from acdrive.export._scenario import DOUBLE_TOLERANCE, compare_in_loop, shortened
    from acdrive.scenarios._loader import load_scenario

    setup = shortened(load_scenario(args.scenario), args.duration, "--duration")
    report = compare_in_loop(setup, args.real)
    if args.json:
        print(strict_json(report))
        return 0
    print(f"{setup.name}: C controller ({args.real}) in acdrive's loop, {setup.duration:g} s, "
          f"strict math {'on' if report['strict_math'] else 'off'}")  # fmt: skip
    width = max(len(c) for c in report["signals"])
    for column, row in report["signals"].items():
        print(f"  {column:<{width}}  max |diff| {row['max_difference']:.3e}  peak "
              f"{row['peak']:.3e}  ratio {row['ratio']:.3e}")  # fmt: skip
    print(f"worst: {report['worst_signal']} at {report['worst_ratio']:.3e} of its peak; "
          f"events {'equal' if report['events_equal'] else 'differ:'}")  # fmt: skip
    for row in report["events_differing"]:
        first = row["first_difference_s"]
        when = (f"first at t = {first:.6g} s" if first is not None
                else "the logged samples agree (a difference between them)")  # fmt: skip
        print(f"  {row['event']}: raised on {row['acdrive']} samples by acdrive, "
              f"{row['c']} by the C; {when}")  # fmt: skip
    if args.real == "double":
        ok = report["worst_ratio"] <= DOUBLE_TOLERANCE and report["events_equal"]
        print(f"double build within {DOUBLE_TOLERANCE:g} of each signal's peak: "
              f"{'yes' if ok else 'no'}")  # fmt: skip
    else:
        left_out = ", ".join(report["modulator_signals_left_out"]) or "none"
        print(f"float build: worst {report['bounded_worst_signal']} at "
              f"{report['bounded_worst_ratio']:.3e} of its peak (modulators' switched outputs "
              f"left out: {left_out}), within its bound {report['float_bound']:.3e} "
              f"({report['float_margin']:g} x {report['input_rounding_ratio']:.3e}, the double "
              f"build with float32-rounded inputs, worst {report['input_rounding_signal']}): "
              f"{'yes' if report['within_float_bound'] else 'no'}")  # fmt: skip
    return 0


def run_m4(args) -> int:
    from acdrive._output import OutputFolder, strict_json
    from acdrive.errors import named_as
    from acdrive.export._cost import CASES, report_lines, target_report
    from acdrive.export._sil import find_compiler
    from acdrive.export._target import find_cross_tools

    find_compiler()  # every missing tool named before any work
    find_cross_tools()
    targets = args.targets or list(CASES)
    with named_as({"duration": "--duration"}):
        if args.out is None:
            report = target_report(targets, args.duration)
        else:
            with OutputFolder(args.out, "m4") as output:
                report = target_report(targets, args.duration, output.staging)
                (output.staging / "report.json").write_text(strict_json(report))
                output.publish()
    print(strict_json(report) if args.json else "\n".join(report_lines(report)))
    return 0


def run_fmu(args) -> int:
    import tempfile
    from pathlib import Path

    from acdrive._output import OutputFolder
    from acdrive.export._fmu_check import PARTS, scenario_fmus
    from acdrive.scenarios._loader import load_scenario
    from acdrive.sim._ccode._c_source import require_c_name

    setup = load_scenario(args.scenario)
    if args.name is not None:
        require_c_name("--name", args.name)
    parts = PARTS if args.part == "both" else (args.part,)
    # built in a scratch folder first: every error (a part without C, feedthrough, no
    # compiler) comes before the output folder is touched
    with tempfile.TemporaryDirectory(prefix="acdrive-fmu-") as scratch:
        built = scenario_fmus(setup, parts, Path(scratch), args.name, args.fmi)
        with OutputFolder(args.out, f"{setup.name}-fmu") as output:
            for path in built.values():
                (output.staging / path.name).write_bytes(path.read_bytes())
            target = output.publish()
    names = ", ".join(p.name for p in built.values())
    print(f"wrote {names} into {target}")
    return 0


def run_fmu_check(args) -> int:
    from acdrive._output import strict_json
    from acdrive.export._fmu_check import PARTS, compare_fmus
    from acdrive.scenarios._loader import load_scenario

    parts = PARTS if args.part == "both" else (args.part,)
    report = compare_fmus(load_scenario(args.scenario), args.duration, parts)
    if args.json:
        print(strict_json(report))
        return 0
    print(f"{report['scenario']}: FMUs against acdrive's run, {report['duration']:g} s, "
          f"{report['samples']} samples, strict math {'on' if report['strict_math'] else 'off'}")  # fmt: skip
    for check in ("controller", "plant", "closed_loop"):
        row = report[check]
        if row is None:
            print(f"  {check:<12} not run")
            continue
        print(f"  {check:<12} worst {row['worst_signal']} at {row['worst_ratio']:.3e} of its peak")
    if report["not_compared"]:
        print(
            f"  not compared (a switching modulator's segments): {', '.join(report['not_compared'])}"
        )
    if report["controller"] is not None:
        exact = report["controller"]["worst_ratio"] == 0.0
        print(f"controller exact: {'yes' if exact else 'no'}")
    checked = [report[c]["worst_ratio"] for c in ("plant", "closed_loop") if report[c] is not None]
    if checked:
        ok = max(checked) <= report["plant_tolerance"]
        print(f"plant{' and closed loop' if len(checked) == 2 else ''} within "
              f"{report['plant_tolerance']:g} of each signal's peak: {'yes' if ok else 'no'}")  # fmt: skip
    return 0
