"""A part kind's C from its kernels: the ``CStep`` of a sampled kind (``c_step``) and the
``PlantC`` of a continuous kind or a modulator (``c_plant``), each body written by the kernel
translator (``sim._ccode._translate``) against the structs the kind's layouts declare; a kind
whose layouts are set per instance gets its C per instance (``translate_part``, with its
``STRUCTURAL`` parameters bound). Also the arithmetic of a real mixed with a complex number the
translated bodies call (``KERNEL_ARITHMETIC``)."""

from __future__ import annotations

import inspect

from acdrive.sim._ccode._pieces import (
    TABLE2D_AT,
    TABLE_AT,
    TANH,
    CStep,
    CSupport,
    PlantC,
    kind_name,
)
from acdrive.sim._ccode._translate import (
    Role,
    Translated,
    UnsupportedKernel,
    _fast_math,
    _Function,
    _Module,
    _python_function,
    translate_step,
)


#: the mixed real and complex operations of the translated kernels (module docstring)
KERNEL_ARITHMETIC = r"""
/* -z */
static inline acd_complex acd_cneg(acd_complex z)
{
    return acd_c(-z.re, -z.im);
}

/* fast-math forms of a real mixed with a complex number (module docstring) */
static inline acd_complex acd_caddr(acd_complex z, ACDRIVE_REAL r)
{
    return acd_c(z.re + r, z.im);
}

static inline acd_complex acd_raddc(ACDRIVE_REAL r, acd_complex z)
{
    return acd_c(r + z.re, z.im);
}

static inline acd_complex acd_csubr(acd_complex z, ACDRIVE_REAL r)
{
    return acd_c(z.re - r, z.im);
}

static inline acd_complex acd_rsubc(ACDRIVE_REAL r, acd_complex z)
{
    return acd_c(r - z.re, -z.im);
}

static inline acd_complex acd_cmulr(acd_complex z, ACDRIVE_REAL r)
{
    return acd_c(z.re * r, z.im * r);
}

static inline acd_complex acd_cdivr(acd_complex z, ACDRIVE_REAL r)
{
    return acd_c(z.re / r, z.im / r);
}

/* the C library's sine and cosine (numba's complex exp calls them, not acdrive's) */
#ifdef ACDRIVE_FLOAT
#define ACD_LIB_SIN sinf
#define ACD_LIB_COS cosf
#else
#define ACD_LIB_SIN sin
#define ACD_LIB_COS cos
#endif

/* exp(z) as numba computes it (cmath.exp): exp(re) (cos im + j sin im), and its values at
   infinities and NaN */
static acd_complex acd_cexp(acd_complex z)
{
    ACDRIVE_REAL x = z.re, y = z.im, r, c, s;
    if (isfinite(x)) {
        if (!isfinite(y)) {
            return acd_c(NAN, NAN);
        }
        c = ACD_LIB_COS(y);
        s = ACD_LIB_SIN(y);
        r = ACD_EXP(x);
        return acd_c(r * c, r * s);
    }
    if (isnan(x)) {
        return y != ACD_R(0.0) ? acd_c(x, x) : acd_c(x, y);
    }
    if (x > ACD_R(0.0)) { /* +inf: a zero cosine or sine stays zero */
        if (!isfinite(y)) {
            return acd_c(x, NAN);
        }
        c = ACD_LIB_COS(y);
        s = ACD_LIB_SIN(y);
        return acd_c(c != ACD_R(0.0) ? c * x : c, s != ACD_R(0.0) ? s * x : s);
    }
    if (!isfinite(y)) { /* -inf */
        return acd_c(ACD_R(0.0), ACD_R(0.0));
    }
    r = ACD_EXP(x);
    c = ACD_LIB_COS(y);
    s = ACD_LIB_SIN(y);
    return acd_c(r * c, r * s);
}
"""


def _kernel_layouts(cls, part=None) -> dict[str, Role]:
    """The step's roles from the class's layouts (or the instance's, for a per-instance kind)."""
    kind, of = kind_name(cls), part if part is not None else cls
    return {"u": Role(of.INPUTS, "u", f"acd_{kind}_in", True, kind),
            "p": Role(of.PARAMS, "p", f"acd_{kind}_params", True, kind),
            "s": Role(of.STATES, "s", f"acd_{kind}_state", False, kind),
            "y": Role(of.OUTPUTS, "y", f"acd_{kind}_out", False, kind)}  # fmt: skip


def _support(translated: Translated) -> tuple:
    helpers = tuple(CSupport(name, text) for name, text in translated.helpers)
    return (TABLE_AT, TABLE2D_AT, TANH, CSupport("kernel_arithmetic", KERNEL_ARITHMETIC), *helpers)


#: translations of per-instance kinds, by what they depend on (``_structure``): the body and the
#: support of an instance are read separately, and instances of one structure share their C
_PER_INSTANCE: dict[tuple, Translated] = {}


def _structure(part, role: str) -> tuple:
    """What a per-instance kind's C depends on: its class, the kernel role, the instance's
    layouts (names and kinds of every quantity) and its ``STRUCTURAL`` values."""
    layouts = tuple(tuple((v.name, v.kind) for v in getattr(part, attr))
                    for attr in ("PARAMS", "STATES", "INPUTS", "OUTPUTS"))  # fmt: skip
    structural = tuple(float(part.p[part.PARAMS.slot(name)])
                       for name in getattr(type(part), "STRUCTURAL", ()))  # fmt: skip
    return type(part), role, layouts, structural


def _once(part, role: str, translate) -> Translated:
    key = _structure(part, role)
    if key not in _PER_INSTANCE:
        _PER_INSTANCE[key] = translate()
    return _PER_INSTANCE[key]


