/*
 * fmu_host.c - a minimal native co-simulation host, as system-simulation tools are, for Linux
 * and Windows, for FMI 2.0 and FMI 3.0: it loads an FMU's binary (dlopen / LoadLibraryW),
 * drives it with inputs read from a CSV file and writes its outputs to another CSV file.  C99
 * with the standard's headers (fmi2FunctionTypes.h or fmi3FunctionTypes.h, shipped with fmpy
 * and inside every native FMU's sources/).  The standard is chosen when it is compiled:
 * FMU_HOST_FMI3 defined, FMI 3.0 (the headers of FMI 3.0 on the include path); otherwise FMI
 * 2.0.  What differs between the standards is the adapter below (the calls and their
 * arguments); the files, the call sequence and the checks are the same.
 *
 * No Python anywhere: on Linux it fails (exit code 3) if a libpython is mapped into the
 * process at the end of the run, unless the environment variable FMU_HOST_ALLOW_PYTHON is set
 * (a pythonfmu FMU, which needs libpython preloaded: docs/native_host.md).  Used by
 * tests/faces/test_hosts.py (docs/tools.md, "Native (C/C++) hosts"),
 * tests/adversarial/test_native_host.py, tests/fmu/test_platforms.py and, built with the
 * sanitizers, tests/sanitize (it frees what it allocates: a leak reported there is the FMU's).
 *
 * The FMU library is never unloaded: pythonfmu keeps the embedded interpreter in process-wide
 * state of its library and tears it down from library destructors, which has been seen to
 * corrupt the heap at an unload (docs/fmi.md, "How it is built"); the process exit releases it.
 *
 * Usage:
 *   fmu_host BINARY RESOURCES TOKEN INPUTS_CSV OUTPUTS_CSV INPUT_VRS OUTPUT...
 *
 *   BINARY      the FMU binary, e.g. <unpacked>/binaries/linux64/GearMeshRattle.so,
 *               <unpacked>/binaries/x86_64-linux/GearMeshRattle.so or
 *               <unpacked>\binaries\win64\GearMeshRattle.dll (UTF-8)
 *   RESOURCES   FMI 2.0's fmuResourceLocation: a file:// URI of <unpacked>/resources
 *               (percent-encoded) or its absolute path; FMI 3.0's resourcePath: the absolute
 *               path of <unpacked>/resources with a trailing separator; "-" for NULL
 *   TOKEN       the guid (FMI 2.0) or instantiationToken (FMI 3.0) of modelDescription.xml
 *   INPUTS_CSV  "time,<input names...>", then one row per communication point t_0 < ... <
 *               t_N: the time and the input values to hold over the step from t_k to t_{k+1}
 *               (full-precision decimals, e.g. Python repr()); the last row only defines t_N
 *   OUTPUTS_CSV written: "time,<output names...>", one row per communication point t_0 (after
 *               initialization) to t_N; reals "%.17g" (exact round trip), integers "%d"
 *   INPUT_VRS   comma-separated value references of the real inputs, in column order
 *   OUTPUT      R:<vr>:<name> or F:<vr>:<name> (a real: fmi2GetReal, fmi3GetFloat64) or
 *               I:<vr>:<name> (an integer: fmi2GetInteger, fmi3GetInt32), per column
 *
 * Call sequence: instantiate (co-simulation; visible, loggingOn and FMI 3.0's eventModeUsed
 * and earlyReturnAllowed false, no intermediate variables), enter initialization at t_0 (FMI
 * 2.0: fmi2SetupExperiment, then fmi2EnterInitializationMode), set the reals of row 0, exit
 * initialization, record t_0; for k = 0 .. N-1: set the reals of row k, do a step from t_k to
 * t_{k+1} (noSetFMUStatePriorToCurrentPoint true), record t_{k+1}; terminate, free.  Anything
 * but OK, or (FMI 3.0) a step that reports an event, a request to terminate, an early return
 * or a last successful time other than t_{k+1}, ends the run with a message on stderr and exit
 * code 1 (2 for a usage or input-file error).  The FMU's log messages go to stderr as
 * "[<status>] <category>: <text>".
 */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L
#endif
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <windows.h>
#else
#include <dlfcn.h>
#endif

#if defined(FMU_HOST_FMI3)
#include "fmi3FunctionTypes.h"
typedef fmi3ValueReference ValueReference;
typedef fmi3Int32 Integer;
#else
#include "fmi2FunctionTypes.h"
typedef fmi2ValueReference ValueReference;
typedef fmi2Integer Integer;
#endif

