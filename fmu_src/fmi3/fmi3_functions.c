/*
 * fmi3_functions.c - the FMI 3.0 co-simulation face of the native drive-rattle FMUs over the
 * model library's unit API (rattle_model.h), written once for both units: the generated
 * rattle_fmu_config.h names the unit (RATTLE_UNIT_KIND), the model identifier and the
 * instantiation token (RATTLE_GUID, the GUID scheme of the FMI 2.0 FMUs).
 *
 * The same model as the FMI 2.0 face (fmu_src/fmi2/fmi2_functions.c): every fmi3 function maps
 * to rm_* calls, and the model's phases, checks, statuses and messages are the library's,
 * passed on verbatim.  What is FMI 3.0's is here:
 *
 *   - fmi3InstantiateCoSimulation's checks: the instance name, the instantiation token, no
 *     event mode (hasEventMode = false), no intermediate variables (providesIntermediateUpdate
 *     = false), the resources folder (rattle_resources_folder; FMI 3.0 passes a path, NULL
 *     when the importer has none: then relative speed-table paths resolve against the
 *     working directory);
 *   - the variable types of FMI 3.0 on the library's four: Float64 (the library's Real),
 *     Int32 (Integer), Enumeration (an Integer with named codes, accessed as Int64 as FMI 3.0
 *     requires), Boolean (bool <-> 0/1), String; which Integer is an Enumeration comes from
 *     the library's tables (choices), never from a list here;
 *   - the independent variable `time` (FMI 3.0 requires one) at the value reference after the
 *     unit's variables: readable, never settable, the unit's time in every mode (rm_time: a
 *     restored state's too);
 *   - the pointers, arrays and nValues the importer passes, checked before anything reaches
 *     the library;
 *   - logging through logMessage (no format string in FMI 3.0): errors always, warnings when
 *     their category is on (loggingOn, fmi3SetDebugLogging), as FMI 3.0 asks;
 *   - FMU states as in the FMI 2.0 face: tagged with the token, on the instance's list,
 *     holding the unit's record (rm_save), serialized in the envelope of rattle_fmi_common.h;
 *   - fmi3DoStep's outputs: never an event, never a request to terminate, never an early
 *     return; lastSuccessfulTime the end of the last step the unit accepted;
 *   - the functions these units do not provide, refused with a message (all are exported).
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

#include "fmi3Functions.h"
#include "rattle_fmi_common.h"
#include "rattle_fmu_config.h"
#include "rattle_model.h"

/* fmi3Int32 is the library's 32-bit integer. */
typedef char int32_is_int32[sizeof(fmi3Int32) == sizeof(int32_t) ? 1 : -1];

/* The prefix of the instantiation functions' messages, before an instance exists. */
#define PREFIX "rattle native FMU: "
/* Up to this many values are converted on the stack; more in allocated memory. */
#define STACK_VALUES 64

/* The log categories (the modelDescription's <LogCategories>, in this order). */
static const char* const CATEGORIES[] = {"logStatusWarning", "logStatusDiscard",
                                         "logStatusError", "logStatusFatal", "logAll"};
enum { CATEGORY_WARNING = 0, CATEGORY_ALL = 4, N_CATEGORIES = 5 };

typedef RattleRecordState State;

typedef struct {
    char* name;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    int enabled[N_CATEGORIES]; /* the log categories switched on */
    char* resources;           /* the canonical path of the resources folder, or NULL */
    RmUnit* unit;
    const RmVariable* variables;
    size_t n_variables;
    fmi3ValueReference time_vr; /* the independent variable's value reference */
    State* states;              /* the FMU states made by this instance */
} Instance;

/* ------------------------------------------------------------------ logging */
/* A message to the importer, verbatim: errors always, warnings when their category is on. */
static void host_log(const Instance* inst, int status, const char* message)
{
    if (inst->log == NULL) return;
    if (status == RM_WARNING && !inst->enabled[CATEGORY_WARNING] && !inst->enabled[CATEGORY_ALL])
        return;
    inst->log(inst->env, (fmi3Status)status, rattle_status_category(status), message);
}

/* The status of a library call, its message logged when it is not OK. */
static fmi3Status done(const Instance* inst, int status)
{
    if (status != RM_OK) host_log(inst, status, rm_message(inst->unit));
    return (fmi3Status)status;
}

/* A refusal of the glue's own checks: "<function>: <reason>" logged, fmi3Error. */
static fmi3Status refuse(const Instance* inst, const char* function, const char* fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static fmi3Status refuse(const Instance* inst, const char* function, const char* fmt, ...)
{
    char text[1024];
    int n = snprintf(text, sizeof text, "%s: ", function);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text + n, sizeof text - (size_t)n, fmt, ap);
    va_end(ap);
    host_log(inst, fmi3Error, text);
    return fmi3Error;
}

