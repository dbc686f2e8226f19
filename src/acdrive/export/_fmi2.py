"""The FMI 2.0 co-simulation interface in C, the same for the controller FMU and the plant FMU.

It is written against a small model interface the generator writes per FMU (``_fmu.glue``):

* ``acd_fmu_model``: a struct holding the generated C's parameters, states, inputs, outputs;
* ``acd_fmu_defaults(m)``: the exported values (``_set_params``, the inputs' start values);
* ``acd_fmu_start(m, t0)``: the start at ``t0`` (``_reset``), called on entering initialisation
  and again whenever a parameter is set during it;
* ``acd_fmu_period(m)``: the control period T_s [s];
* ``acd_fmu_advance(m, t, t_next)``: one period from t (the sampled step or the plant's
  modulation and integration), the outputs then hold their values at ``t_next``;
* ``acd_fmu_real(m, vr)``: the address of Real variable ``vr`` (NULL if none) and
  ``acd_fmu_access[vr]``: 1 output, 2 input, 3 parameter;
* ``acd_fmu_integer(m, vr, &value)``: Integer variable ``vr`` (the event bits), 0 if none.

``fmi2DoStep`` advances whole periods: a communication step of n periods (n >= 1, within 1e-9
of a period, the rounding of a master's t_{k+1} - t_k) runs n periods; the time of period k is
``t0 + k T_s`` from the FMU's own count, as in acdrive's loop. A step that is not a whole number
of periods, or a communication point that is not the FMU's time, is refused with ``fmi2Error``
and a message to the logger. No FMU state (get/set/serialise), no directional derivatives, no
input derivatives: the capability flags say so and those functions return ``fmi2Error``.
"""

