/*
 * fmi2_functions.c - the FMI 2.0 co-simulation face of the native drive-rattle FMUs over the
 * model library's unit API (rattle_model.h), written once for both units: the generated
 * rattle_fmu_config.h names the unit (RATTLE_UNIT_KIND), the model identifier and the GUID.
 *
 * Every fmi2 function maps to rm_* calls; the model's phases, checks, statuses and messages
 * are the library's (the same in the pythonfmu FMUs by construction).  What is FMI's is here:
 *
 *   - fmi2Instantiate's checks (instance name, fmuType, GUID: rattle_check_instantiate) and
 *     the resource location, decoded to this FMU's resources folder, which must hold
 *     model_identifier.txt naming it (rattle_resources_folder);
 *   - the pointers and arrays the host passes, checked before anything reaches the library;
 *   - the host's logger: every non-OK status is logged with the library's message verbatim
 *     (as "%s", message), whatever debug logging says, in the category of its status;
 *   - FMU states: tagged with the GUID (RattleStateTag), kept on the instance's list, holding
 *     the unit's record (rm_save); serialized in the envelope of rattle_fmi_common.h;
 *     fmi2SetFMUstate is rm_restore, which checks the record whole;
 *   - the status inquiries and the functions these units do not provide.
 *
 * Nothing here aborts or longjmps out to the host: allocation failures are refusals.
 */
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "rattle_fmi2_common.h"
#include "rattle_fmu_config.h"
#include "rattle_model.h"

/* fmi2Integer and fmi2Boolean are the library's 32-bit integers. */
typedef char integer_is_int32[sizeof(fmi2Integer) == sizeof(int32_t) ? 1 : -1];
typedef char boolean_is_int32[sizeof(fmi2Boolean) == sizeof(int32_t) ? 1 : -1];

/* The prefix of fmi2Instantiate's messages, before an instance exists. */
#define PREFIX "rattle native FMU: "

typedef RattleRecordState State;

typedef struct {
    fmi2CallbackFunctions host;
    char* name;
    int logging_on;
    char* resources; /* the canonical path of this FMU's resources folder */
    RmUnit* unit;
    State* states; /* the FMU states made by this instance */
} Instance;

/* ------------------------------------------------------------------ logging */
/* A message to the host's logger, verbatim (never as a format string). */
static void host_log(const Instance* inst, int status, const char* message)
{
    if (inst->host.logger != NULL)
        inst->host.logger(inst->host.componentEnvironment, inst->name, (fmi2Status)status,
                          rattle_status_category(status), "%s", message);
}

/* The status of a library call, its message logged when it is not OK. */
static fmi2Status done(const Instance* inst, int status)
{
    if (status != RM_OK) host_log(inst, status, rm_message(inst->unit));
    return (fmi2Status)status;
}

/* A refusal of the glue's own checks: "<function>: <reason>" logged, fmi2Error. */
static fmi2Status refuse(const Instance* inst, const char* function, const char* fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static fmi2Status refuse(const Instance* inst, const char* function, const char* fmt, ...)
{
    char text[1024];
    int n = snprintf(text, sizeof text, "%s: ", function);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text + n, sizeof text - (size_t)n, fmt, ap);
    va_end(ap);
    host_log(inst, fmi2Error, text);
    return fmi2Error;
}

/* nvr > 0 with a NULL array: refused. */
static int arrays_missing(const Instance* inst, const char* function, size_t nvr,
                          const void* vr, const void* values)
{
    if (nvr == 0 || (vr != NULL && values != NULL)) return 0;
    refuse(inst, function, "nvr = %zu but the %s array is NULL; nothing done", nvr,
           vr == NULL ? "value-reference" : "value");
    return 1;
}

static char* copy_string(const char* s)
{
    size_t n = strlen(s) + 1;
    char* p = malloc(n);
    if (p != NULL) memcpy(p, s, n);
    return p;
}

/* ------------------------------------------------------------------ resource location */
/* The canonical path of this FMU's resources folder that `location` names (malloc'ed), or
 * NULL with the reason (rattle_resources_folder). */
