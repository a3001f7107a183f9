/*
 * fmi_abuse.c - bad calls to a native drive-rattle FMU's binary, for the build under
 * AddressSanitizer and UndefinedBehaviorSanitizer (tests/sanitize/test_native_sanitizers.py):
 * NULL pointers and arrays, unknown value references, calls out of order, non-finite values,
 * resource locations that are not this FMU's (relative, empty, NULL, other schemes, a FIFO as
 * the marker file), FMU states that are foreign, truncated, corrupted or re-sealed around a
 * damaged record (so that the record reaches rm_restore).  Every call must return, with the
 * status expected; a sanitizer report ends the run (halt_on_error) and fails the test.
 *
 * Usage: fmi_abuse BINARY RESOURCES_URI GUID UNPACKED_ROOT FIFO_FOLDER VR_PARAMETER VR_INPUT
 *                  VR_OUTPUT VR_INTEGER_OUTPUT|- VR_STRING|-
 * (value references of a Real parameter, a Real input, a Real output, an Integer output and a
 * String parameter of the FMU; "-" where it has none).  Prints "cases N failures F"; exit
 * code 0 when no expectation failed.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"

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

static struct {
#define MEMBER(name) name##TYPE* name;
    API(MEMBER)
#undef MEMBER
} F;

static int cases, failures, logged;
static char last_message[4096];

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    va_list ap;
    (void)env, (void)instance;
    logged++;
    if (message == NULL || strcmp(message, "%s") != 0) {
        printf("FAIL: a message passed as the format: %s\n", message ? message : "(null)");
        failures++;
        return;
    }
    va_start(ap, message);
    vsnprintf(last_message, sizeof last_message, message, ap);
    va_end(ap);
    if (category == NULL || strncmp(category, "logStatus", 9) != 0 || status == fmi2OK) {
        printf("FAIL: status %d logged in category %s\n", (int)status, category ? category : "");
        failures++;
    }
}

static void expect(int ok, const char* what)
{
    cases++;
    if (!ok) {
        failures++;
        printf("FAIL: %s (last message: %s)\n", what, last_message);
    }
}

static void expect_status(fmi2Status got, fmi2Status want, const char* what)
{
    cases++;
    if (got != want) {
        failures++;
        printf("FAIL: %s returned %d, expected %d (last message: %s)\n", what, (int)got,
               (int)want, last_message);
    }
}

static fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
static const char* resources;
static const char* guid;

static fmi2Component instantiate(void)
{
    fmi2Component c = F.fmi2Instantiate("abuse", fmi2CoSimulation, guid, resources, &callbacks,
                                        fmi2False, fmi2False);
    expect(c != NULL, "a valid fmi2Instantiate");
    return c;
}

static int initialize(fmi2Component c)
{
    return F.fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK
           && F.fmi2EnterInitializationMode(c) == fmi2OK
           && F.fmi2ExitInitializationMode(c) == fmi2OK;
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

/* A sealed envelope (header of `blob`) around `record` of n bytes (malloc'ed, *size). */
static unsigned char* reseal(const unsigned char* blob, const unsigned char* record, size_t n,
                             size_t* size)
{
    unsigned char* out = malloc(96 + n + 1);
    memcpy(out, blob, 96);
    memcpy(out + 96, record, n);
    put_le64(out + 16, n);
    put_le64(out + 24, fnv1a64(record, n));
    *size = 96 + n;
    return out;
}

/* The serialized current state of c (malloc'ed, *size). */
static unsigned char* serialized(fmi2Component c, size_t* size)
{
    fmi2FMUstate state = NULL;
    unsigned char* blob;
    expect_status(F.fmi2GetFMUstate(c, &state), fmi2OK, "fmi2GetFMUstate");
    expect_status(F.fmi2SerializedFMUstateSize(c, state, size), fmi2OK,
                  "fmi2SerializedFMUstateSize");
    blob = malloc(*size);
    expect_status(F.fmi2SerializeFMUstate(c, state, (fmi2Byte*)blob, *size), fmi2OK,
                  "fmi2SerializeFMUstate");
    expect_status(F.fmi2FreeFMUstate(c, &state), fmi2OK, "fmi2FreeFMUstate");
    return blob;
}

