/*
 * fmi_abuse.c - bad calls to a native drive-rattle FMU's binary, for the build under
 * AddressSanitizer and UndefinedBehaviorSanitizer (tests/sanitize/test_native_sanitizers.py,
 * tests/sanitize/test_fmi3_sanitizers.py).  One host for both standards: what differs is an
 * adapter, chosen when the host is compiled (FMI 2.0 by default, FMI 3.0 with
 * -DFMI_ABUSE_FMI3), as in tests/faces/fmu_host.c.
 *
 * The calls: instantiation arguments that are not this FMU's (names, tokens, resource
 * locations: relative, empty, NULL, other schemes, another host, the unpacked root, a FIFO
 * as the marker file), every function on a NULL instance, NULL pointers and arrays, unknown
 * value references, calls out of order, non-finite values, strings that are not UTF-8 or
 * NULL in every mode, FMU states that are foreign, misaddressed, serialized into buffers of
 * every size around the right one, truncated at every length, bit-flipped, and re-sealed
 * around a damaged record (so that the record reaches rm_restore), many instances; then
 * each standard's own (its adapter's own_* functions).  Every call must return, with the
 * status expected; a sanitizer report ends the run (halt_on_error) and fails the test.
 *
 * Usage: fmi_abuse BINARY RESOURCES TOKEN UNPACKED_ROOT FIFO_FOLDER VR_PARAMETER VR_INPUT
 *                  VR_OUTPUT VR_INTEGER_OUTPUT|- VR_STRING|- VR_ENUMERATION|- VR_TIME|-
 * (RESOURCES: the resources folder in the standard's form, FMI 2.0's URI, FMI 3.0's path;
 * TOKEN: FMI 2.0's GUID, FMI 3.0's instantiationToken; value references of a Real parameter,
 * a Real input, a Real output, an Integer output, a String parameter, an Enumeration
 * parameter and the independent variable time, "-" where the FMU has none).  Prints
 * "cases N failures F logged L"; exit code 0 when no expectation failed.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* fmi2Status and fmi3Status share these values */
enum { OK = 0, WARNING = 1, ERROR = 3 };

static int cases, failures, logged;
static char last_message[4096];

/* A message the FMU logged: always in the category of its status (logStatus...), never with
 * status OK (the units log only what is not), never empty. */
static void record(int status, const char* category, const char* message)
{
    logged++;
    snprintf(last_message, sizeof last_message, "%s", message ? message : "(null)");
    if (category == NULL || strncmp(category, "logStatus", 9) != 0 || status == OK
        || message == NULL || message[0] == '\0') {
        printf("FAIL: status %d logged in category %s: %s\n", status, category ? category : "",
               last_message);
        failures++;
    }
}

static void check(int ok, const char* what, int line)
{
    cases++;
    if (!ok) {
        failures++;
        printf("FAIL line %d: %s (last message: %s)\n", line, what, last_message);
    }
}

static void check_status(int got, int want, const char* what, int line)
{
    cases++;
    if (got != want) {
        failures++;
        printf("FAIL line %d: %s returned %d, expected %d (last message: %s)\n", line, what, got,
               want, last_message);
    }
}
/* EXPECT(condition, what); EXPECT_STATUS(call, status) */
#define EXPECT(ok, what) check((ok), (what), __LINE__)
#define EXPECT_STATUS(call, want) check_status((int)(call), (want), #call, __LINE__)

/* ------------------------------------------------------------------ the adapters
 * One standard's calls behind the host's: loading its functions, instantiating, the life
 * cycle, values, FMU states; and its own cases (own_*). */
typedef void* Instance;
typedef void* State;

static const char* token;
static const char* resources;
static int has_string, has_int, has_enum, has_time;
static unsigned int vr_param, vr_input, vr_output, vr_int, vr_string, vr_enum, vr_time;
static const unsigned int unknown = 0xFFFFFFFFu;

#if defined(FMI_ABUSE_FMI3)
#include "fmi3FunctionTypes.h"
#define STANDARD "3.0"
#define API(X)                                                                                 \
    X(fmi3GetVersion) X(fmi3InstantiateCoSimulation) X(fmi3InstantiateModelExchange)           \
    X(fmi3FreeInstance) X(fmi3SetDebugLogging) X(fmi3EnterInitializationMode)                 \
    X(fmi3ExitInitializationMode) X(fmi3Terminate) X(fmi3Reset) X(fmi3GetFloat64)              \
    X(fmi3SetFloat64) X(fmi3GetInt64) X(fmi3SetInt64) X(fmi3GetInt32) X(fmi3GetBoolean)       \
    X(fmi3SetBoolean) X(fmi3GetString) X(fmi3SetString) X(fmi3GetFloat32) X(fmi3SetUInt64)    \
    X(fmi3GetBinary) X(fmi3GetClock) X(fmi3DoStep) X(fmi3GetFMUState) X(fmi3SetFMUState)       \
    X(fmi3FreeFMUState) X(fmi3SerializedFMUStateSize) X(fmi3SerializeFMUState)                 \
    X(fmi3DeserializeFMUState) X(fmi3EnterEventMode) X(fmi3EnterStepMode)                      \
    X(fmi3UpdateDiscreteStates) X(fmi3GetDirectionalDerivative) X(fmi3SetTime)
typedef fmi3ValueReference VR;
typedef fmi3Int32 Integer;
/* FMI 3.0 takes a resources folder as NULL: the instance then has none */
#define NULL_RESOURCES_REFUSED 0

