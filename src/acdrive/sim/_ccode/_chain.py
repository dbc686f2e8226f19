"""The controller chains of a system: its sampled parts, split into the groups wired to one
another (one chain per motor of a multi-motor drive), each with the plant outputs it reads and
the commands it gives."""

from __future__ import annotations

from dataclasses import dataclass

from acdrive.core._parts import Port, SampledPart
from acdrive.errors import InputError


@dataclass(frozen=True)
class Chain:
    """One chain: ``parts`` in the system's wiring order (sensors, estimators, controllers);
    ``inputs`` the outputs of plant parts and modulators it reads (each once, in order of first
    use); ``outputs`` its parts' outputs wired to a plant part or a modulator."""

    name: str
    parts: tuple
    inputs: tuple[Port, ...]
    outputs: tuple[Port, ...]


def _components(system) -> list[list]:
    """The sampled parts grouped by the wires between them (union-find), groups ordered by
    their first part in ``system.sampled``."""
    parent = {p.name: p.name for p in system.sampled}

    def root(name):
        while parent[name] != name:
            parent[name] = parent[parent[name]]
            name = parent[name]
        return name

    for (dst_name, _), src in system.source_of.items():
        if dst_name in parent and isinstance(src.part, SampledPart):
            parent[root(dst_name)] = root(src.part.name)
    groups: dict[str, list] = {}
    for part in system.sampled:
        groups.setdefault(root(part.name), []).append(part)
    return list(groups.values())


def chains_of(system, name: str) -> list[Chain]:
    """The chains of ``system``, named ``name`` (one chain) or ``name0``, ``name1``, ... ."""
    if not system.sampled:
        raise InputError("system", "has no sampled parts: there is no controller to export")
    groups = _components(system)
    chains = []
    for k, parts in enumerate(groups):
        members = {id(p) for p in parts}
        inputs: list[Port] = []
        for part in parts:
            for v in part.INPUTS:
                src = system.source_of[(part.name, v.name)]
                if id(src.part) not in members and all(
                    (q.part is not src.part or q.var.name != src.var.name) for q in inputs
                ):
                    inputs.append(src)
        outputs: list[Port] = []
        for (dst_name, _), src in system.source_of.items():
            crosses = id(src.part) in members and id(system.part(dst_name)) not in members
            if crosses and all(
                q.part is not src.part or q.var.name != src.var.name for q in outputs
            ):
                outputs.append(src)
        order = {p.name: i for i, p in enumerate(system.parts)}
        outputs.sort(
            key=lambda port: (order[port.part.name], port.part.OUTPUTS.slot(port.var.name))
        )
        chains.append(
            Chain(
                name=name if len(groups) == 1 else f"{name}{k}",
                parts=tuple(parts),
                inputs=tuple(inputs),
                outputs=tuple(outputs),
            )
        )
    return chains