static char* resolve_resources(const char* location, char* why, size_t why_size)
{
    if (location == NULL) {
        snprintf(why, why_size, "is NULL; allowed: the URI of this FMU's resources folder");
        return NULL;
    }
    return rattle_resources_folder(location, RATTLE_MODEL_IDENTIFIER, why, why_size);
}

/* ------------------------------------------------------------------ FMU states */
/* An FMU state: a RattleRecordState (rattle_fmi_common.h). */
/* The host's state pointer as one of ours, or NULL (refused, logged). */
static State* own_state(const Instance* inst, fmi2FMUstate state, const char* function)
{
    char why[300];
    if (!rattle_state_is_ours(state, RATTLE_GUID, why, sizeof why)) {
        refuse(inst, function, "%s", why);
        return NULL;
    }
    return state;
}

/* `record` (taken over) into the reused state, or into a new one stored in *state. */
static fmi2Status keep_record(Instance* inst, const char* function, State* reuse,
                              fmi2FMUstate* state, unsigned char* record, size_t size)
{
    State* made = NULL;
    if (!rattle_record_state_keep(&inst->states, reuse, &made, record, size, RATTLE_GUID))
        return refuse(inst, function, "out of memory; nothing changed");
    if (made != NULL) *state = made;
    return fmi2OK;
}

/* ------------------------------------------------------------------ the API */
const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    char name[256], why[1536];
    Instance* inst;
    char* resources;
    (void)visible;
    if (functions == NULL) return NULL; /* nobody to tell */
    if (!rattle_check_instantiate(instanceName, (int)fmuType, fmuGUID, RATTLE_GUID, name,
                                  sizeof name, why, sizeof why)) {
        rattle_instantiate_log(functions, name, fmi2Error, PREFIX, "%s", why);
        return NULL;
    }
    resources = resolve_resources(fmuResourceLocation, why, sizeof why);
    if (resources == NULL) {
        char location[512];
        rattle_printable(location, sizeof location,
                         fmuResourceLocation != NULL ? fmuResourceLocation : "(null)");
        rattle_instantiate_log(functions, name, fmi2Error, PREFIX,
                               "fmuResourceLocation '%s' %s", location, why);
        return NULL;
    }
    inst = calloc(1, sizeof *inst);
    if (inst == NULL || (inst->name = copy_string(instanceName)) == NULL
        || (inst->unit = rm_new(RATTLE_UNIT_KIND, resources)) == NULL) {
        rattle_instantiate_log(functions, name, fmi2Fatal, PREFIX, "out of memory");
        if (inst != NULL) free(inst->name);
        free(inst);
        free(resources);
        return NULL;
    }
    inst->host = *functions;
    inst->logging_on = loggingOn != fmi2False;
    inst->resources = resources;
    return inst;
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance* inst = c;
    if (inst == NULL) return;
    while (inst->states != NULL) rattle_record_state_delete(inst->states);
    rm_free(inst->unit);
    free(inst->resources);
    free(inst->name);
    free(inst);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    static const char function[] = "fmi2SetDebugLogging";
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (nCategories > 0 && categories == NULL)
        return refuse(inst, function, "nCategories = %zu but categories is NULL; nothing "
                      "changed", nCategories);
    for (size_t i = 0; i < nCategories; i++) {
        size_t bad;
        if (categories[i] == NULL)
            return refuse(inst, function, "category %zu of %zu is NULL; nothing changed", i,
                          nCategories);
        bad = rm_utf8_string_error_at(categories[i]);
        if (bad != (size_t)-1)
            return refuse(inst, function, "category %zu is not valid UTF-8 (offset %zu); "
                          "nothing changed", i, bad);
    }
    /* Every non-OK status is logged whatever this says; the units log nothing else. */
    inst->logging_on = loggingOn != fmi2False;
    return fmi2OK;
}

/* ------------------------------------------------------------------ life cycle */
fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    Instance* inst = c;
    (void)toleranceDefined, (void)tolerance, (void)stopTimeDefined, (void)stopTime;
    if (inst == NULL) return fmi2Error;
    return done(inst, rm_setup(inst->unit, startTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    return done(inst, rm_enter_initialization(inst->unit));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    return done(inst, rm_exit_initialization(inst->unit));
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    return done(inst, rm_terminate(inst->unit));
}

fmi2Status fmi2Reset(fmi2Component c)
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    return done(inst, rm_reset(inst->unit));
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    Instance* inst = c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (inst == NULL) return fmi2Error;
    return done(inst, rm_do_step(inst->unit, currentCommunicationPoint, communicationStepSize));
}

