"""The FMI 2.0 co-simulation interface in C, the same for the controller FMU and the plant FMU.

It is written against a small model interface the generator writes per FMU (``_fmu.glue``):

* ``acd_fmu_model``: a struct holding the generated C's parameters, states, inputs, outputs;
* ``acd_fmu_defaults(m)``: the exported values (``_set_params``, the inputs' start values);
* ``acd_fmu_start(m, t0)``: the start at ``t0`` (``_reset``), called on entering initialisation
  and again whenever a parameter is set during it;
* ``acd_fmu_period(m)``: the control period T_s [s];
* ``acd_fmu_advance(m, t, t_next)``: one period from t (the sampled step or the plant's
  modulation and integration), the outputs then hold their values at ``t_next``;
* ``acd_fmu_real(m, vr)``: the address of Real variable ``vr`` (NULL if none),
  ``acd_fmu_get_integer(m, vr, &value)`` / ``acd_fmu_set_integer(m, vr, value)``: an Integer
  (event bits; a parameter whose rule makes it an integer, stored as a real of the C), 0 if
  none; ``acd_fmu_access[vr]``: 1 output, 2 input, 3 parameter, 4 calculated parameter;
  ``acd_fmu_names[vr]`` its name;
* ``acd_fmu_broken_rule(vr, value)``: the declared rule (``core._signals.RULES``) a parameter's
  value breaks, NULL if none; ``acd_fmu_relations`` and ``acd_fmu_relation_holds(m, i)``: the
  rules over several parameters (``core._signals.Relation``) that declare their C;
* ``acd_fmu_real_outputs``: the Real outputs.

The C that does the work (the checks below, the stepping) is ``_fmi_core``, shared with the
FMI 3.0 interface (``_fmi3``); this module adds the FMI 2.0 functions around it.

``fmi2DoStep`` advances whole periods; the time of period k is ``t0 + k T_s`` from the FMU's own
count, as in acdrive's loop. A master's communication point t and the end of its step t + h are
compared with the FMU's times within ``acd_fmu_time_tolerance``: a master that adds h to its time
at every step (fmpy's SSP master does) is off by the rounding of those sums, at most half an ulp
of t per sum (eps |t| / 2, eps = DBL_EPSILON), so at most k eps |t| / 2 after k steps; the
tolerance is four times that, 2 (k + 1) eps max(|t|, T_s), never below 1e-9 of a period (the
rounding of h itself), never above a quarter period (so a point or a step end that lies nearer
another period, a step of 1.5 periods, is always refused). A refused step, a parameter value
that breaks its declared rule, a relation broken when initialisation ends, an output that is
not finite after a period: each is ``fmi2Error`` with one message to the logger naming the
variable and the rule. After a non-finite output the instance refuses further steps
(``fmi2Reset`` starts it again). No FMU state (get/set/serialise), no directional derivatives,
no input derivatives: the capability flags say so and those functions return ``fmi2Error``.
"""

from acdrive.export._fmi_core import FMI_CORE

FMI2_WRAPPER = (
    r"""
/* ---- FMI 2.0 co-simulation interface (acdrive.export._fmi2) ---- */

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef fmi2Status acd_fmu_status;
typedef fmi2ValueReference acd_fmu_vr;
typedef fmi2Integer acd_fmu_int;
#define ACD_FMU_OK fmi2OK
#define ACD_FMU_ERROR fmi2Error
#define ACD_FMU_API "fmi2"
#define ACD_FMU_NAME0 "(no such variable)"

typedef enum {
    ACD_INSTANTIATED, ACD_INITIALISING, ACD_STEPPING, ACD_FAILED, ACD_TERMINATED
} acd_fmu_phase;

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
    char message[512];
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

"""
    + FMI_CORE
    + r"""
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
    if (acd_fmu_check_relations(instance) != fmi2OK) {
        return fmi2Error;
    }
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
    instance->phase = ACD_INSTANTIATED; /* also after a failed step */
    instance->k = 0;
    acd_fmu_defaults(&instance->model);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    return acd_fmu_get_reals((acd_fmu_instance *)c, "fmi2GetReal", vr, nvr, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    return acd_fmu_get_integers((acd_fmu_instance *)c, "fmi2GetInteger", vr, nvr, value);
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
    return acd_fmu_set_reals((acd_fmu_instance *)c, "fmi2SetReal", vr, nvr, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    return acd_fmu_set_integers((acd_fmu_instance *)c, "fmi2SetInteger", vr, nvr, value);
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
    int failed;
    (void)noSetFMUStatePriorToCurrentPoint;
    return acd_fmu_step((acd_fmu_instance *)c, currentCommunicationPoint, communicationStepSize,
                        &failed);
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
)
