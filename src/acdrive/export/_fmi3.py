"""The FMI 3.0 co-simulation interface in C, beside the FMI 2.0 one (``_fmi2``).

It is written against the same model interface and value-reference tables the generator writes
per FMU (``_fmu.fmi_source``, described in ``_fmi2``'s docstring), with the FMI 3.0 types:
Real variables are ``Float64``, Integer ones ``Int32``, and value reference 0 is the
independent variable ``time`` FMI 3.0 requires (the FMU's time t0 + k T_s). The behaviour is
the FMI 2.0 interface's: whole periods per ``fmi3DoStep`` within the same time tolerance,
parameters checked against their declared rules in ``fmi3SetFloat64``/``fmi3SetInt32`` and
their relations in ``fmi3ExitInitializationMode``, a non-finite output an ``fmi3Error`` naming
it, each refusal one message to ``logMessage``. Co-simulation only, without event mode, early
return, intermediate updates, clocks, FMU state or derivatives: ``fmi3InstantiateModelExchange``
and ``fmi3InstantiateScheduledExecution`` return NULL, the other functions of those features
return ``fmi3Error`` with a message, and the capability flags say so.
"""

#: the functions of the features the FMU does not have: (name, parameters after the instance)
_UNSUPPORTED = (
    ("fmi3EnterEventMode", ""),
    ("fmi3GetNumberOfVariableDependencies",
     "fmi3ValueReference valueReference, size_t *nDependencies"),
    ("fmi3GetVariableDependencies",
     "fmi3ValueReference dependent, size_t elementIndicesOfDependent[], "
     "fmi3ValueReference independents[], size_t elementIndicesOfIndependents[], "
     "fmi3DependencyKind dependencyKinds[], size_t nDependencies"),
    ("fmi3GetFMUState", "fmi3FMUState *FMUState"),
    ("fmi3SetFMUState", "fmi3FMUState FMUState"),
    ("fmi3FreeFMUState", "fmi3FMUState *FMUState"),
    ("fmi3SerializedFMUStateSize", "fmi3FMUState FMUState, size_t *size"),
    ("fmi3SerializeFMUState", "fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size"),
    ("fmi3DeserializeFMUState",
     "const fmi3Byte serializedState[], size_t size, fmi3FMUState *FMUState"),
    ("fmi3GetDirectionalDerivative",
     "const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], "
     "size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], "
     "size_t nSensitivity"),
    ("fmi3GetAdjointDerivative",
     "const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], "
     "size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], "
     "size_t nSensitivity"),
    ("fmi3EnterConfigurationMode", ""),
    ("fmi3ExitConfigurationMode", ""),
    ("fmi3GetClock", "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "fmi3Clock values[]"),
    ("fmi3SetClock", "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "const fmi3Clock values[]"),
    ("fmi3GetIntervalDecimal",
     "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]"),
    ("fmi3GetIntervalFraction",
     "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]"),
    ("fmi3GetShiftDecimal",
     "const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 shifts[]"),
    ("fmi3GetShiftFraction",
     "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "fmi3UInt64 counters[], fmi3UInt64 resolutions[]"),
    ("fmi3SetIntervalDecimal",
     "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "const fmi3Float64 intervals[]"),
    ("fmi3SetIntervalFraction",
     "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]"),
    ("fmi3SetShiftDecimal",
     "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "const fmi3Float64 shifts[]"),
    ("fmi3SetShiftFraction",
     "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]"),
    ("fmi3EvaluateDiscreteStates", ""),
    ("fmi3UpdateDiscreteStates",
     "fmi3Boolean *discreteStatesNeedUpdate, fmi3Boolean *terminateSimulation, "
     "fmi3Boolean *nominalsOfContinuousStatesChanged, "
     "fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined, "
     "fmi3Float64 *nextEventTime"),
    ("fmi3EnterContinuousTimeMode", ""),
    ("fmi3CompletedIntegratorStep",
     "fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *enterEventMode, "
     "fmi3Boolean *terminateSimulation"),
    ("fmi3SetTime", "fmi3Float64 time"),
    ("fmi3SetContinuousStates", "const fmi3Float64 continuousStates[], size_t nContinuousStates"),
    ("fmi3GetContinuousStateDerivatives", "fmi3Float64 derivatives[], size_t nContinuousStates"),
    ("fmi3GetEventIndicators", "fmi3Float64 eventIndicators[], size_t nEventIndicators"),
    ("fmi3GetContinuousStates", "fmi3Float64 continuousStates[], size_t nContinuousStates"),
    ("fmi3GetNominalsOfContinuousStates", "fmi3Float64 nominals[], size_t nContinuousStates"),
    ("fmi3GetNumberOfEventIndicators", "size_t *nEventIndicators"),
    ("fmi3GetNumberOfContinuousStates", "size_t *nContinuousStates"),
    ("fmi3GetOutputDerivatives",
     "const fmi3ValueReference valueReferences[], size_t nValueReferences, "
     "const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues"),
    ("fmi3ActivateModelPartition",
     "fmi3ValueReference clockReference, fmi3Float64 activationTime"),
)  # fmt: skip

#: the variable types the FMU has none of: Get/Set succeed for no value reference only
_ABSENT_TYPES = (
    ("Float32", "fmi3Float32"), ("Int8", "fmi3Int8"), ("UInt8", "fmi3UInt8"),
    ("Int16", "fmi3Int16"), ("UInt16", "fmi3UInt16"), ("UInt32", "fmi3UInt32"),
    ("Int64", "fmi3Int64"), ("UInt64", "fmi3UInt64"), ("Boolean", "fmi3Boolean"),
    ("String", "fmi3String"),
)  # fmt: skip


def _names(parameters: str) -> list[str]:
    """The parameter names of a C parameter list ("const double x[], size_t n" -> x, n)."""
    out = []
    for parameter in parameters.split(","):
        word = parameter.strip().split()[-1] if parameter.strip() else ""
        if word:
            out.append(word.lstrip("*").removesuffix("[]"))
    return out


def _unsupported() -> str:
    L = []
    for name, parameters in _UNSUPPORTED:
        L += [f"fmi3Status {name}(fmi3Instance instance{', ' if parameters else ''}{parameters})",
              "{", *(f"    (void){n};" for n in _names(parameters)),
              f'    return acd_fmu_unsupported(instance, "{name}");', "}", ""]  # fmt: skip
    for kind, c_type in _ABSENT_TYPES:
        for verb, const in (("Get", ""), ("Set", "const ")):
            L += [f"fmi3Status fmi3{verb}{kind}(fmi3Instance instance, "
                  "const fmi3ValueReference valueReferences[],",
                  f"    size_t nValueReferences, {const}{c_type} values[], size_t nValues)", "{",
                  "    (void)valueReferences;", "    (void)values;", "    (void)nValues;",
                  f'    return acd_fmu_absent(instance, "fmi3{verb}{kind}", nValueReferences);',
                  "}", ""]  # fmt: skip
    for verb, const in (("Get", ""), ("Set", "const ")):
        sizes = "size_t valueSizes[]" if verb == "Get" else "const size_t valueSizes[]"
        L += [f"fmi3Status fmi3{verb}Binary(fmi3Instance instance, "
              "const fmi3ValueReference valueReferences[],",
              f"    size_t nValueReferences, {sizes}, {const}fmi3Binary values[], "
              "size_t nValues)", "{",
              "    (void)valueReferences;", "    (void)valueSizes;", "    (void)values;",
              "    (void)nValues;",
              f'    return acd_fmu_absent(instance, "fmi3{verb}Binary", nValueReferences);',
              "}", ""]  # fmt: skip
    return "\n".join(L)


FMI3_WRAPPER = (
    r"""
/* ---- FMI 3.0 co-simulation interface (acdrive.export._fmi3) ---- */

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef enum {
    ACD_INSTANTIATED, ACD_INITIALISING, ACD_STEPPING, ACD_FAILED, ACD_TERMINATED
} acd_fmu_phase;

typedef struct {
    acd_fmu_model model;
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log_message;
    acd_fmu_phase phase;
    fmi3Boolean logging;
    double t0;        /* start time (fmi3EnterInitializationMode) */
    unsigned long k;  /* periods done since t0 */
} acd_fmu_instance;

static void acd_fmu_log(acd_fmu_instance *c, fmi3Status status, const char *format, ...)
{
    char message[512];
    va_list args;
    if (c->log_message == NULL) {
        return;
    }
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    c->log_message(c->environment, status, status == fmi3OK ? "logAll" : "logStatusError",
                   message);
}

static const char *acd_fmu_name(fmi3ValueReference vr)
{
    return vr >= 1 && vr <= ACD_FMU_VARIABLES ? acd_fmu_names[vr] : "(no such variable)";
}

static int acd_fmu_access_of(fmi3ValueReference vr)
{
    return vr >= 1 && vr <= ACD_FMU_VARIABLES ? acd_fmu_access[vr] : 0;
}

/* The difference accepted between a master's time and the FMU's own time t after k periods
   (acdrive.export._fmi2): 2 (k + 1) eps max(|t|, T_s), at least 1e-9 T_s, at most T_s / 4. */
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

static double acd_fmu_time(const acd_fmu_instance *c)
{
    return c->t0 + (double)c->k * acd_fmu_period(&c->model);
}

static fmi3Status acd_fmu_check_value(acd_fmu_instance *c, const char *function,
                                      fmi3ValueReference vr, double value)
{
    const char *rule = acd_fmu_broken_rule(vr, value);
    if (rule == NULL) {
        return fmi3OK;
    }
    acd_fmu_log(c, fmi3Error, "%s: %s = %.17g refused: %s", function, acd_fmu_name(vr), value,
                rule);
    return fmi3Error;
}

static fmi3Status acd_fmu_settable(acd_fmu_instance *c, const char *function,
                                   fmi3ValueReference vr)
{
    switch (acd_fmu_access_of(vr)) {
    case 1:
        acd_fmu_log(c, fmi3Error, "%s: %s is an output: not settable", function,
                    acd_fmu_name(vr));
        return fmi3Error;
    case 2:
        return fmi3OK;
    case 3:
        if (c->phase == ACD_INSTANTIATED || c->phase == ACD_INITIALISING) {
            return fmi3OK;
        }
        acd_fmu_log(c, fmi3Error, "%s: %s is a fixed parameter: set it before "
                    "fmi3ExitInitializationMode", function, acd_fmu_name(vr));
        return fmi3Error;
    case 4:
        acd_fmu_log(c, fmi3Error, "%s: %s is a calculated parameter (derived when the FMU was "
                    "built from the scenario): not settable", function, acd_fmu_name(vr));
        return fmi3Error;
    default:
        acd_fmu_log(c, fmi3Error, "%s: no settable variable of value reference %u", function,
                    (unsigned)vr);
        return fmi3Error;
    }
}

static fmi3Status acd_fmu_unsupported(fmi3Instance c, const char *what)
{
    acd_fmu_log((acd_fmu_instance *)c, fmi3Error, "%s is not supported by this FMU", what);
    return fmi3Error;
}

static fmi3Status acd_fmu_absent(fmi3Instance c, const char *what, size_t n)
{
    if (n == 0) {
        return fmi3OK;
    }
    acd_fmu_log((acd_fmu_instance *)c, fmi3Error, "%s: the FMU has no variable of that type",
                what);
    return fmi3Error;
}

const char *fmi3GetVersion(void)
{
    return fmi3Version;
}

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    (void)nCategories;
    (void)categories;
    ((acd_fmu_instance *)instance)->logging = loggingOn;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName,
                                          fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    if (logMessage != NULL) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "this FMU is for co-simulation only");
    }
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate)
{
    acd_fmu_instance *c;
    (void)instanceName;
    (void)resourcePath;
    (void)visible;
    (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    if (instantiationToken == NULL || strcmp(instantiationToken, ACD_FMU_GUID) != 0
        || eventModeUsed) {
        if (logMessage != NULL) {
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "wrong instantiation token, or event mode asked for: this is a "
                       "co-simulation FMU without event mode of token " ACD_FMU_GUID);
        }
        return NULL;
    }
    c = (acd_fmu_instance *)calloc(1, sizeof(acd_fmu_instance));
    if (c == NULL) {
        return NULL;
    }
    c->environment = instanceEnvironment;
    c->log_message = logMessage;
    c->phase = ACD_INSTANTIATED;
    c->logging = loggingOn;
    c->t0 = 0.0;
    c->k = 0;
    acd_fmu_defaults(&c->model);
    return c;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName,
                                               fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    if (logMessage != NULL) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "this FMU is for co-simulation only");
    }
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    free(instance);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    acd_fmu_instance *c = (acd_fmu_instance *)instance;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    c->t0 = startTime;
    c->phase = ACD_INITIALISING;
    acd_fmu_start(&c->model, c->t0);
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    acd_fmu_instance *c = (acd_fmu_instance *)instance;
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
            const fmi3Float64 *value = acd_fmu_real(&c->model, relation->vr[j]);
            int written = snprintf(values + used, sizeof values - used, "%s%s = %.17g",
                                   j > 0 ? ", " : "", acd_fmu_name(relation->vr[j]),
                                   value != NULL ? *value : 0.0);
            if (written < 0) {
                break;
            }
            used += (size_t)written;
        }
        acd_fmu_log(c, fmi3Error, "fmi3ExitInitializationMode: %s (%s)", relation->rule, values);
        return fmi3Error;
    }
    c->phase = ACD_STEPPING;
    c->k = 0;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    (void)instance;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    ((acd_fmu_instance *)instance)->phase = ACD_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    acd_fmu_instance *c = (acd_fmu_instance *)instance;
    c->phase = ACD_INSTANTIATED; /* also after a failed step */
    c->t0 = 0.0;
    c->k = 0;
    acd_fmu_defaults(&c->model);
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues)
{
    acd_fmu_instance *c = (acd_fmu_instance *)instance;
    size_t i;
    (void)nValues;
    for (i = 0; i < nValueReferences; ++i) {
        fmi3Float64 *ref;
        if (valueReferences[i] == 0) { /* time */
            values[i] = acd_fmu_time(c);
            continue;
        }
        ref = acd_fmu_real(&c->model, valueReferences[i]);
        if (ref == NULL) {
            acd_fmu_log(c, fmi3Error, "fmi3GetFloat64: %u (%s) is not a Float64 variable",
                        (unsigned)valueReferences[i], acd_fmu_name(valueReferences[i]));
            return fmi3Error;
        }
        values[i] = *ref;
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int32 values[], size_t nValues)
{
    acd_fmu_instance *c = (acd_fmu_instance *)instance;
    size_t i;
    (void)nValues;
    for (i = 0; i < nValueReferences; ++i) {
        if (!acd_fmu_get_integer(&c->model, valueReferences[i], &values[i])) {
            acd_fmu_log(c, fmi3Error, "fmi3GetInt32: %u (%s) is not an Int32 variable",
                        (unsigned)valueReferences[i], acd_fmu_name(valueReferences[i]));
            return fmi3Error;
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues)
{
    acd_fmu_instance *c = (acd_fmu_instance *)instance;
    int restart = 0;
    size_t i;
    (void)nValues;
    for (i = 0; i < nValueReferences; ++i) { /* every value checked before any is set */
        const fmi3ValueReference vr = valueReferences[i];
        if (vr == 0 || acd_fmu_real(&c->model, vr) == NULL) {
            acd_fmu_log(c, fmi3Error, "fmi3SetFloat64: %u (%s) is not a settable Float64 "
                        "variable", (unsigned)vr, vr == 0 ? "time" : acd_fmu_name(vr));
            return fmi3Error;
        }
        if (acd_fmu_settable(c, "fmi3SetFloat64", vr) != fmi3OK) {
            return fmi3Error;
        }
        if (acd_fmu_access[vr] == 3
            && acd_fmu_check_value(c, "fmi3SetFloat64", vr, values[i]) != fmi3OK) {
            return fmi3Error;
        }
    }
    for (i = 0; i < nValueReferences; ++i) {
        *acd_fmu_real(&c->model, valueReferences[i]) = values[i];
        restart |= acd_fmu_access[valueReferences[i]] == 3;
    }
    if (restart && c->phase == ACD_INITIALISING) {
        acd_fmu_start(&c->model, c->t0); /* outputs of the new parameters */
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int32 values[], size_t nValues)
{
    acd_fmu_instance *c = (acd_fmu_instance *)instance;
    fmi3Int32 held;
    size_t i;
    (void)nValues;
    for (i = 0; i < nValueReferences; ++i) { /* every value checked before any is set */
        const fmi3ValueReference vr = valueReferences[i];
        if (!acd_fmu_get_integer(&c->model, vr, &held)) {
            acd_fmu_log(c, fmi3Error, "fmi3SetInt32: %u (%s) is not an Int32 variable",
                        (unsigned)vr, acd_fmu_name(vr));
            return fmi3Error;
        }
        if (acd_fmu_settable(c, "fmi3SetInt32", vr) != fmi3OK
            || acd_fmu_check_value(c, "fmi3SetInt32", vr, (double)values[i]) != fmi3OK) {
            return fmi3Error;
        }
    }
    for (i = 0; i < nValueReferences; ++i) {
        (void)acd_fmu_set_integer(&c->model, valueReferences[i], values[i]);
    }
    if (nValueReferences > 0 && c->phase == ACD_INITIALISING) {
        acd_fmu_start(&c->model, c->t0); /* outputs of the new parameters */
    }
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    acd_fmu_instance *c = (acd_fmu_instance *)instance;
    const double period = acd_fmu_period(&c->model);
    const double k = (double)c->k;
    const double now = c->t0 + k * period;
    const double n = floor(communicationStepSize / period + 0.5);
    const double end = c->t0 + (k + n) * period;
    double step_end;
    unsigned long i;
    size_t j;
    (void)noSetFMUStatePriorToCurrentPoint;
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = now;
    if (c->phase == ACD_FAILED) {
        acd_fmu_log(c, fmi3Error, "fmi3DoStep: the FMU stopped at an error at %.17g s: "
                    "fmi3Reset starts it again", now);
        return fmi3Error;
    }
    if (c->phase != ACD_STEPPING) {
        acd_fmu_log(c, fmi3Error, "fmi3DoStep: the FMU is not initialised");
        return fmi3Error;
    }
    if (!(fabs(currentCommunicationPoint - now) <= acd_fmu_time_tolerance(period, k, now))) {
        acd_fmu_log(c, fmi3Error,
                    "fmi3DoStep: the communication point %.17g s is not the FMU's time "
                    "%.17g s (the start of period %lu) within %.3g s", currentCommunicationPoint,
                    now, c->k, acd_fmu_time_tolerance(period, k, now));
        return fmi3Error;
    }
    step_end = currentCommunicationPoint + communicationStepSize;
    if (!(n >= 1.0 && n < 1e15
          && fabs(step_end - end) <= acd_fmu_time_tolerance(period, k + n, end))) {
        acd_fmu_log(c, fmi3Error,
                    "fmi3DoStep: the communication step %.17g s is not a whole number of the "
                    "control period %.17g s (it ends at %.17g s, not at the start of a period)",
                    communicationStepSize, period, step_end);
        return fmi3Error;
    }
    for (i = 0; i < (unsigned long)n; ++i) {
        double t = c->t0 + (double)c->k * period;
        double t_next = c->t0 + (double)(c->k + 1) * period;
        acd_fmu_advance(&c->model, t, t_next);
        c->k += 1;
        *lastSuccessfulTime = t_next;
        for (j = 0; j < acd_fmu_real_output_count; ++j) {
            const fmi3ValueReference vr = acd_fmu_real_outputs[j];
            const double value = *acd_fmu_real(&c->model, vr);
            if (!isfinite(value)) {
                c->phase = ACD_FAILED;
                *terminateSimulation = fmi3True;
                acd_fmu_log(c, fmi3Error,
                            "fmi3DoStep: output %s is %s at %.17g s (after the period from "
                            "%.17g s): the run cannot go on", acd_fmu_name(vr),
                            isnan(value) ? "NaN" : "infinite", t_next, t);
                return fmi3Error;
            }
        }
    }
    return fmi3OK;
}

"""
    + _unsupported()
)