static struct {
#define MEMBER(name) name##TYPE* name;
    API(MEMBER)
#undef MEMBER
} F;

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                        fmi3String message)
{
    (void)env;
    record((int)status, category, message);
}

static Instance instantiate_as(const char* name, const char* tok, const char* res)
{
    return F.fmi3InstantiateCoSimulation(name, tok, res, fmi3False, fmi3False, fmi3False,
                                         fmi3False, NULL, 0, NULL, log_message, NULL);
}

static int version_is_the_standards(void) { return strcmp(F.fmi3GetVersion(), "3.0") == 0; }
static void free_instance(Instance c) { F.fmi3FreeInstance(c); }
static int set_logging(Instance c, int on, size_t n, const char* const* categories)
{
    return F.fmi3SetDebugLogging(c, on != 0, n, categories);
}
static int enter(Instance c, double t0)
{
    return F.fmi3EnterInitializationMode(c, fmi3False, 0.0, t0, fmi3False, 0.0);
}
static int exit_initialization(Instance c) { return F.fmi3ExitInitializationMode(c); }
static int terminate(Instance c) { return F.fmi3Terminate(c); }
static int reset(Instance c) { return F.fmi3Reset(c); }
static int do_step(Instance c, double t, double h)
{
    fmi3Boolean event, stop, early;
    double last;
    return F.fmi3DoStep(c, t, h, fmi3True, &event, &stop, &early, &last);
}
static int get_reals(Instance c, const VR* vr, size_t n, double* v)
{
    return F.fmi3GetFloat64(c, vr, n, v, n);
}
static int set_reals(Instance c, const VR* vr, size_t n, const double* v)
{
    return F.fmi3SetFloat64(c, vr, n, v, n);
}
static int get_integers(Instance c, const VR* vr, size_t n, Integer* v)
{
    return F.fmi3GetInt32(c, vr, n, v, n);
}
static int get_strings(Instance c, const VR* vr, size_t n, const char** v)
{
    return F.fmi3GetString(c, vr, n, v, n);
}
static int set_strings(Instance c, const VR* vr, size_t n, const char* const* v)
{
    return F.fmi3SetString(c, vr, n, v, n);
}
static int get_state(Instance c, State* s) { return F.fmi3GetFMUState(c, s); }
static int set_state(Instance c, State s) { return F.fmi3SetFMUState(c, s); }
static int free_state(Instance c, State* s) { return F.fmi3FreeFMUState(c, s); }
static int state_size(Instance c, State s, size_t* n)
{
    return F.fmi3SerializedFMUStateSize(c, s, n);
}
static int serialize(Instance c, State s, unsigned char* buf, size_t n)
{
    return F.fmi3SerializeFMUState(c, s, buf, n);
}
static int deserialize(Instance c, const unsigned char* buf, size_t n, State* s)
{
    return F.fmi3DeserializeFMUState(c, buf, n, s);
}
/* The time reached: the independent variable time */
static int time_reached(Instance c, double* t) { return F.fmi3GetFloat64(c, &vr_time, 1, t, 1); }

static void own_instantiation_refusals(void)
{
    static const fmi3ValueReference required[1] = {0};
    EXPECT(F.fmi3InstantiateCoSimulation("x", token, resources, fmi3False, fmi3False, fmi3True,
                                         fmi3False, NULL, 0, NULL, log_message, NULL) == NULL,
           "event mode (the units have none)");
    EXPECT(F.fmi3InstantiateCoSimulation("x", token, resources, fmi3False, fmi3False, fmi3False,
                                         fmi3False, required, 1, NULL, log_message, NULL)
               == NULL,
           "a required intermediate variable");
    EXPECT(F.fmi3InstantiateModelExchange("x", token, resources, fmi3False, fmi3False, NULL,
                                          log_message) == NULL,
           "model exchange");
}

static void own_null_instance(void)
{
    VR vr = 0;
    fmi3Int64 code = 0;
    EXPECT_STATUS(F.fmi3GetInt64(NULL, &vr, 1, &code, 1), ERROR);
    EXPECT_STATUS(F.fmi3SetInt64(NULL, &vr, 1, &code, 1), ERROR);
    EXPECT_STATUS(F.fmi3EnterEventMode(NULL), ERROR);
    EXPECT_STATUS(F.fmi3SetTime(NULL, 0.0), ERROR);
}

/* Before initialization: the time reads 0; what the units do not provide is refused. */
static void own_out_of_order(Instance c)
{
    double t = 1.0;
    EXPECT_STATUS(time_reached(c, &t), OK);
    EXPECT(t == 0.0, "the time before initialization is 0");
    EXPECT_STATUS(F.fmi3EnterEventMode(c), ERROR);
    EXPECT_STATUS(F.fmi3EnterStepMode(c), ERROR);
    EXPECT_STATUS(F.fmi3UpdateDiscreteStates(c, NULL, NULL, NULL, NULL, NULL, NULL), ERROR);
    EXPECT_STATUS(F.fmi3GetDirectionalDerivative(c, NULL, 0, NULL, 0, NULL, 0, NULL, 0), ERROR);
    EXPECT_STATUS(F.fmi3SetTime(c, 0.0), ERROR);
}

static void own_enter_twice(Instance c) { EXPECT_STATUS(enter(c, 0.0), ERROR); }

