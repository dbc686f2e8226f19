"""C generated from a part kind's numba kernel: the kernel is the one place its equations are
written, and its C (native tier, export, SIL, FMU) is derived from it.

The kernel language is the subset of Python the part kernels are written in (docs/guide/parts.md):

* **arrays by role**: the kernel's array arguments are its part's layouts, read and written at
  slots that are constants of the module (``y[_F_O_IS]``, ``y[_F_O_IS + 1]``, ``u[i]`` inside a
  ``for i in range(4)`` with a constant bound). Each slot resolves through the layout to a struct
  member: a real quantity ``p->R_r``, the parts of a complex one ``y->i_s_ref.re`` and ``.im``;
  a table by ``table_at(p, TABLE, t)`` (its start slot, or ``table_offset(p, START, k)``), a
  2-D table by ``table2d_at(p, TABLE2D, x, y)`` (the start slot of the layout's tables when it
  has no 1-D table, or ``table2d_offset(p, START, k)`` from there); a
  modulator's segment lengths ``dt[i]`` and outputs ``v[i, SLOT]`` at run-time indices; an
  array passed on to a helper, which is then written for that kind's struct;
* **scalars**: float, int and bool locals (declared at the top of the C function with the type
  every assignment agrees on: an int that is also given a float is a real), Python complex
  numbers (``complex(a, b)``, ``.real``, ``.imag``, ``np.conj``, ``np.abs``);
* **statements**: assignment (also to several targets at once, evaluated before any is
  written), augmented assignment, ``if``/``elif``/``else`` (a test on constants keeps only its
  branch), ``for`` over a constant ``range`` of at most 64 (unrolled; integers computed from
  the index inside are constants), ``return``, a call whose value is unused; a docstring and
  ``pass``. In a plant kernel (a continuous part or a modulator) also ``for`` over a run-time
  range (its stop evaluated once), ``while``, ``continue`` and ``break``: a sampled step, whose C
  is exported to a processor, keeps literal loop bounds;
* **expressions**: arithmetic, comparisons (chained), ``and``/``or``/``not``, ``x if c else
  y``, ``abs``, ``min``/``max`` (Python's: the first extreme), ``float``/``int``, ``x ** 2``,
  complex literals, ``.conjugate()``, numpy's and math's elementary
  functions, and calls of other jit functions of the kernel language (each becomes a static C
  function; one returning a tuple returns its first element and writes the others through
  pointers).

Rounding follows the compiled tiers operation for operation: the same operations in the same
order; Python's ``%`` by ``acd_pymod``; ``np.sin``, ``np.cos``, ``np.sqrt`` and ``np.abs`` of a
complex number by acdrive's own functions (``sim._lane_math``, the C's ``ACD_SIN``, ``ACD_COS``,
``ACD_SQRT``, ``acd_cabs``), which the loops rebind numpy's to; complex products and quotients
as ``acd_cmul``/``acd_cdiv`` (numba's formulas). A real mixed with a complex number is promoted
to ``r + 0j`` first, as numba does, and the complex operation follows: in a kernel compiled
without fast-math (the sampled steps, ``jit``) the products and sums with that zero are kept
(they decide the sign of a zero result); in one compiled with acdrive's fast-math flags (the
plant's kernels, ``jit_fast``: no NaN, no infinity, no signed zero) numba folds them away, and
the C writes what remains: ``r z = (r z.re, r z.im)``, ``z + r = (z.re + r, z.im)``,
``r - z = (r - z.re, -z.im)``, ``z / r = (z.re / r, z.im / r)``. The flag is read from the
kernel's own options, so with ``ACDRIVE_STRICT_MATH=1`` (no fast-math anywhere) every kernel
takes the promoted form.

A construct outside the language is an ``UnsupportedKernel`` naming the kernel, the line and
the construct.
"""

from __future__ import annotations

import ast
import inspect
import math
import textwrap
import types
from dataclasses import dataclass, field, replace

import numpy as np

from acdrive.sim._ccode._helpers import names_in

REAL, INT, BOOL, COMPLEX = "real", "int", "bool", "complex"
#: names a local may not take in C: the generated functions' arguments and C's keywords
_RESERVED = frozenset({"n", "t", "T_s", "u", "p", "s", "x", "y", "dx", "dt", "v", "int", "double",
                       "float", "char", "long", "short", "unsigned", "signed", "void", "static",
                       "const", "return", "if", "else", "for", "while", "do", "switch", "case",
                       "default", "break", "continue", "struct", "union", "enum", "typedef",
                       "goto", "sizeof", "register", "extern", "auto", "volatile", "inline",
                       "restrict"})
_C_TYPE = {REAL: "ACDRIVE_REAL", INT: "int", BOOL: "int", COMPLEX: "acd_complex"}

#: numpy's and math's functions of one or two reals -> the prelude's macros
_REAL_FUNCTIONS = {
    "sqrt": "ACD_SQRT", "exp": "ACD_EXP", "log": "ACD_LOG", "floor": "ACD_FLOOR",
    "sin": "ACD_SIN", "cos": "ACD_COS", "arccos": "ACD_ACOS", "acos": "ACD_ACOS",
    "arctan2": "ACD_ATAN2", "atan2": "ACD_ATAN2", "hypot": "ACD_HYPOT", "fabs": "ACD_FABS",
    "nextafter": "ACD_NEXTAFTER", "tanh": "ACD_TANH",
}  # fmt: skip
_TWO_ARGUMENTS = {"arctan2", "atan2", "hypot", "nextafter"}


class UnsupportedKernel(Exception):  # noqa: N818 (a reason, raised to the caller's fallback)
    """A kernel construct the translator does not take: ``str`` names the kernel, its line and
    the construct."""


@dataclass
class Role:
    """An array argument of a kernel: its layout and its C name (``u``, ``p``, ``s``, ``y``);
    ``struct``, ``const`` and ``kind``: its C struct type, whether the step reads it only, and
    the kind's C name (for a helper that takes the array); ``structural``: the instance's
    values of the quantities its class names in ``STRUCTURAL`` (the C is written for them)."""

    layout: object
    name: str
    struct: str = ""
    const: bool = False
    kind: str = ""
    #: slot -> value of the quantities that set a per-instance kind's structure (``STRUCTURAL``)
    structural: dict = field(default_factory=dict)
    #: "struct" (slots of a layout), "reals" (a modulator's segment lengths ``dt[i]``) or
    #: "segments" (a modulator's outputs per segment ``v[i, slot]``)
    shape: str = "struct"
    #: the array is the layout's slots from this one on (a helper given ``p[K:]``): its slot k
    #: is the layout's k + offset
    offset: int = 0

    def size(self) -> int | None:
        """The number of slots the array has (None for a layout with tables)."""
        return None if self.layout.tables else self.layout.fixed_size - self.offset


@dataclass
class Translated:
    """A kernel's C: ``body`` (statements of the step function) and ``helpers`` ((C name, text)
    of the static functions it calls, in definition order: each after those it calls)."""

    body: str
    helpers: list[str] = field(default_factory=list)


