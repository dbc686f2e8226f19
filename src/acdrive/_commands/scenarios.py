"""``acdrive scenarios``: list the built-in scenarios."""

from __future__ import annotations


def register(subparsers):
    p = subparsers.add_parser("scenarios", help="list the built-in scenarios")
    p.add_argument("--show", metavar="NAME", help="print the TOML of one built-in scenario")
    p.set_defaults(handler=run)


def run(args) -> int:
    from acdrive.errors import InputError
    from acdrive.scenarios._loader import builtin_names, builtin_text, read_scenario

    if args.show:
        if args.show not in builtin_names():
            raise InputError("--show", f"must be one of {', '.join(builtin_names())}")
        print(builtin_text(args.show), end="")
        return 0
    names = builtin_names()
    width = max(map(len, names))
    for name in names:
        print(f"{name:<{width}}  {read_scenario(name).get('description', '')}")
    return 0