/* ------------------------------------------------------------------ values */
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (arrays_missing(inst, "fmi2GetReal", nvr, vr, value)) return fmi2Error;
    return done(inst, rm_get_real(inst->unit, vr, nvr, value));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (arrays_missing(inst, "fmi2GetInteger", nvr, vr, value)) return fmi2Error;
    return done(inst, rm_get_integer(inst->unit, vr, nvr, (int32_t*)value));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (arrays_missing(inst, "fmi2GetBoolean", nvr, vr, value)) return fmi2Error;
    return done(inst, rm_get_boolean(inst->unit, vr, nvr, (int32_t*)value));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (arrays_missing(inst, "fmi2GetString", nvr, vr, value)) return fmi2Error;
    return done(inst, rm_get_string(inst->unit, vr, nvr, value));
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (arrays_missing(inst, "fmi2SetReal", nvr, vr, value)) return fmi2Error;
    return done(inst, rm_set_real(inst->unit, vr, nvr, value));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (arrays_missing(inst, "fmi2SetInteger", nvr, vr, value)) return fmi2Error;
    return done(inst, rm_set_integer(inst->unit, vr, nvr, (const int32_t*)value));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (arrays_missing(inst, "fmi2SetBoolean", nvr, vr, value)) return fmi2Error;
    return done(inst, rm_set_boolean(inst->unit, vr, nvr, (const int32_t*)value));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (arrays_missing(inst, "fmi2SetString", nvr, vr, value)) return fmi2Error;
    return done(inst, rm_set_string(inst->unit, vr, nvr, value));
}

/* ------------------------------------------------------------------ FMU states */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    static const char function[] = "fmi2GetFMUstate";
    Instance* inst = c;
    State* reuse = NULL;
    unsigned char* record = NULL;
    size_t size = 0;
    int status;
    if (inst == NULL) return fmi2Error;
    if (state == NULL) return refuse(inst, function, "the FMUstate pointer is NULL");
    if (rattle_state_misaddressed(state))
        return refuse(inst, function, "FMUstate " RATTLE_STATE_MISADDRESSED "; nothing done");
    if (*state != NULL && (reuse = own_state(inst, *state, function)) == NULL) return fmi2Error;
    status = rm_save_alloc(inst->unit, &record, &size);
    if (status != RM_OK) return done(inst, status);
    return keep_record(inst, function, reuse, state, record, size);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    Instance* inst = c;
    State* st;
    if (inst == NULL) return fmi2Error;
    if ((st = own_state(inst, state, "fmi2SetFMUstate")) == NULL) return fmi2Error;
    return done(inst, rm_restore(inst->unit, st->record, st->size));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    Instance* inst = c;
    State* st;
    if (inst == NULL) return fmi2Error;
    if (state == NULL) return fmi2OK; /* FMI 2.0: the call is ignored */
    if (rattle_state_misaddressed(state))
        return refuse(inst, "fmi2FreeFMUstate", "FMUstate " RATTLE_STATE_MISADDRESSED
                      "; nothing freed");
    if (*state == NULL) return fmi2OK;
    if ((st = own_state(inst, *state, "fmi2FreeFMUstate")) == NULL) return fmi2Error;
    rattle_record_state_delete(st);
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size)
{
    static const char function[] = "fmi2SerializedFMUstateSize";
    Instance* inst = c;
    State* st;
    if (inst == NULL) return fmi2Error;
    if (size == NULL) return refuse(inst, function, "size is NULL");
    if ((st = own_state(inst, state, function)) == NULL) return fmi2Error;
    *size = RATTLE_STATE_HEADER + st->size;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte serializedState[],
                                 size_t size)
{
    static const char function[] = "fmi2SerializeFMUstate";
    Instance* inst = c;
    State* st;
    char why[200];
    unsigned char* out = (unsigned char*)serializedState;
    if (inst == NULL) return fmi2Error;
    if ((st = own_state(inst, state, function)) == NULL) return fmi2Error;
    if (serializedState == NULL) return refuse(inst, function, "the buffer is NULL");
    if (!rattle_state_fits(size, st->size, why, sizeof why))
        return refuse(inst, function, "%s", why);
    memcpy(out + RATTLE_STATE_HEADER, st->record, st->size);
    rattle_state_seal(out, size, st->size, RATTLE_GUID);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* state)
{
    static const char function[] = "fmi2DeSerializeFMUstate";
    Instance* inst = c;
    const unsigned char* in = (const unsigned char*)serializedState;
    State* reuse = NULL;
    unsigned char* record;
    uint64_t n;
    char why[300];
    if (inst == NULL) return fmi2Error;
    if (state == NULL) return refuse(inst, function, "the FMUstate pointer is NULL");
    if (serializedState == NULL) return refuse(inst, function, "the buffer is NULL");
    if (!rattle_state_open(in, size, RATTLE_GUID, &n, why, sizeof why))
        return refuse(inst, function, "%s", why);
    if (rattle_state_misaddressed(state))
        return refuse(inst, function, "FMUstate " RATTLE_STATE_MISADDRESSED "; nothing done");
    if (*state != NULL && (reuse = own_state(inst, *state, function)) == NULL) return fmi2Error;
    /* the record's bytes as they are: rm_restore checks them when the state is set */
    record = malloc(n > 0 ? (size_t)n : 1);
    if (record == NULL) return refuse(inst, function, "out of memory; nothing changed");
    memcpy(record, in + RATTLE_STATE_HEADER, (size_t)n);
    return keep_record(inst, function, reuse, state, record, (size_t)n);
}

