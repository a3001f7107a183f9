/*
 * native_host.c - a minimal native FMI 2.0 co-simulation host, as system-simulation tools are:
 * it dlopen()s an FMU's binary, drives it with inputs read from a CSV file and records its
 * outputs to another CSV file.  Used by tests/adversarial/test_native_host.py (see
 * docs/native_host.md).  C99, libc and libdl only, and the FMI 2.0 headers.
 *
 * Usage:
 *   native_host FMU_SO RESOURCES GUID INPUTS_CSV OUTPUTS_CSV INPUT_VRS OUTPUT...
 *
 *   FMU_SO      the FMU binary, e.g. <unpacked>/binaries/linux64/GearMeshRattle.so
 *   RESOURCES   fmuResourceLocation for fmi2Instantiate: a file:// URI (percent-encoded) or a
 *               plain path of <unpacked>/resources
 *   GUID        the guid attribute of modelDescription.xml
 *   INPUTS_CSV  a header line "time,<input names...>", then one row per communication point
 *               t_0 < t_1 < ... < t_N: the time and the input values to hold over the step
 *               from t_k to t_{k+1}.  Numbers as full-precision decimals (e.g. Python repr());
 *               the last row only defines t_N.
 *   OUTPUTS_CSV written: "time,<output names...>", then one row per communication point,
 *               t_0 (after initialization) to t_N; Reals printed "%.17g" (exact round trip),
 *               Integers "%d".
 *   INPUT_VRS   comma-separated value references of the Real inputs, one per input column of
 *               INPUTS_CSV, in column order (the header's names are not interpreted).
 *   OUTPUT      one argument per recorded output, in column order: R:<vr>:<name> for a Real
 *               (fmi2GetReal), I:<vr>:<name> for an Integer (fmi2GetInteger).
 *
 * Call sequence: fmi2Instantiate(fmi2CoSimulation, visible = false, loggingOn = false),
 * fmi2SetupExperiment(no tolerance, start t_0, no stop time), fmi2EnterInitializationMode,
 * fmi2SetReal(row 0 inputs), fmi2ExitInitializationMode, record t_0; then for k = 0 .. N-1:
 * fmi2SetReal(row k inputs), fmi2DoStep(t_k, t_{k+1} - t_k, true), record t_{k+1}; finally
 * fmi2Terminate and fmi2FreeInstance.  Every status is checked: anything but fmi2OK ends the
 * run with a message on stderr and exit code 1 (2 for a usage or input-file error).
 *
 * The FMU's log messages go to stderr as "[<status>] <category>: <message>".
 *
 * The FMU library is deliberately never dlclose()d.  pythonfmu keeps the embedded Python
 * interpreter and the slaves' Python objects in process-wide state of its library and tears
 * them down from library destructors; unloading at a dlclose (or a host that reloads the
 * library) runs that teardown while the interpreter may still be needed and has been seen to
 * corrupt the heap (docs/fmi.md, "How it is built").  The process exit releases it instead.
 *
 * Numbers are parsed with strtod and printed with printf in the "C" numeric locale: the host
 * never calls setlocale, and Python's initialization changes only LC_CTYPE.
 *
 * The Python FMU needs libpython in the process before it is loaded (LD_PRELOAD) and the right
 * python3 first on PATH; see docs/native_host.md.
 */
#define _POSIX_C_SOURCE 200809L

#include <dlfcn.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ FMI 2.0 types
 * The official FMI 2.0 headers, as fmpy ships them (fmpy/c-code/; the test passes -I): the
 * types of every function this host calls through a pointer. */
#include "fmi2FunctionTypes.h"

#define API(X)                                                                                 \
    X(fmi2GetVersion) X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment)            \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2Terminate)              \
    X(fmi2GetReal) X(fmi2GetInteger) X(fmi2SetReal) X(fmi2DoStep)

typedef struct {
#define MEMBER(name) name##TYPE* name;
    API(MEMBER)
#undef MEMBER
} Api;