static const char* status_name(int status)
{
    /* fmi2Status and fmi3Status share their first five values; Pending is FMI 2.0's */
    static const char* names[] = {"OK", "Warning", "Discard", "Error", "Fatal", "Pending"};
    return status >= 0 && status <= 5 ? names[status] : "unknown status";
}

static int failed(int status, const char* call, double t)
{
    if (status == 0) return 0; /* fmi2OK, fmi3OK */
    if (isnan(t))
        fprintf(stderr, "fmu_host: %s returned %s\n", call, status_name(status));
    else
        fprintf(stderr, "fmu_host: %s at t = %.17g s returned %s\n", call, t, status_name(status));
    return 1;
}

/* ------------------------------------------------------------------ the adapters
 * One standard's calls behind the host's: load its functions, instantiate, enter
 * initialization at t0, set and get values, step, terminate, free.  Each returns 0 on OK
 * and 1 after a message on stderr. */
typedef void* Instance;

#if defined(FMU_HOST_FMI3)
#define STANDARD "3.0"
#define API(X)                                                                                 \
    X(fmi3GetVersion) X(fmi3InstantiateCoSimulation) X(fmi3FreeInstance)                       \
    X(fmi3EnterInitializationMode) X(fmi3ExitInitializationMode) X(fmi3Terminate)              \
    X(fmi3GetFloat64) X(fmi3GetInt32) X(fmi3SetFloat64) X(fmi3DoStep)
#define GET_VERSION fmi3GetVersion
#define INSTANTIATE "fmi3InstantiateCoSimulation"
#else
#define STANDARD "2.0"
#define API(X)                                                                                 \
    X(fmi2GetVersion) X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment)            \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2Terminate)              \
    X(fmi2GetReal) X(fmi2GetInteger) X(fmi2SetReal) X(fmi2DoStep)
#define GET_VERSION fmi2GetVersion
#define INSTANTIATE "fmi2Instantiate"
#endif

static struct {
#define MEMBER(name) name##TYPE* name;
    API(MEMBER)
#undef MEMBER
} api;

#if defined(FMU_HOST_FMI3)
static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                        fmi3String message)
{
    (void)env;
    fprintf(stderr, "[%s] %s: %s\n", status_name(status), category ? category : "",
            message ? message : "");
    fflush(stderr);
}

static Instance instantiate(const char* token, const char* resources)
{
    return api.fmi3InstantiateCoSimulation("fmu_host", token, resources, fmi3False, fmi3False,
                                           fmi3False, fmi3False, NULL, 0, NULL, log_message,
                                           NULL);
}

static int enter(Instance c, double t0)
{
    return failed(api.fmi3EnterInitializationMode(c, fmi3False, 0.0, t0, fmi3False, 0.0),
                  "fmi3EnterInitializationMode", NAN);
}

static int set_reals(Instance c, const ValueReference* vr, size_t n, const double* v, double t)
{
    return failed(api.fmi3SetFloat64(c, vr, n, v, n), "fmi3SetFloat64", t);
}

static int get_reals(Instance c, const ValueReference* vr, size_t n, double* v, double t)
{
    return failed(api.fmi3GetFloat64(c, vr, n, v, n), "fmi3GetFloat64", t);
}

static int get_integers(Instance c, const ValueReference* vr, size_t n, Integer* v, double t)
{
    return failed(api.fmi3GetInt32(c, vr, n, v, n), "fmi3GetInt32", t);
}

static int do_step(Instance c, double t, double h)
{
    double last = NAN;
    fmi3Boolean event = fmi3True, terminate = fmi3True, early = fmi3True;
    if (failed(api.fmi3DoStep(c, t, h, fmi3True, &event, &terminate, &early, &last),
               "fmi3DoStep", t))
        return 1;
    if (event || terminate || early || last != t + h) {
        fprintf(stderr, "fmu_host: fmi3DoStep at t = %.17g s reported event %d, terminate %d, "
                "early return %d, last successful time %.17g\n", t, (int)event, (int)terminate,
                (int)early, last);
        return 1;
    }
    return 0;
}

static int exit_initialization(Instance c)
{
    return failed(api.fmi3ExitInitializationMode(c), "fmi3ExitInitializationMode", NAN);
}

static int terminate(Instance c) { return failed(api.fmi3Terminate(c), "fmi3Terminate", NAN); }
static void free_instance(Instance c) { api.fmi3FreeInstance(c); }
#else
static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    va_list ap;
    (void)env;
    (void)instance;
    fprintf(stderr, "[%s] %s: ", status_name(status), category ? category : "");
    va_start(ap, message);
    vfprintf(stderr, message ? message : "", ap);
    va_end(ap);
    fputc('\n', stderr);
    fflush(stderr);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static Instance instantiate(const char* token, const char* resources)
{
    return api.fmi2Instantiate("fmu_host", fmi2CoSimulation, token, resources, &callbacks,
                               fmi2False, fmi2False);
}