/* ------------------------------------------------------------------ not provided */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    Instance* inst = c;
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown;
    (void)dvUnknown;
    if (inst == NULL) return fmi2Error;
    return refuse(inst, "fmi2GetDirectionalDerivative", "%s", RATTLE_NO_DIRECTIONAL_DERIVATIVES);
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    Instance* inst = c;
    (void)vr, (void)nvr, (void)order, (void)value;
    if (inst == NULL) return fmi2Error;
    return refuse(inst, "fmi2SetRealInputDerivatives", "%s", RATTLE_NO_INPUT_DERIVATIVES);
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    Instance* inst = c;
    (void)vr, (void)nvr, (void)order, (void)value;
    if (inst == NULL) return fmi2Error;
    return refuse(inst, "fmi2GetRealOutputDerivatives", "%s", RATTLE_NO_OUTPUT_DERIVATIVES);
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    return refuse(inst, "fmi2CancelStep", "%s", RATTLE_NO_ASYNCHRONOUS_STEP);
}

/* ------------------------------------------------------------------ status inquiries */
static fmi2Status status_refused(const Instance* inst, const char* function, int kind,
                                 const char* allowed)
{
    char why[400];
    rattle_status_refusal(why, sizeof why, kind, allowed);
    return refuse(inst, function, "%s", why);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status* value)
{
    Instance* inst = c;
    (void)value;
    if (inst == NULL) return fmi2Error;
    return status_refused(inst, "fmi2GetStatus", (int)kind, "none");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real* value)
{
    static const char function[] = "fmi2GetRealStatus";
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (kind != fmi2LastSuccessfulTime)
        return status_refused(inst, function, (int)kind, "fmi2LastSuccessfulTime");
    if (value == NULL) return refuse(inst, function, "value is NULL");
    return done(inst, rm_last_successful_time(inst->unit, value));
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer* value)
{
    Instance* inst = c;
    (void)value;
    if (inst == NULL) return fmi2Error;
    return status_refused(inst, "fmi2GetIntegerStatus", (int)kind,
                          "none (FMI 2.0 defines no Integer status)");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean* value)
{
    static const char function[] = "fmi2GetBooleanStatus";
    Instance* inst = c;
    if (inst == NULL) return fmi2Error;
    if (kind != fmi2Terminated)
        return status_refused(inst, function, (int)kind, "fmi2Terminated");
    if (value == NULL) return refuse(inst, function, "value is NULL");
    *value = fmi2False; /* the units never ask to end the simulation */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String* value)
{
    Instance* inst = c;
    (void)value;
    if (inst == NULL) return fmi2Error;
    return status_refused(inst, "fmi2GetStringStatus", (int)kind, "none");
}