/* ------------------------------------------------------------------ helpers */

static const char* status_name(int status)
{
    static const char* names[] = {"OK", "Warning", "Discard", "Error", "Fatal", "Pending"};
    return status >= 0 && status <= 5 ? names[status] : "unknown status";
}

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

static void* xrealloc(void* p, size_t size)
{
    void* q = realloc(p, size ? size : 1);
    if (q == NULL) {
        fprintf(stderr, "native_host: out of memory\n");
        exit(2);
    }
    return q;
}

/* A whole-field double; 0 on success.  "inf" and "nan" are accepted (the FMU judges its
 * inputs); an overflowing literal is not.  ERANGE from an underflow is no error: strtod sets it
 * for subnormal results such as "5e-324", which are exact. */
static int parse_double(const char* text, double* out)
{
    char* end;
    errno = 0;
    *out = strtod(text, &end);
    return end == text || *end != '\0' || (errno == ERANGE && isinf(*out));
}

static int parse_vr(const char* text, char** end, fmi2ValueReference* out)
{
    unsigned long v;
    if (*text < '0' || *text > '9') return 1;
    errno = 0;
    v = strtoul(text, end, 10);
    if (errno != 0 || v > 0xFFFFFFFFUL) return 1;
    *out = (fmi2ValueReference)v;
    return 0;
}

/* Splits a CSV line in place at commas (no quoting: plain numbers and names); returns the
 * number of fields, at most max_fields + 1 (one more than allowed means "too many"). */
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

/* Reads one line without its line ending into a growing buffer; 0 at end of file. */
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

/* ------------------------------------------------------------------ inputs */

typedef struct {
    size_t n_rows, n_inputs;
    double* time;   /* [n_rows] */
    double* values; /* [n_rows * n_inputs] */
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
        fprintf(stderr, "native_host: cannot open %s: %s\n", path, strerror(errno));
        goto done;
    }
    if (!read_line(f, &line, &cap)) {
        fprintf(stderr, "native_host: %s is empty (expected a header line)\n", path);
        goto done;
    }
    if (split(line, fields, n_inputs + 1) != n_inputs + 1 || strcmp(fields[0], "time") != 0) {
        fprintf(stderr, "native_host: %s:1: header must be 'time' and %zu input names, one "
                        "per value reference of INPUT_VRS\n", path, n_inputs);
        goto done;
    }
    while (read_line(f, &line, &cap)) {
        size_t j;
        lineno++;
        if (line[0] == '\0') continue;
        if (split(line, fields, n_inputs + 1) != n_inputs + 1) {
            fprintf(stderr, "native_host: %s:%zu: expected %zu fields\n", path, lineno,
                    n_inputs + 1);
            goto done;
        }
        if (in->n_rows == rows_cap) {
            rows_cap = rows_cap ? 2 * rows_cap : 1024;
            in->time = xrealloc(in->time, rows_cap * sizeof *in->time);
            in->values = xrealloc(in->values, rows_cap * n_inputs * sizeof *in->values);
        }
        for (j = 0; j <= n_inputs; j++) {
            double v;
            if (parse_double(fields[j], &v)) {
                fprintf(stderr, "native_host: %s:%zu: field %zu '%s' is not a number\n", path,
                        lineno, j + 1, fields[j]);
                goto done;
            }
            if (j == 0) in->time[in->n_rows] = v;
            else in->values[in->n_rows * n_inputs + j - 1] = v;
        }
        if (!isfinite(in->time[in->n_rows])
            || (in->n_rows > 0 && !(in->time[in->n_rows] > in->time[in->n_rows - 1]))) {
            fprintf(stderr, "native_host: %s:%zu: times must be finite and increasing\n", path,
                    lineno);
            goto done;
        }
        in->n_rows++;
    }
    if (in->n_rows == 0) {
        fprintf(stderr, "native_host: %s has no data rows\n", path);
        goto done;
    }
    err = 0;
done:
    if (f != NULL) fclose(f);
    free(line);
    free(fields);
    return err;
}

