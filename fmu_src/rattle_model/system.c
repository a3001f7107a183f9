/*
 * system.c - the two units coupled in a compiled loop: the co-simulation of GearMeshRattle and
 * Driveline that the fmpy harness, libcosim and the in-process twin run, with the same fixed
 * step, Jacobi exchange (both units step from the outputs of the last communication point)
 * and integer-nanosecond grid t_k = (t0_ns + k step_ns) / 1e9, each step t_{k+1} - t_k, made
 * through the same unit calls the FMUs make: so its numbers are theirs, bit for bit, at the
 * cost of the model alone (studies: sweeps, rattle maps, multistability grids).
 */
#include <stdio.h>

#include "rm_private.h"

/* The coupling (drive_rattle.interface.CONNECTIONS): the mesh's inputs from the driveline's
 * outputs of the same names, the driveline's from the mesh's. */
static const unsigned MESH_IN[4] = {RM_MESH_PINION_PHI, RM_MESH_PINION_W, RM_MESH_PINION_A,
                                    RM_MESH_WHEEL_TAU_LOAD};
static const unsigned DRIVE_OUT[4] = {RM_DRIVELINE_PINION_PHI, RM_DRIVELINE_PINION_W,
                                      RM_DRIVELINE_PINION_A, RM_DRIVELINE_WHEEL_TAU_LOAD};
static const unsigned DRIVE_IN[2] = {RM_DRIVELINE_WHEEL_PHI, RM_DRIVELINE_WHEEL_W};
static const unsigned MESH_OUT[2] = {RM_MESH_WHEEL_PHI, RM_MESH_WHEEL_W};

/* The failure of a unit's call in the loop, as the mesh's message. */
static int failed(RmUnit* mesh, RmUnit* unit, const char* what, double t)
{
    char text[4096];
    rm_format(text, sizeof text, "coupled run: %s at t = %r s: %s", what, t, rm_message(unit));
    mesh->status = RM_OK;
    rm_report(mesh, RM_ERROR, text);
    return RM_ERROR;
}

int rm_run_coupled(RmUnit* mesh, RmUnit* drive, int64_t start_ns, int64_t step_ns,
                   int64_t steps, const unsigned* record_vr, const int* record_unit,
                   size_t n_record, double* record, double* onsets, size_t onset_capacity,
                   size_t* n_onsets)
{
    if (mesh == NULL || drive == NULL) return RM_ERROR;
    mesh->status = RM_OK;
    rm_text_clear(&mesh->message);
    *n_onsets = 0;
    if (mesh->kind != RM_MESH || drive->kind != RM_DRIVELINE || mesh->phase != RM_STEPPING
        || drive->phase != RM_STEPPING || step_ns <= 0 || steps < 0) {
        rm_report(mesh, RM_ERROR, "coupled run: expected an initialized GearMeshRattle and "
                                  "Driveline, a step > 0 ns and steps >= 0");
        return RM_ERROR;
    }
    for (size_t i = 0; i < n_record; i++) {
        RmUnit* u = record_unit[i] == RM_MESH ? mesh : drive;
        if (record_vr[i] >= u->n_variables || u->variables[record_vr[i]].type == RM_STRING
            || u->variables[record_vr[i]].type == RM_BOOLEAN) {
            rm_report(mesh, RM_ERROR, "coupled run: a recorded variable is not a Real or "
                                      "Integer variable of its unit");
            return RM_ERROR;
        }
    }
    double mesh_out[2], drive_out[4];
    for (int64_t k = 0;; k++) {
        double t = (double)(start_ns + k * step_ns) / 1e9;
        for (size_t i = 0; i < n_record; i++) {
            RmUnit* u = record_unit[i] == RM_MESH ? mesh : drive;
            double* slot = &record[i * ((size_t)steps + 1) + (size_t)k]; /* by column */
            if (u->variables[record_vr[i]].type == RM_REAL) {
                if (rm_get_real(u, &record_vr[i], 1, slot) != RM_OK)
                    return failed(mesh, u, "getReal", t);
            }
            else {
                int32_t n;
                if (rm_get_integer(u, &record_vr[i], 1, &n) != RM_OK)
                    return failed(mesh, u, "getInteger", t);
                *slot = (double)n;
            }
        }
        if (k == steps) break;
        double h = (double)(start_ns + (k + 1) * step_ns) / 1e9 - t;
        if (rm_get_real(mesh, MESH_OUT, 2, mesh_out) != RM_OK)
            return failed(mesh, mesh, "getReal", t);
        if (rm_set_real(drive, DRIVE_IN, 2, mesh_out) != RM_OK)
            return failed(mesh, drive, "setReal", t);
        if (rm_get_real(drive, DRIVE_OUT, 4, drive_out) != RM_OK)
            return failed(mesh, drive, "getReal", t);
        if (rm_set_real(mesh, MESH_IN, 4, drive_out) != RM_OK)
            return failed(mesh, mesh, "setReal", t);
        if (rm_do_step(mesh, t, h) == RM_ERROR) return failed(mesh, mesh, "doStep", t);
        if (rm_do_step(drive, t, h) == RM_ERROR) return failed(mesh, drive, "doStep", t);
        const RmStepLog* log = mesh->cls->step_log(mesh->model);
        for (size_t e = 0; e < log->n_events; e++) {
            const RmEvent* ev = &log->events[e];
            if (ev->kind != RM_EVENT_ONSET) continue;
            if (*n_onsets < onset_capacity) {
                double* row = &onsets[3 * *n_onsets];
                row[0] = t + ev->time;
                row[1] = ev->speed;
                row[2] = (double)ev->flank;
            }
            (*n_onsets)++;
        }
    }
    return RM_OK;
}