/* A refusal of an instantiation function, before any instance exists. */
static void instantiate_log(fmi3LogMessageCallback log, fmi3InstanceEnvironment env,
                            fmi3Status status, const char* function, const char* fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;
static void instantiate_log(fmi3LogMessageCallback log, fmi3InstanceEnvironment env,
                            fmi3Status status, const char* function, const char* fmt, ...)
{
    char text[3072];
    int n;
    va_list ap;
    if (log == NULL) return;
    n = snprintf(text, sizeof text, PREFIX "%s: ", function);
    va_start(ap, fmt);
    vsnprintf(text + n, sizeof text - (size_t)n, fmt, ap);
    va_end(ap);
    log(env, status, rattle_status_category(status), text);
}

static char* copy_string(const char* s)
{
    size_t n = strlen(s) + 1;
    char* p = malloc(n);
    if (p != NULL) memcpy(p, s, n);
    return p;
}

/* ------------------------------------------------------------------ arguments */
/* The arrays of a get or set: nValueReferences > 0 with a NULL array, or nValues other than
 * nValueReferences (every variable of these units is a scalar), refused. */
static int bad_arrays(const Instance* inst, const char* function, size_t nvr, const void* vr,
                      const void* values, size_t n_values)
{
    if (n_values != nvr) {
        refuse(inst, function, "nValues = %zu but nValueReferences = %zu: every variable of "
               "this FMU is a scalar, so they must be equal; nothing done", n_values, nvr);
        return 1;
    }
    if (nvr == 0 || (vr != NULL && values != NULL)) return 0;
    refuse(inst, function, "nValueReferences = %zu but the %s array is NULL; nothing done", nvr,
           vr == NULL ? "value-reference" : "value");
    return 1;
}

/* A scratch array of n elements of `size` bytes: `stack` when it fits, else allocated (NULL:
 * out of memory).  Released with release(). */
static void* scratch(void* stack, size_t stack_bytes, size_t n, size_t size)
{
    if (n * size <= stack_bytes) return stack;
    return n > SIZE_MAX / size ? NULL : malloc(n * size);
}

static void release(void* p, const void* stack)
{
    if (p != stack) free(p);
}

/* The variable with value reference vr, or NULL. */
static const RmVariable* variable(const Instance* inst, fmi3ValueReference vr)
{
    return vr < inst->n_variables ? &inst->variables[vr] : NULL;
}

/* An Integer of the library is an FMI 3.0 Enumeration when it has named codes (the tables'
 * choices, from the specs), else an Int32. */
static int is_enumeration(const RmVariable* v)
{
    return v != NULL && v->type == RM_INTEGER && v->n_choices > 0;
}

/* The entries of an Int32 call that name Enumerations, and of an Int64 call that name anything
 * but an Enumeration, refused (FMI 3.0 gets and sets Enumerations as Int64). */
static int wrong_integer_kind(const Instance* inst, const char* function,
                              const fmi3ValueReference vr[], size_t nvr, int enumeration)
{
    for (size_t i = 0; i < nvr; i++) {
        const RmVariable* v = variable(inst, vr[i]);
        if (enumeration && !is_enumeration(v)) {
            if (v != NULL && v->type == RM_INTEGER)
                refuse(inst, function, "'%s' (value reference %u) is an Int32, not an "
                       "Enumeration; allowed: %s; nothing done", v->name, (unsigned)vr[i],
                       function[4] == 'G' ? "fmi3GetInt32" : "fmi3SetInt32");
            else
                refuse(inst, function, "no Enumeration (Int64) variable with value reference "
                       "%u; nothing done", (unsigned)vr[i]);
            return 1;
        }
        if (!enumeration && is_enumeration(v)) {
            refuse(inst, function, "'%s' (value reference %u) is an Enumeration: FMI 3.0 gets "
                   "and sets it as Int64; allowed: %s; nothing done", v->name, (unsigned)vr[i],
                   function[4] == 'G' ? "fmi3GetInt64" : "fmi3SetInt64");
            return 1;
        }
    }
    return 0;
}

/* The value of the independent variable: the unit's, in every mode (the start time until the
 * first step, a restored state's time). */
static double current_time(const Instance* inst) { return rm_time(inst->unit); }

/* ------------------------------------------------------------------ resource location */
/* The resources folder `path` names (malloc'ed; the model library resolves relative
 * speed-table paths against it), or NULL with the reason.  A NULL path (FMI 3.0: the importer
 * cannot provide one) is accepted: *none is set. */
static char* resolve_resources(const char* path, int* none, char* why, size_t why_size)
{
    *none = path == NULL;
    if (path == NULL) return NULL;
    return rattle_resources_folder(path, RATTLE_MODEL_IDENTIFIER, why, why_size);
}

/* ------------------------------------------------------------------ FMU states */
#define STATE_MAKERS "fmi3GetFMUState or fmi3DeserializeFMUState"

/* An FMU state: a RattleRecordState (rattle_fmi_common.h), tagged with the instantiation
 * token. */
/* The importer's state pointer as one of ours, or NULL (refused, logged). */
static State* own_state(const Instance* inst, fmi3FMUState state, const char* function)
{
    char why[300];
    if (!rattle_state_check(state, RATTLE_GUID, STATE_MAKERS, why, sizeof why)) {
        refuse(inst, function, "%s", why);
        return NULL;
    }
    return state;
}

/* `record` (taken over) into the reused state, or into a new one stored in *state. */
static fmi3Status keep_record(Instance* inst, const char* function, State* reuse,
                              fmi3FMUState* state, unsigned char* record, size_t size)
{
    State* made = NULL;
    if (!rattle_record_state_keep(&inst->states, reuse, &made, record, size, RATTLE_GUID))
        return refuse(inst, function, "out of memory; nothing changed");
    if (made != NULL) *state = made;
    return fmi3OK;
}

/* ------------------------------------------------------------------ common functions */
const char* fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    static const char function[] = "fmi3SetDebugLogging";
    Instance* inst = instance;
    int chosen[N_CATEGORIES] = {0};
    if (inst == NULL) return fmi3Error;
    if (nCategories > 0 && categories == NULL)
        return refuse(inst, function, "nCategories = %zu but categories is NULL; nothing "
                      "changed", nCategories);
    for (size_t i = 0; i < nCategories; i++) {
        char shown[80];
        int k;
        if (categories[i] == NULL)
            return refuse(inst, function, "category %zu of %zu is NULL; nothing changed", i,
                          nCategories);
        for (k = 0; k < N_CATEGORIES && strcmp(categories[i], CATEGORIES[k]) != 0; k++) {}
        if (k == N_CATEGORIES) {
            rattle_printable(shown, sizeof shown, categories[i]);
            return refuse(inst, function, "category '%s' is not one of this FMU's; allowed: "
                          "%s, %s, %s, %s, %s; nothing changed", shown, CATEGORIES[0],
                          CATEGORIES[1], CATEGORIES[2], CATEGORIES[3], CATEGORIES[4]);
        }
        chosen[k] = 1;
    }
    /* no categories: all of them (FMI 3.0) */
    for (int k = 0; k < N_CATEGORIES; k++)
        if (nCategories == 0 || chosen[k]) inst->enabled[k] = loggingOn ? 1 : 0;
    return fmi3OK;
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
    static const char function[] = "fmi3InstantiateCoSimulation";
    char name[256], why[1536];
    Instance* inst;
    char* resources;
    int no_resources;
    /* never returns early (the importer may allow it), never calls intermediateUpdate */
    (void)visible, (void)earlyReturnAllowed, (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    if (!rattle_check_instance_name(instanceName, "FMI 3.0, fmi3InstantiateCoSimulation", name,
                                    sizeof name, why, sizeof why)
        || !rattle_check_token(instantiationToken, RATTLE_GUID, "instantiationToken", why,
                               sizeof why)) {
        instantiate_log(logMessage, instanceEnvironment, fmi3Error, function, "%s", why);
        return NULL;
    }
    if (eventModeUsed) {
        instantiate_log(logMessage, instanceEnvironment, fmi3Error, function, "eventModeUsed = "
                        "true, but this FMU has no Event Mode (hasEventMode = false); allowed: "
                        "false");
        return NULL;
    }
    if (nRequiredIntermediateVariables > 0) {
        instantiate_log(logMessage, instanceEnvironment, fmi3Error, function,
                        "nRequiredIntermediateVariables = %zu, but no variable of this FMU can "
                        "be accessed in an intermediate update (providesIntermediateUpdate = "
                        "false); allowed: 0", nRequiredIntermediateVariables);
        return NULL;
    }
    resources = resolve_resources(resourcePath, &no_resources, why, sizeof why);
    if (resources == NULL && !no_resources) {
        char location[512];
        rattle_printable(location, sizeof location, resourcePath);
        instantiate_log(logMessage, instanceEnvironment, fmi3Error, function,
                        "resourcePath '%s' %s", location, why);
        return NULL;
    }
    inst = calloc(1, sizeof *inst);
    if (inst == NULL || (inst->name = copy_string(instanceName)) == NULL
        || (inst->unit = rm_new(RATTLE_UNIT_KIND, resources)) == NULL) {
        instantiate_log(logMessage, instanceEnvironment, fmi3Fatal, function, "out of memory");
        if (inst != NULL) free(inst->name);
        free(inst);
        free(resources);
        return NULL;
    }
    inst->env = instanceEnvironment;
    inst->log = logMessage;
    for (int k = 0; k < N_CATEGORIES; k++) inst->enabled[k] = loggingOn ? 1 : 0;
    inst->resources = resources;
    inst->variables = rm_variables(RATTLE_UNIT_KIND);
    inst->n_variables = rm_variable_count(RATTLE_UNIT_KIND);
    inst->time_vr = (fmi3ValueReference)inst->n_variables;
    return inst;
}

/* An instantiation function of an interface these units do not have: NULL, logged. */
static fmi3Instance not_this_interface(const char* function, fmi3InstanceEnvironment env,
                                       fmi3LogMessageCallback log)
{
    instantiate_log(log, env, fmi3Error, function, "this FMU is for co-simulation only (its "
                    "modelDescription has no <ModelExchange> or <ScheduledExecution>); "
                    "allowed: fmi3InstantiateCoSimulation");
    return NULL;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName,
                                          fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn;
    return not_this_interface("fmi3InstantiateModelExchange", instanceEnvironment, logMessage);
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    return not_this_interface("fmi3InstantiateScheduledExecution", instanceEnvironment,
                              logMessage);
}

void fmi3FreeInstance(fmi3Instance instance)
{
    Instance* inst = instance;
    if (inst == NULL) return;
    while (inst->states != NULL) rattle_record_state_delete(inst->states);
    rm_free(inst->unit);
    free(inst->resources);
    free(inst->name);
    free(inst);
}

/* ------------------------------------------------------------------ life cycle */
fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    Instance* inst = instance;
    int status;
    (void)toleranceDefined, (void)tolerance, (void)stopTimeDefined, (void)stopTime;
    if (inst == NULL) return fmi3Error;
    /* FMI 2.0's fmi2SetupExperiment and fmi2EnterInitializationMode in one call; the second
     * cannot be refused once the first was accepted (both need phase INSTANTIATED) */
    status = rm_setup(inst->unit, startTime);
    if (status == RM_OK) status = rm_enter_initialization(inst->unit);
    return done(inst, status);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    return done(inst, rm_exit_initialization(inst->unit));
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    return done(inst, rm_terminate(inst->unit));
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    return done(inst, rm_reset(inst->unit));
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean* eventHandlingNeeded, fmi3Boolean* terminateSimulation,
                      fmi3Boolean* earlyReturn, fmi3Float64* lastSuccessfulTime)
{
    static const char function[] = "fmi3DoStep";
    Instance* inst = instance;
    fmi3Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (inst == NULL) return fmi3Error;
    if (eventHandlingNeeded == NULL || terminateSimulation == NULL || earlyReturn == NULL
        || lastSuccessfulTime == NULL)
        return refuse(inst, function, "%s is NULL; allowed: a pointer to the importer's "
                      "variable; nothing done",
                      eventHandlingNeeded == NULL ? "eventHandlingNeeded"
                      : terminateSimulation == NULL ? "terminateSimulation"
                      : earlyReturn == NULL ? "earlyReturn" : "lastSuccessfulTime");
    status = done(inst, rm_do_step(inst->unit, currentCommunicationPoint,
                                   communicationStepSize));
    /* the units have no events and never end a simulation; every step runs to its end (or
     * is refused whole, the unit then still at the end of the last accepted one) */
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = current_time(inst);
    return status;
}

