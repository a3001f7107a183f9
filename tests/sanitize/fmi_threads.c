/*
 * fmi_threads.c - instances of a native drive-rattle FMU's binary created, stepped, saved,
 * restored and freed by several threads at once, for the build under ThreadSanitizer
 * (tests/sanitize/test_native_sanitizers.py): the model library keeps no global state, so the
 * threads must not race, and each thread's outputs must equal a sequential run's bit for bit.
 *
 * Usage: fmi_threads BINARY RESOURCES_URI GUID THREADS ROUNDS STEPS VR_INPUT INPUT VR_OUTPUT
 *                    [VR_STRING STRING]
 * Each thread, ROUNDS times: instantiate, (set the String parameter,) initialize with the Real
 * input at INPUT, step STEPS times by 1e-4 s, serialize its state half way and restore it into
 * a second instance that finishes the run too, read the Real output, free both.  Prints the
 * output's bits per run; exit code 0 when every run gave the sequential run's.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"

#define API(X)                                                                                 \
    X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment)                              \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2GetReal) X(fmi2SetReal) \
    X(fmi2SetString) X(fmi2DoStep) X(fmi2GetFMUstate) X(fmi2FreeFMUstate)                      \
    X(fmi2SerializedFMUstateSize) X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate)          \
    X(fmi2SetFMUstate)

static struct {
#define MEMBER(name) name##TYPE* name;
    API(MEMBER)
#undef MEMBER
} F;

static const char* resources;
static const char* guid;
static const char* string_value;
static fmi2ValueReference vr_input, vr_output, vr_string;
static double input;
static int rounds, steps;

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    char text[2048];
    va_list ap;
    (void)env, (void)category;
    va_start(ap, message);
    vsnprintf(text, sizeof text, message, ap);
    va_end(ap);
    fprintf(stderr, "[%d] %s: %s\n", (int)status, instance, text);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static fmi2Component start(const char* name)
{
    fmi2Component c = F.fmi2Instantiate(name, fmi2CoSimulation, guid, resources, &callbacks,
                                        fmi2False, fmi2False);
    if (c == NULL) return NULL;
    if ((string_value != NULL && F.fmi2SetString(c, &vr_string, 1, &string_value) != fmi2OK)
        || F.fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK
        || F.fmi2EnterInitializationMode(c) != fmi2OK
        || F.fmi2SetReal(c, &vr_input, 1, &input) != fmi2OK
        || F.fmi2ExitInitializationMode(c) != fmi2OK) {
        F.fmi2FreeInstance(c);
        return NULL;
    }
    return c;
}

static int step(fmi2Component c, int k)
{
    fmi2Status st = F.fmi2DoStep(c, k * 1e-4, 1e-4, fmi2True);
    return st == fmi2OK || st == fmi2Warning;
}

/* One run: the output's bits at the end, or 1 (never a double's bits here) on failure. */
static uint64_t run(const char* name)
{
    fmi2Component c = start(name), d = NULL;
    fmi2FMUstate state = NULL, copy = NULL;
    unsigned char* blob = NULL;
    size_t size = 0;
    double out[2];
    uint64_t bits[2];
    int ok = c != NULL;
    for (int k = 0; ok && k < steps / 2; k++) ok = step(c, k);
    ok = ok && F.fmi2GetFMUstate(c, &state) == fmi2OK
         && F.fmi2SerializedFMUstateSize(c, state, &size) == fmi2OK
         && (blob = malloc(size)) != NULL
         && F.fmi2SerializeFMUstate(c, state, (fmi2Byte*)blob, size) == fmi2OK
         && (d = start(name)) != NULL
         && F.fmi2DeSerializeFMUstate(d, (fmi2Byte*)blob, size, &copy) == fmi2OK
         && F.fmi2SetFMUstate(d, copy) == fmi2OK;
    for (int k = steps / 2; ok && k < steps; k++) ok = step(c, k) && step(d, k);
    ok = ok && F.fmi2GetReal(c, &vr_output, 1, &out[0]) == fmi2OK
         && F.fmi2GetReal(d, &vr_output, 1, &out[1]) == fmi2OK;
    free(blob);
    if (c != NULL) F.fmi2FreeInstance(c); /* frees its state */
    if (d != NULL) F.fmi2FreeInstance(d);
    if (!ok) return 1;
    memcpy(&bits[0], &out[0], 8);
    memcpy(&bits[1], &out[1], 8);
    return bits[0] == bits[1] ? bits[0] : 1;
}

typedef struct {
    int index;
    uint64_t result[64];
} Job;

static void* worker(void* arg)
{
    Job* job = arg;
    char name[32];
    snprintf(name, sizeof name, "thread %d", job->index);
    for (int r = 0; r < rounds && r < 64; r++) job->result[r] = run(name);
    return NULL;
}

int main(int argc, char** argv)
{
    void* lib;
    int threads;
    uint64_t expected;
    int failures = 0;
    Job jobs[16];
    pthread_t ids[16];
    if (argc != 10 && argc != 12) {
        fprintf(stderr, "usage: %s BINARY RESOURCES_URI GUID THREADS ROUNDS STEPS VR_INPUT INPUT "
                        "VR_OUTPUT [VR_STRING STRING]\n", argv[0]);
        return 2;
    }
    resources = argv[2];
    guid = argv[3];
    threads = atoi(argv[4]);
    rounds = atoi(argv[5]);
    steps = atoi(argv[6]);
    vr_input = (fmi2ValueReference)strtoul(argv[7], NULL, 10);
    input = strtod(argv[8], NULL);
    vr_output = (fmi2ValueReference)strtoul(argv[9], NULL, 10);
    if (argc == 12) {
        vr_string = (fmi2ValueReference)strtoul(argv[10], NULL, 10);
        string_value = argv[11];
    }
    if (threads < 1 || threads > 16 || rounds < 1 || rounds > 64 || steps < 2) return 2;
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "cannot load %s: %s\n", argv[1], dlerror());
        return 2;
    }
#define LOAD(name)                                                                             \
    {                                                                                          \
        void* p = dlsym(lib, #name);                                                           \
        if (p == NULL) return 2;                                                               \
        memcpy(&F.name, &p, sizeof p);                                                         \
    }
    API(LOAD)
#undef LOAD
    expected = run("sequential");
    if (expected == 1) {
        fprintf(stderr, "the sequential run failed\n");
        return 1;
    }
    for (int t = 0; t < threads; t++) {
        jobs[t].index = t;
        if (pthread_create(&ids[t], NULL, worker, &jobs[t]) != 0) return 2;
    }
    for (int t = 0; t < threads; t++) pthread_join(ids[t], NULL);
    for (int t = 0; t < threads; t++)
        for (int r = 0; r < rounds; r++) {
            printf("thread %d round %d: %016llx\n", t, r, (unsigned long long)jobs[t].result[r]);
            if (jobs[t].result[r] != expected) failures++;
        }
    printf("sequential: %016llx, runs differing: %d\n", (unsigned long long)expected, failures);
    return failures != 0;
}