def _python_function(kernel):
    return getattr(kernel, "py_func", kernel)


def _stored_names(function) -> set[str]:
    """The names a function assigns (its parameters among them are not bound as constants)."""
    func = _python_function(function)
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return set()
    return {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}


def _fast_math(kernel, default: bool) -> bool:
    """Whether ``kernel`` is compiled with fast-math flags (its own ``fastmath`` option: a
    numba dispatcher's target options, or acdrive's lazy kernel's options); ``default`` for a
    plain Python function."""
    # acdrive's lazy kernel keeps its options itself: reading them creates no dispatcher (a
    # native run imports no numba); a numba dispatcher has them as its target options
    options = kernel.__dict__.get("_options") if hasattr(kernel, "__dict__") else None
    if options is None and type(kernel).__module__.startswith("numba"):
        options = getattr(kernel, "targetoptions", None)
    if options is None:
        return default
    return bool(options.get("fastmath"))


def _is_kernel_function(value) -> bool:
    return callable(getattr(value, "py_func", None)) or isinstance(value, types.FunctionType)


class _Module:
    """What the translation of one kernel and its helpers shares: the helper functions already
    written (by Python function), in order."""

    def __init__(self):
        self.helpers: dict = {}
        self.order: list[str] = []


def _bare(text: str) -> str:
    """``text`` without one pair of parentheses around all of it (a condition inside ``if
    (...)``: clang warns of ``if ((a == b))``)."""
    if not (text.startswith("(") and text.endswith(")")):
        return text
    depth = 0
    for k, ch in enumerate(text):
        depth += (ch == "(") - (ch == ")")
        if depth == 0 and k < len(text) - 1:
            return text  # the first parenthesis closes before the end
    return text[1:-1]


def c_literal(value: float) -> str:
    if not math.isfinite(value):
        return "ACD_INF" if value > 0 else "(-ACD_INF)" if value < 0 else "(ACD_INF - ACD_INF)"
    return f"ACD_R({float(value)!r})"