/* nValues, the types the units lack, Enumerations as Int64, the independent variable. */
static void own_values(Instance c)
{
    double values[4];
    fmi3Int64 codes[2];
    fmi3Boolean flags[3];
    size_t size = 0;
    VR vrs[4] = {vr_time, vr_param, unknown, vr_time};
    EXPECT_STATUS(F.fmi3GetFloat64(c, &vr_param, 1, values, 2), ERROR);
    EXPECT_STATUS(F.fmi3GetFloat64(c, vrs, 4, values, 4), ERROR);
    EXPECT_STATUS(F.fmi3SetFloat64(c, vrs, 4, values, 4), ERROR);
    vrs[2] = vr_input;
    EXPECT_STATUS(F.fmi3GetFloat64(c, vrs, 4, values, 4), OK);
    EXPECT_STATUS(F.fmi3SetFloat64(c, &vr_time, 1, values, 1), ERROR);
    EXPECT_STATUS(F.fmi3GetFloat32(c, &vr_param, 1, (fmi3Float32*)values, 1), ERROR);
    EXPECT_STATUS(F.fmi3SetUInt64(c, &vr_param, 1, (fmi3UInt64*)values, 1), ERROR);
    EXPECT_STATUS(F.fmi3GetBinary(c, &vr_param, 1, &size, (fmi3Binary*)values, 1), ERROR);
    EXPECT_STATUS(F.fmi3GetClock(c, &vr_param, 1, flags), ERROR);
    EXPECT_STATUS(F.fmi3GetInt64(c, &vr_param, 1, codes, 1), ERROR);
    EXPECT_STATUS(F.fmi3GetBoolean(c, &vr_param, 1, flags, 1), ERROR);
    if (has_enum) {
        codes[0] = INT64_MAX;
        EXPECT_STATUS(F.fmi3SetInt64(c, &vr_enum, 1, codes, 1), ERROR);
        codes[0] = INT64_MIN;
        EXPECT_STATUS(F.fmi3SetInt64(c, &vr_enum, 1, codes, 1), ERROR);
        EXPECT_STATUS(F.fmi3GetInt32(c, &vr_enum, 1, (fmi3Int32*)codes, 1), ERROR);
        EXPECT_STATUS(F.fmi3GetInt64(c, &vr_enum, 1, codes, 1), OK);
        EXPECT_STATUS(F.fmi3SetInt64(c, &vr_enum, 1, codes, 1), OK);
    }
}

/* fmi3DoStep's output pointers. */
static void own_after_steps(Instance c, double t)
{
    fmi3Boolean flags[3];
    double last = 0.0;
    EXPECT_STATUS(F.fmi3DoStep(c, t, 1e-4, fmi3True, NULL, &flags[1], &flags[2], &last), ERROR);
    EXPECT_STATUS(F.fmi3DoStep(c, t, 1e-4, fmi3True, &flags[0], &flags[1], &flags[2], NULL),
                  ERROR);
}
#else
#include "fmi2FunctionTypes.h"
#define STANDARD "2.0"
#define API(X)                                                                                 \
    X(fmi2GetTypesPlatform) X(fmi2GetVersion) X(fmi2SetDebugLogging) X(fmi2Instantiate)        \
    X(fmi2FreeInstance) X(fmi2SetupExperiment) X(fmi2EnterInitializationMode)                 \
    X(fmi2ExitInitializationMode) X(fmi2Terminate) X(fmi2Reset) X(fmi2GetReal)                 \
    X(fmi2GetInteger) X(fmi2GetBoolean) X(fmi2GetString) X(fmi2SetReal) X(fmi2SetInteger)      \
    X(fmi2SetBoolean) X(fmi2SetString) X(fmi2GetFMUstate) X(fmi2SetFMUstate)                   \
    X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize) X(fmi2SerializeFMUstate)                 \
    X(fmi2DeSerializeFMUstate) X(fmi2GetDirectionalDerivative)                                 \
    X(fmi2SetRealInputDerivatives) X(fmi2GetRealOutputDerivatives) X(fmi2DoStep)               \
    X(fmi2CancelStep) X(fmi2GetStatus) X(fmi2GetRealStatus) X(fmi2GetIntegerStatus)            \
    X(fmi2GetBooleanStatus) X(fmi2GetStringStatus)
typedef fmi2ValueReference VR;
typedef fmi2Integer Integer;
#define NULL_RESOURCES_REFUSED 1

static struct {
#define MEMBER(name) name##TYPE* name;
    API(MEMBER)
#undef MEMBER
} F;

/* FMI 2.0's logger takes a printf format: the faces always log as ("%s", message). */
static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    va_list ap;
    char text[4096];
    (void)env, (void)instance;
    if (message == NULL || strcmp(message, "%s") != 0) {
        printf("FAIL: a message passed as the format: %s\n", message ? message : "(null)");
        failures++;
        return;
    }
    va_start(ap, message);
    vsnprintf(text, sizeof text, message, ap);
    va_end(ap);
    record((int)status, category, text);
}

static fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static Instance instantiate_as(const char* name, const char* tok, const char* res)
{
    return F.fmi2Instantiate(name, fmi2CoSimulation, tok, res, &callbacks, fmi2False,
                             fmi2False);
}