/* ------------------------------------------------------------------ Float64 */
fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues)
{
    static const char function[] = "fmi3GetFloat64";
    Instance* inst = instance;
    size_t n_time = 0, k = 0;
    fmi3ValueReference vr_stack[STACK_VALUES];
    double value_stack[STACK_VALUES];
    fmi3ValueReference* vr;
    double* value;
    int status;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, function, nValueReferences, valueReferences, values, nValues))
        return fmi3Error;
    for (size_t i = 0; i < nValueReferences; i++) n_time += valueReferences[i] == inst->time_vr;
    if (n_time == 0)
        return done(inst, rm_get_real(inst->unit, valueReferences, nValueReferences, values));
    /* the independent variable is the glue's: the others asked of the library */
    vr = scratch(vr_stack, sizeof vr_stack, nValueReferences - n_time, sizeof *vr);
    value = scratch(value_stack, sizeof value_stack, nValueReferences - n_time, sizeof *value);
    if (vr == NULL || value == NULL) {
        release(vr, vr_stack);
        release(value, value_stack);
        return refuse(inst, function, "out of memory; nothing done");
    }
    for (size_t i = 0; i < nValueReferences; i++)
        if (valueReferences[i] != inst->time_vr) vr[k++] = valueReferences[i];
    status = k > 0 ? rm_get_real(inst->unit, vr, k, value) : RM_OK;
    status = done(inst, status);
    k = 0;
    for (size_t i = 0; i < nValueReferences; i++)
        values[i] = valueReferences[i] == inst->time_vr ? current_time(inst) : value[k++];
    release(vr, vr_stack);
    release(value, value_stack);
    return (fmi3Status)status;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues)
{
    static const char function[] = "fmi3SetFloat64";
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, function, nValueReferences, valueReferences, values, nValues))
        return fmi3Error;
    for (size_t i = 0; i < nValueReferences; i++)
        if (valueReferences[i] == inst->time_vr)
            return refuse(inst, function, "'time' (value reference %u) is the independent "
                          "variable and cannot be set; nothing of this call was stored",
                          (unsigned)inst->time_vr);
    return done(inst, rm_set_real(inst->unit, valueReferences, nValueReferences, values));
}