static int enter(Instance c, double t0)
{
    return failed(api.fmi2SetupExperiment(c, 0, 0.0, t0, 0, 0.0), "fmi2SetupExperiment", NAN)
           || failed(api.fmi2EnterInitializationMode(c), "fmi2EnterInitializationMode", NAN);
}

static int set_reals(Instance c, const ValueReference* vr, size_t n, const double* v, double t)
{
    return failed(api.fmi2SetReal(c, vr, n, v), "fmi2SetReal", t);
}

static int get_reals(Instance c, const ValueReference* vr, size_t n, double* v, double t)
{
    return failed(api.fmi2GetReal(c, vr, n, v), "fmi2GetReal", t);
}

static int get_integers(Instance c, const ValueReference* vr, size_t n, Integer* v, double t)
{
    return failed(api.fmi2GetInteger(c, vr, n, v), "fmi2GetInteger", t);
}

static int do_step(Instance c, double t, double h)
{
    return failed(api.fmi2DoStep(c, t, h, fmi2True), "fmi2DoStep", t);
}

static int exit_initialization(Instance c)
{
    return failed(api.fmi2ExitInitializationMode(c), "fmi2ExitInitializationMode", NAN);
}

static int terminate(Instance c) { return failed(api.fmi2Terminate(c), "fmi2Terminate", NAN); }
static void free_instance(Instance c) { api.fmi2FreeInstance(c); }
#endif

static void* xrealloc(void* p, size_t size)
{
    void* q = realloc(p, size ? size : 1);
    if (q == NULL) {
        fprintf(stderr, "fmu_host: out of memory\n");
        exit(2);
    }
    return q;
}

static int parse_double(const char* text, double* out)
{
    char* end;
    errno = 0;
    *out = strtod(text, &end);
    return end == text || *end != '\0' || (errno == ERANGE && isinf(*out));
}

static int parse_vr(const char* text, char** end, ValueReference* out)
{
    unsigned long v;
    if (*text < '0' || *text > '9') return 1;
    errno = 0;
    v = strtoul(text, end, 10);
    if (errno != 0 || v > 0xFFFFFFFFUL) return 1;
    *out = (ValueReference)v;
    return 0;
}

static size_t split(char* line, char** fields, size_t max_fields)
{
    size_t n = 0;
    char* p = line;
    for (;;) {
        char* comma = strchr(p, ',');
        if (n <= max_fields) fields[n] = p;
        n++;
        if (comma == NULL) break;
        *comma = '\0';
        p = comma + 1;
    }
    return n;
}

static int read_line(FILE* f, char** buf, size_t* cap)
{
    size_t len = 0;
    int c;
    while ((c = fgetc(f)) != EOF && c != '\n') {
        if (len + 2 > *cap) {
            *cap = *cap ? 2 * *cap : 256;
            *buf = xrealloc(*buf, *cap);
        }
        (*buf)[len++] = (char)c;
    }
    if (c == EOF && len == 0) return 0;
    if (*buf == NULL) *buf = xrealloc(NULL, *cap = 256);
    if (len > 0 && (*buf)[len - 1] == '\r') len--;
    (*buf)[len] = '\0';
    return 1;
}

typedef struct {
    size_t n_rows, n_inputs;
    double* time;
    double* values;
} Inputs;