class _Function:
    """One kernel or helper: the type pass, then the C text."""

    def __init__(self, func, roles: dict[str, Role], module: _Module, c_name: str,
                 arg_types: dict[str, str] | None = None, is_step: bool = False,
                 fast: bool = False, top: bool = False):  # fmt: skip
        self.func = _python_function(func)
        self.roles = roles
        self.module = module
        self.c_name = c_name
        self.is_step = is_step
        #: the kernel runs with fast-math flags (module docstring: mixed real-complex forms)
        self.fast = fast
        #: a plant kernel's own body (returns nothing)
        self.top = top
        try:
            source = textwrap.dedent(inspect.getsource(self.func))
        except (OSError, TypeError):
            raise UnsupportedKernel(f"{self.func.__module__}.{self.func.__qualname__}: its "
                                    "source is not available to read") from None  # fmt: skip
        tree = ast.parse(source)
        self.node = next(n for n in tree.body if isinstance(n, ast.FunctionDef))
        self.first_line = self.func.__code__.co_firstlineno - 1
        self.where = f"{self.func.__module__}.{self.func.__qualname__}"
        self.globals = self.func.__globals__
        self.arg_types = dict(arg_types or {})
        self.types: dict[str, str] = dict(self.arg_types)
        self.constants: dict[str, int] = {}  # loop variables of unrolled loops
        self.tables: dict[str, str] = {}  # locals holding a table (table_offset): its name
        self.unrolling = 0  # depth of unrolled loops being written
        self.loops = 0  # depth of C loops (run-time bounds, while) being written
        self.loop_bound: set[str] = set()  # names bound per pass of an unrolled loop
        self.return_type = None
        self.temp = 0

    # --- errors and constants -----------------------------------------------------------

    def fail(self, node, what: str):
        line = self.first_line + getattr(node, "lineno", 1)
        raise UnsupportedKernel(f"{self.where} (line {line}): {what}")

    def constant(self, node):
        """The value of ``node`` if it is a constant of the module (or of an unrolled loop),
        else None."""
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float, bool)):
            return node.value
        if isinstance(node, ast.Name):
            if node.id in self.constants:
                return self.constants[node.id]
            if node.id in self.types:
                return None
            value = self.globals.get(node.id)
            if isinstance(value, (bool, int, float, np.integer, np.floating)):
                return value.item() if isinstance(value, np.generic) else value
            return None
        if (isinstance(node, ast.Attribute) and node.attr == "size"
                and isinstance(node.value, ast.Name) and node.value.id in self.roles):  # fmt: skip
            return self.roles[node.value.id].size()
        if isinstance(node, ast.Attribute):
            value = self._attribute_value(node)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                return value
            return None
        if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name):
            role = self.roles.get(node.value.id)
            k = self.constant(node.slice)
            if role is not None and isinstance(k, int) and k + role.offset in role.structural:
                return role.structural[k + role.offset]
            return None
        if (isinstance(node, ast.Subscript) and isinstance(node.value, ast.Attribute)
                and node.value.attr == "shape" and isinstance(node.value.value, ast.Name)
                and node.value.value.id in self.roles and self.constant(node.slice) == 0):  # fmt: skip
            return self.roles[node.value.value.id].size()
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd, ast.Not)):
            a = self.constant(node.operand)
            if a is None:
                return None
            return not a if isinstance(node.op, ast.Not) else -a if isinstance(node.op, ast.USub) else a
        if isinstance(node, ast.IfExp):
            test = self.constant(node.test)
            return None if test is None else self.constant(node.body if test else node.orelse)
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id in ("int", "float") and len(node.args) == 1
                and node.func.id not in self.globals):  # fmt: skip
            value = self.constant(node.args[0])
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                return int(value) if node.func.id == "int" else float(value)
            return None
        if isinstance(node, ast.Compare) and len(node.ops) == 1:
            a, b = self.constant(node.left), self.constant(node.comparators[0])
            ops = {ast.Lt: float.__lt__, ast.LtE: float.__le__, ast.Gt: float.__gt__,
                   ast.GtE: float.__ge__, ast.Eq: float.__eq__, ast.NotEq: float.__ne__}  # fmt: skip
            if a is None or b is None or type(node.ops[0]) not in ops:
                return None
            return bool(ops[type(node.ops[0])](float(a), float(b)))
        if isinstance(node, ast.BinOp):
            a, b = self.constant(node.left), self.constant(node.right)
            if isinstance(a, int) and isinstance(b, int):
                op = type(node.op)
                if op is ast.Add:
                    return a + b
                if op is ast.Sub:
                    return a - b
                if op is ast.Mult:
                    return a * b
                if op is ast.FloorDiv and b != 0:
                    return a // b
        return None

    def _attribute_value(self, node):
        if isinstance(node.value, ast.Name) and node.value.id not in self.types:
            owner = self.globals.get(node.value.id)
            if isinstance(owner, types.ModuleType):
                return getattr(owner, node.attr, None)
        return None

    # --- slots ------------------------------------------------------------------------------

    def member(self, node: ast.Subscript) -> tuple[str, str]:
        """(C lvalue, type) of ``array[slot]`` for a role array (``dt[i]`` and ``v[i, slot]``
        of a modulator's segments)."""
        role = self.roles[node.value.id]
        if role.shape == "reals":
            index, t = self.expr(node.slice)
            if t not in (INT, BOOL):
                self.fail(node, f"an index of {node.value.id} that is not an integer")
            return f"{role.name}[{index}]", REAL
        prefix = f"{role.name}->"
        if role.shape == "segments":
            if not (isinstance(node.slice, ast.Tuple) and len(node.slice.elts) == 2):
                self.fail(node, f"{node.value.id}[...] other than {node.value.id}[segment, slot]")
            index, t = self.expr(node.slice.elts[0])
            if t not in (INT, BOOL):
                self.fail(node, f"a segment index of {node.value.id} that is not an integer")
            prefix = f"{role.name}[{index}]."
            node = ast.Subscript(node.value, node.slice.elts[1], node.ctx)
        k = self.constant(node.slice)
        if not isinstance(k, int):
            self.fail(node, f"the slot of {node.value.id}[...] is not a constant of the module")
        k += role.offset
        for v in role.layout:
            if v.kind in ("table", "table2d"):
                continue
            first = role.layout.slot(v.name)
            if first <= k < first + v.width:
                if v.kind == "complex":
                    return f"{prefix}{v.name}.{'re' if k == first else 'im'}", REAL
                return f"{prefix}{v.name}", REAL
        self.fail(node, f"slot {k} of {node.value.id} is no real or complex quantity")

    # --- types ------------------------------------------------------------------------------

    def unify(self, node, a: str | None, b: str) -> str:
        if a is None or a == b:
            return b
        if {a, b} <= {INT, BOOL}:
            return INT
        if {a, b} <= {INT, BOOL, REAL}:
            return REAL
        self.fail(node, f"a variable given both a {a} and a {b} value")

    def infer(self, body: list) -> None:
        """Types of every local (two passes: a loop may read a later assignment). A local
        assigned once, at the top level, to an integer constant (a slot computed from others,
        an order) is that constant, not a variable."""
        stores = [n.id for n in ast.walk(self.node) if isinstance(n, ast.Name)
                  and isinstance(n.ctx, ast.Store)]  # fmt: skip
        for stmt in body:
            if (isinstance(stmt, ast.Assign) and len(stmt.targets) == 1
                    and isinstance(stmt.targets[0], ast.Name)
                    and stores.count(stmt.targets[0].id) == 1):  # fmt: skip
                k = self.constant(stmt.value)
                if isinstance(k, int):  # a slot, an order or a flag
                    self.constants[stmt.targets[0].id] = k
        for _ in range(2):
            self._infer_block(body)

    def _infer_block(self, body):
        for stmt in body:
            if isinstance(stmt, ast.Assign):
                if self._is_local_constant(stmt):
                    continue
                value = self.type_of(stmt.value)
                for target in stmt.targets:
                    self._assign_type(target, value, stmt)
            elif isinstance(stmt, ast.AugAssign):
                if isinstance(stmt.target, ast.Name):
                    value = self.type_of(ast.BinOp(stmt.target, stmt.op, stmt.value))
                    self.types[stmt.target.id] = self.unify(
                        stmt, self.types.get(stmt.target.id), value
                    )
            elif isinstance(stmt, ast.If):
                k = self.constant(stmt.test)
                if k is None or k:
                    self._infer_block(stmt.body)
                if k is None or not k:
                    self._infer_block(stmt.orelse)
            elif isinstance(stmt, ast.For):
                how = self._range_of(stmt)
                name = stmt.target.id
                if how[0] == "loop":
                    self.types[name] = self.unify(stmt, self.types.get(name), INT)
                    self.loops += 1
                    self._infer_block(stmt.body)
                    self.loops -= 1
                    continue
                self.unrolling += 1
                for i in how[1]:
                    self.constants[name] = i
                    self._infer_block(stmt.body)
                self.unrolling -= 1
                self.constants.pop(name, None)
            elif isinstance(stmt, ast.While):
                self._while_allowed(stmt)
                self.loops += 1
                self._infer_block(stmt.body)
                self.loops -= 1
            elif isinstance(stmt, ast.Return) and stmt.value is not None:
                t = self.type_of(stmt.value)
                self.return_type = t if self.return_type is None else self._unify_return(
                    stmt, self.return_type, t)  # fmt: skip

    def _while_allowed(self, stmt) -> None:
        """A ``while`` loop only in a plant kernel (an exported controller's loops keep literal
        bounds: docs/guide/export.md, "Firmware rules")."""
        if self.is_step or self.top is False:
            self.fail(stmt, "the statement While")

    def _is_local_constant(self, stmt) -> bool:
        """A top-level integer constant (``infer``), or, inside an unrolled loop, a name given
        an integer computed from constants and the loop's index (a slot ``o = FIRST + 5 k``):
        bound for this pass of the loop."""
        target = stmt.targets[0] if len(stmt.targets) == 1 else None
        if not isinstance(target, ast.Name):
            return False
        if target.id in self.constants and target.id not in self.loop_bound:
            return True
        if self.unrolling and target.id not in self.types:
            k = self.constant(stmt.value)
            if isinstance(k, int) and not isinstance(k, bool):
                self.constants[target.id] = k
                self.loop_bound.add(target.id)
                return True
        return False

    def _unify_return(self, node, a, b):
        if isinstance(a, tuple) and isinstance(b, tuple) and len(a) == len(b):
            return tuple(self.unify(node, x, y) for x, y in zip(a, b, strict=True))
        return self.unify(node, a, b)

    def _assign_type(self, target, value, stmt):
        if isinstance(target, ast.Name) and isinstance(value, tuple) and value[:1] == ("table",):
            self.tables[target.id] = value[1]
            return
        if isinstance(target, ast.Name):
            if isinstance(value, tuple):
                self.fail(stmt, "a tuple kept in one variable")
            self.types[target.id] = self.unify(stmt, self.types.get(target.id), value)
        elif isinstance(target, ast.Tuple):
            if not (isinstance(value, tuple) and len(value) == len(target.elts)):
                self.fail(stmt, "an unpacking whose value is not a tuple of that length")
            for t, v in zip(target.elts, value, strict=True):
                self._assign_type(t, v, stmt)
        elif isinstance(target, ast.Subscript):
            if not (isinstance(target.value, ast.Name) and target.value.id in self.roles):
                self.fail(stmt, "a subscript of something other than the kernel's arrays")
            if value == COMPLEX:
                self.fail(stmt, "a complex value written to one slot")
        else:
            self.fail(stmt, f"assignment to {type(target).__name__}")

    def _range_of(self, stmt: ast.For):
        """("unroll", range) of a loop over a constant range of at most 64, or ("loop", start
        node, stop node) of one whose bounds are known at run time (a plant kernel's only: an
        exported controller's loops keep literal bounds)."""
        it = stmt.iter
        if not (isinstance(it, ast.Call) and isinstance(it.func, ast.Name)
                and it.func.id == "range" and len(it.args) in (1, 2)
                and isinstance(stmt.target, ast.Name) and not stmt.orelse):  # fmt: skip
            self.fail(stmt, "a loop other than 'for i in range(N)' or 'range(M, N)'")
        start = it.args[0] if len(it.args) == 2 else ast.Constant(0)
        stop = it.args[-1]
        a, b = self.constant(start), self.constant(stop)
        if isinstance(a, int) and isinstance(b, int) and b - a <= 64:
            return "unroll", range(a, b)
        if self.is_step or self.top is False:
            self.fail(stmt, "a loop whose bound is not a constant of at most 64")
        return "loop", start, stop

    def type_of(self, node) -> str | tuple:
        return self.expr(node)[1]

    # --- expressions: (C text, type) ---------------------------------------------------------

    def expr(self, node) -> tuple[str, object]:
        k = self.constant(node)
        if k is not None:
            if isinstance(k, bool):
                return ("1" if k else "0"), BOOL
            if isinstance(k, int):
                return (str(k) if k >= 0 else f"({k})"), INT
            return c_literal(k), REAL
        method = getattr(self, f"_{type(node).__name__}", None)
        if method is None:
            self.fail(node, f"the expression {type(node).__name__}")
        return method(node)

    def _Constant(self, node):
        if isinstance(node.value, complex):
            return f"acd_c({c_literal(node.value.real)}, {c_literal(node.value.imag)})", COMPLEX
        self.fail(node, f"the constant {node.value!r}")

    def local(self, name: str) -> str:
        """The C name of a local: a name the C function's own arguments take (a modulator's
        ``n``) or a C keyword gets a prefix."""
        return f"k_{name}" if name in _RESERVED and name not in self.arg_types else name

    def _Name(self, node):
        if node.id in self.types:
            return self.local(node.id), self.types[node.id]
        if node.id in self.arg_types:
            return node.id, self.arg_types[node.id]
        if node.id in ("t", "T_s") and (self.is_step or self.top):
            return node.id, REAL
        self.fail(node, f"the name {node.id!r} (not a local, an argument or a constant)")

    def _Attribute(self, node):
        value = self._attribute_value(node)
        if value is not None:
            self.fail(node, f"the module attribute {ast.unparse(node)!r}")
        text, t = self.expr(node.value)
        if t == COMPLEX and node.attr in ("real", "imag"):
            return f"({text}).{'re' if node.attr == 'real' else 'im'}", REAL
        self.fail(node, f"the attribute .{node.attr} of a {t}")

    def _Subscript(self, node):
        if isinstance(node.value, ast.Name) and node.value.id in self.roles:
            return self.member(node)
        self.fail(node, "a subscript of something other than the kernel's arrays")

    def _UnaryOp(self, node):
        text, t = self.expr(node.operand)
        if isinstance(node.op, ast.USub):
            if t == COMPLEX:
                return f"acd_cneg({text})", COMPLEX
            return f"(-{text})", REAL if t == REAL else INT
        if isinstance(node.op, ast.UAdd):
            return text, t
        if isinstance(node.op, ast.Not):
            return f"(!{self.truth(text, t)})", BOOL
        self.fail(node, f"the operator {type(node.op).__name__}")

    def truth(self, text, t):
        return f"({text} != 0)" if t == REAL else text

    def _BinOp(self, node):
        a, ta = self.expr(node.left)
        b, tb = self.expr(node.right)
        op = type(node.op)
        if COMPLEX in (ta, tb):
            return self._complex_op(node, op, a, ta, b, tb)
        if op is ast.Div:
            if ta != REAL and tb != REAL:
                return f"((ACDRIVE_REAL){a} / (ACDRIVE_REAL){b})", REAL
            return f"({a} / {b})", REAL
        if op is ast.Mod:
            if REAL in (ta, tb):
                return f"acd_pymod({a}, {b})", REAL
            self.fail(node, "% of two integers")
        if op is ast.Pow:
            if self.constant(node.right) != 2 or ta != REAL:
                self.fail(node, "the operator Pow other than a real squared (x ** 2)")
            return f"({a} * {a})", REAL  # numba: a constant integer power by multiplication
        symbol = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.BitOr: "|",
                  ast.BitAnd: "&"}.get(op)  # fmt: skip
        if symbol is None:
            self.fail(node, f"the operator {op.__name__}")
        if symbol in "|&" and REAL in (ta, tb):
            self.fail(node, f"the bit operator {symbol} on a real")
        result = REAL if REAL in (ta, tb) else INT
        return f"({a} {symbol} {b})", result

    def _complex_op(self, node, op, a, ta, b, tb):
        if ta == COMPLEX and tb == COMPLEX:
            name = {ast.Add: "acd_cadd", ast.Sub: "acd_csub", ast.Mult: "acd_cmul",
                    ast.Div: "acd_cdiv"}.get(op)  # fmt: skip
            if name is None:
                self.fail(node, f"the operator {op.__name__} on complex numbers")
            return f"{name}({a}, {b})", COMPLEX
        if self.fast:  # the forms fast-math folds the promoted operation to (module docstring)
            if ta == COMPLEX:
                name = {ast.Add: "acd_caddr", ast.Sub: "acd_csubr", ast.Mult: "acd_cmulr",
                        ast.Div: "acd_cdivr"}.get(op)  # fmt: skip
                if name is None:
                    self.fail(node, f"the operator {op.__name__} on complex numbers")
                return f"{name}({a}, {self.as_real(b, tb)})", COMPLEX
            name = {ast.Add: "acd_raddc", ast.Sub: "acd_rsubc", ast.Mult: "acd_cscale"}.get(op)
            if name is None:
                self.fail(node, f"the operator {op.__name__} of a real by a complex number")
            return f"{name}({self.as_real(a, ta)}, {b})", COMPLEX
        # a real operand promoted to r + 0j (module docstring), then the complex operation
        if ta != COMPLEX:
            a = f"acd_c({self.as_real(a, ta)}, ACD_R(0.0))"
        if tb != COMPLEX:
            b = f"acd_c({self.as_real(b, tb)}, ACD_R(0.0))"
        return self._complex_op(node, op, a, COMPLEX, b, COMPLEX)

    def _Compare(self, node):
        symbols = {ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==",
                   ast.NotEq: "!="}  # fmt: skip
        parts = []
        left = node.left
        for op, right in zip(node.ops, node.comparators, strict=True):
            if type(op) not in symbols:
                self.fail(node, f"the comparison {type(op).__name__}")
            a, ta = self.expr(left)
            b, tb = self.expr(right)
            if COMPLEX in (ta, tb):
                self.fail(node, "a comparison of complex numbers")
            parts.append(f"({a} {symbols[type(op)]} {b})")
            left = right
        return ("(" + " && ".join(parts) + ")") if len(parts) > 1 else parts[0], BOOL

    def _BoolOp(self, node):
        symbol = " && " if isinstance(node.op, ast.And) else " || "
        values = []
        for v in node.values:
            text, t = self.expr(v)
            if t not in (BOOL, INT, REAL):
                self.fail(node, f"'and'/'or' of a {t}")
            values.append(self.truth(text, t))
        return "(" + symbol.join(values) + ")", BOOL

    def _IfExp(self, node):
        test = self.constant(node.test)
        if test is not None:  # a test on constants (a structural parameter): the branch taken
            text, t = self.expr(node.body if test else node.orelse)
            other = node.orelse if test else node.body
            if t in (INT, BOOL) and isinstance(other, ast.Constant) and isinstance(other.value, float):
                return self.as_real(text, t), REAL  # numba's type of the whole expression
            return text, t
        c, tc = self.expr(node.test)
        a, ta = self.expr(node.body)
        b, tb = self.expr(node.orelse)
        t = self.unify(node, ta, tb)
        if t == REAL:
            a, b = self.as_real(a, ta), self.as_real(b, tb)
        return f"({self.truth(c, tc)} ? {a} : {b})", t

    def as_real(self, text, t):
        return text if t == REAL else f"(ACDRIVE_REAL)({text})"

    def _Tuple(self, node):
        items = [self.expr(e) for e in node.elts]
        return [x for x, _ in items], tuple(t for _, t in items)

    def _Call(self, node):
        func = node.func
        if node.keywords:
            self.fail(node, "a call with keyword arguments")
        name = None
        if isinstance(func, ast.Name):
            name = func.id
            target = self.globals.get(name, getattr(__builtins__, name, None)
                                      if not isinstance(__builtins__, dict)
                                      else __builtins__.get(name))  # fmt: skip
        elif isinstance(func, ast.Attribute) and func.attr == "conjugate" and not node.args:
            text, t = self.expr(func.value)
            if t != COMPLEX:
                self.fail(node, f".conjugate() of a {t}")
            return f"acd_conj({text})", COMPLEX
        elif isinstance(func, ast.Attribute):
            owner = func.value.id if isinstance(func.value, ast.Name) else None
            module = self.globals.get(owner) if owner else None
            if module is None or not isinstance(module, types.ModuleType):
                self.fail(node, f"the call {ast.unparse(func)}")
            name = func.attr
            target = getattr(module, name, None)
            if module.__name__ in ("numpy", "math") or getattr(module, "__name__", "").startswith(
                "acdrive.sim._lane_math"
            ):
                return self._library_call(node, name)
        else:
            self.fail(node, "a call of an expression")
        from acdrive.core import _tables

        if target is _tables.table_at:
            return self._table_at(node)
        if target is _tables.table_offset:
            return self._table_offset(node)
        if target is _tables.table2d_at:
            return self._table2d_at(node)
        if target is _tables.table2d_offset:
            return self._table2d_offset(node)
        if target is not None and _is_kernel_function(target):
            return self._helper_call(node, target)
        args = [self.expr(a) for a in node.args]
        if name in ("abs", "min", "max", "complex", "float", "int") and target in (
            abs, min, max, complex, float, int
        ):
            return self._builtin(node, name, args)
        self.fail(node, f"the call {name}(...)")

    def _library_call(self, node, name):
        args = [self.expr(a) for a in node.args]
        if name == "abs" and len(args) == 1:
            text, t = args[0]
            if t == COMPLEX:
                return f"acd_cabs({text})", REAL
            return f"ACD_FABS({self.as_real(text, t)})", REAL
        if name == "conj" and len(args) == 1 and args[0][1] == COMPLEX:
            return f"acd_conj({args[0][0]})", COMPLEX
        if name == "angle" and len(args) == 1 and args[0][1] == COMPLEX:
            return f"acd_carg({args[0][0]})", REAL
        if name == "exp" and len(args) == 1 and args[0][1] == COMPLEX:
            return f"acd_cexp({args[0][0]})", COMPLEX
        if name in _REAL_FUNCTIONS:
            want = 2 if name in _TWO_ARGUMENTS else 1
            if len(args) != want or any(t not in (REAL, INT) for _, t in args):
                self.fail(node, f"{name} of other than {want} real argument(s)")
            inner = ", ".join(self.as_real(x, t) for x, t in args)
            return f"{_REAL_FUNCTIONS[name]}({inner})", REAL
        self.fail(node, f"the library function {name}")

    def _builtin(self, node, name, args):
        if name == "abs" and len(args) == 1:
            text, t = args[0]
            if t == COMPLEX:
                return f"ACD_HYPOT(({text}).re, ({text}).im)", REAL
            if t == REAL:
                return f"ACD_FABS({text})", REAL
            return f"abs({text})", INT
        if name in ("min", "max") and len(args) > 2 and all(t in (REAL, INT) for _, t in args):
            text = self.as_real(*args[0])  # Python's: the first extreme, left to right
            for b, tb in args[1:]:
                text = f"acd_{name}({text}, {self.as_real(b, tb)})"
            return text, REAL
        if name in ("min", "max") and len(args) == 2:
            (a, ta), (b, tb) = args
            if REAL in (ta, tb):
                return f"acd_{name}({self.as_real(a, ta)}, {self.as_real(b, tb)})", REAL
            symbol = ">" if name == "max" else "<"
            return f"(({b}) {symbol} ({a}) ? ({b}) : ({a}))", INT
        if name == "complex" and len(args) == 2:
            (a, ta), (b, tb) = args
            return f"acd_c({self.as_real(a, ta)}, {self.as_real(b, tb)})", COMPLEX
        if name == "float" and len(args) == 1:
            return self.as_real(*args[0]), REAL
        if name == "int" and len(args) == 1:
            return f"((int)({args[0][0]}))", INT
        self.fail(node, f"{name} with {len(args)} argument(s)")

    def _table(self, node, array, where) -> tuple[Role, str]:
        """(role, table name) of a table argument: the first table's start slot, a local
        holding a ``table_offset``, or a ``table_offset`` call."""
        role = self.roles.get(array.id) if isinstance(array, ast.Name) else None
        if role is None:
            self.fail(node, f"{where} of other than one of the kernel's arrays")
        names = [v.name for v in role.layout.tables]
        if isinstance(where_node := node.args[1], ast.Name) and where_node.id in self.tables:
            if self.tables[where_node.id] not in names:
                self.fail(node, f"{where} of a 2-D table")
            return role, self.tables[where_node.id]
        if isinstance(where_node, ast.Call):
            text, t = self.expr(where_node)
            if isinstance(t, tuple) and t[0] == "table" and t[1] in names:
                return role, t[1]
        start = self.constant(where_node)
        tables = role.layout.tables
        if not tables or start != role.layout.table_start:
            self.fail(node, f"{where} of other than a table of the kernel's layouts")
        return role, tables[0].name

    def _table_at(self, node):
        if len(node.args) != 3:
            self.fail(node, "table_at other than table_at(p, TABLE, t)")
        role, name = self._table(node, node.args[0], "table_at")
        t, tt = self.expr(node.args[2])
        v = f"{role.name}->{name}"
        return f"acd_table_at({v}.n, {v}.t, {v}.v, {self.as_real(t, tt)})", REAL

    def _table_offset(self, node):
        """``table_offset(p, START, k)``: table k of the layout; ``table_offset(p, q, k)`` with
        ``q`` itself a table of the layout: the k-th table after it (a name, no C)."""
        if len(node.args) != 3 or not isinstance(node.args[0], ast.Name):
            self.fail(node, "table_offset other than table_offset(p, START, k)")
        role = self.roles.get(node.args[0].id)
        k = self.constant(node.args[2])
        start, first = node.args[1], None
        if role is not None and self.constant(start) == role.layout.table_start:
            first = 0
        elif role is not None and isinstance(start, ast.Name) and start.id in self.tables:
            names = [v.name for v in role.layout.tables]
            if self.tables[start.id] in names:
                first = names.index(self.tables[start.id])
        if (first is None or not isinstance(k, int)
                or not 0 <= first + k < len(role.layout.tables)):  # fmt: skip
            self.fail(node, "table_offset of other than a table of the kernel's layouts")
        return "", ("table", role.layout.tables[first + k].name)

    def _table2d(self, node, where_node) -> tuple[Role, str]:
        """(role, 2-D table name) of ``table2d_at``'s first two arguments: the layout's table
        start slot (the first 2-D table of a layout without tables), a local holding a
        ``table2d_offset`` or a ``table2d_offset`` call."""
        array = node.args[0]
        role = self.roles.get(array.id) if isinstance(array, ast.Name) else None
        if role is None:
            self.fail(node, "table2d_at of other than one of the kernel's arrays")
        names = [v.name for v in role.layout.tables2d]
        if isinstance(where_node, ast.Name) and where_node.id in self.tables:
            if self.tables[where_node.id] not in names:
                self.fail(node, "table2d_at of a table that is not a 2-D table")
            return role, self.tables[where_node.id]
        if isinstance(where_node, ast.Call):
            _, t = self.expr(where_node)
            if isinstance(t, tuple) and t[0] == "table" and t[1] in names:
                return role, t[1]
        start = self.constant(where_node)
        if not names or role.layout.tables or start != role.layout.table_start:
            self.fail(node, "table2d_at of other than a 2-D table of the kernel's layouts")
        return role, names[0]

    def _table2d_at(self, node):
        if len(node.args) != 4:
            self.fail(node, "table2d_at other than table2d_at(p, TABLE2D, x, y)")
        role, name = self._table2d(node, node.args[1])
        x, tx = self.expr(node.args[2])
        y, ty = self.expr(node.args[3])
        v = f"{role.name}->{name}"
        return (f"acd_table2d_at({v}.nx, {v}.ny, {v}.x, {v}.y, {v}.v, {self.as_real(x, tx)}, "
                f"{self.as_real(y, ty)})", REAL)  # fmt: skip

    def _table2d_offset(self, node):
        """``table2d_offset(p, START, k)``: 2-D table k of a layout without tables (START its
        table start slot); ``table2d_offset(p, q, k)`` with ``q`` a 2-D table of the layout:
        the k-th 2-D table after it (a name, no C)."""
        if len(node.args) != 3 or not isinstance(node.args[0], ast.Name):
            self.fail(node, "table2d_offset other than table2d_offset(p, START, k)")
        role = self.roles.get(node.args[0].id)
        k = self.constant(node.args[2])
        start, first = node.args[1], None
        names = [v.name for v in role.layout.tables2d] if role is not None else []
        if (role is not None and not role.layout.tables
                and self.constant(start) == role.layout.table_start):  # fmt: skip
            first = 0
        elif isinstance(start, ast.Name) and self.tables.get(start.id) in names:
            first = names.index(self.tables[start.id])
        if first is None or not isinstance(k, int) or not 0 <= first + k < len(names):
            self.fail(node, "table2d_offset of other than a 2-D table of the kernel's layouts")
        return "", ("table", names[first + k])

    def _helper_call(self, node, target):
        """A call of another kernel-language function. An array argument passes the struct
        (the helper is written for this kind's struct); with one, an integer constant argument
        (a slot) is bound inside the helper, which is written for that value."""
        roles = [self._role_argument(a) for a in node.args]
        stored = _stored_names(target)
        params = list(inspect.signature(_python_function(target)).parameters)
        args = []
        for a, role, param in zip(node.args, roles, params + [None] * len(node.args),
                                  strict=False):  # fmt: skip
            k = self.constant(a)
            if role is not None:
                args.append((role.name, ("role", role)))
            elif any(roles) and isinstance(k, int) and param not in stored:
                args.append(("", ("const", k)))  # a slot or a flag (a bool is bound as 0 or 1)
            else:
                text, t = self.expr(a)
                if isinstance(t, tuple):
                    self.fail(node, "a tuple passed to a function")
                args.append((text, t))
        helper = _helper(self.module, target, tuple(t for _, t in args), node, self)
        passed = [x for x, t in args if not (isinstance(t, tuple) and t[0] == "const")]
        return f"{helper.c_name}({', '.join(passed)})", helper.return_type

    def _role_argument(self, node) -> Role | None:
        """The role a helper's argument passes: a role array, or a slice ``p[K:]`` of one with a
        constant start (the helper sees its slot k as the layout's K + k); else None."""
        if isinstance(node, ast.Name):
            return self.roles.get(node.id)
        if (isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name)
                and node.value.id in self.roles and isinstance(node.slice, ast.Slice)
                and node.slice.upper is None and node.slice.step is None):  # fmt: skip
            role = self.roles[node.value.id]
            start = self.constant(node.slice.lower) if node.slice.lower is not None else 0
            if role.shape != "struct" or not isinstance(start, int) or isinstance(start, bool):
                self.fail(node, f"a slice of {node.value.id} with a start that is not a constant")
            return replace(role, offset=role.offset + start)
        return None

    # --- statements -------------------------------------------------------------------------

    def new_temp(self) -> str:
        self.temp += 1
        return f"acd_t{self.temp}"

    def block(self, body, depth: int) -> list[str]:
        pad = "    " * depth
        lines = []
        for stmt in body:
            if (isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant)
                    and isinstance(stmt.value.value, str)):  # fmt: skip
                continue  # a docstring
            if isinstance(stmt, ast.Pass):
                continue
            if isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Call):
                text, _ = self.expr(stmt.value)
                lines.append(f"{pad}(void){text};" if self._returns_value(text) else
                             f"{pad}{text};")  # fmt: skip
                continue
            if isinstance(stmt, ast.Assign):
                if self._is_local_constant(stmt):
                    continue
                lines += self.assign(stmt, pad)
            elif isinstance(stmt, ast.AugAssign):
                target = ast.Name(stmt.target.id, ast.Load()) if isinstance(
                    stmt.target, ast.Name) else stmt.target  # fmt: skip
                lvalue, lt = self.expr(target)
                value, vt = self.expr(ast.BinOp(target, stmt.op, stmt.value))
                lines.append(f"{pad}{lvalue} = {self.cast_to(value, vt, lt)};")
            elif isinstance(stmt, ast.If) and self.constant(stmt.test) is not None:
                # a test on constants (a structural parameter): only the branch taken
                taken = stmt.body if self.constant(stmt.test) else stmt.orelse
                lines += self.block(taken, depth)
                if taken and isinstance(taken[-1], ast.Return):
                    break  # the rest of the block never runs
            elif isinstance(stmt, ast.If):
                test, tt = self.expr(stmt.test)
                lines.append(f"{pad}if ({_bare(self.truth(test, tt))}) {{")
                lines += self.block(stmt.body, depth + 1)
                orelse = stmt.orelse
                while len(orelse) == 1 and isinstance(orelse[0], ast.If):
                    test, tt = self.expr(orelse[0].test)
                    lines.append(f"{pad}}} else if ({_bare(self.truth(test, tt))}) {{")
                    lines += self.block(orelse[0].body, depth + 1)
                    orelse = orelse[0].orelse
                if orelse:
                    lines.append(f"{pad}}} else {{")
                    lines += self.block(orelse, depth + 1)
                lines.append(f"{pad}}}")
            elif isinstance(stmt, ast.For):
                how = self._range_of(stmt)
                name = stmt.target.id
                if how[0] == "loop":  # the stop evaluated once, as Python's range does
                    start, st = self.expr(how[1])
                    stop, tt = self.expr(how[2])
                    if st not in (INT, BOOL) or tt not in (INT, BOOL):
                        self.fail(stmt, "a range of other than integers")
                    end, i = self.new_temp(), self.local(name)
                    lines += [f"{pad}{{", f"{pad}    int {end} = {stop};",
                              f"{pad}    for ({i} = {start}; {i} < {end}; ++{i}) {{"]  # fmt: skip
                    self.loops += 1
                    lines += self.block(stmt.body, depth + 2)
                    self.loops -= 1
                    lines += [f"{pad}    }}", f"{pad}}}"]
                    continue
                self.unrolling += 1
                for i in how[1]:
                    self.constants[name] = i
                    lines += self.block(stmt.body, depth)
                self.unrolling -= 1
                self.constants.pop(name, None)
            elif isinstance(stmt, ast.While):
                self._while_allowed(stmt)
                test, tt = self.expr(stmt.test)
                lines.append(f"{pad}while ({_bare(self.truth(test, tt))}) {{")
                self.loops += 1
                lines += self.block(stmt.body, depth + 1)
                self.loops -= 1
                lines.append(f"{pad}}}")
            elif isinstance(stmt, (ast.Continue, ast.Break)):
                if not self.loops or self.unrolling:
                    self.fail(stmt, f"{type(stmt).__name__.lower()} outside a run-time loop")
                lines.append(f"{pad}{type(stmt).__name__.lower()};")
            elif isinstance(stmt, ast.Return):
                lines += self.return_lines(stmt, pad)
                break  # what follows a return in its block never runs
            else:
                self.fail(stmt, f"the statement {type(stmt).__name__}")
        return lines

    def cast_to(self, text, t, want):
        if want == REAL and t in (INT, BOOL):
            return f"(ACDRIVE_REAL)({text})"
        return text

    def lvalue(self, target):
        if isinstance(target, ast.Name):
            return self.local(target.id), self.types[target.id]
        return self.member(target)

    def assign(self, stmt, pad) -> list[str]:
        if len(stmt.targets) != 1:
            self.fail(stmt, "a chained assignment a = b = c")
        target = stmt.targets[0]
        if isinstance(target, ast.Name) and (target.id in self.tables
                                             or target.id in self.constants):  # fmt: skip
            return []  # a table's name or a constant: nothing to compute
        if not isinstance(target, ast.Tuple):
            lvalue, lt = self.lvalue(target)
            value, vt = self.expr(stmt.value)
            return [f"{pad}{lvalue} = {self.cast_to(value, vt, lt)};"]
        targets = [self.lvalue(t) for t in target.elts]
        if isinstance(stmt.value, ast.Tuple):
            values = [self.expr(v) for v in stmt.value.elts]
            if len(values) != len(targets):
                self.fail(stmt, "an unpacking of a tuple of another length")
            reads = " ".join(v for v, _ in values)
            names = names_in(reads)
            if not any(lv in names if isinstance(t, ast.Name) else lv in reads
                       for (lv, _), t in zip(targets, target.elts, strict=True)):  # fmt: skip
                # no value reads a target: written in order
                return [f"{pad}{lv} = {self.cast_to(v, vt, lt)};"
                        for (lv, lt), (v, vt) in zip(targets, values, strict=True)]  # fmt: skip
            temps = [self.new_temp() for _ in values]
            lines = [f"{pad}{{"]
            for temp, (v, vt), (_, lt) in zip(temps, values, targets, strict=True):
                lines.append(f"{pad}    {_C_TYPE[lt]} {temp} = {self.cast_to(v, vt, lt)};")
            for temp, (lv, _) in zip(temps, targets, strict=True):
                lines.append(f"{pad}    {lv} = {temp};")
            return [*lines, f"{pad}}}"]
        if not isinstance(stmt.value, ast.Call):
            self.fail(stmt, "an unpacking of other than a tuple or a function's tuple")
        value, vt = self.expr(stmt.value)
        if not (isinstance(vt, tuple) and len(vt) == len(targets)):
            self.fail(stmt, "an unpacking whose value is not a tuple of that length")
        temps = [self.new_temp() for _ in vt]
        lines = [f"{pad}{{"]
        for temp, t in zip(temps[1:], vt[1:], strict=True):
            lines.append(f"{pad}    {_C_TYPE[t]} {temp};")
        outs = "".join(f", &{temp}" for temp in temps[1:])
        lines.append(f"{pad}    {_C_TYPE[vt[0]]} {temps[0]} = {value[:-1]}{outs});")
        for temp, t, (lv, lt) in zip(temps, vt, targets, strict=True):
            lines.append(f"{pad}    {lv} = {self.cast_to(temp, t, lt)};")
        return [*lines, f"{pad}}}"]

    def _returns_value(self, call: str) -> bool:
        name = call.split("(", 1)[0]
        helper = next((h for h in self.module.helpers.values() if h.c_name == name), None)
        return helper is None or helper.return_type is not None

    def return_lines(self, stmt, pad) -> list[str]:
        if stmt.value is None:
            if self.is_step:
                self.fail(stmt, "a return without a value")
            return [f"{pad}return;"]
        if self.top is True:
            self.fail(stmt, "a plant kernel returning a value")
        if self.top == "segments":
            value, vt = self.expr(stmt.value)
            if not (isinstance(vt, tuple) and len(vt) == 2 and all(t in (INT, BOOL) for t in vt)):
                self.fail(stmt, "a modulator returning other than (segments, event bits)")
            return [f"{pad}*n = {value[0]};", f"{pad}return (uint32_t)({value[1]});"]
        if self.top is True:
            self.fail(stmt, "a plant kernel returning a value")
        if self.is_step:
            value, vt = self.expr(stmt.value)
            if vt not in (INT, BOOL):
                self.fail(stmt, "a step returning other than its integer event bits")
            return [f"{pad}return (uint32_t)({value});"]
        value, vt = self.expr(stmt.value)
        if isinstance(self.return_type, tuple):  # the first element returned, the others out
            if isinstance(stmt.value, ast.Call) and vt == self.return_type:
                outs = "".join(f", acd_r{k}" for k in range(1, len(vt)))
                return [f"{pad}return {value[:-1]}{outs});"]  # the same tuple passed through
            if not isinstance(stmt.value, ast.Tuple):
                self.fail(stmt, "a tuple returned from other than a tuple expression")
            lines = [f"{pad}*acd_r{k} = {self.cast_to(v, t, want)};" for k, (v, t, want)
                     in enumerate(zip(value, vt, self.return_type, strict=True)) if k > 0]  # fmt: skip
            return [*lines, f"{pad}return {self.cast_to(value[0], vt[0], self.return_type[0])};"]
        return [f"{pad}return {self.cast_to(value, vt, self.return_type)};"]

    def declarations(self) -> list[str]:
        """The locals' declarations; a step's ``t`` or ``T_s`` that the kernel assigns is a
        local that starts as the argument (Python reads the argument until it is assigned)."""
        by_type: dict[str, list[str]] = {}
        rebound = []
        for name, t in self.types.items():
            if name in self.arg_types:
                continue
            if name in ("t", "T_s") and (self.is_step or self.top):
                rebound.append(f"    {_C_TYPE[t]} {self.local(name)} = {name};")
                continue
            by_type.setdefault(_C_TYPE[t], []).append(self.local(name))
        return [*(f"    {c} {', '.join(names)};" for c, names in by_type.items()), *rebound]


