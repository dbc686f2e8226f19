"""The C both FMI interfaces (``_fmi2``, ``_fmi3``) share: everything but the FMI functions'
signatures, written once against the model interface and tables of ``_fmu.fmi_source``.

Each interface defines before it: ``acd_fmu_status`` (its status type), ``acd_fmu_vr`` (its
value-reference type), ``acd_fmu_int`` (its integer type), ``ACD_FMU_OK``/``ACD_FMU_ERROR``,
``ACD_FMU_API`` (the functions' prefix, "fmi2" or "fmi3", for the messages),
``ACD_FMU_NAME0`` (what value reference 0 is), the instance struct ``acd_fmu_instance`` (with
``model``, ``phase``, ``t0``, ``k``), the phases and ``acd_fmu_log(c, status, format, ...)``.

The rules (``_fmi2``'s docstring): whole periods per step, a master's time within
``acd_fmu_time_tolerance`` of the FMU's, a parameter's value against its declared rule when it
is set, the relations when initialisation ends, every Real output finite after every period;
each refusal one message naming the variable and the rule.
"""

FMI_CORE = r"""
/* ---- shared by the FMI 2.0 and 3.0 interfaces (acdrive.export._fmi_core) ---- */

/* the name of variable vr for a message */
static const char *acd_fmu_name(acd_fmu_vr vr)
{
    if (vr == 0) {
        return ACD_FMU_NAME0;
    }
    return vr <= ACD_FMU_VARIABLES ? acd_fmu_names[vr] : "(no such variable)";
}

static int acd_fmu_access_of(acd_fmu_vr vr)
{
    return vr >= 1 && vr <= ACD_FMU_VARIABLES ? acd_fmu_access[vr] : 0;
}

/* The difference accepted between a master's time and the FMU's own time t after k periods
   (module docstring of acdrive.export._fmi2): 2 (k + 1) eps max(|t|, T_s), four times the
   rounding a master adding its step k times accumulates, at least 1e-9 T_s, at most T_s / 4. */
static double acd_fmu_time_tolerance(double period, double k, double t)
{
    const double scale = fabs(t) > period ? fabs(t) : period;
    double tolerance = 2.0 * (k + 1.0) * DBL_EPSILON * scale;
    if (tolerance < 1e-9 * period) {
        tolerance = 1e-9 * period;
    }
    if (tolerance > 0.25 * period) {
        tolerance = 0.25 * period;
    }
    return tolerance;
}

/* ACD_FMU_OK if a parameter's value obeys its declared rule, else an error with the message */
static acd_fmu_status acd_fmu_check_value(acd_fmu_instance *c, const char *function,
                                          acd_fmu_vr vr, double value)
{
    const char *rule = acd_fmu_broken_rule(vr, value);
    if (rule == NULL) {
        return ACD_FMU_OK;
    }
    acd_fmu_log(c, ACD_FMU_ERROR, "%s: %s = %.17g refused: %s", function, acd_fmu_name(vr),
                value, rule);
    return ACD_FMU_ERROR;
}

/* ACD_FMU_OK if variable vr may be set now, else an error with the message */
static acd_fmu_status acd_fmu_settable(acd_fmu_instance *c, const char *function, acd_fmu_vr vr)
{
    switch (acd_fmu_access_of(vr)) {
    case 1:
        acd_fmu_log(c, ACD_FMU_ERROR, "%s: %s is an output: not settable", function,
                    acd_fmu_name(vr));
        return ACD_FMU_ERROR;
    case 2:
        return ACD_FMU_OK;
    case 3:
        if (c->phase == ACD_INSTANTIATED || c->phase == ACD_INITIALISING) {
            return ACD_FMU_OK;
        }
        acd_fmu_log(c, ACD_FMU_ERROR, "%s: %s is a fixed parameter: set it before "
                    ACD_FMU_API "ExitInitializationMode", function, acd_fmu_name(vr));
        return ACD_FMU_ERROR;
    case 4:
        acd_fmu_log(c, ACD_FMU_ERROR, "%s: %s is a calculated parameter (derived when the FMU "
                    "was built from the scenario): not settable", function, acd_fmu_name(vr));
        return ACD_FMU_ERROR;
    default:
        acd_fmu_log(c, ACD_FMU_ERROR, "%s: %s (%u) is not a settable variable", function,
                    acd_fmu_name(vr), (unsigned)vr);
        return ACD_FMU_ERROR;
    }
}

static acd_fmu_status acd_fmu_get_reals(acd_fmu_instance *c, const char *function,
                                        const acd_fmu_vr vr[], size_t n, double value[])
{
    size_t i;
    for (i = 0; i < n; ++i) {
        double *ref = acd_fmu_real(&c->model, vr[i]);
        if (ref == NULL) {
            acd_fmu_log(c, ACD_FMU_ERROR, "%s: %u (%s) is not a real variable", function,
                        (unsigned)vr[i], acd_fmu_name(vr[i]));
            return ACD_FMU_ERROR;
        }
        value[i] = *ref;
    }
    return ACD_FMU_OK;
}

static acd_fmu_status acd_fmu_get_integers(acd_fmu_instance *c, const char *function,
                                           const acd_fmu_vr vr[], size_t n, acd_fmu_int value[])
{
    size_t i;
    for (i = 0; i < n; ++i) {
        if (!acd_fmu_get_integer(&c->model, vr[i], &value[i])) {
            acd_fmu_log(c, ACD_FMU_ERROR, "%s: %u (%s) is not an integer variable", function,
                        (unsigned)vr[i], acd_fmu_name(vr[i]));
            return ACD_FMU_ERROR;
        }
    }
    return ACD_FMU_OK;
}

/* every value checked (settable now, its rule) before any is set */
static acd_fmu_status acd_fmu_set_reals(acd_fmu_instance *c, const char *function,
                                        const acd_fmu_vr vr[], size_t n, const double value[])
{
    int restart = 0;
    size_t i;
    for (i = 0; i < n; ++i) {
        if (acd_fmu_real(&c->model, vr[i]) == NULL) {
            acd_fmu_log(c, ACD_FMU_ERROR, "%s: %u (%s) is not a real variable", function,
                        (unsigned)vr[i], acd_fmu_name(vr[i]));
            return ACD_FMU_ERROR;
        }
        if (acd_fmu_settable(c, function, vr[i]) != ACD_FMU_OK) {
            return ACD_FMU_ERROR;
        }
        if (acd_fmu_access[vr[i]] == 3
            && acd_fmu_check_value(c, function, vr[i], value[i]) != ACD_FMU_OK) {
            return ACD_FMU_ERROR;
        }
    }
    for (i = 0; i < n; ++i) {
        *acd_fmu_real(&c->model, vr[i]) = value[i];
        restart |= acd_fmu_access[vr[i]] == 3;
    }
    if (restart && c->phase == ACD_INITIALISING) {
        acd_fmu_start(&c->model, c->t0); /* outputs of the new parameters */
    }
    return ACD_FMU_OK;
}

static acd_fmu_status acd_fmu_set_integers(acd_fmu_instance *c, const char *function,
                                           const acd_fmu_vr vr[], size_t n,
                                           const acd_fmu_int value[])
{
    acd_fmu_int held;
    size_t i;
    for (i = 0; i < n; ++i) {
        if (!acd_fmu_get_integer(&c->model, vr[i], &held)) {
            acd_fmu_log(c, ACD_FMU_ERROR, "%s: %u (%s) is not an integer variable", function,
                        (unsigned)vr[i], acd_fmu_name(vr[i]));
            return ACD_FMU_ERROR;
        }
        if (acd_fmu_settable(c, function, vr[i]) != ACD_FMU_OK
            || acd_fmu_check_value(c, function, vr[i], (double)value[i]) != ACD_FMU_OK) {
            return ACD_FMU_ERROR;
        }
    }
    for (i = 0; i < n; ++i) {
        (void)acd_fmu_set_integer(&c->model, vr[i], value[i]);
    }
    if (n > 0 && c->phase == ACD_INITIALISING) {
        acd_fmu_start(&c->model, c->t0); /* outputs of the new parameters */
    }
    return ACD_FMU_OK;
}

/* the relations over several parameters, when initialisation ends */
static acd_fmu_status acd_fmu_check_relations(acd_fmu_instance *c)
{
    int i;
    for (i = 0; i < ACD_FMU_RELATIONS; ++i) {
        const acd_fmu_relation *relation = &acd_fmu_relations[i];
        char values[256];
        size_t used = 0;
        unsigned j;
        if (acd_fmu_relation_holds(&c->model, i)) {
            continue;
        }
        values[0] = '\0';
        for (j = 0; j < relation->n && used < sizeof values; ++j) {
            const double *value = acd_fmu_real(&c->model, relation->vr[j]);
            int written = snprintf(values + used, sizeof values - used, "%s%s = %.17g",
                                   j > 0 ? ", " : "", acd_fmu_name(relation->vr[j]),
                                   value != NULL ? *value : 0.0);
            if (written < 0) {
                break;
            }
            used += (size_t)written;
        }
        acd_fmu_log(c, ACD_FMU_ERROR, ACD_FMU_API "ExitInitializationMode: %s (%s)",
                    relation->rule, values);
        return ACD_FMU_ERROR;
    }
    return ACD_FMU_OK;
}

/* A communication step from t of h: whole periods of the FMU's own time; *failed set when an
   output is not finite (the instance then refuses further steps) */
static acd_fmu_status acd_fmu_step(acd_fmu_instance *c, double t, double h, int *failed)
{
    const double period = acd_fmu_period(&c->model);
    const double k = (double)c->k;
    const double now = c->t0 + k * period;
    const double n = floor(h / period + 0.5);
    const double end = c->t0 + (k + n) * period;
    double step_end;
    unsigned long i;
    size_t j;
    *failed = 0;
    if (c->phase == ACD_FAILED) {
        acd_fmu_log(c, ACD_FMU_ERROR, ACD_FMU_API "DoStep: the FMU stopped at an error at "
                    "%.17g s: " ACD_FMU_API "Reset starts it again", now);
        return ACD_FMU_ERROR;
    }
    if (c->phase != ACD_STEPPING) {
        acd_fmu_log(c, ACD_FMU_ERROR, ACD_FMU_API "DoStep: the FMU is not initialised");
        return ACD_FMU_ERROR;
    }
    if (!(fabs(t - now) <= acd_fmu_time_tolerance(period, k, now))) {
        acd_fmu_log(c, ACD_FMU_ERROR,
                    ACD_FMU_API "DoStep: the communication point %.17g s is not the FMU's time "
                    "%.17g s (the start of period %lu) within %.3g s", t, now, c->k,
                    acd_fmu_time_tolerance(period, k, now));
        return ACD_FMU_ERROR;
    }
    step_end = t + h;
    if (!(n >= 1.0 && n < 1e15
          && fabs(step_end - end) <= acd_fmu_time_tolerance(period, k + n, end))) {
        acd_fmu_log(c, ACD_FMU_ERROR,
                    ACD_FMU_API "DoStep: the communication step %.17g s is not a whole number "
                    "of the control period %.17g s (it ends at %.17g s, not at the start of a "
                    "period)", h, period, step_end);
        return ACD_FMU_ERROR;
    }
    for (i = 0; i < (unsigned long)n; ++i) {
        double t_k = c->t0 + (double)c->k * period;
        double t_next = c->t0 + (double)(c->k + 1) * period;
        acd_fmu_advance(&c->model, t_k, t_next);
        c->k += 1;
        for (j = 0; j < acd_fmu_real_output_count; ++j) {
            const acd_fmu_vr vr = acd_fmu_real_outputs[j];
            const double value = *acd_fmu_real(&c->model, vr);
            if (!isfinite(value)) {
                c->phase = ACD_FAILED;
                *failed = 1;
                acd_fmu_log(c, ACD_FMU_ERROR,
                            ACD_FMU_API "DoStep: output %s is %s at %.17g s (after the period "
                            "from %.17g s): the run cannot go on", acd_fmu_name(vr),
                            isnan(value) ? "NaN" : "infinite", t_next, t_k);
                return ACD_FMU_ERROR;
            }
        }
    }
    return ACD_FMU_OK;
}

static acd_fmu_status acd_fmu_unsupported(void *c, const char *what)
{
    acd_fmu_log((acd_fmu_instance *)c, ACD_FMU_ERROR, "%s is not supported by this FMU", what);
    return ACD_FMU_ERROR;
}
"""