static int version_is_the_standards(void)
{
    return strcmp(F.fmi2GetVersion(), "2.0") == 0
           && strcmp(F.fmi2GetTypesPlatform(), "default") == 0;
}
static void free_instance(Instance c) { F.fmi2FreeInstance(c); }
static int set_logging(Instance c, int on, size_t n, const char* const* categories)
{
    return F.fmi2SetDebugLogging(c, on, n, categories);
}
/* FMI 2.0 takes the start time in fmi2SetupExperiment */
static int enter(Instance c, double t0)
{
    int st = F.fmi2SetupExperiment(c, fmi2False, 0.0, t0, fmi2False, 0.0);
    return st != OK ? st : (int)F.fmi2EnterInitializationMode(c);
}
static int exit_initialization(Instance c) { return F.fmi2ExitInitializationMode(c); }
static int terminate(Instance c) { return F.fmi2Terminate(c); }
static int reset(Instance c) { return F.fmi2Reset(c); }
static int do_step(Instance c, double t, double h) { return F.fmi2DoStep(c, t, h, fmi2True); }
static int get_reals(Instance c, const VR* vr, size_t n, double* v)
{
    return F.fmi2GetReal(c, vr, n, v);
}
static int set_reals(Instance c, const VR* vr, size_t n, const double* v)
{
    return F.fmi2SetReal(c, vr, n, v);
}
static int get_integers(Instance c, const VR* vr, size_t n, Integer* v)
{
    return F.fmi2GetInteger(c, vr, n, v);
}
static int get_strings(Instance c, const VR* vr, size_t n, const char** v)
{
    return F.fmi2GetString(c, vr, n, v);
}
static int set_strings(Instance c, const VR* vr, size_t n, const char* const* v)
{
    return F.fmi2SetString(c, vr, n, v);
}
static int get_state(Instance c, State* s) { return F.fmi2GetFMUstate(c, s); }
static int set_state(Instance c, State s) { return F.fmi2SetFMUstate(c, s); }
static int free_state(Instance c, State* s) { return F.fmi2FreeFMUstate(c, s); }
static int state_size(Instance c, State s, size_t* n)
{
    return F.fmi2SerializedFMUstateSize(c, s, n);
}
static int serialize(Instance c, State s, unsigned char* buf, size_t n)
{
    return F.fmi2SerializeFMUstate(c, s, (fmi2Byte*)buf, n);
}
static int deserialize(Instance c, const unsigned char* buf, size_t n, State* s)
{
    return F.fmi2DeSerializeFMUstate(c, (const fmi2Byte*)buf, n, s);
}
/* The time reached: fmi2LastSuccessfulTime */
static int time_reached(Instance c, double* t)
{
    return F.fmi2GetRealStatus(c, fmi2LastSuccessfulTime, t);
}

static void own_instantiation_refusals(void)
{
    fmi2CallbackFunctions no_logger = {NULL, calloc, free, NULL, NULL};
    EXPECT(F.fmi2Instantiate("abuse", fmi2ModelExchange, token, resources, &callbacks, 0, 0)
               == NULL,
           "model exchange");
    EXPECT(F.fmi2Instantiate("abuse", (fmi2Type)7, token, resources, &callbacks, 0, 0) == NULL,
           "fmuType 7");
    EXPECT(F.fmi2Instantiate("abuse", fmi2CoSimulation, token, resources, NULL, 0, 0) == NULL,
           "NULL callbacks");
    EXPECT(F.fmi2Instantiate("abuse", fmi2CoSimulation, token, "resources", &no_logger, 0, 0)
               == NULL,
           "no logger");
}

static void own_null_instance(void)
{
    fmi2ValueReference vr = 0;
    double x = 0.0;
    fmi2Integer i = 0;
    EXPECT_STATUS(F.fmi2EnterInitializationMode(NULL), ERROR);
    EXPECT_STATUS(F.fmi2GetInteger(NULL, &vr, 1, &i), ERROR);
    EXPECT_STATUS(F.fmi2GetBoolean(NULL, &vr, 1, &i), ERROR);
    EXPECT_STATUS(F.fmi2SetInteger(NULL, &vr, 1, &i), ERROR);
    EXPECT_STATUS(F.fmi2SetBoolean(NULL, &vr, 1, &i), ERROR);
    EXPECT_STATUS(F.fmi2CancelStep(NULL), ERROR);
    EXPECT_STATUS(F.fmi2GetDirectionalDerivative(NULL, &vr, 1, &vr, 1, &x, &x), ERROR);
}

/* Before initialization: no time reached yet. */
static void own_out_of_order(Instance c)
{
    double x = 0.0;
    EXPECT_STATUS(time_reached(c, &x), ERROR);
}

static void own_enter_twice(Instance c)
{
    EXPECT_STATUS(F.fmi2EnterInitializationMode(c), ERROR);
    EXPECT_STATUS(F.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), ERROR);
}

static void own_values(Instance c)
{
    fmi2Integer i = 0;
    EXPECT_STATUS(F.fmi2GetInteger(c, NULL, 2, &i), ERROR);
    EXPECT_STATUS(F.fmi2SetBoolean(c, &vr_param, 1, NULL), ERROR);
    EXPECT_STATUS(F.fmi2GetInteger(c, &vr_param, 1, &i), ERROR);
}