/* ------------------------------------------------------------------ Int32 and Enumerations */
fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int32 values[], size_t nValues)
{
    static const char function[] = "fmi3GetInt32";
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, function, nValueReferences, valueReferences, values, nValues)
        || wrong_integer_kind(inst, function, valueReferences, nValueReferences, 0))
        return fmi3Error;
    return done(inst, rm_get_integer(inst->unit, valueReferences, nValueReferences, values));
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int32 values[], size_t nValues)
{
    static const char function[] = "fmi3SetInt32";
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, function, nValueReferences, valueReferences, values, nValues)
        || wrong_integer_kind(inst, function, valueReferences, nValueReferences, 0))
        return fmi3Error;
    return done(inst, rm_set_integer(inst->unit, valueReferences, nValueReferences, values));
}

fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int64 values[], size_t nValues)
{
    static const char function[] = "fmi3GetInt64";
    Instance* inst = instance;
    int32_t stack[STACK_VALUES];
    int32_t* codes;
    int status;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, function, nValueReferences, valueReferences, values, nValues))
        return fmi3Error;
    if (wrong_integer_kind(inst, function, valueReferences, nValueReferences, 1)) {
        memset(values, 0, nValueReferences * sizeof *values);
        return fmi3Error;
    }
    codes = scratch(stack, sizeof stack, nValueReferences, sizeof *codes);
    if (codes == NULL) return refuse(inst, function, "out of memory; nothing done");
    status = done(inst, rm_get_integer(inst->unit, valueReferences, nValueReferences, codes));
    for (size_t i = 0; i < nValueReferences; i++) values[i] = codes[i];
    release(codes, stack);
    return (fmi3Status)status;
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int64 values[], size_t nValues)
{
    static const char function[] = "fmi3SetInt64";
    Instance* inst = instance;
    int32_t stack[STACK_VALUES];
    int32_t* codes;
    int status;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, function, nValueReferences, valueReferences, values, nValues)
        || wrong_integer_kind(inst, function, valueReferences, nValueReferences, 1))
        return fmi3Error;
    /* the library's codes are 32-bit: a wider value cannot be one of them */
    for (size_t i = 0; i < nValueReferences; i++)
        if (values[i] < INT32_MIN || values[i] > INT32_MAX) {
            const RmVariable* v = variable(inst, valueReferences[i]);
            return refuse(inst, function, "value %zu ('%s') = %lld is not one of its codes; "
                          "allowed: %s; nothing of this call was stored", i, v->name,
                          (long long)values[i], v->allowed);
        }
    codes = scratch(stack, sizeof stack, nValueReferences, sizeof *codes);
    if (codes == NULL) return refuse(inst, function, "out of memory; nothing done");
    for (size_t i = 0; i < nValueReferences; i++) codes[i] = (int32_t)values[i];
    status = done(inst, rm_set_integer(inst->unit, valueReferences, nValueReferences, codes));
    release(codes, stack);
    return (fmi3Status)status;
}