/* ------------------------------------------------------------------ outputs */

typedef struct {
    size_t n, n_real, n_int;
    char* kind;                   /* [n] 'R' or 'I' */
    const char** name;            /* [n] */
    fmi2ValueReference* real_vr;  /* [n_real] */
    fmi2ValueReference* int_vr;   /* [n_int] */
    double* real;                 /* [n_real] */
    fmi2Integer* integer;         /* [n_int] */
} Outputs;

static int parse_outputs(int argc, char** argv, Outputs* out)
{
    int i;
    out->n = (size_t)argc;
    out->n_real = out->n_int = 0;
    out->kind = xrealloc(NULL, out->n);
    out->name = xrealloc(NULL, out->n * sizeof *out->name);
    out->real_vr = xrealloc(NULL, out->n * sizeof *out->real_vr);
    out->int_vr = xrealloc(NULL, out->n * sizeof *out->int_vr);
    out->real = xrealloc(NULL, out->n * sizeof *out->real);
    out->integer = xrealloc(NULL, out->n * sizeof *out->integer);
    for (i = 0; i < argc; i++) {
        const char* a = argv[i];
        char* end;
        fmi2ValueReference vr;
        if ((a[0] != 'R' && a[0] != 'I') || a[1] != ':' || parse_vr(a + 2, &end, &vr)
            || *end != ':' || end[1] == '\0') {
            fprintf(stderr, "native_host: output '%s' must be R:<vr>:<name> or I:<vr>:<name>\n",
                    a);
            return 1;
        }
        out->kind[i] = a[0];
        out->name[i] = end + 1;
        if (a[0] == 'R') out->real_vr[out->n_real++] = vr;
        else out->int_vr[out->n_int++] = vr;
    }
    return 0;
}

/* ------------------------------------------------------------------ the run */

typedef struct {
    const Api* api;
    fmi2Component c;
    const Outputs* out;
    FILE* csv;
} Run;

/* Reports a status other than fmi2OK; returns 1 for it. */
static int failed(fmi2Status status, const char* call, double t)
{
    if (status == fmi2OK) return 0;
    if (isnan(t)) fprintf(stderr, "native_host: %s returned %s\n", call, status_name(status));
    else fprintf(stderr, "native_host: %s at t = %.17g s returned %s\n", call, t,
                 status_name(status));
    return 1;
}

static int record(Run* r, double t)
{
    const Outputs* o = r->out;
    size_t i, ir = 0, ii = 0;
    if (o->n_real && failed(r->api->fmi2GetReal(r->c, o->real_vr, o->n_real, o->real),
                            "fmi2GetReal", t))
        return 1;
    if (o->n_int && failed(r->api->fmi2GetInteger(r->c, o->int_vr, o->n_int, o->integer),
                           "fmi2GetInteger", t))
        return 1;
    fprintf(r->csv, "%.17g", t);
    for (i = 0; i < o->n; i++) {
        if (o->kind[i] == 'R') fprintf(r->csv, ",%.17g", o->real[ir++]);
        else fprintf(r->csv, ",%d", (int)o->integer[ii++]);
    }
    fputc('\n', r->csv);
    if (ferror(r->csv)) {
        fprintf(stderr, "native_host: writing the outputs failed\n");
        return 1;
    }
    return 0;
}

static int simulate(Run* r, const Inputs* in, const fmi2ValueReference* input_vr)
{
    const Api* api = r->api;
    size_t k, m = in->n_inputs;
    double t0 = in->time[0];

    if (failed(api->fmi2SetupExperiment(r->c, 0, 0.0, t0, 0, 0.0), "fmi2SetupExperiment", NAN)
        || failed(api->fmi2EnterInitializationMode(r->c), "fmi2EnterInitializationMode", NAN)
        || failed(api->fmi2SetReal(r->c, input_vr, m, in->values), "fmi2SetReal", t0)
        || failed(api->fmi2ExitInitializationMode(r->c), "fmi2ExitInitializationMode", NAN)
        || record(r, t0))
        return 1;
    for (k = 0; k + 1 < in->n_rows; k++) {
        double t = in->time[k], h = in->time[k + 1] - in->time[k];
        if (failed(api->fmi2SetReal(r->c, input_vr, m, in->values + k * m), "fmi2SetReal", t)
            || failed(api->fmi2DoStep(r->c, t, h, 1), "fmi2DoStep", t)
            || record(r, in->time[k + 1]))
            return 1;
    }
    return failed(api->fmi2Terminate(r->c), "fmi2Terminate", NAN);
}