def _helper(module: _Module, target, arg_types: tuple, node, caller: _Function):
    func = _python_function(target)
    key = (func, _fast_math(target, caller.fast), tuple((t[0], t[1].struct, t[1].const, t[1].offset)
                                    if isinstance(t, tuple) and t[0] == "role" else t
                                    for t in arg_types))  # fmt: skip
    found = module.helpers.get(key)
    if found is not None:
        return found
    params = list(inspect.signature(func).parameters)
    if len(params) != len(arg_types):
        caller.fail(node, f"{func.__name__} called with {len(arg_types)} of {len(params)} "
                    "arguments")  # fmt: skip
    # the name follows from the function, its argument types and, for a helper of a kind's
    # arrays, the kind and the bound slots, so the kinds of one file share one definition
    c_name = f"acd_{func.__module__.rsplit('.', 1)[-1].lstrip('_')}_{func.__name__.lstrip('_')}"
    roles = {p: t[1] for p, t in zip(params, arg_types, strict=True)
             if isinstance(t, tuple) and t[0] == "role"}  # fmt: skip
    constants = {p: t[1] for p, t in zip(params, arg_types, strict=True)
                 if isinstance(t, tuple) and t[0] == "const"}  # fmt: skip
    scalars = {p: t for p, t in zip(params, arg_types, strict=True) if not isinstance(t, tuple)}
    if roles:  # written for the kind's structs (each array's role named) and the bound slots
        kind = next(iter(roles.values())).kind
        c_name = f"acd_{kind}_{func.__name__.lstrip('_')}"
        c_name += "".join(f"_{r.struct.rsplit('_', 1)[-1]}{r.offset or ''}" for r in roles.values())
        c_name += "".join(f"_{p}{'m' if k < 0 else ''}{abs(k)}" for p, k in constants.items())
    if any(t != REAL for t in scalars.values()):
        c_name += "_" + "".join({REAL: "r", INT: "i", BOOL: "b", COMPLEX: "c"}[t]
                                for t in scalars.values())  # fmt: skip
    fast = _fast_math(target, caller.fast)
    if fast:
        c_name += "_fast"
    inner = {p: replace(r, name=p) for p, r in roles.items()}
    f = _Function(func, inner, module, c_name, scalars, fast=fast)
    f.constants.update(constants)
    f.infer(f.node.body)
    body = f.block(f.node.body, 1)
    ret = f.return_type
    c_ret = "void" if ret is None else _C_TYPE[ret[0]] if isinstance(ret, tuple) else _C_TYPE[ret]
    args = []
    for p in params:
        if p in inner and inner[p].shape == "reals":
            args.append(f"{'const ' if inner[p].const else ''}ACDRIVE_REAL *{p}")
        elif p in inner:
            args.append(f"{'const ' if inner[p].const else ''}{inner[p].struct} *{p}")
        elif p in scalars:
            args.append(f"{_C_TYPE[scalars[p]]} {p}")
    if isinstance(ret, tuple):  # the other elements through pointers
        args += [f"{_C_TYPE[t]} *acd_r{k}" for k, t in enumerate(ret) if k > 0]
    doc = (inspect.getdoc(func) or func.__name__).split("\n")[0].replace("*/", "* /")
    unused = [f"    (void){p};" for p in params if p in inner or p in scalars]  # -Wextra
    text = "\n".join([f"/* {f.where}: {doc} */",
                      f"static {c_ret} {c_name}({', '.join(args) or 'void'})", "{",
                      *f.declarations(), *unused, *body, "}"])  # fmt: skip
    entry = types.SimpleNamespace(c_name=c_name, text=text, return_type=ret)
    module.helpers[key] = entry
    module.order.append(key)
    return entry