/* ------------------------------------------------------------------ Boolean and String */
fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Boolean values[], size_t nValues)
{
    static const char function[] = "fmi3GetBoolean";
    Instance* inst = instance;
    int32_t stack[STACK_VALUES];
    int32_t* flags;
    int status;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, function, nValueReferences, valueReferences, values, nValues))
        return fmi3Error;
    flags = scratch(stack, sizeof stack, nValueReferences, sizeof *flags);
    if (flags == NULL) return refuse(inst, function, "out of memory; nothing done");
    status = done(inst, rm_get_boolean(inst->unit, valueReferences, nValueReferences, flags));
    for (size_t i = 0; i < nValueReferences; i++) values[i] = flags[i] != 0;
    release(flags, stack);
    return (fmi3Status)status;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Boolean values[], size_t nValues)
{
    static const char function[] = "fmi3SetBoolean";
    Instance* inst = instance;
    int32_t stack[STACK_VALUES];
    int32_t* flags;
    int status;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, function, nValueReferences, valueReferences, values, nValues))
        return fmi3Error;
    flags = scratch(stack, sizeof stack, nValueReferences, sizeof *flags);
    if (flags == NULL) return refuse(inst, function, "out of memory; nothing done");
    for (size_t i = 0; i < nValueReferences; i++) flags[i] = values[i] ? 1 : 0;
    status = done(inst, rm_set_boolean(inst->unit, valueReferences, nValueReferences, flags));
    release(flags, stack);
    return (fmi3Status)status;
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, fmi3String values[], size_t nValues)
{
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, "fmi3GetString", nValueReferences, valueReferences, values, nValues))
        return fmi3Error;
    return done(inst, rm_get_string(inst->unit, valueReferences, nValueReferences, values));
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const fmi3String values[], size_t nValues)
{
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    if (bad_arrays(inst, "fmi3SetString", nValueReferences, valueReferences, values, nValues))
        return fmi3Error;
    return done(inst, rm_set_string(inst->unit, valueReferences, nValueReferences, values));
}

