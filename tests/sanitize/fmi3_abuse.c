/*
 * fmi3_abuse.c - bad calls to an FMI 3.0 drive-rattle FMU's binary, for the build under
 * AddressSanitizer and UndefinedBehaviorSanitizer (tests/sanitize/test_fmi3_sanitizers.py):
 * instantiation arguments that are not this FMU's, NULL pointers and arrays, nValues that do
 * not match, types the FMU lacks, Enumerations beyond 32 bits, the independent variable set,
 * calls out of order, FMU states that are foreign, misaddressed, truncated, corrupted or
 * serialized into buffers of every size around the right one.  Every call must return, with
 * the status expected; a sanitizer report ends the run (halt_on_error) and fails the test.
 *
 * Usage: fmi3_abuse BINARY RESOURCES TOKEN UNPACKED_ROOT VR_FLOAT_PARAMETER VR_INPUT VR_TIME
 *                   VR_ENUMERATION|- VR_STRING|-
 * Prints "cases N failures F"; exit code 0 when no expectation failed.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3FunctionTypes.h"

#define API(X)                                                                                 \
    X(fmi3InstantiateCoSimulation) X(fmi3InstantiateModelExchange) X(fmi3FreeInstance)        \
    X(fmi3SetDebugLogging) X(fmi3EnterInitializationMode) X(fmi3ExitInitializationMode)       \
    X(fmi3Terminate) X(fmi3Reset) X(fmi3GetFloat64) X(fmi3SetFloat64) X(fmi3GetInt64)          \
    X(fmi3SetInt64) X(fmi3GetInt32) X(fmi3GetBoolean) X(fmi3SetBoolean) X(fmi3GetString)      \
    X(fmi3SetString) X(fmi3GetFloat32) X(fmi3SetUInt64) X(fmi3GetBinary) X(fmi3GetClock)        \
    X(fmi3DoStep) X(fmi3GetFMUState) X(fmi3SetFMUState) X(fmi3FreeFMUState)                    \
    X(fmi3SerializedFMUStateSize) X(fmi3SerializeFMUState) X(fmi3DeserializeFMUState)          \
    X(fmi3EnterEventMode) X(fmi3UpdateDiscreteStates) X(fmi3GetDirectionalDerivative)          \
    X(fmi3SetTime)

static struct {
#define MEMBER(name) name##TYPE* name;
    API(MEMBER)
#undef MEMBER
} F;

static int cases, failures;

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                        fmi3String message)
{
    (void)env, (void)status;
    if (category == NULL || message == NULL || message[0] == '\0') {
        printf("FAIL: a message without category or text\n");
        failures++;
    }
}

static void expect(int got, int want, const char* what, int line)
{
    cases++;
    if (got != want) {
        printf("FAIL line %d: %s returned %d, expected %d\n", line, what, got, want);
        failures++;
    }
}
#define EXPECT(call, want) expect((int)(call), (want), #call, __LINE__)

static fmi3Instance instantiate(const char* name, const char* token, const char* path,
                                fmi3Boolean event_mode, size_t n_required)
{
    static const fmi3ValueReference required[1] = {0};
    return F.fmi3InstantiateCoSimulation(name, token, path, fmi3False, fmi3False, event_mode,
                                         fmi3False, n_required ? required : NULL, n_required,
                                         NULL, log_message, NULL);
}

int main(int argc, char** argv)
{
    void* lib;
    const char *token, *resources, *root;
    fmi3ValueReference vr_param, vr_input, vr_time, vr_enum = 0, vr_string = 0;
    int has_enum, has_string;
    fmi3Instance c, other;
    fmi3FMUState state = NULL, state2 = NULL;
    double value = 0.0, values[4];
    fmi3Int64 codes[2];
    fmi3Boolean flags[3];
    fmi3String text[2];
    size_t size = 0;
    unsigned char* blob;
    char path[4096];
    if (argc != 10) {
        fprintf(stderr, "usage: %s BINARY RESOURCES TOKEN ROOT VR_PARAM VR_INPUT VR_TIME VR_ENUM "
                "VR_STRING\n", argv[0]);
        return 2;
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "%s\n", dlerror());
        return 2;
    }
#define LOAD(name)                                                                             \
    {                                                                                          \
        void* s = dlsym(lib, #name);                                                           \
        if (s == NULL) return 2;                                                               \
        memcpy(&F.name, &s, sizeof s);                                                         \
    }
    API(LOAD)
#undef LOAD
    resources = argv[2];
    token = argv[3];
    root = argv[4];
    vr_param = (fmi3ValueReference)strtoul(argv[5], NULL, 10);
    vr_input = (fmi3ValueReference)strtoul(argv[6], NULL, 10);
    vr_time = (fmi3ValueReference)strtoul(argv[7], NULL, 10);
    has_enum = strcmp(argv[8], "-") != 0;
    has_string = strcmp(argv[9], "-") != 0;
    if (has_enum) vr_enum = (fmi3ValueReference)strtoul(argv[8], NULL, 10);
    if (has_string) vr_string = (fmi3ValueReference)strtoul(argv[9], NULL, 10);

    /* ---------------------------------------------------------------- instantiation */
    EXPECT(instantiate(NULL, token, resources, fmi3False, 0) == NULL, 1);
    EXPECT(instantiate(" \t", token, resources, fmi3False, 0) == NULL, 1);
    EXPECT(instantiate("\xff\xfe", token, resources, fmi3False, 0) == NULL, 1);
    EXPECT(instantiate("x", NULL, resources, fmi3False, 0) == NULL, 1);
    EXPECT(instantiate("x", "{0}", resources, fmi3False, 0) == NULL, 1);
    EXPECT(instantiate("x", token, resources, fmi3True, 0) == NULL, 1);
    EXPECT(instantiate("x", token, resources, fmi3False, 1) == NULL, 1);
    EXPECT(instantiate("x", token, "", fmi3False, 0) == NULL, 1);
    EXPECT(instantiate("x", token, "r", fmi3False, 0) == NULL, 1);
    EXPECT(instantiate("x", token, "file:///%00", fmi3False, 0) == NULL, 1);
    EXPECT(instantiate("x", token, "file://host/x", fmi3False, 0) == NULL, 1);
    EXPECT(instantiate("x", token, root, fmi3False, 0) == NULL, 1);
    snprintf(path, sizeof path, "%s/no such folder/", root);
    EXPECT(instantiate("x", token, path, fmi3False, 0) == NULL, 1);
    EXPECT(F.fmi3InstantiateModelExchange("x", token, resources, fmi3False, fmi3False, NULL,
                                          log_message) == NULL, 1);
    other = instantiate("null resources", token, NULL, fmi3False, 0);
    EXPECT(other != NULL, 1);

    c = instantiate("abuse", token, resources, fmi3False, 0);
    if (c == NULL) {
        printf("FAIL: instantiate\n");
        return 1;
    }
    /* ---------------------------------------------------------------- values */
    EXPECT(F.fmi3GetFloat64(c, NULL, 1, values, 1), fmi3Error);
    EXPECT(F.fmi3GetFloat64(c, &vr_param, 1, NULL, 1), fmi3Error);
    EXPECT(F.fmi3GetFloat64(c, &vr_param, 1, values, 2), fmi3Error);
    EXPECT(F.fmi3GetFloat64(c, NULL, 0, NULL, 0), fmi3OK);
    {
        fmi3ValueReference vrs[4] = {vr_time, vr_param, 0xFFFFFFFFu, vr_time};
        EXPECT(F.fmi3GetFloat64(c, vrs, 4, values, 4), fmi3Error);
        EXPECT(F.fmi3SetFloat64(c, vrs, 4, values, 4), fmi3Error);
        vrs[2] = vr_input;
        EXPECT(F.fmi3GetFloat64(c, vrs, 4, values, 4), fmi3OK);
    }
    value = NAN;
    EXPECT(F.fmi3SetFloat64(c, &vr_input, 1, &value, 1), fmi3OK); /* checked at the step */
    value = 0.0;
    EXPECT(F.fmi3SetFloat64(c, &vr_input, 1, &value, 1), fmi3OK);
    EXPECT(F.fmi3GetFloat32(c, &vr_param, 1, (fmi3Float32*)values, 1), fmi3Error);
    EXPECT(F.fmi3SetUInt64(c, &vr_param, 1, (fmi3UInt64*)values, 1), fmi3Error);
    EXPECT(F.fmi3GetBinary(c, &vr_param, 1, &size, (fmi3Binary*)values, 1), fmi3Error);
    EXPECT(F.fmi3GetClock(c, &vr_param, 1, flags), fmi3Error);
    EXPECT(F.fmi3GetInt64(c, &vr_param, 1, codes, 1), fmi3Error);
    EXPECT(F.fmi3GetBoolean(c, &vr_param, 1, flags, 1), fmi3Error);
    if (has_enum) {
        codes[0] = INT64_MAX;
        EXPECT(F.fmi3SetInt64(c, &vr_enum, 1, codes, 1), fmi3Error);
        codes[0] = INT64_MIN;
        EXPECT(F.fmi3SetInt64(c, &vr_enum, 1, codes, 1), fmi3Error);
        EXPECT(F.fmi3GetInt32(c, &vr_enum, 1, (fmi3Int32*)codes, 1), fmi3Error);
        EXPECT(F.fmi3GetInt64(c, &vr_enum, 1, codes, 1), fmi3OK);
        EXPECT(F.fmi3SetInt64(c, &vr_enum, 1, codes, 1), fmi3OK);
    }
    if (has_string) {
        text[0] = "\xc3\x28";
        EXPECT(F.fmi3SetString(c, &vr_string, 1, text, 1), fmi3Error);
        text[0] = NULL;
        EXPECT(F.fmi3SetString(c, &vr_string, 1, text, 1), fmi3Error);
        EXPECT(F.fmi3GetString(c, &vr_string, 1, text, 1), fmi3OK);
    }
    {
        const fmi3String categories[2] = {"logAll", NULL};
        EXPECT(F.fmi3SetDebugLogging(c, fmi3True, 2, categories), fmi3Error);
        EXPECT(F.fmi3SetDebugLogging(c, fmi3True, 1, NULL), fmi3Error);
        EXPECT(F.fmi3SetDebugLogging(c, fmi3True, 1, categories), fmi3OK);
        EXPECT(F.fmi3SetDebugLogging(c, fmi3False, 0, NULL), fmi3OK);
    }
    /* ---------------------------------------------------------------- order of calls */
    EXPECT(F.fmi3DoStep(c, 0.0, 1e-4, fmi3True, &flags[0], &flags[1], &flags[2], &value),
           fmi3Error);
    EXPECT(F.fmi3ExitInitializationMode(c), fmi3Error);
    EXPECT(F.fmi3EnterEventMode(c), fmi3Error);
    EXPECT(F.fmi3UpdateDiscreteStates(c, NULL, NULL, NULL, NULL, NULL, NULL), fmi3Error);
    EXPECT(F.fmi3GetDirectionalDerivative(c, NULL, 0, NULL, 0, NULL, 0, NULL, 0), fmi3Error);
    EXPECT(F.fmi3SetTime(c, 0.0), fmi3Error);
    EXPECT(F.fmi3EnterInitializationMode(c, fmi3False, 0.0, NAN, fmi3False, 0.0), fmi3Error);
    EXPECT(F.fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0), fmi3OK);
    EXPECT(F.fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0), fmi3Error);
    EXPECT(F.fmi3ExitInitializationMode(c), fmi3OK);
    EXPECT(F.fmi3DoStep(c, 0.0, 1e-4, fmi3True, NULL, &flags[1], &flags[2], &value), fmi3Error);
    EXPECT(F.fmi3DoStep(c, 0.0, -1.0, fmi3True, &flags[0], &flags[1], &flags[2], &value),
           fmi3Error);
    EXPECT(F.fmi3DoStep(c, 0.0, 1e-4, fmi3True, &flags[0], &flags[1], &flags[2], &value),
           fmi3OK);
    if (has_string) { /* a NULL String in Step Mode: the fixed parameter's refusal */
        text[0] = NULL;
        EXPECT(F.fmi3SetString(c, &vr_string, 1, text, 1), fmi3Error);
    }
    /* ---------------------------------------------------------------- FMU states */
    EXPECT(F.fmi3GetFMUState(c, NULL), fmi3Error);
    EXPECT(F.fmi3GetFMUState(c, &state), fmi3OK);
    EXPECT(F.fmi3GetFMUState(c, (fmi3FMUState*)state), fmi3Error); /* the state, not &state */
    EXPECT(F.fmi3FreeFMUState(c, (fmi3FMUState*)state), fmi3Error);
    EXPECT(F.fmi3GetFMUState(c, &state), fmi3OK); /* reused */
    EXPECT(F.fmi3SerializedFMUStateSize(c, state, NULL), fmi3Error);
    EXPECT(F.fmi3SerializedFMUStateSize(c, NULL, &size), fmi3Error);
    EXPECT(F.fmi3SerializedFMUStateSize(c, state, &size), fmi3OK);
    blob = malloc(size + 64);
    for (size_t n = 0; n < size + 64; n += (n < 100 || n + 100 > size ? 1 : 97)) {
        int fits = n >= size;
        memset(blob, 0xA5, size + 64);
        EXPECT(F.fmi3SerializeFMUState(c, state, blob, n), fits ? fmi3OK : fmi3Error);
        if (fits) EXPECT(F.fmi3DeserializeFMUState(c, blob, n, &state2), fmi3OK);
    }
    EXPECT(F.fmi3SerializeFMUState(c, state, blob, size), fmi3OK);
    for (size_t n = 0; n < size; n += (n < 200 ? 1 : 53)) /* truncated */
        EXPECT(F.fmi3DeserializeFMUState(c, blob, n, &state2), fmi3Error);
    for (size_t k = 0; k < size; k += 7) { /* one bit flipped anywhere: it must return */
        blob[k] ^= 0x10;
        EXPECT(F.fmi3DeserializeFMUState(c, blob, size, &state2) <= fmi3Error, 1);
        blob[k] ^= 0x10;
    }
    EXPECT(F.fmi3DeserializeFMUState(c, blob, size, (fmi3FMUState*)state), fmi3Error);
    EXPECT(F.fmi3DeserializeFMUState(c, NULL, size, &state2), fmi3Error);
    EXPECT(F.fmi3SetFMUState(c, state2), fmi3OK);
    EXPECT(F.fmi3SetFMUState(c, NULL), fmi3Error);
    EXPECT(F.fmi3SetFMUState(c, (fmi3FMUState)blob), fmi3Error); /* not a state */
    EXPECT(F.fmi3SetFMUState(other, state), fmi3OK);              /* another instance's */
    EXPECT(F.fmi3FreeFMUState(c, NULL), fmi3OK);
    EXPECT(F.fmi3FreeFMUState(c, &state2), fmi3OK);
    EXPECT(F.fmi3GetFloat64(c, &vr_time, 1, &value, 1), fmi3OK);
    /* ---------------------------------------------------------------- the end */
    EXPECT(F.fmi3Terminate(c), fmi3OK);
    EXPECT(F.fmi3SetFloat64(c, &vr_input, 1, &value, 1), fmi3Error);
    if (has_string) {
        text[0] = NULL;
        EXPECT(F.fmi3SetString(c, &vr_string, 1, text, 1), fmi3Error);
    }
    EXPECT(F.fmi3Reset(c), fmi3OK);
    F.fmi3FreeInstance(c); /* with its live state */
    F.fmi3FreeInstance(other);
    F.fmi3FreeInstance(NULL);
    free(blob);
    printf("cases %d failures %d\n", cases, failures);
    return failures != 0;
}
