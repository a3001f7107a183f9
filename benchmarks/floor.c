/*
 * floor.c - the cost floor of benchmarks/run.py: the model's own work on the paper scenario,
 * without Python, without FMI and without the unit layer.  Compiled together with the model
 * library's sources (benchmarks/run.py does it), so it calls the library's internal stepper:
 *
 *   floor DATA_FILE REPEATS
 *
 * DATA_FILE: doubles -- steps, then per step h, phi_p, w_p, a_p, tau_load (the mesh's inputs
 * of a coupled run of the default parameters, recorded by the compiled loop).  The mesh model
 * is built for the default parameters, the wheel started in the static equilibrium for the
 * first step's inputs, then rm_wheel_step runs over every step: the integration, the event
 * location and the guards -- what any face must pay at least.  Prints the best wall time of
 * REPEATS runs [s] and the final wheel state (%.17g: the same for every repeat).
 *
 * C99, POSIX clock_gettime.
 */
#define _POSIX_C_SOURCE 200809L

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "rm_private.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char** argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: floor DATA_FILE REPEATS\n");
        return 2;
    }
    FILE* f = fopen(argv[1], "rb");
    double n_steps;
    if (f == NULL || fread(&n_steps, sizeof n_steps, 1, f) != 1) {
        fprintf(stderr, "floor: cannot read %s\n", argv[1]);
        return 1;
    }
    size_t n = (size_t)n_steps;
    double* data = malloc(5 * n * sizeof *data);
    if (data == NULL || fread(data, sizeof *data, 5 * n, f) != 5 * n) {
        fprintf(stderr, "floor: %s holds fewer than %zu steps\n", argv[1], n);
        return 1;
    }
    fclose(f);
    RmUnit* u = rm_new(RM_MESH, NULL);
    RmMeshParams p;
    static RmMesh mesh;
    static RmStepLog log;
    RmText err;
    rm_text_init(&err);
    rm_mesh_params(u->values, &p);
    if (!rm_mesh_build(&p, &mesh, &err)) {
        fprintf(stderr, "floor: %s\n", rm_text_str(&err));
        return 1;
    }
    int repeats = atoi(argv[2]);
    double best = 1e300;
    RmWheel wheel;
    for (int r = 0; r < repeats; r++) {
        RmLast last = {0};
        double values[4];
        if (!rm_equilibrium_start(&mesh, data[1], data[2], data[4], &wheel, &err)) {
            fprintf(stderr, "floor: %s\n", rm_text_str(&err));
            return 1;
        }
        double t0 = now();
        for (size_t k = 0; k < n; k++) {
            const double* s = &data[5 * k];
            int code = rm_wheel_step(&mesh, &wheel, &last, s[0], s[1], s[2], s[3], s[4], &log,
                                     values);
            if (code != RM_FAIL_NONE) {
                rm_refusal_text(&err, code, values);
                fprintf(stderr, "floor: step %zu refused: %s\n", k, rm_text_str(&err));
                return 1;
            }
        }
        double wall = now() - t0;
        if (wall < best) best = wall;
    }
    printf("%.6f %.17g %.17g\n", best, wheel.phi, wheel.w);
    rm_free(u);
    free(data);
    rm_text_free(&err);
    return 0;
}