/* ------------------------------------------------------------------ types these units lack */
/* A get or set of a type no variable of these units has: nothing asked is OK, else refused. */
static fmi3Status no_such_type(fmi3Instance instance, const char* function, const char* type,
                               const fmi3ValueReference vr[], size_t nvr)
{
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    if (nvr == 0) return fmi3OK;
    if (vr == NULL)
        return refuse(inst, function, "nValueReferences = %zu but the value-reference array "
                      "is NULL; nothing done", nvr);
    return refuse(inst, function, "no %s variable with value reference %u: the variables of "
                  "this FMU are Float64, Int32, Enumeration (as Int64), Boolean and String; "
                  "nothing done", type, (unsigned)vr[0]);
}

#define ABSENT_TYPE(TYPE)                                                                      \
    fmi3Status fmi3Get##TYPE(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                             size_t nValueReferences, fmi3##TYPE values[], size_t nValues)     \
    {                                                                                          \
        (void)values, (void)nValues;                                                           \
        return no_such_type(instance, "fmi3Get" #TYPE, #TYPE, valueReferences,                 \
                            nValueReferences);                                                 \
    }                                                                                          \
    fmi3Status fmi3Set##TYPE(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                             size_t nValueReferences, const fmi3##TYPE values[],               \
                             size_t nValues)                                                   \
    {                                                                                          \
        (void)values, (void)nValues;                                                           \
        return no_such_type(instance, "fmi3Set" #TYPE, #TYPE, valueReferences,                 \
                            nValueReferences);                                                 \
    }

ABSENT_TYPE(Float32)
ABSENT_TYPE(Int8)
ABSENT_TYPE(UInt8)
ABSENT_TYPE(Int16)
ABSENT_TYPE(UInt16)
ABSENT_TYPE(UInt32)
ABSENT_TYPE(UInt64)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[],
                         size_t nValues)
{
    (void)valueSizes, (void)values, (void)nValues;
    return no_such_type(instance, "fmi3GetBinary", "Binary", valueReferences, nValueReferences);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues)
{
    (void)valueSizes, (void)values, (void)nValues;
    return no_such_type(instance, "fmi3SetBinary", "Binary", valueReferences, nValueReferences);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[])
{
    (void)values;
    return no_such_type(instance, "fmi3GetClock", "Clock", valueReferences, nValueReferences);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[])
{
    (void)values;
    return no_such_type(instance, "fmi3SetClock", "Clock", valueReferences, nValueReferences);
}