/* Deserialize and set `blob`: the status of whichever refused (or OK). */
static fmi2Status try_state(fmi2Component c, const unsigned char* blob, size_t size)
{
    fmi2FMUstate state = NULL;
    fmi2Status st = F.fmi2DeSerializeFMUstate(c, (const fmi2Byte*)blob, size, &state);
    if (st != fmi2OK) return st;
    st = F.fmi2SetFMUstate(c, state);
    F.fmi2FreeFMUstate(c, &state);
    return st;
}

static void instantiate_refusals(const char* root, const char* fifo_folder)
{
    static const char* const locations[] = {
        "", "resources", "a", "file:", "file://", "file:///", "file:/", "http://example.org/r",
        "file://otherhost/r", "file:///nonexistent%20folder", "file:///tmp/x%00y",
        "file:///tmp/x%", "file:///tmp/x%2", "C:", "//", "/nonexistent",
    };
    fmi2CallbackFunctions no_logger = {NULL, calloc, free, NULL, NULL};
    for (size_t k = 0; k < sizeof locations / sizeof *locations; k++) {
        /* the location copied to a block of its exact size: a read past it is reported */
        size_t n = strlen(locations[k]) + 1;
        char* location = malloc(n);
        memcpy(location, locations[k], n);
        expect(F.fmi2Instantiate("abuse", fmi2CoSimulation, guid, location, &callbacks,
                                 fmi2False, fmi2False) == NULL, locations[k]);
        free(location);
    }
    expect(F.fmi2Instantiate("abuse", fmi2CoSimulation, guid, NULL, &callbacks, 0, 0) == NULL,
           "a NULL resource location");
    expect(F.fmi2Instantiate("abuse", fmi2CoSimulation, guid, root, &callbacks, 0, 0) == NULL,
           "the folder the FMU was unpacked to");
    expect(F.fmi2Instantiate("abuse", fmi2CoSimulation, guid, fifo_folder, &callbacks, 0, 0)
               == NULL,
           "a FIFO as the marker file");
    expect(strstr(last_message, "is a FIFO, not a regular file") != NULL, "the FIFO named");
    expect(F.fmi2Instantiate(NULL, fmi2CoSimulation, guid, resources, &callbacks, 0, 0) == NULL,
           "a NULL instance name");
    expect(F.fmi2Instantiate("", fmi2CoSimulation, guid, resources, &callbacks, 0, 0) == NULL,
           "an empty instance name");
    expect(F.fmi2Instantiate("\xff\xfe", fmi2CoSimulation, guid, resources, &callbacks, 0, 0)
               == NULL,
           "an instance name that is not UTF-8");
    expect(F.fmi2Instantiate("abuse", fmi2ModelExchange, guid, resources, &callbacks, 0, 0)
               == NULL,
           "model exchange");
    expect(F.fmi2Instantiate("abuse", (fmi2Type)7, guid, resources, &callbacks, 0, 0) == NULL,
           "fmuType 7");
    expect(F.fmi2Instantiate("abuse", fmi2CoSimulation, NULL, resources, &callbacks, 0, 0)
               == NULL,
           "a NULL GUID");
    expect(F.fmi2Instantiate("abuse", fmi2CoSimulation, "{x}", resources, &callbacks, 0, 0)
               == NULL,
           "another GUID");
    expect(F.fmi2Instantiate("abuse", fmi2CoSimulation, guid, resources, NULL, 0, 0) == NULL,
           "NULL callbacks");
    expect(F.fmi2Instantiate("abuse", fmi2CoSimulation, guid, "resources", &no_logger, 0, 0)
               == NULL,
           "no logger");
}

