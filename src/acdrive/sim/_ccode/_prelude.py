"""The C text every exported file starts with: the real type, the <math.h> functions by
precision, the complex space vector and its arithmetic.

``ACDRIVE_REAL`` is ``double`` unless the file is compiled with ``-DACDRIVE_FLOAT``, which makes
it ``float`` and switches every math function to its ``f`` form (sinf, sqrtf, ...) so that a
Cortex-M4F's single-precision FPU does all the work. Of C99 <math.h> the files of the built-in
scenarios call, all of it in newlib's libm: the controller chains call ``acos, atan2, exp,
fabs, floor, fmod, log, sqrt``, and in the float build also ``cos, hypot, sin``; the plant calls
``cos, exp, floor, nextafter, sin, sqrt, tanh``, in the double build also ``fabs``, and in the
float build also ``hypot`` (the double build's sine, cosine and magnitude are acdrive's own,
below, whose reduction calls ``fabs`` and ``floor``; the library's sine and cosine are those of
numba's complex exponential, which the unbalanced grid's EMFs take). These are the calls
compiled into the objects, not a list kept by hand: ``tests/test_export_compilers.py`` compiles
every built-in scenario's files and compares.

A file holds only the helpers below that its code calls (``_helpers``): an unused ``static``
function is a warning on clang, ``static inline`` too.

The complex helpers repeat, operation for operation, what numba compiles for the kernels'
Python complex numbers (CPython's algorithms): a product is (ac - bd) + j(ad + bc), a quotient
is Smith's algorithm as in CPython's ``_Py_c_quot``, an angle is ``atan2(im, re)``. Sine, cosine
and a magnitude are acdrive's own, as every compiled tier computes them (``sim._lane_math``):
``acd_sincos`` is the same reduction and series with the same constants, a magnitude is
sqrt(re^2 + im^2). With ``-ffp-contract=off`` the double build then rounds as the kernels do.
The float build keeps the C library's ``sinf``, ``cosf`` and ``hypotf`` (newlib's on the
Cortex-M4F): its series would need constants of its own, and nothing compares it bit for bit.
"""

from acdrive.sim._sincos_constants import (
    COSINE_TERMS,
    PIO2_PARTS,
    QUADRANT_LIMIT,
    SINE_TERMS,
    TWO_OVER_PI,
)

#: the float build's finite stand-in for "no limit" (``ACD_HUGE``; the kernels' and the double
#: build's is 1e300, beyond float's range): a float comparison leaves out the samples where
#: both runs hold their stand-in (the export's software-in-the-loop comparison,
#: ``acdrive.export._sil.deviation``)
FLOAT_NO_LIMIT = 1e38

PRELUDE = r"""
#ifndef ACDRIVE_PRELUDE_H /* once per translation unit, whichever generated headers it includes */
#define ACDRIVE_PRELUDE_H
#ifdef ACDRIVE_FLOAT
#define ACDRIVE_REAL float
#define ACD_SQRT sqrtf
#define ACD_SIN sinf
#define ACD_COS cosf
#define ACD_ATAN2 atan2f
#define ACD_HYPOT hypotf
#define ACD_EXP expf
#define ACD_LOG logf
#define ACD_FLOOR floorf
#define ACD_FMOD fmodf
#define ACD_FABS fabsf
#define ACD_ACOS acosf
#define ACD_NEXTAFTER nextafterf
#define ACD_HUGE ACD_R(@FLOAT_NO_LIMIT@) /* a finite stand-in for "no limit" (1e300 in the double build) */
#else
#define ACDRIVE_REAL double
#define ACD_SQRT sqrt
#define ACD_SIN acd_sin /* acdrive's sine and cosine (the helpers' acd_sincos) */
#define ACD_COS acd_cos
#define ACD_ATAN2 atan2
#define ACD_HYPOT hypot
#define ACD_EXP exp
#define ACD_LOG log
#define ACD_FLOOR floor
#define ACD_FMOD fmod
#define ACD_FABS fabs
#define ACD_ACOS acos
#define ACD_NEXTAFTER nextafter
#define ACD_HUGE ACD_R(1e300) /* a finite stand-in for "no limit" */
#endif

/* a literal in the build's precision (folded by the compiler) */
#define ACD_R(x) ((ACDRIVE_REAL)(x))
#define ACD_PI ACD_R(3.141592653589793)
#define ACD_INF ((ACDRIVE_REAL)HUGE_VAL) /* +infinity (HUGE_VAL of <math.h>) */
/* a stage time t held at cap (Python's min(t, cap) for numbers: the first of two equal ones) */
#define ACD_CAPPED(t, cap) ((cap) < (t) ? (cap) : (t))

/* a space vector: real and imaginary parts (the kernels' complex numbers) */
typedef struct {
    ACDRIVE_REAL re;
    ACDRIVE_REAL im;
} acd_complex;
#endif /* ACDRIVE_PRELUDE_H */
"""

PRELUDE = PRELUDE.replace("@FLOAT_NO_LIMIT@", repr(FLOAT_NO_LIMIT))