def translate_part(part) -> Translated:
    """The C of a per-instance kind's step for ``part``: its own layouts, and the values of
    the parameters its class names in ``STRUCTURAL`` (the controller's order) bound."""
    return _once(part, "step", lambda: _translate_part(part))


def _translate_part(part) -> Translated:
    roles = _kernel_layouts(type(part), part)
    for name in getattr(type(part), "STRUCTURAL", ()):
        slot = part.PARAMS.slot(name)
        roles["p"].structural[slot] = float(part.p[slot])
    return translate_step(type(part).step, roles)


def c_step(cls, source: str):
    """The ``CStep`` of sampled part class ``cls`` generated from its ``step`` kernel
    (``translate_step``), ``source`` naming the paper and equations it implements. A kind
    whose layouts are set per instance (``PER_INSTANCE``), or whose C is written for the values
    of some of its parameters (``STRUCTURAL``), gets its C per instance (``translate_part``),
    once per structure."""
    if getattr(cls, "PER_INSTANCE", None) or getattr(cls, "STRUCTURAL", None):
        return CStep(body=lambda part: translate_part(part).body, source=source,
                     support=lambda part: _support(translate_part(part)), from_kernel=True)  # fmt: skip
    translated = translate_step(cls.step, _kernel_layouts(cls))
    return CStep(body=translated.body, source=source, support=_support(translated),
                 from_kernel=True)  # fmt: skip


#: the arguments of each plant kernel role (``sim._kernels.ROLES``) -> the layout each array is
#: and whether the kernel writes it
PLANT_SIGNATURES = {
    "state_outputs": ("t", "x", "p", "y"),
    "direct_outputs": ("t", "x", "u", "p", "y"),
    "rhs": ("t", "x", "u", "p", "y", "dx"),
    "project": ("x", "p"),
    "segments": ("T_s", "u", "p", "s", "dt", "v"),
}
_PLANT_ARRAYS = {"x": ("STATES", "state"), "u": ("INPUTS", "in"), "p": ("PARAMS", "params"),
                 "y": ("OUTPUTS", "out"), "dx": ("STATES", "state"), "s": ("STATES", "state"),
                 "dt": ("STATES", "reals"), "v": ("OUTPUTS", "out")}  # fmt: skip
_PLANT_WRITES = {"state_outputs": {"y"}, "direct_outputs": {"y"}, "rhs": {"dx"},
                 "project": {"x"}, "segments": {"s", "dt", "v"}}  # fmt: skip
_SHAPES = {"dt": "reals", "v": "segments"}


def translate_plant(kernel, role: str, of) -> Translated:
    """The C body of a continuous part's kernel ``role`` (``PLANT_SIGNATURES``) for the class
    (or, per instance, the part) ``of``. A kernel compiled with fast-math flags (``jit_fast``:
    every tier inlines it with its own flags) has a real mixed with a complex number in the
    form those flags fold the promoted operation to (module docstring)."""
    cls = of if isinstance(of, type) else type(of)
    kind = kind_name(cls)
    func = _python_function(kernel)
    params = list(inspect.signature(func).parameters)
    standard = PLANT_SIGNATURES[role]
    if len(params) != len(standard):
        raise UnsupportedKernel(f"{func.__module__}.{func.__name__}: a {role} kernel takes "
                                f"({', '.join(standard)})")  # fmt: skip
    roles = {}
    for name, std in zip(params, standard, strict=True):
        if std in ("t", "T_s"):
            continue
        attr, suffix = _PLANT_ARRAYS[std]
        roles[name] = Role(getattr(of, attr), std, f"acd_{kind}_{suffix}",
                           std not in _PLANT_WRITES[role], kind,
                           shape=_SHAPES.get(std, "struct"))  # fmt: skip
    top = "segments" if role == "segments" else True
    f = _Function(func, roles, _Module(), role, fast=_fast_math(kernel, False), top=top)
    if standard[0] in ("t", "T_s") and params[0] != standard[0]:
        f.fail(f.node, f"argument 1 named {params[0]!r} (the kernel's is {standard[0]!r})")
    f.infer(f.node.body)
    body = f.block(f.node.body, 1)
    module = f.module
    helpers = [(module.helpers[k].c_name, module.helpers[k].text) for k in module.order]
    return Translated("\n".join([*f.declarations(), *body]) + "\n", helpers)


def _plant_part(kernel, role: str, part) -> Translated:
    """``translate_plant`` for an instance of a per-instance kind, once per structure."""
    return _once(part, role, lambda: translate_plant(kernel, role, part))


def _body_or_none(body: str) -> str | None:
    """A kernel that does nothing (a part without states has an empty ``rhs``) has no C."""
    return body if body.strip() else None


def c_plant(cls, source: str):
    """The ``PlantC`` of continuous part class ``cls`` generated from its kernels
    (``translate_plant``; per instance for a kind whose layouts are set per instance)."""
    kernels = {role: kernel for role, kernel in cls.kernels(cls.__new__(cls)).items()
               if role in PLANT_SIGNATURES}  # fmt: skip
    per_instance = bool(getattr(cls, "PER_INSTANCE", None))
    bodies, supports = {}, []
    for role, kernel in kernels.items():
        if per_instance:
            bodies[role] = (lambda part, kernel=kernel, role=role:
                            _body_or_none(_plant_part(kernel, role, part).body))  # fmt: skip
        else:
            translated = translate_plant(kernel, role, cls)
            bodies[role] = _body_or_none(translated.body)
            supports += list(_support(translated))
    if per_instance:
        def support(part):
            out = []
            for role, kernel in kernels.items():
                out += list(_support(_plant_part(kernel, role, part)))
            return tuple(out)
        return PlantC(source=source, support=support, from_kernel=True, **bodies)
    return PlantC(source=source, support=tuple(supports), from_kernel=True, **bodies)
