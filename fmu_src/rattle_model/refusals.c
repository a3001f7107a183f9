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

/* What a libm call of the physics that has no finite result means (RM_FAIL_MATH). */
#define NO_FINITE_RESULT                                                                        \
    " has no finite real result: the inputs or parameters are beyond what the integrator "      \
    "resolves (reduce solver.h_max or the communication step)"

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
        rm_printf(t, "the step diverged (wheel angle %r rad, speed %r rad/s); the inputs or "
                     "parameters are beyond what the integrator resolves (reduce solver.h_max or "
                     "the communication step)", v[0], v[1]);
        return;
    case RM_FAIL_PENETRATION:
        rm_printf(t, "the flanks would penetrate %.4r mm in this step, beyond the validity of the "
                     "Hertz contact (allowed: %.4r mm = %r gear.m_n); the inputs drive the teeth "
                     "into each other far harder than any transmission (check wheel.tau_load and "
                     "the pinion kinematics, or reduce the communication step)",
                  v[0] * 1e3, v[1] * 1e3, RM_MAX_PENETRATION_MODULES);
        return;
    case RM_FAIL_TOO_STIFF: /* v: fastest rate [1/s], the budget's substeps, h */
        rm_printf(t, "the contact is too stiff to resolve in this step: the flanks are pressed so "
                     "deep into each other that its fastest time scale falls to %.3r s, which "
                     "would take more than the step's budget of %r substeps (%r per 1e-4 s of "
                     "the step); reduce the communication step, the impact speed (inputs) or "
                     "contact.damping, or raise wheel.J",
                  1.0 / v[0], v[1], (double)RM_WORK_SUBSTEPS);
        return;
    case RM_FAIL_NO_BRACKET:
        rm_printf(t, "Brent's method: f(%r) = %r and f(%r) = %r do not bracket a root",
                  v[0], v[1], v[2], v[3]);
        return;
    case RM_FAIL_MATH:
        if ((int)v[0] == RM_MATH_POW)
            rm_printf(t, "pow(%r, %r)%s", v[1], v[2], NO_FINITE_RESULT);
        else
            rm_printf(t, "%s(%r)%s", math_call((int)v[0]), v[1], NO_FINITE_RESULT);
        return;
    case RM_FAIL_TOO_MANY_PAIRS:
        rm_printf(t, "more than %d tooth pairs in the zone of action", (int)v[0]);
        return;
    case RM_FAIL_PAIR_RANGE:
        rm_printf(t, "roll coordinate %r m beyond the model's range (pair number %r; |pinion "
                     "angle| too large)", v[0], v[1]);
        return;
    case RM_FAIL_NO_PROGRESS:
        rm_printf(t, "the step makes no progress at t = %r s (the integrator is stuck; reduce "
                     "solver.h_max or the communication step)", v[0]);
        return;
    case RM_FAIL_SUBSTEPS: /* v: h, substeps, the budget's substeps */
        rm_printf(t, "step size h = %r s needs %r substeps of solver.h_max, more than the step's "
                     "budget of %r substeps (%r per 1e-4 s of the step); raise solver.h_max or "
                     "reduce the step", v[0], v[1], v[2], (double)RM_WORK_SUBSTEPS);
        return;
    case RM_FAIL_WORK: /* v: time in the step, the budget's substeps and evaluations by then, h */
        rm_printf(t, "the step does more work than its budget allows: %r s into this step of %r s "
                     "it took more than %r substeps or %r evaluations of the mesh's loads "
                     "(allowed: %r and %r per 1e-4 s of the step, one 1e-4 s's from its start); "
                     "the inputs move the teeth faster than the contact can be resolved in time "
                     "(check the pinion's inputs, or reduce the communication step or raise "
                     "solver.h_max)", v[0], v[3], v[1], v[2], (double)RM_WORK_SUBSTEPS,
                  (double)RM_WORK_EVALUATIONS);
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