static int read_inputs(const char* path, size_t n_inputs, Inputs* in)
{
    FILE* f = fopen(path, "r");
    char* line = NULL;
    size_t cap = 0, lineno = 1, rows_cap = 0;
    char** fields = xrealloc(NULL, (n_inputs + 2) * sizeof *fields);
    int err = 1;
    memset(in, 0, sizeof *in);
    in->n_inputs = n_inputs;
    if (f == NULL) {
        fprintf(stderr, "fmu_host: cannot open %s: %s\n", path, strerror(errno));
        goto done;
    }
    if (!read_line(f, &line, &cap) || split(line, fields, n_inputs + 1) != n_inputs + 1
        || strcmp(fields[0], "time") != 0) {
        fprintf(stderr, "fmu_host: %s:1: header must be 'time' and %zu input names\n", path,
                n_inputs);
        goto done;
    }
    while (read_line(f, &line, &cap)) {
        lineno++;
        if (line[0] == '\0') continue;
        if (split(line, fields, n_inputs + 1) != n_inputs + 1) {
            fprintf(stderr, "fmu_host: %s:%zu: expected %zu fields\n", path, lineno, n_inputs + 1);
            goto done;
        }
        if (in->n_rows == rows_cap) {
            rows_cap = rows_cap ? 2 * rows_cap : 1024;
            in->time = xrealloc(in->time, rows_cap * sizeof *in->time);
            in->values = xrealloc(in->values, rows_cap * n_inputs * sizeof *in->values);
        }
        for (size_t j = 0; j <= n_inputs; j++) {
            double v;
            if (parse_double(fields[j], &v)) {
                fprintf(stderr, "fmu_host: %s:%zu: field %zu '%s' is not a number\n", path,
                        lineno, j + 1, fields[j]);
                goto done;
            }
            if (j == 0)
                in->time[in->n_rows] = v;
            else
                in->values[in->n_rows * n_inputs + j - 1] = v;
        }
        if (!isfinite(in->time[in->n_rows])
            || (in->n_rows > 0 && !(in->time[in->n_rows] > in->time[in->n_rows - 1]))) {
            fprintf(stderr, "fmu_host: %s:%zu: times must be finite and increasing\n", path,
                    lineno);
            goto done;
        }
        in->n_rows++;
    }
    err = in->n_rows == 0;
    if (err) fprintf(stderr, "fmu_host: %s has no data rows\n", path);
done:
    if (f != NULL) fclose(f);
    free(line);
    free(fields);
    return err;
}

typedef struct {
    size_t n, n_real, n_int;
    char* kind;
    const char** name;
    ValueReference *real_vr, *int_vr;
    double* real;
    Integer* integer;
} Outputs;

static int parse_outputs(int argc, char** argv, Outputs* out)
{
    out->n = (size_t)argc;
    out->n_real = out->n_int = 0;
    out->kind = xrealloc(NULL, out->n);
    out->name = xrealloc(NULL, out->n * sizeof *out->name);
    out->real_vr = xrealloc(NULL, out->n * sizeof *out->real_vr);
    out->int_vr = xrealloc(NULL, out->n * sizeof *out->int_vr);
    out->real = xrealloc(NULL, out->n * sizeof *out->real);
    out->integer = xrealloc(NULL, out->n * sizeof *out->integer);
    for (int i = 0; i < argc; i++) {
        const char* a = argv[i];
        char* end;
        ValueReference vr;
        int real = a[0] == 'R' || a[0] == 'F';
        if ((!real && a[0] != 'I') || a[1] != ':' || parse_vr(a + 2, &end, &vr) || *end != ':'
            || end[1] == '\0') {
            fprintf(stderr, "fmu_host: output '%s' must be R:<vr>:<name>, F:<vr>:<name> or "
                            "I:<vr>:<name>\n", a);
            return 1;
        }
        out->kind[i] = real ? 'R' : 'I';
        out->name[i] = end + 1;
        if (real)
            out->real_vr[out->n_real++] = vr;
        else
            out->int_vr[out->n_int++] = vr;
    }
    return 0;
}

typedef struct {
    Instance c;
    const Outputs* out;
    FILE* csv;
} Run;

static int record(Run* r, double t)
{
    const Outputs* o = r->out;
    size_t ir = 0, ii = 0;
    if ((o->n_real && get_reals(r->c, o->real_vr, o->n_real, o->real, t))
        || (o->n_int && get_integers(r->c, o->int_vr, o->n_int, o->integer, t)))
        return 1;
    fprintf(r->csv, "%.17g", t);
    for (size_t i = 0; i < o->n; i++) {
        if (o->kind[i] == 'R')
            fprintf(r->csv, ",%.17g", o->real[ir++]);
        else
            fprintf(r->csv, ",%d", (int)o->integer[ii++]);
    }
    fputc('\n', r->csv);
    return ferror(r->csv) != 0;
}

static int simulate(Run* r, const Inputs* in, const ValueReference* input_vr)
{
    size_t m = in->n_inputs;
    double t0 = in->time[0];
    if (enter(r->c, t0) || set_reals(r->c, input_vr, m, in->values, t0)
        || exit_initialization(r->c) || record(r, t0))
        return 1;
    for (size_t k = 0; k + 1 < in->n_rows; k++) {
        double t = in->time[k], h = in->time[k + 1] - in->time[k];
        if (set_reals(r->c, input_vr, m, in->values + k * m, t) || do_step(r->c, t, h)
            || record(r, in->time[k + 1]))
            return 1;
    }
    return terminate(r->c);
}