static void null_instance(void)
{
    fmi2ValueReference vr = 0;
    double x = 0.0;
    fmi2Integer i = 0;
    fmi2String s = NULL;
    fmi2FMUstate state = NULL;
    size_t size = 0;
    fmi2Status st;
    F.fmi2FreeInstance(NULL);
    expect_status(F.fmi2SetDebugLogging(NULL, fmi2True, 0, NULL), fmi2Error, "NULL: logging");
    expect_status(F.fmi2SetupExperiment(NULL, 0, 0.0, 0.0, 0, 0.0), fmi2Error, "NULL: setup");
    expect_status(F.fmi2EnterInitializationMode(NULL), fmi2Error, "NULL: enter");
    expect_status(F.fmi2ExitInitializationMode(NULL), fmi2Error, "NULL: exit");
    expect_status(F.fmi2Terminate(NULL), fmi2Error, "NULL: terminate");
    expect_status(F.fmi2Reset(NULL), fmi2Error, "NULL: reset");
    expect_status(F.fmi2GetReal(NULL, &vr, 1, &x), fmi2Error, "NULL: getReal");
    expect_status(F.fmi2GetInteger(NULL, &vr, 1, &i), fmi2Error, "NULL: getInteger");
    expect_status(F.fmi2GetBoolean(NULL, &vr, 1, &i), fmi2Error, "NULL: getBoolean");
    expect_status(F.fmi2GetString(NULL, &vr, 1, &s), fmi2Error, "NULL: getString");
    expect_status(F.fmi2SetReal(NULL, &vr, 1, &x), fmi2Error, "NULL: setReal");
    expect_status(F.fmi2SetInteger(NULL, &vr, 1, &i), fmi2Error, "NULL: setInteger");
    expect_status(F.fmi2SetBoolean(NULL, &vr, 1, &i), fmi2Error, "NULL: setBoolean");
    expect_status(F.fmi2SetString(NULL, &vr, 1, &s), fmi2Error, "NULL: setString");
    expect_status(F.fmi2GetFMUstate(NULL, &state), fmi2Error, "NULL: getFMUstate");
    expect_status(F.fmi2SetFMUstate(NULL, state), fmi2Error, "NULL: setFMUstate");
    expect_status(F.fmi2FreeFMUstate(NULL, &state), fmi2Error, "NULL: freeFMUstate");
    expect_status(F.fmi2SerializedFMUstateSize(NULL, state, &size), fmi2Error, "NULL: size");
    expect_status(F.fmi2SerializeFMUstate(NULL, state, NULL, 0), fmi2Error, "NULL: serialize");
    expect_status(F.fmi2DeSerializeFMUstate(NULL, NULL, 0, &state), fmi2Error,
                  "NULL: deserialize");
    expect_status(F.fmi2DoStep(NULL, 0.0, 1e-4, 1), fmi2Error, "NULL: doStep");
    expect_status(F.fmi2CancelStep(NULL), fmi2Error, "NULL: cancelStep");
    expect_status(F.fmi2GetRealStatus(NULL, fmi2LastSuccessfulTime, &x), fmi2Error,
                  "NULL: getRealStatus");
    st = F.fmi2GetDirectionalDerivative(NULL, &vr, 1, &vr, 1, &x, &x);
    expect_status(st, fmi2Error, "NULL: directional derivative");
}

