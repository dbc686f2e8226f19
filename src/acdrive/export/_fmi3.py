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

from acdrive.export._fmi_core import FMI_CORE

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

typedef fmi3Status acd_fmu_status;
typedef fmi3ValueReference acd_fmu_vr;
typedef fmi3Int32 acd_fmu_int;
#define ACD_FMU_OK fmi3OK
#define ACD_FMU_ERROR fmi3Error
#define ACD_FMU_API "fmi3"
#define ACD_FMU_NAME0 "time"

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

"""
    + FMI_CORE
    + r"""
static double acd_fmu_time(const acd_fmu_instance *c)
{
    return c->t0 + (double)c->k * acd_fmu_period(&c->model);
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
    if (acd_fmu_check_relations(c) != fmi3OK) {
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
        if (valueReferences[i] == 0) { /* time */
            values[i] = acd_fmu_time(c);
        } else if (acd_fmu_get_reals(c, "fmi3GetFloat64", &valueReferences[i], 1, &values[i])
                   != fmi3OK) {
            return fmi3Error;
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int32 values[], size_t nValues)
{
    (void)nValues;
    return acd_fmu_get_integers((acd_fmu_instance *)instance, "fmi3GetInt32", valueReferences,
                                nValueReferences, values);
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues)
{
    (void)nValues;
    return acd_fmu_set_reals((acd_fmu_instance *)instance, "fmi3SetFloat64", valueReferences,
                             nValueReferences, values);
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int32 values[], size_t nValues)
{
    (void)nValues;
    return acd_fmu_set_integers((acd_fmu_instance *)instance, "fmi3SetInt32", valueReferences,
                                nValueReferences, values);
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    acd_fmu_instance *c = (acd_fmu_instance *)instance;
    int failed;
    fmi3Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    status = acd_fmu_step(c, currentCommunicationPoint, communicationStepSize, &failed);
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = failed ? fmi3True : fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = acd_fmu_time(c);
    return status;
}

"""
    + _unsupported()
)