def translate_step(kernel, roles: dict[str, Role]) -> Translated:
    """The C body of a sampled part's step kernel (``step(t, T_s, u, p, s, y)``): ``roles``
    maps the kernel's array arguments by position name (``u``, ``p``, ``s``, ``y``) to their
    layouts. Raises ``UnsupportedKernel`` naming the construct."""
    module = _Module()
    func = _python_function(kernel)
    params = list(inspect.signature(func).parameters)
    if len(params) != 6:
        raise UnsupportedKernel(f"{func.__module__}.{func.__name__}: a step takes "
                                "(t, T_s, u, p, s, y)")  # fmt: skip
    by_name = {params[i]: roles[r] for i, r in ((2, "u"), (3, "p"), (4, "s"), (5, "y"))
               if r in roles}  # fmt: skip
    f = _Function(func, by_name, module, "step", is_step=True, fast=_fast_math(kernel, False))
    for k, standard in ((0, "t"), (1, "T_s")):
        if params[k] != standard:
            f.fail(f.node, f"argument {k + 1} named {params[k]!r} (the step's is {standard!r})")
    f.infer(f.node.body)
    body = f.block(f.node.body, 1)
    helpers = [(module.helpers[k].c_name, module.helpers[k].text) for k in module.order]
    return Translated("\n".join([*f.declarations(), *body]) + "\n", helpers)