/* ------------------------------------------------------------------ the library */
#if defined(_WIN32)
typedef HMODULE Library;
static Library open_library(const char* path)
{
    wchar_t wide[4096];
    if (MultiByteToWideChar(CP_UTF8, 0, path, -1, wide, 4096) == 0) return NULL;
    return LoadLibraryW(wide);
}
static void* symbol(Library lib, const char* name)
{
    FARPROC f = GetProcAddress(lib, name);
    void* p;
    memcpy(&p, &f, sizeof p);
    return p;
}
static void library_error(const char* path)
{
    fprintf(stderr, "fmu_host: cannot load %s: error %lu\n", path, (unsigned long)GetLastError());
}
#else
typedef void* Library;
static Library open_library(const char* path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void* symbol(Library lib, const char* name) { return dlsym(lib, name); }
static void library_error(const char* path)
{
    fprintf(stderr, "fmu_host: cannot load %s: %s\n", path, dlerror());
}
#endif

/* Linux: 1 if a libpython is mapped into this process. */
static int python_loaded(void)
{
#if defined(__linux__)
    FILE* maps = fopen("/proc/self/maps", "r");
    char line[4096];
    int found = 0;
    if (maps == NULL) return 0;
    while (fgets(line, sizeof line, maps) != NULL)
        if (strstr(line, "libpython") != NULL) found = 1;
    fclose(maps);
    return found;
#else
    return 0;
#endif
}

int main(int argc, char** argv)
{
    Inputs in;
    Outputs out;
    Run run;
    ValueReference* input_vr;
    size_t n_inputs = 0;
    const char* p;
    char* end;
    Library lib;
    int rc;
    if (argc < 8) {
        fprintf(stderr, "usage: %s BINARY RESOURCES TOKEN INPUTS_CSV OUTPUTS_CSV INPUT_VRS "
                        "OUTPUT...\n  OUTPUT: R:<vr>:<name> | F:<vr>:<name> | I:<vr>:<name>\n",
                argv[0]);
        return 2;
    }
    input_vr = xrealloc(NULL, (strlen(argv[6]) / 2 + 1) * sizeof *input_vr);
    for (p = argv[6];; p = end + 1) {
        if (parse_vr(p, &end, &input_vr[n_inputs]) || (*end != ',' && *end != '\0')) {
            fprintf(stderr, "fmu_host: INPUT_VRS '%s' must be comma-separated numbers\n",
                    argv[6]);
            return 2;
        }
        n_inputs++;
        if (*end == '\0') break;
    }
    if (read_inputs(argv[4], n_inputs, &in) || parse_outputs(argc - 7, argv + 7, &out)) return 2;
    lib = open_library(argv[1]);
    if (lib == NULL) {
        library_error(argv[1]);
        return 1;
    }
#define LOAD(name)                                                                             \
    {                                                                                          \
        void* s = symbol(lib, #name);                                                          \
        if (s == NULL) {                                                                       \
            fprintf(stderr, "fmu_host: %s has no symbol %s\n", argv[1], #name);                \
            return 1;                                                                          \
        }                                                                                      \
        memcpy(&api.name, &s, sizeof s);                                                       \
    }
    API(LOAD)
#undef LOAD
    if (strcmp(api.GET_VERSION(), STANDARD) != 0) {
        fprintf(stderr, "fmu_host: the FMU's version is '%s', not " STANDARD "\n",
                api.GET_VERSION());
        return 1;
    }
    run.out = &out;
    run.c = instantiate(argv[3], strcmp(argv[2], "-") == 0 ? NULL : argv[2]);
    if (run.c == NULL) {
        fprintf(stderr, "fmu_host: " INSTANTIATE " returned NULL\n");
        return 1;
    }
    run.csv = fopen(argv[5], "w");
    if (run.csv == NULL) {
        fprintf(stderr, "fmu_host: cannot write %s: %s\n", argv[5], strerror(errno));
        return 2;
    }
    fprintf(run.csv, "time");
    for (size_t i = 0; i < out.n; i++) fprintf(run.csv, ",%s", out.name[i]);
    fputc('\n', run.csv);
    rc = simulate(&run, &in, input_vr);
    free_instance(run.c);
    if (fclose(run.csv) != 0) rc = 1;
    /* everything the host allocated, freed: a leak in a sanitized run is the FMU's */
    free(input_vr);
    free(in.time);
    free(in.values);
    free(out.kind);
    free((void*)out.name);
    free(out.real_vr);
    free(out.int_vr);
    free(out.real);
    free(out.integer);
    if (rc == 0 && getenv("FMU_HOST_ALLOW_PYTHON") == NULL && python_loaded()) {
        fprintf(stderr, "fmu_host: a libpython is loaded in this process\n");
        return 3;
    }
    return rc;
}
