/*
 * refusals.c - the wording of the refusals the physics reports as a code and its numbers
 * (RM_FAIL_...), written once for every face, and the failure exit itself.
 */
#include <stdio.h>
#include <stdlib.h>

#include "rm_private.h"

void rm_fail(RmFail* f, int code, double v0, double v1, double v2, double v3)
{
    f->code = code;
    f->values[0] = v0;
    f->values[1] = v1;
    f->values[2] = v2;
    f->values[3] = v3;
    longjmp(f->jb, 1);
}

static const char* math_call(int which)
{
    switch (which) {
    case RM_MATH_POW: return "pow";
    case RM_MATH_SQRT: return "sqrt";
    case RM_MATH_LOG: return "log";
    case RM_MATH_EXP: return "exp";
    case RM_MATH_FLOOR: return "floor";
    case RM_MATH_CEIL: return "ceil";
    default: return "an integer conversion";
    }
}

void rm_refusal_text(RmText* t, int code, const double* v)
{
    switch (code) {
    case RM_FAIL_DIVERGED:
        rm_puts(t, "the step diverged (wheel angle ");
        rm_put_number(t, v[0]);
        rm_puts(t, " rad, speed ");
        rm_put_number(t, v[1]);
        rm_puts(t, " rad/s); the inputs or parameters are beyond what the integrator resolves "
                   "(reduce solver.h_max or the communication step)");
        return;
    case RM_FAIL_PENETRATION:
        rm_puts(t, "the flanks would penetrate ");
        rm_put_g(t, v[0] * 1e3, 4);
        rm_puts(t, " mm in this step, beyond the validity of the Hertz contact (allowed: ");
        rm_put_g(t, v[1] * 1e3, 4);
        rm_puts(t, " mm = ");
        rm_put_number(t, RM_MAX_PENETRATION_MODULES);
        rm_puts(t, " gear.m_n); the inputs drive the teeth into each other far harder than any "
                   "transmission (check wheel.tau_load and the pinion kinematics, or reduce the "
                   "communication step)");
        return;
    case RM_FAIL_TOO_STIFF: /* v: fastest rate [1/s], the budget's substeps, h */
        rm_puts(t, "the contact is too stiff to resolve in this step: the flanks are pressed so "
                   "deep into each other that its fastest time scale falls to ");
        rm_put_g(t, 1.0 / v[0], 3);
        rm_puts(t, " s, which would take more than the step's budget of ");
        rm_put_number(t, v[1]);
        rm_puts(t, " substeps (");
        rm_put_number(t, (double)RM_WORK_SUBSTEPS);
        rm_puts(t, " per 1e-4 s of the step); reduce the communication step, the impact speed "
                   "(inputs) or contact.damping, or raise wheel.J");
        return;
    case RM_FAIL_NO_BRACKET:
        rm_puts(t, "Brent's method: f(");
        rm_put_number(t, v[0]);
        rm_puts(t, ") = ");
        rm_put_number(t, v[1]);
        rm_puts(t, " and f(");
        rm_put_number(t, v[2]);
        rm_puts(t, ") = ");
        rm_put_number(t, v[3]);
        rm_puts(t, " do not bracket a root");
        return;
    case RM_FAIL_MATH:
        rm_printf(t, "%s(", math_call((int)v[0]));
        rm_put_number(t, v[1]);
        if ((int)v[0] == RM_MATH_POW) {
            rm_puts(t, ", ");
            rm_put_number(t, v[2]);
        }
        rm_puts(t, ") has no finite real result: the inputs or parameters are beyond what the "
                   "integrator resolves (reduce solver.h_max or the communication step)");
        return;
    case RM_FAIL_TOO_MANY_PAIRS:
        rm_printf(t, "more than %d tooth pairs in the zone of action", (int)v[0]);
        return;
    case RM_FAIL_PAIR_RANGE:
        rm_puts(t, "roll coordinate ");
        rm_put_number(t, v[0]);
        rm_puts(t, " m beyond the model's range (pair number ");
        rm_put_number(t, v[1]);
        rm_puts(t, "; |pinion angle| too large)");
        return;
    case RM_FAIL_NO_PROGRESS:
        rm_puts(t, "the step makes no progress at t = ");
        rm_put_number(t, v[0]);
        rm_puts(t, " s (the integrator is stuck; reduce solver.h_max or the communication "
                   "step)");
        return;
    case RM_FAIL_SUBSTEPS: /* v: h, substeps, the budget's substeps */
        rm_puts(t, "step size h = ");
        rm_put_number(t, v[0]);
        rm_puts(t, " s needs ");
        rm_put_number(t, v[1]);
        rm_puts(t, " substeps of solver.h_max, more than the step's budget of ");
        rm_put_number(t, v[2]);
        rm_puts(t, " substeps (");
        rm_put_number(t, (double)RM_WORK_SUBSTEPS);
        rm_puts(t, " per 1e-4 s of the step); raise solver.h_max or reduce the step");
        return;
    case RM_FAIL_WORK: /* v: time in the step, the budget's substeps and evaluations by then, h */
        rm_puts(t, "the step does more work than its budget allows: ");
        rm_put_number(t, v[0]);
        rm_puts(t, " s into this step of ");
        rm_put_number(t, v[3]);
        rm_puts(t, " s it took more than ");
        rm_put_number(t, v[1]);
        rm_puts(t, " substeps or ");
        rm_put_number(t, v[2]);
        rm_puts(t, " evaluations of the mesh's loads (allowed: ");
        rm_put_number(t, (double)RM_WORK_SUBSTEPS);
        rm_puts(t, " and ");
        rm_put_number(t, (double)RM_WORK_EVALUATIONS);
        rm_puts(t, " per 1e-4 s of the step, one 1e-4 s's from its start); the inputs move the "
                   "teeth faster than the contact can be resolved in time (check the pinion's "
                   "inputs, or reduce the communication step or raise solver.h_max)");
        return;
    case RM_FAIL_PAIR_LEFT:
        rm_puts(t, "a tooth pair left the zone of action while its engagement was located "
                   "(reduce solver.h_max)");
        return;
    default:
        rm_printf(t, "internal refusal %d", code);
        return;
    }
}
