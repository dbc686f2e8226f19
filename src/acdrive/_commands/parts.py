"""``acdrive parts [NAME]``: the built-in part kinds, or one kind's declarations table."""

from __future__ import annotations

import shutil

HELP = "list the built-in part kinds, or describe one (parameters, states, ports, units)"


def register(subparsers):
    p = subparsers.add_parser("parts", help=HELP, description=HELP)
    p.add_argument(
        "name", nargs="?", metavar="NAME", help="a part kind, e.g. AveragedConverter (case matters)"
    )
    p.set_defaults(handler=run)


def run(args) -> int:
    from acdrive._part_catalog import find_part_kind, namespace_of, part_kinds
    from acdrive.core._describe import summary_of

    if args.name is not None:
        kind = find_part_kind(args.name, field="NAME")
        print(f"from {namespace_of(kind)} import {kind.__name__}\n")
        print(kind.describe().table())
        return 0
    kinds = part_kinds()
    width = max(len(k) for k in kinds)
    columns = shutil.get_terminal_size((100, 24)).columns
    package = None
    for name, kind in kinds.items():
        home = namespace_of(kind)
        if home != package:
            print(("" if package is None else "\n") + f"{home}:")
            package = home
        summary = summary_of(kind, width=max(40, columns - width - 4))
        print(f"  {name:<{width}}  {summary}")
    print("\nacdrive parts NAME shows one kind's parameters, states, inputs and outputs.")
    return 0