/* ------------------------------------------------------------------ FMU states */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState* FMUState)
{
    static const char function[] = "fmi3GetFMUState";
    Instance* inst = instance;
    State* reuse = NULL;
    unsigned char* record = NULL;
    size_t size = 0;
    int status;
    if (inst == NULL) return fmi3Error;
    if (FMUState == NULL) return refuse(inst, function, "the FMUState pointer is NULL");
    if (rattle_state_misaddressed(FMUState))
        return refuse(inst, function, "FMUState " RATTLE_STATE_MISADDRESSED "; nothing done");
    if (*FMUState != NULL && (reuse = own_state(inst, *FMUState, function)) == NULL)
        return fmi3Error;
    status = rm_save_alloc(inst->unit, &record, &size);
    if (status != RM_OK) return done(inst, status);
    return keep_record(inst, function, reuse, FMUState, record, size);
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    Instance* inst = instance;
    State* st;
    if (inst == NULL) return fmi3Error;
    if ((st = own_state(inst, FMUState, "fmi3SetFMUState")) == NULL) return fmi3Error;
    return done(inst, rm_restore(inst->unit, st->record, st->size));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState* FMUState)
{
    Instance* inst = instance;
    State* st;
    if (inst == NULL) return fmi3Error;
    if (FMUState == NULL) return fmi3OK; /* FMI 3.0: nothing to free */
    if (rattle_state_misaddressed(FMUState))
        return refuse(inst, "fmi3FreeFMUState", "FMUState " RATTLE_STATE_MISADDRESSED
                      "; nothing freed");
    if (*FMUState == NULL) return fmi3OK;
    if ((st = own_state(inst, *FMUState, "fmi3FreeFMUState")) == NULL) return fmi3Error;
    rattle_record_state_delete(st);
    *FMUState = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState,
                                      size_t* size)
{
    static const char function[] = "fmi3SerializedFMUStateSize";
    Instance* inst = instance;
    State* st;
    if (inst == NULL) return fmi3Error;
    if (size == NULL) return refuse(inst, function, "size is NULL");
    if ((st = own_state(inst, FMUState, function)) == NULL) return fmi3Error;
    *size = RATTLE_STATE_HEADER + st->size;
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size)
{
    static const char function[] = "fmi3SerializeFMUState";
    Instance* inst = instance;
    State* st;
    char why[200];
    if (inst == NULL) return fmi3Error;
    if ((st = own_state(inst, FMUState, function)) == NULL) return fmi3Error;
    if (serializedState == NULL) return refuse(inst, function, "the buffer is NULL");
    if (!rattle_state_room(size, st->size, "fmi3SerializedFMUStateSize", why, sizeof why))
        return refuse(inst, function, "%s", why);
    memcpy(serializedState + RATTLE_STATE_HEADER, st->record, st->size);
    rattle_state_seal(serializedState, size, st->size, RATTLE_GUID);
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState* FMUState)
{
    static const char function[] = "fmi3DeserializeFMUState";
    Instance* inst = instance;
    State* reuse = NULL;
    unsigned char* record;
    uint64_t n;
    char why[300];
    if (inst == NULL) return fmi3Error;
    if (FMUState == NULL) return refuse(inst, function, "the FMUState pointer is NULL");
    if (serializedState == NULL) return refuse(inst, function, "the buffer is NULL");
    if (!rattle_state_open(serializedState, size, RATTLE_GUID, &n, why, sizeof why))
        return refuse(inst, function, "%s", why);
    if (rattle_state_misaddressed(FMUState))
        return refuse(inst, function, "FMUState " RATTLE_STATE_MISADDRESSED "; nothing done");
    if (*FMUState != NULL && (reuse = own_state(inst, *FMUState, function)) == NULL)
        return fmi3Error;
    /* the record's bytes as they are: rm_restore checks them when the state is set */
    record = malloc(n > 0 ? (size_t)n : 1);
    if (record == NULL) return refuse(inst, function, "out of memory; nothing changed");
    memcpy(record, serializedState + RATTLE_STATE_HEADER, (size_t)n);
    return keep_record(inst, function, reuse, FMUState, record, (size_t)n);
}

/* ------------------------------------------------------------------ not provided */
/* A function of what these units do not have: refused with `why` (the modelDescription says
 * so). */
static fmi3Status not_provided(fmi3Instance instance, const char* function, const char* why)
{
    Instance* inst = instance;
    if (inst == NULL) return fmi3Error;
    return refuse(inst, function, "%s", why);
}

#define NO_EVENT_MODE                                                                          \
    "this FMU has no Event Mode (hasEventMode = false): after fmi3ExitInitializationMode it "  \
    "is in Step Mode, and fmi3DoStep never asks for event handling; nothing changed"
