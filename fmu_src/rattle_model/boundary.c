/*
 * boundary.c - how a unit reads the inputs a master holds or did not exchange during
 * initialization (its boundary, RmBoundary): the inputs at the end of initialization, whether
 * the first step is still to come, the motion inputs of the last step, whether the master
 * holds them now, and the warning of a first step on other inputs than initialization's.
 * Both kinds of unit read them (unit_mesh.c, unit_driveline.c); their record is record.c's.
 */
#include "rm_private.h"

void rm_boundary_start(const RmUnit* u, RmBoundary* b)
{
    for (int k = 0; k < u->cls->n_start; k++) b->initial_inputs[k] = u->values[u->cls->start_vr[k]].r;
    b->first_step = 1;
    b->has_last_motion = 0;
    for (int k = 0; k < 4; k++) b->last_motion[k] = 0.0;
}

int rm_motion_held(const RmUnit* u, const RmBoundary* b)
{
    if (!u->motion_set) return 1;
    if (!b->has_last_motion) return 0;
    for (int k = 0; k < u->cls->n_motion; k++)
        if (!(u->values[u->cls->motion_vr[k]].r == b->last_motion[k])) return 0;
    return 1;
}

void rm_motion_step_done(RmUnit* u, RmBoundary* b)
{
    for (int k = 0; k < u->cls->n_motion; k++) b->last_motion[k] = u->values[u->cls->motion_vr[k]].r;
    b->has_last_motion = 1;
    b->first_step = 0;
    u->motion_set = 0;
}

int rm_first_step_differs(const RmBoundary* b, int settle, const double* values, int n)
{
    if (!b->first_step || !settle) return 0;
    for (int k = 0; k < n; k++)
        if (values[k] != b->initial_inputs[k]) return 1;
    return 0;
}

void rm_settled_warning(const RmUnit* u, const RmBoundary* b, const double* given,
                        const char* what, RmText* t)
{
    RmText now, before; /* the two lists of the inputs, each comma-separated */
    rm_text_init(&now);
    rm_text_init(&before);
    for (int k = 0; k < u->cls->n_start; k++) {
        const RmVariable* v = &u->variables[u->cls->start_vr[k]];
        rm_printf(&now, "%s%s = %r %s", k ? ", " : "", v->name, given[k], v->unit);
        rm_printf(&before, "%s%r", k ? ", " : "", b->initial_inputs[k]);
    }
    rm_printf(t, "doStep at the first step: the inputs (%s) differ from those at the end of "
                 "initialization (%s): %s (init.settle_first_step; a master that exchanges no "
                 "values during initialization)", rm_text_str(&now), rm_text_str(&before), what);
    if (now.failed || before.failed) t->failed = 1; /* a list is incomplete */
    rm_text_free(&now);
    rm_text_free(&before);
}
