/*
 * fmu3_host.c - a minimal native FMI 3.0 co-simulation host, as system-simulation tools are,
 * for Linux and Windows: it loads an FMU's binary (dlopen / LoadLibraryW), drives it with
 * inputs read from a CSV file and writes its outputs to another CSV file.  C99 with the FMI 3.0
 * headers (fmi3FunctionTypes.h, shipped with fmpy and inside every FMI 3.0 FMU's sources/).
 * The FMI 3.0 counterpart of tests/native/fmu_host.c (the same files, the same call sequence),
 * used by tests/fmi3/test_fmi3_hosts.py.  On Linux it fails (exit code 3) if a libpython is
 * mapped into the process at the end of the run.
 *
 * Usage:
 *   fmu3_host BINARY RESOURCES TOKEN INPUTS_CSV OUTPUTS_CSV INPUT_VRS OUTPUT...
 *
 *   BINARY      the FMU binary, e.g. <unpacked>/binaries/x86_64-linux/GearMeshRattle.so
 *   RESOURCES   resourcePath: the absolute path of <unpacked>/resources with a trailing
 *               separator (FMI 3.0), or "-" for NULL
 *   TOKEN       the instantiationToken attribute of modelDescription.xml
 *   INPUTS_CSV  "time,<input names...>", then one row per communication point t_0 < ... <
 *               t_N: the time and the Float64 inputs to hold over the step from t_k to t_{k+1};
 *               the last row only defines t_N
 *   OUTPUTS_CSV written: "time,<output names...>", one row per communication point t_0 (after
 *               initialization) to t_N; Float64 "%.17g" (exact round trip), Int32 "%d"
 *   INPUT_VRS   comma-separated value references of the Float64 inputs, in column order
 *   OUTPUT      F:<vr>:<name> (fmi3GetFloat64) or I:<vr>:<name> (fmi3GetInt32), per column
 *
 * Call sequence: fmi3InstantiateCoSimulation(visible, loggingOn, eventModeUsed and
 * earlyReturnAllowed false, no intermediate variables), fmi3EnterInitializationMode(start t_0),
 * fmi3SetFloat64(row 0), fmi3ExitInitializationMode, record t_0; for k = 0 .. N-1:
 * fmi3SetFloat64(row k), fmi3DoStep(t_k, t_{k+1} - t_k, true), record t_{k+1};
 * fmi3Terminate, fmi3FreeInstance.  Anything but fmi3OK, or a step that reports an event, a
 * request to terminate, an early return or a last successful time other than t_{k+1}, ends
 * the run with a message on stderr and exit code 1 (2 for a usage or input-file error).  The
 * FMU's log messages go to stderr as "[<status>] <category>: <text>".
 */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L
#endif
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <windows.h>
#else
#include <dlfcn.h>
#endif

#include "fmi3FunctionTypes.h"

#define API(X)                                                                                 \
    X(fmi3GetVersion) X(fmi3InstantiateCoSimulation) X(fmi3FreeInstance)                       \
    X(fmi3EnterInitializationMode) X(fmi3ExitInitializationMode) X(fmi3Terminate)              \
    X(fmi3GetFloat64) X(fmi3GetInt32) X(fmi3SetFloat64) X(fmi3DoStep)

typedef struct {
#define MEMBER(name) name##TYPE* name;
    API(MEMBER)
#undef MEMBER
} Api;

static const char* status_name(int status)
{
    static const char* names[] = {"OK", "Warning", "Discard", "Error", "Fatal"};
    return status >= 0 && status <= 4 ? names[status] : "unknown status";
}

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                        fmi3String message)
{
    (void)env;
    fprintf(stderr, "[%s] %s: %s\n", status_name(status), category ? category : "",
            message ? message : "");
    fflush(stderr);
}

