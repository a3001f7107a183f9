/*
 * c_master.c - a C co-simulation master for benchmarks/run.py: the native GearMeshRattle and
 * Driveline FMUs dlopen'ed and coupled exactly as the fmpy harness couples them (two rounds of
 * output->input exchange in initialization mode, Jacobi steps on the integer-nanosecond grid,
 * the recorded output read at every point), without Python:
 *
 *   c_master MESH_SO MESH_URI MESH_GUID DRIVE_SO DRIVE_URI DRIVE_GUID STOP STEP
 *            M2D_OUT M2D_IN D2M_OUT D2M_IN RECORD
 *
 * The value-reference lists are comma-separated; RECORD is one Real of the mesh.  Prints the
 * wall time of the stepping loop [s] and the last recorded value (%.17g, for the bit-for-bit
 * check against the compiled loop).
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
        fprintf(stderr, "c_master: no symbol %s\n", name);
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
        fprintf(stderr, "c_master: %s\n", dlerror());
        exit(1);
    }
    void* p;
#define GET(field, name) p = sym(lib, name); memcpy(&u->field, &p, sizeof p);
    GET(instantiate, "fmi2Instantiate")
    GET(setup, "fmi2SetupExperiment")
    GET(enter, "fmi2EnterInitializationMode")
    GET(exit_init, "fmi2ExitInitializationMode")
    GET(get_real, "fmi2GetReal")
    GET(set_real, "fmi2SetReal")
    GET(do_step, "fmi2DoStep")
    GET(free_instance, "fmi2FreeInstance")
#undef GET
    u->c = u->instantiate("c_master", fmi2CoSimulation, guid, uri, cb, fmi2False, fmi2False);
    if (u->c == NULL) exit(1);
}

static void check(fmi2Status s, const char* what)
{
    if (s > fmi2Warning) {
        fprintf(stderr, "c_master: %s returned %d\n", what, (int)s);
        exit(1);
    }
}

static int co_simulate(char** a)
{
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    Unit mesh, drive;
    fmi2ValueReference m2d_out[8], m2d_in[8], d2m_out[8], d2m_in[8], rec_vr[1];
    double buf[64], rec = 0.0;
    load_unit(&mesh, a[0], a[1], a[2], &cb);
    load_unit(&drive, a[3], a[4], a[5], &cb);
    double stop = atof(a[6]), step = atof(a[7]);
    size_t n_m2d = vr_list(a[8], m2d_out, 8), n_d2m = vr_list(a[10], d2m_out, 8);
    vr_list(a[9], m2d_in, 8);
    vr_list(a[11], d2m_in, 8);
    if (vr_list(a[12], rec_vr, 1) != 1) {
        fprintf(stderr, "c_master: RECORD must be one value reference\n");
        return 2;
    }
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
        check(mesh.get_real(mesh.c, rec_vr, 1, &rec), "record");
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
    printf("%.9f %.17g\n", wall, rec);
    mesh.free_instance(mesh.c);
    drive.free_instance(drive.c);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc == 14) return co_simulate(argv + 1);
    fprintf(stderr, "usage: see the top of c_master.c\n");
    return 2;
}