#define NO_CLOCKS "this FMU has no clocks; nothing done"
#define MODEL_EXCHANGE_ONLY                                                                    \
    "a Model Exchange function, and this FMU is for co-simulation only; nothing done"

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EnterEventMode", NO_EVENT_MODE);
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EnterStepMode", NO_EVENT_MODE);
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate,
                                    fmi3Boolean* terminateSimulation,
                                    fmi3Boolean* nominalsOfContinuousStatesChanged,
                                    fmi3Boolean* valuesOfContinuousStatesChanged,
                                    fmi3Boolean* nextEventTimeDefined,
                                    fmi3Float64* nextEventTime)
{
    (void)discreteStatesNeedUpdate, (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged, (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined, (void)nextEventTime;
    return not_provided(instance, "fmi3UpdateDiscreteStates", NO_EVENT_MODE);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EvaluateDiscreteStates",
                        "not provided by this FMU (providesEvaluateDiscreteStates = false); "
                        "nothing done");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EnterConfigurationMode",
                        "this FMU has no structural parameters; nothing changed");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3ExitConfigurationMode",
                        "this FMU has no structural parameters; nothing changed");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t* nDependencies)
{
    (void)valueReference, (void)nDependencies;
    return not_provided(instance, "fmi3GetNumberOfVariableDependencies",
                        "not provided by this FMU (providesPerElementDependencies = false): "
                        "the dependencies are in the modelDescription's <ModelStructure>");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies)
{
    (void)dependent, (void)elementIndicesOfDependent, (void)independents;
    (void)elementIndicesOfIndependents, (void)dependencyKinds, (void)nDependencies;
    return not_provided(instance, "fmi3GetVariableDependencies",
                        "not provided by this FMU (providesPerElementDependencies = false): "
                        "the dependencies are in the modelDescription's <ModelStructure>");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance,
                                        const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns,
                                        const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    return not_provided(instance, "fmi3GetDirectionalDerivative",
                        "not provided by this FMU (providesDirectionalDerivatives = false)");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    return not_provided(instance, "fmi3GetAdjointDerivative",
                        "not provided by this FMU (providesAdjointDerivatives = false)");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance,
                                    const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t nValues)
{
    (void)valueReferences, (void)nValueReferences, (void)orders, (void)values, (void)nValues;
    return not_provided(instance, "fmi3GetOutputDerivatives",
                        "not provided by this FMU (maxOutputDerivativeOrder = 0)");
}

/* Clocks */
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance,
                                  const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences, (void)nValueReferences, (void)intervals, (void)qualifiers;
    return not_provided(instance, "fmi3GetIntervalDecimal", NO_CLOCKS);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[],
                                   fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    (void)qualifiers;
    return not_provided(instance, "fmi3GetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[])
{
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    return not_provided(instance, "fmi3GetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[],
                                fmi3UInt64 resolutions[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return not_provided(instance, "fmi3GetShiftFraction", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance,
                                  const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[])
{
    (void)valueReferences, (void)nValueReferences, (void)intervals;
    return not_provided(instance, "fmi3SetIntervalDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return not_provided(instance, "fmi3SetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[])
{
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    return not_provided(instance, "fmi3SetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return not_provided(instance, "fmi3SetShiftFraction", NO_CLOCKS);
}

/* Model Exchange */
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EnterContinuousTimeMode", MODEL_EXCHANGE_ONLY);
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean* enterEventMode,
                                       fmi3Boolean* terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
    return not_provided(instance, "fmi3CompletedIntegratorStep", MODEL_EXCHANGE_ONLY);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    return not_provided(instance, "fmi3SetTime", MODEL_EXCHANGE_ONLY);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates, (void)nContinuousStates;
    return not_provided(instance, "fmi3SetContinuousStates", MODEL_EXCHANGE_ONLY);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    (void)derivatives, (void)nContinuousStates;
    return not_provided(instance, "fmi3GetContinuousStateDerivatives", MODEL_EXCHANGE_ONLY);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators)
{
    (void)eventIndicators, (void)nEventIndicators;
    return not_provided(instance, "fmi3GetEventIndicators", MODEL_EXCHANGE_ONLY);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates, (void)nContinuousStates;
    return not_provided(instance, "fmi3GetContinuousStates", MODEL_EXCHANGE_ONLY);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    (void)nominals, (void)nContinuousStates;
    return not_provided(instance, "fmi3GetNominalsOfContinuousStates", MODEL_EXCHANGE_ONLY);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* nEventIndicators)
{
    (void)nEventIndicators;
    return not_provided(instance, "fmi3GetNumberOfEventIndicators", MODEL_EXCHANGE_ONLY);
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* nContinuousStates)
{
    (void)nContinuousStates;
    return not_provided(instance, "fmi3GetNumberOfContinuousStates", MODEL_EXCHANGE_ONLY);
}

/* Scheduled Execution */
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference, (void)activationTime;
    return not_provided(instance, "fmi3ActivateModelPartition",
                        "a Scheduled Execution function, and this FMU is for co-simulation "
                        "only; nothing done");
}