int main(int argc, char** argv)
{
    Api api;
    Inputs in;
    Outputs out;
    Run run;
    fmi2ValueReference* input_vr;
    size_t n_inputs = 0, i;
    const char* p;
    char* end;
    void* lib;
    const char* version;
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    int rc;

    if (argc < 8) {
        fprintf(stderr, "usage: %s FMU_SO RESOURCES GUID INPUTS_CSV OUTPUTS_CSV INPUT_VRS "
                        "OUTPUT...\n  OUTPUT: R:<vr>:<name> | I:<vr>:<name>\n"
                        "(documented at the top of native_host.c)\n", argv[0]);
        return 2;
    }

    /* value references of the inputs */
    for (p = argv[6]; *p; p++) n_inputs += *p == ',';
    n_inputs++;
    input_vr = xrealloc(NULL, n_inputs * sizeof *input_vr);
    for (i = 0, p = argv[6]; i < n_inputs; i++, p = end + 1) {
        if (parse_vr(p, &end, &input_vr[i]) || (*end != ',' && *end != '\0')) {
            fprintf(stderr, "native_host: INPUT_VRS '%s' must be comma-separated value "
                            "references\n", argv[6]);
            return 2;
        }
    }
    if (parse_outputs(argc - 7, argv + 7, &out) || read_inputs(argv[4], n_inputs, &in))
        return 2;

    /* the FMU binary and its functions */
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "native_host: dlopen %s failed: %s\n", argv[1], dlerror());
        return 1;
    }
#define LOAD(name)                                                                             \
    *(void**)(&api.name) = dlsym(lib, #name);                                                  \
    if (api.name == NULL) {                                                                    \
        fprintf(stderr, "native_host: %s does not export %s\n", argv[1], #name);               \
        return 1;                                                                              \
    }
    API(LOAD)
#undef LOAD
    version = api.fmi2GetVersion();
    if (version == NULL || strcmp(version, "2.0") != 0) {
        fprintf(stderr, "native_host: fmi2GetVersion returned '%s', expected '2.0'\n",
                version ? version : "(null)");
        return 1;
    }

    run.api = &api;
    run.out = &out;
    run.csv = fopen(argv[5], "w");
    if (run.csv == NULL) {
        fprintf(stderr, "native_host: cannot create %s: %s\n", argv[5], strerror(errno));
        return 2;
    }
    fputs("time", run.csv);
    for (i = 0; i < out.n; i++) fprintf(run.csv, ",%s", out.name[i]);
    fputc('\n', run.csv);

    run.c = api.fmi2Instantiate("native_host", fmi2CoSimulation, argv[3], argv[2], &callbacks,
                                0 /* visible */, 0 /* loggingOn */);
    if (run.c == NULL) {
        fprintf(stderr, "native_host: fmi2Instantiate returned NULL\n");
        fclose(run.csv);
        return 1;
    }
    rc = simulate(&run, &in, input_vr);
    api.fmi2FreeInstance(run.c);
    if (fclose(run.csv) != 0) {
        fprintf(stderr, "native_host: closing %s failed\n", argv[5]);
        rc = 1;
    }
    /* no dlclose(lib): see the top of this file */
    free(input_vr);
    free(in.time);
    free(in.values);
    free(out.kind);
    free(out.name);
    free(out.real_vr);
    free(out.int_vr);
    free(out.real);
    free(out.integer);
    return rc;
}
