/*
 * native_floor.c - the cost floors of benchmarks/run.py, measured without Python:
 *
 *   native_floor pair MESH_SO MESH_URI MESH_GUID DRIVE_SO DRIVE_URI DRIVE_GUID STOP STEP
 *                     M2D_OUT M2D_IN D2M_OUT D2M_IN REC_REAL REC_INT
 *       the native GearMeshRattle + Driveline pair co-simulated by this C master exactly as
 *       the fmpy harness does (two rounds of output->input exchange in initialization mode,
 *       Jacobi steps on the integer-nanosecond grid, the recorded outputs read at every
 *       point); the value-reference lists are comma-separated.  Prints the wall time of the
 *       stepping loop [s] and the last recorded Reals (%.17g, for a bit-for-bit check).
 *
 *   native_floor kernel KERNEL_SO DATA_FILE OUTPUTS
 *       rattle_kernel.c's rk_step alone (OUTPUTS = 0) or followed by rk_outputs (1) over the
 *       steps of DATA_FILE (doubles: M_COUNT, S_COUNT, R_COUNT, O_COUNT, steps, the model
 *       array, the start state, then h, phi_p, w_p, a_p, tau_load per step).  Prints the wall
 *       time [s] and the final state's first two entries.
 *
 * C99, POSIX (dlopen, clock_gettime).
 */
#define _POSIX_C_SOURCE 200809L

#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2FunctionTypes.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void* sym(void* lib, const char* name)
{
    void* p = dlsym(lib, name);
    if (p == NULL) {
        fprintf(stderr, "native_floor: no symbol %s\n", name);
        exit(1);
    }
    return p;
}

static size_t vr_list(const char* text, fmi2ValueReference* out, size_t max)
{
    size_t n = 0;
    while (*text != '\0' && n < max) {
        char* end;
        out[n++] = (fmi2ValueReference)strtoul(text, &end, 10);
        text = *end == ',' ? end + 1 : end;
    }
    return n;
}

static void logger(fmi2ComponentEnvironment e, fmi2String i, fmi2Status s, fmi2String c,
                   fmi2String m, ...)
{
    (void)e, (void)i, (void)c;
    fprintf(stderr, "[%d] %s\n", (int)s, m);
}

typedef struct {
    fmi2InstantiateTYPE* instantiate;
    fmi2SetupExperimentTYPE* setup;
    fmi2EnterInitializationModeTYPE* enter;
    fmi2ExitInitializationModeTYPE* exit_init;
    fmi2GetRealTYPE* get_real;
    fmi2GetIntegerTYPE* get_integer;
    fmi2SetRealTYPE* set_real;
    fmi2DoStepTYPE* do_step;
    fmi2FreeInstanceTYPE* free_instance;
    fmi2Component c;
} Unit;

static void load_unit(Unit* u, const char* so, const char* uri, const char* guid,
                      const fmi2CallbackFunctions* cb)
{
    void* lib = dlopen(so, RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "native_floor: %s\n", dlerror());
        exit(1);
    }
    void* p;
#define GET(field, name) p = sym(lib, name); memcpy(&u->field, &p, sizeof p);
    GET(instantiate, "fmi2Instantiate")
    GET(setup, "fmi2SetupExperiment")
    GET(enter, "fmi2EnterInitializationMode")
    GET(exit_init, "fmi2ExitInitializationMode")
    GET(get_real, "fmi2GetReal")
    GET(get_integer, "fmi2GetInteger")
    GET(set_real, "fmi2SetReal")
    GET(do_step, "fmi2DoStep")
    GET(free_instance, "fmi2FreeInstance")
#undef GET
    u->c = u->instantiate("floor", fmi2CoSimulation, guid, uri, cb, fmi2False, fmi2False);
    if (u->c == NULL) exit(1);
}

static void check(fmi2Status s, const char* what)
{
    if (s > fmi2Warning) {
        fprintf(stderr, "native_floor: %s returned %d\n", what, (int)s);
        exit(1);
    }
}