int main(int argc, char** argv)
{
    void* lib;
    fmi2Component c;
    fmi2ValueReference vr_param, vr_input, vr_output, vr_int = 0, vr_string = 0;
    int has_int, has_string;
    fmi2ValueReference unknown = 0xFFFFFFFFu;
    double x = 0.0, values[4];
    fmi2Integer i = 0;
    fmi2String s = NULL;
    fmi2FMUstate state = NULL;
    unsigned char* blob;
    size_t size = 0;
    if (argc != 11) {
        fprintf(stderr, "usage: %s BINARY RESOURCES_URI GUID UNPACKED_ROOT FIFO_FOLDER "
                        "VR_PARAMETER VR_INPUT VR_OUTPUT VR_INTEGER_OUTPUT|- VR_STRING|-\n",
                argv[0]);
        return 2;
    }
    resources = argv[2];
    guid = argv[3];
    vr_param = (fmi2ValueReference)strtoul(argv[6], NULL, 10);
    vr_input = (fmi2ValueReference)strtoul(argv[7], NULL, 10);
    vr_output = (fmi2ValueReference)strtoul(argv[8], NULL, 10);
    has_int = strcmp(argv[9], "-") != 0;
    has_string = strcmp(argv[10], "-") != 0;
    if (has_int) vr_int = (fmi2ValueReference)strtoul(argv[9], NULL, 10);
    if (has_string) vr_string = (fmi2ValueReference)strtoul(argv[10], NULL, 10);
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
    expect(strcmp(F.fmi2GetVersion(), "2.0") == 0, "fmi2GetVersion");
    expect(strcmp(F.fmi2GetTypesPlatform(), "default") == 0, "fmi2GetTypesPlatform");

    instantiate_refusals(argv[4], argv[5]);
    null_instance();

    /* ---------------------------------------------------------------- out of order */
    c = instantiate();
    if (c == NULL) return 1;
    expect_status(F.fmi2DoStep(c, 0.0, 1e-4, 1), fmi2Error, "doStep before initialization");
    expect_status(F.fmi2ExitInitializationMode(c), fmi2Error, "exit before enter");
    expect_status(F.fmi2Terminate(c), fmi2Error, "terminate before initialization");
    expect_status(F.fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &x), fmi2Error,
                  "last successful time before initialization");
    expect_status(F.fmi2SetupExperiment(c, 0, 0.0, NAN, 0, 0.0), fmi2Error, "start time NaN");
    expect_status(F.fmi2SetupExperiment(c, 0, 0.0, 1e300, 0, 0.0), fmi2Error, "start 1e300");
    expect_status(F.fmi2EnterInitializationMode(c), fmi2OK, "enter");
    expect_status(F.fmi2EnterInitializationMode(c), fmi2Error, "enter twice");
    expect_status(F.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), fmi2Error, "setup after enter");
    expect_status(F.fmi2GetReal(c, &vr_output, 1, &x), fmi2OK, "an output in initialization");

    /* ---------------------------------------------------------------- values */
    expect_status(F.fmi2GetReal(c, NULL, 1, &x), fmi2Error, "getReal: NULL references");
    expect_status(F.fmi2GetReal(c, &vr_output, 1, NULL), fmi2Error, "getReal: NULL values");
    expect_status(F.fmi2GetReal(c, NULL, 0, NULL), fmi2OK, "getReal: nothing");
    expect_status(F.fmi2SetReal(c, NULL, 3, values), fmi2Error, "setReal: NULL references");
    expect_status(F.fmi2SetReal(c, &vr_input, 1, NULL), fmi2Error, "setReal: NULL values");
    expect_status(F.fmi2GetInteger(c, NULL, 2, &i), fmi2Error, "getInteger: NULL");
    expect_status(F.fmi2SetBoolean(c, &vr_param, 1, NULL), fmi2Error, "setBoolean: NULL");
    expect_status(F.fmi2GetString(c, &vr_param, 1, NULL), fmi2Error, "getString: NULL");
    expect_status(F.fmi2SetString(c, NULL, 1, &s), fmi2Error, "setString: NULL references");
    expect_status(F.fmi2GetReal(c, &unknown, 1, &x), fmi2Error, "getReal: unknown reference");
    expect(isnan(x), "an unknown reference reads NaN");
    expect_status(F.fmi2SetReal(c, &unknown, 1, &x), fmi2Error, "setReal: unknown reference");
    expect_status(F.fmi2GetInteger(c, &vr_param, 1, &i), fmi2Error, "getInteger of a Real");
    expect_status(F.fmi2SetString(c, &vr_param, 1, &s), fmi2Error, "setString of a Real");
    expect_status(F.fmi2SetReal(c, &vr_output, 1, &x), fmi2Error, "setReal of an output");
    x = NAN;
    expect_status(F.fmi2SetReal(c, &vr_input, 1, &x), fmi2OK, "a NaN input (checked at a step)");
    expect_status(F.fmi2ExitInitializationMode(c), fmi2Error, "exit with a NaN input");
    x = 0.0;
    expect_status(F.fmi2SetReal(c, &vr_input, 1, &x), fmi2OK, "the input again");
    x = INFINITY;
    expect_status(F.fmi2SetReal(c, &vr_param, 1, &x), fmi2OK, "an infinite parameter (stored)");
    expect_status(F.fmi2ExitInitializationMode(c), fmi2Error, "exit: the parameter refused");
    F.fmi2Reset(c);
    if (has_string) {
        const char* bad[2] = {"\xc3\x28", NULL};
        const char* long_name;
        char* huge = malloc(70000);
        memset(huge, 'a', 69999);
        huge[69999] = '\0';
        expect_status(F.fmi2SetString(c, &vr_string, 1, &bad[0]), fmi2Error, "setString: bad UTF-8");
        expect_status(F.fmi2SetString(c, &vr_string, 1, &bad[1]), fmi2Error, "setString: NULL");
        long_name = huge;
        expect_status(F.fmi2SetString(c, &vr_string, 1, &long_name), fmi2OK, "a long string");
        free(huge);
        expect_status(F.fmi2GetString(c, &vr_string, 1, &s), fmi2OK, "getString");
        expect(s != NULL && strlen(s) == 69999, "the long string kept");
        expect(initialize(c) == 0, "a speed table that cannot be read refused");
        F.fmi2Reset(c);
    }
    {
        const char* categories[2] = {"logAll", NULL};
        const char* bad_category[1] = {"\xff"};
        expect_status(F.fmi2SetDebugLogging(c, fmi2True, 2, NULL), fmi2Error, "categories NULL");
        expect_status(F.fmi2SetDebugLogging(c, fmi2True, 2, categories), fmi2Error,
                      "a NULL category");
        expect_status(F.fmi2SetDebugLogging(c, fmi2True, 1, bad_category), fmi2Error,
                      "a category that is not UTF-8");
        expect_status(F.fmi2SetDebugLogging(c, fmi2True, 1, categories), fmi2OK, "logAll");
    }

    /* ---------------------------------------------------------------- steps */
    expect(initialize(c), "initialize");
    expect_status(F.fmi2DoStep(c, 0.0, NAN, 1), fmi2Error, "step size NaN");
    expect_status(F.fmi2DoStep(c, 0.0, -1e-4, 1), fmi2Error, "a negative step");
    expect_status(F.fmi2DoStep(c, 0.0, 0.0, 1), fmi2Error, "a zero step");
    expect_status(F.fmi2DoStep(c, 0.0, INFINITY, 1), fmi2Error, "an infinite step");
    expect_status(F.fmi2DoStep(c, NAN, 1e-4, 1), fmi2Error, "a NaN time");
    expect_status(F.fmi2DoStep(c, 1.0, 1e-4, 1), fmi2Error, "a time that does not continue");
    expect_status(F.fmi2DoStep(c, 0.0, 10.0, 1), fmi2Error, "a step beyond h_comm_max");
    expect_status(F.fmi2SetReal(c, &vr_param, 1, &x), fmi2Error, "a parameter after init");
    x = 1e300;
    expect_status(F.fmi2SetReal(c, &vr_input, 1, &x), fmi2OK, "an input beyond its range");
    expect_status(F.fmi2DoStep(c, 0.0, 1e-4, 1), fmi2Error, "a step with it");
    x = 0.0;
    F.fmi2SetReal(c, &vr_input, 1, &x);
    for (int k = 0; k < 20; k++) {
        fmi2Status st = F.fmi2DoStep(c, k * 1e-4, 1e-4, 1);
        expect(st == fmi2OK || st == fmi2Warning, "a valid step");
    }
    expect_status(F.fmi2GetRealStatus(c, fmi2LastSuccessfulTime, NULL), fmi2Error,
                  "last successful time into NULL");
    expect_status(F.fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &x), fmi2OK,
                  "last successful time");
    expect(fabs(x - 20e-4) < 1e-15, "the last successful time is the end of the last step");
    if (has_int) {
        expect_status(F.fmi2GetInteger(c, &vr_int, 1, &i), fmi2OK, "an Integer output");
    }
    expect_status(F.fmi2GetStatus(c, fmi2DoStepStatus, NULL), fmi2Error, "getStatus");
    expect_status(F.fmi2GetIntegerStatus(c, fmi2DoStepStatus, &i), fmi2Error, "integer status");
    expect_status(F.fmi2GetStringStatus(c, fmi2PendingStatus, &s), fmi2Error, "string status");
    expect_status(F.fmi2GetBooleanStatus(c, fmi2Terminated, NULL), fmi2Error, "bool into NULL");
    expect_status(F.fmi2GetRealStatus(c, (fmi2StatusKind)99, &x), fmi2Error, "status kind 99");
    expect_status(F.fmi2CancelStep(c), fmi2Error, "cancelStep");
    expect_status(F.fmi2SetRealInputDerivatives(c, &vr_input, 1, &i, &x), fmi2Error,
                  "input derivatives");
    expect_status(F.fmi2GetRealOutputDerivatives(c, &vr_output, 1, &i, &x), fmi2Error,
                  "output derivatives");

    /* ---------------------------------------------------------------- FMU states */
    {
        unsigned char junk[256];
        fmi2FMUstate kept = NULL;
        unsigned char* bigger;
        size_t n, k, sealed_size;
        memset(junk, 0x5A, sizeof junk);
        expect_status(F.fmi2GetFMUstate(c, NULL), fmi2Error, "getFMUstate into NULL");
        expect_status(F.fmi2SetFMUstate(c, NULL), fmi2Error, "setFMUstate NULL");
        expect_status(F.fmi2SetFMUstate(c, (fmi2FMUstate)junk), fmi2Error, "a foreign pointer");
        expect_status(F.fmi2FreeFMUstate(c, NULL), fmi2OK, "free NULL (ignored)");
        expect_status(F.fmi2FreeFMUstate(c, &state), fmi2OK, "free *NULL (ignored)");
        expect_status(F.fmi2GetFMUstate(c, &kept), fmi2OK, "a state kept until freeInstance");
        state = (fmi2FMUstate)junk;
        expect_status(F.fmi2GetFMUstate(c, &state), fmi2Error, "getFMUstate into junk");
        state = NULL;
        blob = serialized(c, &size);
        expect_status(F.fmi2SerializedFMUstateSize(c, kept, NULL), fmi2Error, "size into NULL");
        expect_status(F.fmi2SerializeFMUstate(c, kept, NULL, size), fmi2Error, "into NULL");
        expect_status(F.fmi2SerializeFMUstate(c, kept, (fmi2Byte*)junk, 10), fmi2Error,
                      "into a small buffer");
        bigger = malloc(size + 100);
        expect_status(F.fmi2SerializeFMUstate(c, kept, (fmi2Byte*)bigger, size + 100), fmi2OK,
                      "into a larger buffer");
        expect_status(try_state(c, bigger, size + 100), fmi2OK, "a larger buffer back");
        free(bigger);
        expect_status(F.fmi2DeSerializeFMUstate(c, NULL, size, &state), fmi2Error,
                      "deserialize NULL");
        expect_status(F.fmi2DeSerializeFMUstate(c, (fmi2Byte*)blob, size, NULL), fmi2Error,
                      "deserialize into NULL");
        expect_status(try_state(c, blob, size), fmi2OK, "the state back");
        /* every truncation of the envelope: refused, never read past */
        for (n = 0; n < size; n++) {
            unsigned char* cut = malloc(n ? n : 1);
            memcpy(cut, blob, n);
            expect_status(try_state(c, cut, n), fmi2Error, "a truncated state");
            free(cut);
        }
        /* every truncation of the record, re-sealed: rm_restore refuses it */
        for (n = 0; n + 96 < size; n++) {
            unsigned char* sealed = reseal(blob, blob + 96, n, &sealed_size);
            expect_status(try_state(c, sealed, sealed_size), fmi2Error, "a truncated record");
            free(sealed);
        }
        /* every byte of the record changed, re-sealed: refused or accepted, never more */
        for (k = 96; k < size; k++) {
            static const unsigned char flips[3] = {0x01, 0x80, 0xFF};
            for (int f = 0; f < 3; f++) {
                unsigned char* copy = malloc(size);
                fmi2Status st;
                memcpy(copy, blob, size);
                copy[k] ^= flips[f];
                unsigned char* sealed = reseal(copy, copy + 96, size - 96, &sealed_size);
                st = try_state(c, sealed, sealed_size);
                expect(st == fmi2OK || st == fmi2Error, "a damaged record");
                if (st == fmi2OK) /* a step from whatever was accepted must return */
                    (void)F.fmi2DoStep(c, 20e-4, 1e-4, 1);
                free(sealed);
                free(copy);
            }
        }
        /* a corrupted envelope: checksum, GUID, version, length */
        for (k = 0; k < 96; k++) {
            unsigned char* copy = malloc(size);
            memcpy(copy, blob, size);
            copy[k] ^= 0x21;
            fmi2Status st = try_state(c, copy, size);
            expect(st == fmi2Error || (k >= 12 && k < 16) || (k >= 32 + strlen(guid) + 1),
                   "a damaged envelope");
            free(copy);
        }
        expect_status(try_state(c, blob, size), fmi2OK, "the intact state again");
        expect_status(F.fmi2DoStep(c, 20e-4, 1e-4, 1), fmi2OK, "a step after it");
        free(blob);
        expect_status(F.fmi2Reset(c), fmi2OK, "reset with a state kept");
        expect_status(F.fmi2SetFMUstate(c, kept), fmi2OK, "a state kept over reset");
    }
    if (has_string) { /* a NULL String in Step Mode: the fixed parameter's refusal */
        const char* none = NULL;
        expect_status(F.fmi2SetString(c, &vr_string, 1, &none), fmi2Error,
                      "setString: NULL after initialization");
    }
    expect_status(F.fmi2Terminate(c), fmi2OK, "terminate");
    expect_status(F.fmi2Terminate(c), fmi2Error, "terminate twice");
    if (has_string) {
        const char* none = NULL;
        expect_status(F.fmi2SetString(c, &vr_string, 1, &none), fmi2Error,
                      "setString: NULL after terminate");
    }
    x = 0.0;
    /* nothing is set after terminate (the library refuses it: reset first) */
    expect_status(F.fmi2SetReal(c, &vr_input, 1, &x), fmi2Error, "an input after terminate");
    expect_status(F.fmi2SetReal(c, &vr_param, 1, &x), fmi2Error, "a parameter after terminate");
    expect_status(F.fmi2DoStep(c, 21e-4, 1e-4, 1), fmi2Error, "a step after terminate");
    F.fmi2FreeInstance(c); /* with its states: none leaks */

    /* ---------------------------------------------------------------- many instances */
    {
        fmi2Component many[8];
        for (int k = 0; k < 8; k++) many[k] = instantiate();
        for (int k = 0; k < 8; k += 2) F.fmi2FreeInstance(many[k]);
        for (int k = 1; k < 8; k += 2) {
            expect(initialize(many[k]), "initialize one of many");
            expect_status(F.fmi2DoStep(many[k], 0.0, 1e-4, 1), fmi2OK, "step one of many");
            F.fmi2FreeInstance(many[k]);
        }
    }
    printf("cases %d failures %d logged %d\n", cases, failures, logged);
    return failures != 0;
}