HELPERS = r"""
static inline acd_complex acd_c(ACDRIVE_REAL re, ACDRIVE_REAL im)
{
    acd_complex z;
    z.re = re;
    z.im = im;
    return z;
}

static inline acd_complex acd_cadd(acd_complex a, acd_complex b)
{
    return acd_c(a.re + b.re, a.im + b.im);
}

static inline acd_complex acd_csub(acd_complex a, acd_complex b)
{
    return acd_c(a.re - b.re, a.im - b.im);
}

/* (a + jb)(c + jd) = (ac - bd) + j(ad + bc) */
static inline acd_complex acd_cmul(acd_complex z, acd_complex w)
{
    ACDRIVE_REAL ac = z.re * w.re, bd = z.im * w.im, ad = z.re * w.im, bc = z.im * w.re;
    return acd_c(ac - bd, ad + bc);
}

/* a real times a complex, as the complex product with (r + j0) rounds for finite values */
static inline acd_complex acd_cscale(ACDRIVE_REAL r, acd_complex z)
{
    return acd_c(r * z.re, r * z.im);
}

/* z / w by Smith's algorithm (the order of CPython's _Py_c_quot) */
static inline acd_complex acd_cdiv(acd_complex z, acd_complex w)
{
    ACDRIVE_REAL ratio, denom;
    if (ACD_FABS(w.re) >= ACD_FABS(w.im)) {
        ratio = w.im / w.re;
        denom = w.re + w.im * ratio;
        return acd_c((z.re + z.im * ratio) / denom, (z.im - z.re * ratio) / denom);
    }
    ratio = w.re / w.im;
    denom = w.re * ratio + w.im;
    return acd_c((z.re * ratio + z.im) / denom, (z.im * ratio - z.re) / denom);
}

static inline acd_complex acd_conj(acd_complex z)
{
    return acd_c(z.re, -z.im);
}

static inline ACDRIVE_REAL acd_cabs(acd_complex z)
{
#ifdef ACDRIVE_FLOAT
    return ACD_HYPOT(z.re, z.im);
#else
    return ACD_SQRT(z.re * z.re + z.im * z.im); /* sim._lane_math.magnitude */
#endif
}
@SINCOS@
static inline ACDRIVE_REAL acd_carg(acd_complex z)
{
    return ACD_ATAN2(z.im, z.re);
}

/* Python's x % m for reals: the remainder takes the sign of m */
static inline ACDRIVE_REAL acd_pymod(ACDRIVE_REAL x, ACDRIVE_REAL m)
{
    ACDRIVE_REAL r = ACD_FMOD(x, m);
    if (r != ACD_R(0.0)) {
        if ((m < ACD_R(0.0)) != (r < ACD_R(0.0))) {
            r += m;
        }
    } else {
        r = (m < ACD_R(0.0)) ? -ACD_R(0.0) : ACD_R(0.0);
    }
    return r;
}

/* Python's max(a, b) and min(a, b) of two reals */
static inline ACDRIVE_REAL acd_max(ACDRIVE_REAL a, ACDRIVE_REAL b)
{
    return (b > a) ? b : a;
}

static inline ACDRIVE_REAL acd_min(ACDRIVE_REAL a, ACDRIVE_REAL b)
{
    return (b < a) ? b : a;
}
"""


def _horner(variable: str, coefficients) -> str:
    """c_0 + v (c_1 + v (c_2 + ...)) in C, nested as ``sim._lane_math`` writes it."""
    text = repr(coefficients[-1])
    for c in reversed(coefficients[:-1]):
        text = f"{c!r} + {variable} * ({text})"
    return text


#: ``sim._lane_math.sincos`` in C, operation for operation (the double build)
SINCOS = f"""
#ifndef ACDRIVE_FLOAT
/* (cos x, sin x): x reduced by the nearest multiple k of pi/2 in four parts, the Taylor series
   of sine and cosine on |r| <= pi/4, the quadrant k mod 4 (acdrive.sim._lane_math.sincos) */
static inline void acd_sincos(double x, double *cos_x, double *sin_x)
{{
    double k = floor(x * {TWO_OVER_PI!r} + 0.5);
    double r = (((x - k * {PIO2_PARTS[0]!r}) - k * {PIO2_PARTS[1]!r}) - k * {PIO2_PARTS[2]!r}) - k * {PIO2_PARTS[3]!r};
    double r2 = r * r;
    double s = r + r * r2 * ({_horner("r2", SINE_TERMS)});
    double c = 1.0 - 0.5 * r2 + r2 * r2 * ({_horner("r2", COSINE_TERMS)});
    long long q = fabs(k) < {QUADRANT_LIMIT!r} ? ((long long)k & 3) : 0;
    double cos_part = (q & 1) ? s : c, sin_part = (q & 1) ? c : s;
    double sin_sign = 1.0 - 2.0 * (double)((q >> 1) & 1);
    double cos_sign = 1.0 - 2.0 * (double)(((q + 1) >> 1) & 1);
    *cos_x = cos_part * cos_sign;
    *sin_x = sin_part * sin_sign;
}}

static inline double acd_sin(double x)
{{
    double c, s;
    acd_sincos(x, &c, &s);
    return s;
}}

static inline double acd_cos(double x)
{{
    double c, s;
    acd_sincos(x, &c, &s);
    return c;
}}
#endif
"""

HELPERS = HELPERS.replace("@SINCOS@", SINCOS)
