"""The file-level helpers of a generated C file: only those its code calls.

A generated source draws its helpers from a pool: the prelude's (``_prelude.HELPERS``: complex
arithmetic, acdrive's sine and cosine, Python's ``%``, ``max`` and ``min``) and the support
pieces its kinds bring (``_kinds.CSupport``, with the pieces each needs). The pool is split into
its file-level definitions (``split``): a function with the comment above it, a macro, or a
block under ``#if``/``#ifdef``/``#ifndef``: a block without ``#else`` is split in turn, each
definition inside it kept under the same condition (acdrive's sine, its cosine and the
reduction they share are three definitions of the double build); a block with ``#else``
defines its names in both branches and stays whole (the precision's ``tanh``). ``used`` keeps,
in the pool's order, the definitions the file's own code names: directly, through a macro of
the prelude (``ACD_SIN`` names ``acd_sin`` in the double build and ``sinf`` in the float
build: both are followed), or through a definition already kept. An identifier read as a
struct member (after ``.`` or ``->``) names no definition.

Why: an unused ``static`` function is a warning (``-Wunused-function``: gcc's for ``static``,
clang's also for ``static inline``), and an exported file must compile clean with ``-Werror``
on any C99 compiler (docs/guide/export.md). Which of the pool's definitions a file holds
follows from what it calls, not from a list kept by hand (the pool is what the kinds name).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

_COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.DOTALL)
#: an identifier that is not a struct member (``.name``, ``->name``) nor part of a number
_NAME = re.compile(r"(?<![\w.])(?<!->)[A-Za-z_]\w*")
_DEFINE = re.compile(r"#\s*define\s+(\w+)(.*)", re.DOTALL)
_CONDITION = re.compile(r"#\s*(if|ifdef|ifndef)\b")
_ELSE = re.compile(r"#\s*(else|elif)\b")
_END = re.compile(r"#\s*endif\b")


@dataclass(frozen=True)
class Definition:
    """One file-level definition: the identifiers it defines, its text, and the identifiers
    its code names besides its own."""

    names: frozenset[str]
    text: str
    uses: frozenset[str]


def uncommented(text: str) -> str:
    """``text`` with every comment replaced by a space (line breaks kept)."""
    return _COMMENT.sub(lambda m: " " + "\n" * m.group(0).count("\n"), text)


def names_in(code: str) -> set[str]:
    """The identifiers ``code`` names, comments and struct members left out."""
    return set(_NAME.findall(uncommented(code)))


def _lines(text: str) -> list[tuple[str, str]]:
    """(line, its code without comments) of every line of ``text``."""
    return list(zip(text.split("\n"), uncommented(text).split("\n"), strict=True))


def split(text: str) -> list[Definition]:
    """The file-level definitions of a helper text, in order (module docstring). A text with
    anything else at file level (a variable, a statement) is refused: a helper defines."""
    lines = _lines(text)
    found: list[Definition] = []
    leading: list[str] = []  # comment lines above the next definition
    i = 0
    while i < len(lines):
        line, code = lines[i]
        stripped = code.strip()
        if not stripped:
            leading = [*leading, line] if line.strip() else []
            i += 1
            continue
        start = i
        if stripped.startswith("#"):
            if _CONDITION.match(stripped):
                i = _block_end(lines, i)
                found += _conditional(lines[start : i + 1], leading)
            else:
                while lines[i][1].rstrip().endswith("\\"):
                    i += 1
                found.append(_macro(lines[start : i + 1], leading))
        else:
            i = _declaration_end(lines, i)
            found.append(_declaration(lines[start : i + 1], leading))
        leading = []
        i += 1
    return found


def _block_end(lines, i: int) -> int:
    """The line of the ``#endif`` closing the conditional block opened at line ``i``."""
    depth = 0
    for k in range(i, len(lines)):
        code = lines[k][1].strip()
        if _CONDITION.match(code):
            depth += 1
        elif _END.match(code):
            depth -= 1
            if depth == 0:
                return k
    raise ValueError(f"an #if without #endif: {lines[i][0]!r}")