static void* xrealloc(void* p, size_t size)
{
    void* q = realloc(p, size ? size : 1);
    if (q == NULL) {
        fprintf(stderr, "fmu3_host: out of memory\n");
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

static int parse_vr(const char* text, char** end, fmi3ValueReference* out)
{
    unsigned long v;
    if (*text < '0' || *text > '9') return 1;
    errno = 0;
    v = strtoul(text, end, 10);
    if (errno != 0 || v > 0xFFFFFFFFUL) return 1;
    *out = (fmi3ValueReference)v;
    return 0;
}

/* Splits `line` at commas in place; the number of fields (only the first max_fields + 1
 * stored). */
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
        fprintf(stderr, "fmu3_host: cannot open %s: %s\n", path, strerror(errno));
        goto done;
    }
    if (!read_line(f, &line, &cap) || split(line, fields, n_inputs + 1) != n_inputs + 1
        || strcmp(fields[0], "time") != 0) {
        fprintf(stderr, "fmu3_host: %s:1: header must be 'time' and %zu input names\n", path,
                n_inputs);
        goto done;
    }
    while (read_line(f, &line, &cap)) {
        lineno++;
        if (line[0] == '\0') continue;
        if (split(line, fields, n_inputs + 1) != n_inputs + 1) {
            fprintf(stderr, "fmu3_host: %s:%zu: expected %zu fields\n", path, lineno,
                    n_inputs + 1);
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
                fprintf(stderr, "fmu3_host: %s:%zu: field %zu '%s' is not a number\n", path,
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
            fprintf(stderr, "fmu3_host: %s:%zu: times must be finite and increasing\n", path,
                    lineno);
            goto done;
        }
        in->n_rows++;
    }
    err = in->n_rows == 0;
    if (err) fprintf(stderr, "fmu3_host: %s has no data rows\n", path);
done:
    if (f != NULL) fclose(f);
    free(line);
    free(fields);
    return err;
}

typedef struct {
    size_t n, n_float, n_int;
    char* kind;
    const char** name;
    fmi3ValueReference *float_vr, *int_vr;
    double* real;
    fmi3Int32* integer;
} Outputs;

static int parse_outputs(int argc, char** argv, Outputs* out)
{
    out->n = (size_t)argc;
    out->n_float = out->n_int = 0;
    out->kind = xrealloc(NULL, out->n);
    out->name = xrealloc(NULL, out->n * sizeof *out->name);
    out->float_vr = xrealloc(NULL, out->n * sizeof *out->float_vr);
    out->int_vr = xrealloc(NULL, out->n * sizeof *out->int_vr);
    out->real = xrealloc(NULL, out->n * sizeof *out->real);
    out->integer = xrealloc(NULL, out->n * sizeof *out->integer);
    for (int i = 0; i < argc; i++) {
        const char* a = argv[i];
        char* end;
        fmi3ValueReference vr;
        if ((a[0] != 'F' && a[0] != 'I') || a[1] != ':' || parse_vr(a + 2, &end, &vr)
            || *end != ':' || end[1] == '\0') {
            fprintf(stderr, "fmu3_host: output '%s' must be F:<vr>:<name> or I:<vr>:<name>\n",
                    a);
            return 1;
        }
        out->kind[i] = a[0];
        out->name[i] = end + 1;
        if (a[0] == 'F')
            out->float_vr[out->n_float++] = vr;
        else
            out->int_vr[out->n_int++] = vr;
    }
    return 0;
}

typedef struct {
    const Api* api;
    fmi3Instance c;
    const Outputs* out;
    FILE* csv;
} Run;

static int failed(fmi3Status status, const char* call, double t)
{
    if (status == fmi3OK) return 0;
    if (isnan(t))
        fprintf(stderr, "fmu3_host: %s returned %s\n", call, status_name(status));
    else
        fprintf(stderr, "fmu3_host: %s at t = %.17g s returned %s\n", call, t,
                status_name(status));
    return 1;
}

static int record(Run* r, double t)
{
    const Outputs* o = r->out;
    size_t iF = 0, iI = 0;
    if (o->n_float
        && failed(r->api->fmi3GetFloat64(r->c, o->float_vr, o->n_float, o->real, o->n_float),
                  "fmi3GetFloat64", t))
        return 1;
    if (o->n_int
        && failed(r->api->fmi3GetInt32(r->c, o->int_vr, o->n_int, o->integer, o->n_int),
                  "fmi3GetInt32", t))
        return 1;
    fprintf(r->csv, "%.17g", t);
    for (size_t i = 0; i < o->n; i++) {
        if (o->kind[i] == 'F')
            fprintf(r->csv, ",%.17g", o->real[iF++]);
        else
            fprintf(r->csv, ",%d", (int)o->integer[iI++]);
    }
    fputc('\n', r->csv);
    return ferror(r->csv) != 0;
}

static int simulate(Run* r, const Inputs* in, const fmi3ValueReference* input_vr)
{
    const Api* api = r->api;
    size_t m = in->n_inputs;
    double t0 = in->time[0];
    if (failed(api->fmi3EnterInitializationMode(r->c, fmi3False, 0.0, t0, fmi3False, 0.0),
               "fmi3EnterInitializationMode", NAN)
        || failed(api->fmi3SetFloat64(r->c, input_vr, m, in->values, m), "fmi3SetFloat64", t0)
        || failed(api->fmi3ExitInitializationMode(r->c), "fmi3ExitInitializationMode", NAN)
        || record(r, t0))
        return 1;
    for (size_t k = 0; k + 1 < in->n_rows; k++) {
        double t = in->time[k], h = in->time[k + 1] - in->time[k], last = NAN;
        fmi3Boolean event = fmi3True, terminate = fmi3True, early = fmi3True;
        if (failed(api->fmi3SetFloat64(r->c, input_vr, m, in->values + k * m, m),
                   "fmi3SetFloat64", t)
            || failed(api->fmi3DoStep(r->c, t, h, fmi3True, &event, &terminate, &early, &last),
                      "fmi3DoStep", t))
            return 1;
        if (event || terminate || early || last != t + h) {
            fprintf(stderr, "fmu3_host: fmi3DoStep at t = %.17g s reported event %d, terminate "
                    "%d, early return %d, last successful time %.17g\n", t, (int)event,
                    (int)terminate, (int)early, last);
            return 1;
        }
        if (record(r, in->time[k + 1])) return 1;
    }
    return failed(api->fmi3Terminate(r->c), "fmi3Terminate", NAN);
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
    fprintf(stderr, "fmu3_host: cannot load %s: error %lu\n", path,
            (unsigned long)GetLastError());
}
#else
typedef void* Library;
static Library open_library(const char* path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void* symbol(Library lib, const char* name) { return dlsym(lib, name); }
static void library_error(const char* path)
{
    fprintf(stderr, "fmu3_host: cannot load %s: %s\n", path, dlerror());
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
    Api api;
    Inputs in;
    Outputs out;
    Run run;
    fmi3ValueReference* input_vr;
    size_t n_inputs = 0;
    const char* p;
    char* end;
    Library lib;
    int rc;
    if (argc < 8) {
        fprintf(stderr, "usage: %s BINARY RESOURCES TOKEN INPUTS_CSV OUTPUTS_CSV INPUT_VRS "
                        "OUTPUT...\n  OUTPUT: F:<vr>:<name> | I:<vr>:<name>\n", argv[0]);
        return 2;
    }
    input_vr = xrealloc(NULL, (strlen(argv[6]) / 2 + 1) * sizeof *input_vr);
    for (p = argv[6];; p = end + 1) {
        if (parse_vr(p, &end, &input_vr[n_inputs]) || (*end != ',' && *end != '\0')) {
            fprintf(stderr, "fmu3_host: INPUT_VRS '%s' must be comma-separated numbers\n",
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
            fprintf(stderr, "fmu3_host: %s has no symbol %s\n", argv[1], #name);               \
            return 1;                                                                          \
        }                                                                                      \
        memcpy(&api.name, &s, sizeof s);                                                       \
    }
    API(LOAD)
#undef LOAD
    if (strcmp(api.fmi3GetVersion(), "3.0") != 0) {
        fprintf(stderr, "fmu3_host: fmi3GetVersion() = '%s', not 3.0\n", api.fmi3GetVersion());
        return 1;
    }
    run.api = &api;
    run.out = &out;
    run.c = api.fmi3InstantiateCoSimulation("fmu3_host", argv[3],
                                            strcmp(argv[2], "-") == 0 ? NULL : argv[2],
                                            fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0,
                                            NULL, log_message, NULL);
    if (run.c == NULL) {
        fprintf(stderr, "fmu3_host: fmi3InstantiateCoSimulation returned NULL\n");
        return 1;
    }
    run.csv = fopen(argv[5], "w");
    if (run.csv == NULL) {
        fprintf(stderr, "fmu3_host: cannot write %s: %s\n", argv[5], strerror(errno));
        return 2;
    }
    fprintf(run.csv, "time");
    for (size_t i = 0; i < out.n; i++) fprintf(run.csv, ",%s", out.name[i]);
    fputc('\n', run.csv);
    rc = simulate(&run, &in, input_vr);
    api.fmi3FreeInstance(run.c);
    if (fclose(run.csv) != 0) rc = 1;
    free(input_vr);
    free(in.time);
    free(in.values);
    free(out.kind);
    free((void*)out.name);
    free(out.float_vr);
    free(out.int_vr);
    free(out.real);
    free(out.integer);
    if (rc == 0 && python_loaded()) {
        fprintf(stderr, "fmu3_host: a libpython is loaded in this process\n");
        return 3;
    }
    return rc;
}