FMI2_WRAPPER = r"""
/* ---- FMI 2.0 co-simulation interface (acdrive.export._fmi2) ---- */

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define ACD_FMU_STEP_RTOL 1e-9 /* a step within this fraction of a whole number of periods */

typedef enum { ACD_INSTANTIATED, ACD_INITIALISING, ACD_STEPPING, ACD_TERMINATED } acd_fmu_phase;

typedef struct {
    acd_fmu_model model;
    const fmi2CallbackFunctions *functions;
    char name[64];
    acd_fmu_phase phase;
    fmi2Boolean logging;
    double t0;        /* start time (fmi2SetupExperiment) */
    unsigned long k;  /* periods done since t0 */
} acd_fmu_instance;

static void acd_fmu_log(acd_fmu_instance *c, fmi2Status status, const char *format, ...)
{
    char message[256];
    va_list args;
    if (c->functions == NULL || c->functions->logger == NULL) {
        return;
    }
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    c->functions->logger(c->functions->componentEnvironment, c->name, status,
                         status == fmi2OK ? "logAll" : "logStatusError", "%s", message);
}

const char *fmi2GetTypesPlatform(void)
{
    return fmi2TypesPlatform;
}

const char *fmi2GetVersion(void)
{
    return fmi2Version;
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    (void)nCategories;
    (void)categories;
    ((acd_fmu_instance *)c)->logging = loggingOn;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    acd_fmu_instance *c;
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL) {
        return NULL;
    }
    if (fmuType != fmi2CoSimulation || fmuGUID == NULL || strcmp(fmuGUID, ACD_FMU_GUID) != 0) {
        if (functions->logger != NULL) {
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", "%s",
                              "wrong GUID or type: this is a co-simulation FMU of GUID "
                              ACD_FMU_GUID);
        }
        return NULL;
    }
    c = (acd_fmu_instance *)functions->allocateMemory(1, sizeof(acd_fmu_instance));
    if (c == NULL) {
        return NULL;
    }
    c->functions = functions;
    strncpy(c->name, instanceName != NULL ? instanceName : "", sizeof c->name - 1);
    c->name[sizeof c->name - 1] = '\0';
    c->phase = ACD_INSTANTIATED;
    c->logging = loggingOn;
    c->t0 = 0.0;
    c->k = 0;
    acd_fmu_defaults(&c->model);
    return c;
}

void fmi2FreeInstance(fmi2Component c)
{
    acd_fmu_instance *instance = (acd_fmu_instance *)c;
    if (instance != NULL) {
        instance->functions->freeMemory(instance);
    }
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    ((acd_fmu_instance *)c)->t0 = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    acd_fmu_instance *instance = (acd_fmu_instance *)c;
    instance->phase = ACD_INITIALISING;
    acd_fmu_start(&instance->model, instance->t0);
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    acd_fmu_instance *instance = (acd_fmu_instance *)c;
    instance->phase = ACD_STEPPING;
    instance->k = 0;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    ((acd_fmu_instance *)c)->phase = ACD_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    acd_fmu_instance *instance = (acd_fmu_instance *)c;
    instance->phase = ACD_INSTANTIATED;
    instance->k = 0;
    acd_fmu_defaults(&instance->model);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    acd_fmu_instance *instance = (acd_fmu_instance *)c;
    size_t i;
    for (i = 0; i < nvr; ++i) {
        fmi2Real *ref = acd_fmu_real(&instance->model, vr[i]);
        if (ref == NULL) {
            acd_fmu_log(instance, fmi2Error, "fmi2GetReal: no Real variable %u", vr[i]);
            return fmi2Error;
        }
        value[i] = *ref;
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    acd_fmu_instance *instance = (acd_fmu_instance *)c;
    size_t i;
    for (i = 0; i < nvr; ++i) {
        if (!acd_fmu_integer(&instance->model, vr[i], &value[i])) {
            acd_fmu_log(instance, fmi2Error, "fmi2GetInteger: no Integer variable %u", vr[i]);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    if (nvr == 0) {
        return fmi2OK;
    }
    acd_fmu_log((acd_fmu_instance *)c, fmi2Error, "fmi2GetBoolean: the FMU has no Boolean");
    return fmi2Error;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    (void)vr;
    (void)value;
    if (nvr == 0) {
        return fmi2OK;
    }
    acd_fmu_log((acd_fmu_instance *)c, fmi2Error, "fmi2GetString: the FMU has no String");
    return fmi2Error;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    acd_fmu_instance *instance = (acd_fmu_instance *)c;
    int restart = 0;
    size_t i;
    for (i = 0; i < nvr; ++i) {
        fmi2Real *ref = acd_fmu_real(&instance->model, vr[i]);
        int access = ref == NULL ? 0 : acd_fmu_access[vr[i]];
        if (access == 3 && instance->phase == ACD_STEPPING) {
            acd_fmu_log(instance, fmi2Error,
                        "fmi2SetReal: variable %u is a fixed parameter: set it before "
                        "fmi2ExitInitializationMode", vr[i]);
            return fmi2Error;
        }
        if (access < 2) {
            acd_fmu_log(instance, fmi2Error, "fmi2SetReal: variable %u is not settable", vr[i]);
            return fmi2Error;
        }
        *ref = value[i];
        restart |= access == 3;
    }
    if (restart && instance->phase == ACD_INITIALISING) {
        acd_fmu_start(&instance->model, instance->t0); /* outputs of the new parameters */
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    (void)vr;
    (void)value;
    if (nvr == 0) {
        return fmi2OK;
    }
    acd_fmu_log((acd_fmu_instance *)c, fmi2Error, "fmi2SetInteger: no Integer is settable");
    return fmi2Error;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    if (nvr == 0) {
        return fmi2OK;
    }
    acd_fmu_log((acd_fmu_instance *)c, fmi2Error, "fmi2SetBoolean: the FMU has no Boolean");
    return fmi2Error;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    (void)vr;
    (void)value;
    if (nvr == 0) {
        return fmi2OK;
    }
    acd_fmu_log((acd_fmu_instance *)c, fmi2Error, "fmi2SetString: the FMU has no String");
    return fmi2Error;
}

static fmi2Status acd_fmu_unsupported(fmi2Component c, const char *what)
{
    acd_fmu_log((acd_fmu_instance *)c, fmi2Error, "%s is not supported by this FMU", what);
    return fmi2Error;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    (void)FMUstate;
    return acd_fmu_unsupported(c, "fmi2GetFMUstate");
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    (void)FMUstate;
    return acd_fmu_unsupported(c, "fmi2SetFMUstate");
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    (void)FMUstate;
    return acd_fmu_unsupported(c, "fmi2FreeFMUstate");
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    (void)FMUstate;
    (void)size;
    return acd_fmu_unsupported(c, "fmi2SerializedFMUstateSize");
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size)
{
    (void)FMUstate;
    (void)serializedState;
    (void)size;
    return acd_fmu_unsupported(c, "fmi2SerializeFMUstate");
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[],
                                   size_t size, fmi2FMUstate *FMUstate)
{
    (void)serializedState;
    (void)size;
    (void)FMUstate;
    return acd_fmu_unsupported(c, "fmi2DeSerializeFMUstate");
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return acd_fmu_unsupported(c, "fmi2GetDirectionalDerivative");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return acd_fmu_unsupported(c, "fmi2SetRealInputDerivatives");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[])
{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return acd_fmu_unsupported(c, "fmi2GetRealOutputDerivatives");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    acd_fmu_instance *instance = (acd_fmu_instance *)c;
    const double period = acd_fmu_period(&instance->model);
    const double now = instance->t0 + (double)instance->k * period;
    double n = floor(communicationStepSize / period + 0.5);
    unsigned long i;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (instance->phase != ACD_STEPPING) {
        acd_fmu_log(instance, fmi2Error, "fmi2DoStep: the FMU is not initialised");
        return fmi2Error;
    }
    if (n < 1.0 || fabs(communicationStepSize - n * period) > ACD_FMU_STEP_RTOL * period) {
        acd_fmu_log(instance, fmi2Error,
                    "fmi2DoStep: the communication step %.9g s is not a whole number of the "
                    "control period %.9g s", communicationStepSize, period);
        return fmi2Error;
    }
    if (fabs(currentCommunicationPoint - now) > ACD_FMU_STEP_RTOL * period) {
        acd_fmu_log(instance, fmi2Error,
                    "fmi2DoStep: the communication point %.9g s is not the FMU's time "
                    "%.9g s", currentCommunicationPoint, now);
        return fmi2Error;
    }
    for (i = 0; i < (unsigned long)n; ++i) {
        double t = instance->t0 + (double)instance->k * period;
        double t_next = instance->t0 + (double)(instance->k + 1) * period;
        acd_fmu_advance(&instance->model, t, t_next);
        instance->k += 1;
    }
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    return acd_fmu_unsupported(c, "fmi2CancelStep");
}

static fmi2Status acd_fmu_no_status(fmi2Component c, const char *what)
{
    acd_fmu_log((acd_fmu_instance *)c, fmi2Discard, "%s: the FMU never runs asynchronously",
                what);
    return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    (void)value;
    return acd_fmu_no_status(c, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    (void)s;
    (void)value;
    return acd_fmu_no_status(c, "fmi2GetRealStatus");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    (void)value;
    return acd_fmu_no_status(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    (void)s;
    (void)value;
    return acd_fmu_no_status(c, "fmi2GetBooleanStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    (void)value;
    return acd_fmu_no_status(c, "fmi2GetStringStatus");
}
"""