def _declaration_end(lines, i: int) -> int:
    """The last line of the function (or declaration) starting at line ``i``: where its braces
    close, or its ``;`` at file level."""
    depth = 0
    for k in range(i, len(lines)):
        code = lines[k][1]
        depth += code.count("{") - code.count("}")
        ends = code.rstrip().endswith(("}", ";"))
        if depth == 0 and ends:
            return k
    raise ValueError(f"a definition without its end: {lines[i][0]!r}")


def _text(lines, leading: list[str]) -> str:
    return "\n".join([*leading, *(line for line, _ in lines)])


def _macro(lines, leading: list[str]) -> Definition:
    code = " ".join(c.rstrip().removesuffix("\\") for _, c in lines)
    m = _DEFINE.match(code.strip())
    if m is None:
        raise ValueError(f"a helper text holds only definitions: {lines[0][0]!r}")
    name = m.group(1)
    return Definition(frozenset({name}), _text(lines, leading),
                      frozenset(names_in(m.group(2)) - {name}))  # fmt: skip


def _declaration(lines, leading: list[str]) -> Definition:
    code = "\n".join(c for _, c in lines)
    head = code.split("{", 1)[0]
    if "(" not in head:
        raise ValueError(f"a helper text holds only functions and macros: {lines[0][0]!r}")
    name = re.findall(r"(\w+)\s*\(", head)[0]
    return Definition(frozenset({name}), _text(lines, leading),
                      frozenset(names_in(code) - {name}))  # fmt: skip


def _conditional(lines, leading: list[str]) -> list[Definition]:
    """A conditional block: split under its condition, or whole if it has an ``#else``."""
    inner = lines[1:-1]
    depth, branches = 0, False
    for _, code in inner:
        stripped = code.strip()
        if _CONDITION.match(stripped):
            depth += 1
        elif _END.match(stripped):
            depth -= 1
        elif depth == 0 and _ELSE.match(stripped):
            branches = True
    parts = split("\n".join(line for line, _ in inner if not _ELSE.match(line.strip())))
    if branches:
        return [Definition(frozenset().union(*(p.names for p in parts)), _text(lines, leading),
                           frozenset().union(*(p.uses for p in parts)))]  # fmt: skip
    opening, closing = lines[0][0], lines[-1][0]
    return [Definition(p.names, "\n".join([*leading, opening, p.text, closing]), p.uses)
            for p in parts]  # fmt: skip


def macro_names(prelude: str) -> dict[str, set[str]]:
    """Each macro the prelude defines -> the identifiers of its replacement, over every branch
    (``ACD_SIN`` -> ``acd_sin``, ``sinf``)."""
    macros: dict[str, set[str]] = {}
    for _, code in _lines(prelude):
        m = _DEFINE.match(code.strip())
        if m:
            macros.setdefault(m.group(1), set()).update(names_in(m.group(2)))
    return macros


def used(pool: list[Definition], code: str, macros: dict[str, set[str]]) -> list[Definition]:
    """The definitions of ``pool`` that ``code`` reaches (module docstring), in pool order."""
    defining: dict[str, list[int]] = {}
    for k, definition in enumerate(pool):
        for name in definition.names:
            defining.setdefault(name, []).append(k)
    kept: set[int] = set()
    seen: set[str] = set()
    todo = list(names_in(code))
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        todo += macros.get(name, ())
        for k in defining.get(name, ()):
            if k not in kept:
                kept.add(k)
                todo += pool[k].uses
    return [d for k, d in enumerate(pool) if k in kept]


def helper_text(pieces: list[str], code: str, prelude: str) -> str:
    """The helpers ``code`` calls, drawn from the texts ``pieces`` (the prelude's helpers, then
    the support pieces in their order), as one text to write above ``code``."""
    pool = [d for piece in pieces for d in split(piece)]
    return "\n\n".join(d.text.strip("\n") for d in used(pool, code, macro_names(prelude)))