/* The status inquiries; what the units do not provide. */
static void own_after_steps(Instance c, double t)
{
    double x = 0.0;
    fmi2Integer i = 0;
    fmi2String s = NULL;
    (void)t;
    EXPECT_STATUS(F.fmi2GetRealStatus(c, fmi2LastSuccessfulTime, NULL), ERROR);
    EXPECT_STATUS(F.fmi2GetStatus(c, fmi2DoStepStatus, NULL), ERROR);
    EXPECT_STATUS(F.fmi2GetIntegerStatus(c, fmi2DoStepStatus, &i), ERROR);
    EXPECT_STATUS(F.fmi2GetStringStatus(c, fmi2PendingStatus, &s), ERROR);
    EXPECT_STATUS(F.fmi2GetBooleanStatus(c, fmi2Terminated, NULL), ERROR);
    EXPECT_STATUS(F.fmi2GetRealStatus(c, (fmi2StatusKind)99, &x), ERROR);
    EXPECT_STATUS(F.fmi2CancelStep(c), ERROR);
    EXPECT_STATUS(F.fmi2SetRealInputDerivatives(c, &vr_input, 1, &i, &x), ERROR);
    EXPECT_STATUS(F.fmi2GetRealOutputDerivatives(c, &vr_output, 1, &i, &x), ERROR);
}
#endif

/* ------------------------------------------------------------------ shared helpers */
static Instance instantiate(void)
{
    Instance c = instantiate_as("abuse", token, resources);
    EXPECT(c != NULL, "a valid instantiation");
    return c;
}

static int initialize(Instance c)
{
    return enter(c, 0.0) == OK && exit_initialization(c) == OK;
}