static int pair(char** a)
{
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    Unit mesh, drive;
    fmi2ValueReference m2d_out[8], m2d_in[8], d2m_out[8], d2m_in[8], rec_r[64], rec_i[64];
    double buf[64], rec[64];
    fmi2Integer ibuf[64];
    load_unit(&mesh, a[0], a[1], a[2], &cb);
    load_unit(&drive, a[3], a[4], a[5], &cb);
    double stop = atof(a[6]), step = atof(a[7]);
    size_t n_m2d = vr_list(a[8], m2d_out, 8), n_d2m = vr_list(a[10], d2m_out, 8);
    vr_list(a[9], m2d_in, 8);
    vr_list(a[11], d2m_in, 8);
    size_t n_rr = vr_list(a[12], rec_r, 64), n_ri = vr_list(a[13], rec_i, 64);
    check(mesh.setup(mesh.c, 0, 0.0, 0.0, 0, 0.0), "setup");
    check(drive.setup(drive.c, 0, 0.0, 0.0, 0, 0.0), "setup");
    check(mesh.enter(mesh.c), "enter");
    check(drive.enter(drive.c), "enter");
    for (int round = 0; round < 2; round++) { /* the harness: mesh -> driveline, then back */
        check(mesh.get_real(mesh.c, m2d_out, n_m2d, buf), "get");
        check(drive.set_real(drive.c, m2d_in, n_m2d, buf), "set");
        check(drive.get_real(drive.c, d2m_out, n_d2m, buf), "get");
        check(mesh.set_real(mesh.c, d2m_in, n_d2m, buf), "set");
    }
    check(mesh.exit_init(mesh.c), "exit");
    check(drive.exit_init(drive.c), "exit");
    long long step_ns = (long long)(step * 1e9 + 0.5), stop_ns = (long long)(stop * 1e9 + 0.5);
    long long n = stop_ns / step_ns;
    double t0 = now();
    for (long long k = 0; k <= n; k++) {
        double t = (double)(k * step_ns) / 1e9;
        check(mesh.get_real(mesh.c, rec_r, n_rr, rec), "record");
        if (n_ri) check(mesh.get_integer(mesh.c, rec_i, n_ri, ibuf), "record");
        if (k == n) break;
        double h = (double)((k + 1) * step_ns) / 1e9 - t;
        check(mesh.get_real(mesh.c, m2d_out, n_m2d, buf), "get");
        check(drive.set_real(drive.c, m2d_in, n_m2d, buf), "set");
        check(drive.get_real(drive.c, d2m_out, n_d2m, buf), "get");
        check(mesh.set_real(mesh.c, d2m_in, n_d2m, buf), "set");
        check(mesh.do_step(mesh.c, t, h, fmi2True), "doStep");
        check(drive.do_step(drive.c, t, h, fmi2True), "doStep");
    }
    double wall = now() - t0;
    printf("%.9f", wall);
    for (size_t i = 0; i < n_rr; i++) printf(" %.17g", rec[i]);
    printf("\n");
    mesh.free_instance(mesh.c);
    drive.free_instance(drive.c);
    return 0;
}

typedef int StepFn(const double*, double*, const double*, double*, double*, char*, int);
typedef int OutputsFn(const double*, const double*, const double*, double*);

static int kernel(char** a)
{
    void* lib = dlopen(a[0], RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "native_floor: %s\n", dlerror());
        return 1;
    }
    StepFn* rk_step;
    OutputsFn* rk_outputs;
    void* p = sym(lib, "rk_step");
    memcpy(&rk_step, &p, sizeof p);
    p = sym(lib, "rk_outputs");
    memcpy(&rk_outputs, &p, sizeof p);
    FILE* f = fopen(a[1], "rb");
    double head[5];
    if (f == NULL || fread(head, sizeof(double), 5, f) != 5) return 1;
    size_t nm = (size_t)head[0], ns = (size_t)head[1], nr = (size_t)head[2],
           no = (size_t)head[3], steps = (size_t)head[4];
    double* model = malloc(nm * sizeof(double));
    double* state = malloc(ns * sizeof(double));
    double* inputs = malloc(5 * steps * sizeof(double));
    double* result = calloc(nr, sizeof(double));
    double* out = calloc(no, sizeof(double));
    if (fread(model, sizeof(double), nm, f) != nm || fread(state, sizeof(double), ns, f) != ns
        || fread(inputs, sizeof(double), 5 * steps, f) != 5 * steps)
        return 1;
    fclose(f);
    int outputs = atoi(a[2]);
    double err_values[8];
    char err[256];
    double t0 = now();
    for (size_t k = 0; k < steps; k++) {
        if (rk_step(model, state, inputs + 5 * k, result, err_values, err, (int)sizeof err)) {
            fprintf(stderr, "native_floor: rk_step refused step %zu: %s\n", k, err);
            return 1;
        }
        if (outputs) rk_outputs(model, state, result, out);
    }
    printf("%.9f %.17g %.17g\n", now() - t0, state[0], state[1]);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc == 16 && strcmp(argv[1], "pair") == 0) return pair(argv + 2);
    if (argc == 5 && strcmp(argv[1], "kernel") == 0) return kernel(argv + 2);
    fprintf(stderr, "usage: see the top of native_floor.c\n");
    return 2;
}