/* FNV-1a 64 and the envelope of rattle_fmi_common.h, written here independently. */
static uint64_t fnv1a64(const unsigned char* p, size_t n)
{
    uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

static void put_le64(unsigned char* p, uint64_t v)
{
    for (int i = 0; i < 8; i++) p[i] = (unsigned char)(v >> (8 * i));
}

/* A sealed envelope (header of `blob`) around `rec` of n bytes (malloc'ed, *size). */
static unsigned char* reseal(const unsigned char* blob, const unsigned char* rec, size_t n,
                             size_t* size)
{
    unsigned char* out = malloc(96 + n + 1);
    memcpy(out, blob, 96);
    memcpy(out + 96, rec, n);
    put_le64(out + 16, n);
    put_le64(out + 24, fnv1a64(rec, n));
    *size = 96 + n;
    return out;
}

/* The serialized current state of c (malloc'ed, *size). */
static unsigned char* serialized(Instance c, size_t* size)
{
    State state = NULL;
    unsigned char* blob;
    EXPECT_STATUS(get_state(c, &state), OK);
    EXPECT_STATUS(state_size(c, state, size), OK);
    blob = malloc(*size);
    EXPECT_STATUS(serialize(c, state, blob, *size), OK);
    EXPECT_STATUS(free_state(c, &state), OK);
    return blob;
}

/* Deserialize and set `blob`: the status of whichever refused (or OK). */
static int try_state(Instance c, const unsigned char* blob, size_t size)
{
    State state = NULL;
    int st = deserialize(c, blob, size, &state);
    if (st != OK) return st;
    st = set_state(c, state);
    free_state(c, &state);
    return st;
}

/* ------------------------------------------------------------------ the cases */
static void instantiation_refusals(const char* root, const char* fifo_folder)
{
    static const char* const locations[] = {
        "", "resources", "a", "r", "file:", "file://", "file:///", "file:/",
        "http://example.org/r", "file://otherhost/r", "file://host/x",
        "file:///nonexistent%20folder", "file:///tmp/x%00y", "file:///%00", "file:///tmp/x%",
        "file:///tmp/x%2", "C:", "//", "/nonexistent",
    };
    static const char* const names[] = {NULL, "", " \t", "\xff\xfe"};
    char path[4096];
    for (size_t k = 0; k < sizeof locations / sizeof *locations; k++) {
        /* the location copied to a block of its exact size: a read past it is reported */
        size_t n = strlen(locations[k]) + 1;
        char* location = malloc(n);
        memcpy(location, locations[k], n);
        EXPECT(instantiate_as("abuse", token, location) == NULL, locations[k]);
        free(location);
    }
    if (NULL_RESOURCES_REFUSED)
        EXPECT(instantiate_as("abuse", token, NULL) == NULL, "a NULL resource location");
    EXPECT(instantiate_as("abuse", token, root) == NULL, "the folder the FMU was unpacked to");
    snprintf(path, sizeof path, "%s/no such folder/", root);
    EXPECT(instantiate_as("abuse", token, path) == NULL, "a folder that does not exist");
    EXPECT(instantiate_as("abuse", token, fifo_folder) == NULL, "a FIFO as the marker file");
    EXPECT(strstr(last_message, "is a FIFO, not a regular file") != NULL, "the FIFO named");
    for (size_t k = 0; k < sizeof names / sizeof *names; k++)
        EXPECT(instantiate_as(names[k], token, resources) == NULL, "a bad instance name");
    EXPECT(instantiate_as("abuse", NULL, resources) == NULL, "a NULL token");
    EXPECT(instantiate_as("abuse", "{x}", resources) == NULL, "another token");
    EXPECT(instantiate_as("abuse", "{0}", resources) == NULL, "another token");
    own_instantiation_refusals();
}

static void null_instance(void)
{
    VR vr = 0;
    double x = 0.0;
    const char* s = NULL;
    State state = NULL;
    size_t size = 0;
    free_instance(NULL);
    EXPECT_STATUS(set_logging(NULL, 1, 0, NULL), ERROR);
    EXPECT_STATUS(enter(NULL, 0.0), ERROR);
    EXPECT_STATUS(exit_initialization(NULL), ERROR);
    EXPECT_STATUS(terminate(NULL), ERROR);
    EXPECT_STATUS(reset(NULL), ERROR);
    EXPECT_STATUS(get_reals(NULL, &vr, 1, &x), ERROR);
    EXPECT_STATUS(set_reals(NULL, &vr, 1, &x), ERROR);
    EXPECT_STATUS(get_strings(NULL, &vr, 1, &s), ERROR);
    EXPECT_STATUS(set_strings(NULL, &vr, 1, &s), ERROR);
    EXPECT_STATUS(get_state(NULL, &state), ERROR);
    EXPECT_STATUS(set_state(NULL, state), ERROR);
    EXPECT_STATUS(free_state(NULL, &state), ERROR);
    EXPECT_STATUS(state_size(NULL, state, &size), ERROR);
    EXPECT_STATUS(serialize(NULL, state, NULL, 0), ERROR);
    EXPECT_STATUS(deserialize(NULL, NULL, 0, &state), ERROR);
    EXPECT_STATUS(do_step(NULL, 0.0, 1e-4), ERROR);
    EXPECT_STATUS(time_reached(NULL, &x), ERROR);
    own_null_instance();
}

/* Values in Initialization Mode; c is reset at the end. */
static void values(Instance c)
{
    double x = 0.0, several[4] = {0.0, 0.0, 0.0, 0.0};
    const char* s = NULL;
    EXPECT_STATUS(get_reals(c, NULL, 1, &x), ERROR);
    EXPECT_STATUS(get_reals(c, &vr_output, 1, NULL), ERROR);
    EXPECT_STATUS(get_reals(c, NULL, 0, NULL), OK); /* nothing asked */
    EXPECT_STATUS(set_reals(c, NULL, 3, several), ERROR);
    EXPECT_STATUS(set_reals(c, &vr_input, 1, NULL), ERROR);
    EXPECT_STATUS(get_strings(c, &vr_param, 1, NULL), ERROR);
    EXPECT_STATUS(set_strings(c, NULL, 1, &s), ERROR);
    EXPECT_STATUS(get_reals(c, &unknown, 1, &x), ERROR);
    EXPECT(isnan(x), "an unknown reference reads NaN");
    EXPECT_STATUS(set_reals(c, &unknown, 1, &x), ERROR);
    EXPECT_STATUS(set_strings(c, &vr_param, 1, &s), ERROR); /* a String into a Real */
    EXPECT_STATUS(set_reals(c, &vr_output, 1, &x), ERROR);
    own_values(c);
    x = NAN;
    EXPECT_STATUS(set_reals(c, &vr_input, 1, &x), OK); /* checked at the end of initialization */
    EXPECT_STATUS(exit_initialization(c), ERROR);
    x = 0.0;
    EXPECT_STATUS(set_reals(c, &vr_input, 1, &x), OK);
    x = INFINITY;
    EXPECT_STATUS(set_reals(c, &vr_param, 1, &x), OK); /* stored, refused at the end */
    EXPECT_STATUS(exit_initialization(c), ERROR);
    EXPECT_STATUS(reset(c), OK);
    if (has_string) {
        const char* bad[2] = {"\xc3\x28", NULL};
        const char* long_name;
        char* huge = malloc(70000);
        memset(huge, 'a', 69999);
        huge[69999] = '\0';
        EXPECT_STATUS(set_strings(c, &vr_string, 1, &bad[0]), ERROR); /* not UTF-8 */
        EXPECT_STATUS(set_strings(c, &vr_string, 1, &bad[1]), ERROR); /* NULL */
        long_name = huge;
        EXPECT_STATUS(set_strings(c, &vr_string, 1, &long_name), OK);
        free(huge);
        EXPECT_STATUS(get_strings(c, &vr_string, 1, &s), OK);
        EXPECT(s != NULL && strlen(s) == 69999, "the long string kept");
        EXPECT(initialize(c) == 0, "a speed table that cannot be read refused");
        EXPECT_STATUS(reset(c), OK);
    }
    {
        const char* categories[2] = {"logAll", NULL};
        const char* bad_category[1] = {"\xff"};
        EXPECT_STATUS(set_logging(c, 1, 2, NULL), ERROR);
        EXPECT_STATUS(set_logging(c, 1, 1, NULL), ERROR);
        EXPECT_STATUS(set_logging(c, 1, 2, categories), ERROR); /* a NULL category */
        EXPECT_STATUS(set_logging(c, 1, 1, bad_category), ERROR);
        EXPECT_STATUS(set_logging(c, 1, 1, categories), OK);
        EXPECT_STATUS(set_logging(c, 0, 0, NULL), OK);
        EXPECT_STATUS(set_logging(c, 1, 1, categories), OK);
    }
}

/* Steps refused and taken: 20 steps of 1e-4 s from t = 0 at the end. */
static void steps(Instance c)
{
    double x = 0.0;
    EXPECT(initialize(c), "initialize");
    EXPECT_STATUS(do_step(c, 0.0, NAN), ERROR);
    EXPECT_STATUS(do_step(c, 0.0, -1e-4), ERROR);
    EXPECT_STATUS(do_step(c, 0.0, -1.0), ERROR);
    EXPECT_STATUS(do_step(c, 0.0, 0.0), ERROR);
    EXPECT_STATUS(do_step(c, 0.0, INFINITY), ERROR);
    EXPECT_STATUS(do_step(c, NAN, 1e-4), ERROR);
    EXPECT_STATUS(do_step(c, 1.0, 1e-4), ERROR);  /* does not continue */
    EXPECT_STATUS(do_step(c, 0.0, 10.0), ERROR);  /* beyond h_comm_max */
    EXPECT_STATUS(set_reals(c, &vr_param, 1, &x), ERROR); /* a parameter after initialization */
    x = 1e300;
    EXPECT_STATUS(set_reals(c, &vr_input, 1, &x), OK); /* beyond its range: refused at a step */
    EXPECT_STATUS(do_step(c, 0.0, 1e-4), ERROR);
    x = 0.0;
    EXPECT_STATUS(set_reals(c, &vr_input, 1, &x), OK);
    for (int k = 0; k < 20; k++) {
        int st = do_step(c, k * 1e-4, 1e-4);
        EXPECT(st == OK || st == WARNING, "a valid step");
    }
    EXPECT_STATUS(time_reached(c, &x), OK);
    EXPECT(fabs(x - 20e-4) < 1e-15, "the time reached is the end of the last step");
    if (has_int) {
        Integer i = 0;
        EXPECT_STATUS(get_integers(c, &vr_int, 1, &i), OK);
    }
    own_after_steps(c, 20e-4);
}

/* FMU states of c (at t = 20e-4 s); `other` another instance of the FMU. */
static void states(Instance c, Instance other)
{
    unsigned char junk[256];
    State state = NULL, state2 = NULL, kept = NULL;
    unsigned char *blob, *bigger;
    size_t size = 0, n, k, sealed_size;
    double t = 0.0;
    memset(junk, 0x5A, sizeof junk);
    EXPECT_STATUS(get_state(c, NULL), ERROR);
    EXPECT_STATUS(set_state(c, NULL), ERROR);
    EXPECT_STATUS(set_state(c, (State)junk), ERROR); /* a foreign pointer */
    EXPECT_STATUS(free_state(c, NULL), OK);          /* ignored */
    EXPECT_STATUS(free_state(c, &state), OK);        /* *NULL: ignored */
    EXPECT_STATUS(get_state(c, &kept), OK);          /* kept until the instance is freed */
    state = (State)junk;
    EXPECT_STATUS(get_state(c, &state), ERROR); /* into a variable that holds junk */
    state = NULL;
    /* the state passed where its address belongs */
    EXPECT_STATUS(get_state(c, (State*)kept), ERROR);
    EXPECT_STATUS(free_state(c, (State*)kept), ERROR);
    EXPECT_STATUS(get_state(c, &state), OK);
    EXPECT_STATUS(get_state(c, &state), OK); /* reused */
    EXPECT_STATUS(state_size(c, kept, NULL), ERROR);
    EXPECT_STATUS(state_size(c, NULL, &size), ERROR);
    blob = serialized(c, &size);
    EXPECT_STATUS(serialize(c, kept, NULL, size), ERROR);
    EXPECT_STATUS(serialize(c, kept, junk, 10), ERROR); /* a small buffer */
    /* every buffer size around the right one: refused below it, the state at and above */
    bigger = malloc(size + 100);
    for (n = 0; n < size + 100; n += (n < 100 || n + 100 > size ? 1 : 97)) {
        int fits = n >= size;
        memset(bigger, 0xA5, size + 100);
        EXPECT_STATUS(serialize(c, state, bigger, n), fits ? OK : ERROR);
        if (fits) EXPECT_STATUS(try_state(c, bigger, n), OK);
    }
    free(bigger);
    EXPECT_STATUS(deserialize(c, NULL, size, &state2), ERROR);
    EXPECT_STATUS(deserialize(c, blob, size, NULL), ERROR);
    EXPECT_STATUS(deserialize(c, blob, size, (State*)state), ERROR); /* misaddressed */
    EXPECT_STATUS(try_state(c, blob, size), OK);
    /* every truncation of the envelope: refused, never read past */
    for (n = 0; n < size; n++) {
        unsigned char* cut = malloc(n ? n : 1);
        memcpy(cut, blob, n);
        EXPECT_STATUS(try_state(c, cut, n), ERROR);
        free(cut);
    }
    /* every truncation of the record, re-sealed: rm_restore refuses it */
    for (n = 0; n + 96 < size; n++) {
        unsigned char* sealed = reseal(blob, blob + 96, n, &sealed_size);
        EXPECT_STATUS(try_state(c, sealed, sealed_size), ERROR);
        free(sealed);
    }
    /* every byte of the record changed, re-sealed: refused or accepted, never more */
    for (k = 96; k < size; k++) {
        static const unsigned char flips[3] = {0x01, 0x80, 0xFF};
        for (int f = 0; f < 3; f++) {
            unsigned char* copy = malloc(size);
            unsigned char* sealed;
            int st;
            memcpy(copy, blob, size);
            copy[k] ^= flips[f];
            sealed = reseal(copy, copy + 96, size - 96, &sealed_size);
            st = try_state(c, sealed, sealed_size);
            EXPECT(st == OK || st == ERROR, "a damaged record");
            if (st == OK) /* a step from whatever was accepted must return */
                (void)do_step(c, 20e-4, 1e-4);
            free(sealed);
            free(copy);
        }
    }
    /* one bit flipped anywhere, not re-sealed: it must return */
    for (k = 0; k < size; k += 7) {
        blob[k] ^= 0x10;
        EXPECT(deserialize(c, blob, size, &state2) <= ERROR, "a bit flipped");
        free_state(c, &state2);
        blob[k] ^= 0x10;
    }
    /* a corrupted envelope: checksum, token, version, length */
    for (k = 0; k < 96; k++) {
        unsigned char* copy = malloc(size);
        int st;
        memcpy(copy, blob, size);
        copy[k] ^= 0x21;
        st = try_state(c, copy, size);
        EXPECT(st == ERROR || (k >= 12 && k < 16) || (k >= 32 + strlen(token) + 1),
               "a damaged envelope");
        free(copy);
    }
    EXPECT_STATUS(deserialize(c, blob, size, &state2), OK);
    EXPECT_STATUS(set_state(c, (State)blob), ERROR); /* not a state */
    EXPECT_STATUS(set_state(other, state), OK);      /* another instance's */
    EXPECT_STATUS(free_state(c, &state2), OK);
    EXPECT_STATUS(set_state(c, state), OK);
    EXPECT_STATUS(free_state(c, &state), OK);
    EXPECT_STATUS(try_state(c, blob, size), OK); /* the intact state again */
    EXPECT_STATUS(time_reached(c, &t), OK);
    EXPECT(fabs(t - 20e-4) < 1e-15, "the state's time");
    EXPECT_STATUS(do_step(c, 20e-4, 1e-4), OK);
    free(blob);
    EXPECT_STATUS(reset(c), OK); /* with a state kept */
    EXPECT_STATUS(set_state(c, kept), OK);
}

static void the_end(Instance c)
{
    double x = 0.0;
    const char* none = NULL;
    if (has_string) /* a NULL String in Step Mode: the fixed parameter's refusal */
        EXPECT_STATUS(set_strings(c, &vr_string, 1, &none), ERROR);
    EXPECT_STATUS(terminate(c), OK);
    EXPECT_STATUS(terminate(c), ERROR);
    if (has_string) EXPECT_STATUS(set_strings(c, &vr_string, 1, &none), ERROR);
    /* nothing is set after terminate (the library refuses it: reset first) */
    EXPECT_STATUS(set_reals(c, &vr_input, 1, &x), ERROR);
    EXPECT_STATUS(set_reals(c, &vr_param, 1, &x), ERROR);
    EXPECT_STATUS(do_step(c, 21e-4, 1e-4), ERROR);
    EXPECT_STATUS(reset(c), OK);
    free_instance(c); /* with its states: none leaks */
}

static void many_instances(void)
{
    Instance many[8];
    for (int k = 0; k < 8; k++) many[k] = instantiate();
    for (int k = 0; k < 8; k += 2) free_instance(many[k]);
    for (int k = 1; k < 8; k += 2) {
        EXPECT(initialize(many[k]), "initialize one of many");
        EXPECT_STATUS(do_step(many[k], 0.0, 1e-4), OK);
        free_instance(many[k]);
    }
}

static int reference(const char* text, unsigned int* vr)
{
    if (strcmp(text, "-") == 0) return 0;
    *vr = (unsigned int)strtoul(text, NULL, 10);
    return 1;
}

int main(int argc, char** argv)
{
    void* lib;
    Instance c, other;
    if (argc != 13) {
        fprintf(stderr, "usage: %s BINARY RESOURCES TOKEN UNPACKED_ROOT FIFO_FOLDER "
                        "VR_PARAMETER VR_INPUT VR_OUTPUT VR_INTEGER_OUTPUT|- VR_STRING|- "
                        "VR_ENUMERATION|- VR_TIME|-  (FMI " STANDARD ")\n", argv[0]);
        return 2;
    }
    resources = argv[2];
    token = argv[3];
    reference(argv[6], &vr_param);
    reference(argv[7], &vr_input);
    reference(argv[8], &vr_output);
    has_int = reference(argv[9], &vr_int);
    has_string = reference(argv[10], &vr_string);
    has_enum = reference(argv[11], &vr_enum);
    has_time = reference(argv[12], &vr_time);
    if (!has_time && strcmp(STANDARD, "3.0") == 0) {
        fprintf(stderr, "an FMI 3.0 FMU has the independent variable time: VR_TIME\n");
        return 2;
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "cannot load %s: %s\n", argv[1], dlerror());
        return 2;
    }
#define LOAD(name)                                                                             \
    {                                                                                          \
        void* p = dlsym(lib, #name);                                                           \
        if (p == NULL) {                                                                       \
            fprintf(stderr, "no symbol %s\n", #name);                                          \
            return 2;                                                                          \
        }                                                                                      \
        memcpy(&F.name, &p, sizeof p);                                                         \
    }
    API(LOAD)
#undef LOAD
    EXPECT(version_is_the_standards(), "the version is FMI " STANDARD "'s");

    instantiation_refusals(argv[4], argv[5]);
    null_instance();
    other = instantiate_as("other", token, NULL_RESOURCES_REFUSED ? resources : NULL);
    EXPECT(other != NULL, "another instance");

    /* ---------------------------------------------------------------- out of order */
    c = instantiate();
    if (c == NULL || other == NULL) return 1;
    EXPECT_STATUS(do_step(c, 0.0, 1e-4), ERROR);
    EXPECT_STATUS(exit_initialization(c), ERROR);
    EXPECT_STATUS(terminate(c), ERROR);
    own_out_of_order(c);
    EXPECT_STATUS(enter(c, NAN), ERROR);
    EXPECT_STATUS(enter(c, 1e300), ERROR);
    EXPECT_STATUS(enter(c, 0.0), OK);
    own_enter_twice(c);
    {
        double x = 0.0;
        EXPECT_STATUS(get_reals(c, &vr_output, 1, &x), OK); /* an output in initialization */
    }
    values(c);
    steps(c);
    states(c, other);
    the_end(c);
    free_instance(other);
    many_instances();
    printf("cases %d failures %d logged %d\n", cases, failures, logged);
    return failures != 0;
}
