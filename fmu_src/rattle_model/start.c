/*
 * start.c - the start solutions of the wheel: the static flank equilibrium for the initial
 * load (init.in_contact), or a given angle and speed checked against the pinion, and which
 * flank a state is in contact with.
 */
#include <string.h>

#include "rm_private.h"

/* Largest flank penetration [m] accepted in a start state given by wheel.phi_start: ten times
 * the penetrations of loaded operation; more means a wheel angle that does not match the
 * pinion's (the teeth would start deep inside each other). */
#define MAX_INITIAL_PENETRATION 10e-6
/* The static equilibrium: the first penetration [m] tried as the bracket's upper end (doubled
 * until it brackets), the largest searched, and Brent's tolerance on it. */
#define EQUILIBRIUM_FIRST_BRACKET 1e-9
#define EQUILIBRIUM_MAX_PENETRATION 1e-2
#define EQUILIBRIUM_XTOL 1e-18

/* The flank in contact for the wheel state against the pinion (phi_p, w_p, a_p) under
 * tau_load: the flank that penetrates (the current one first), or one exactly touching that
 * the motion drives into contact -- approaching, or at rest and accelerated towards it. */
int rm_contact_flank(const RmMesh* M, double phi_p, double w_p, double a_p, double tau_load,
                     const RmWheel* st)
{
    double accel_w = -tau_load / M->p.J_wheel; /* free wheel: no force at zero penetration */
    int order[3] = {st->flank, RM_DRIVE, RM_COAST};
    for (int i = 0; i < 3; i++) {
        int flank = order[i];
        if (flank == 0) continue;
        double pen = rm_penetration(M, flank, phi_p, st->phi);
        if (pen > 0.0) return flank;
        if (pen == 0.0) {
            double rate = rm_approach_rate(M, flank, w_p, st->w);
            if (rate > 0.0) return flank;
            if (rate == 0.0 && rm_approach_rate(M, flank, a_p, accel_w) > 0.0) return flank;
        }
    }
    return 0;
}

/* The wheel angle at which `flank` has penetration delta against the pinion at phi_p. */
static double wheel_angle(const RmMesh* M, int flank, double phi_p, double delta)
{
    double x = (double)flank * (M->g.half_backlash + delta);
    return (M->arm_pinion * phi_p - x) / M->arm_wheel;
}

typedef struct {
    const RmMesh* M;
    RmFail* f;
    RmPairCache cache;
    int flank;
    double phi_p, w_p, w_w, tau_load;
} Residual;

/* The mesh torque on the wheel minus the load, at penetration delta. */
static double equilibrium_residual(void* vctx, double delta)
{
    Residual* r = vctx;
    RmLoads L;
    double phi_w = wheel_angle(r->M, r->flank, r->phi_p, delta);
    rm_mesh_loads(r->M, r->f, &r->cache, r->flank, r->phi_p, r->w_p, phi_w, r->w_w, 0.0,
                  rm_resting_dissipation(r->M), NULL, NULL, 0, &L, NULL, 0);
    return L.tau_w - r->tau_load;
}

/* The penetration at which the mesh torque balances the load: 1, or 0 with the refusal (a
 * failure of the loads longjmps out through r->f). */
static int balance(Residual* r, double* delta, RmText* err)
{
    int flank = r->flank;
    double hi = EQUILIBRIUM_FIRST_BRACKET;
    double r_hi = equilibrium_residual(r, hi);
    while ((r_hi > 0.0) != (flank == RM_DRIVE) || r_hi == 0.0) {
        hi *= 2.0;
        if (hi > EQUILIBRIUM_MAX_PENETRATION) {
            rm_printf(err, "no static flank equilibrium for wheel.tau_load = %r N.m: the mesh "
                           "torque does not reach it within %.6r mm penetration (friction "
                           "dominates the normal force?); allowed: init.in_contact = false (a "
                           "free start)", r->tau_load, EQUILIBRIUM_MAX_PENETRATION * 1e3);
            return 0;
        }
        r_hi = equilibrium_residual(r, hi);
    }
    double r_0 = equilibrium_residual(r, 0.0);
    if ((r_0 >= 0.0) == (flank == RM_DRIVE))
        /* a load so small that the rounding-level penetration of the touching state (~1e-18 m)
         * already carries it: the flanks just touch */
        *delta = 0.0;
    else
        *delta = rm_brent(r->f, equilibrium_residual, r, 0.0, hi, r_0, r_hi, EQUILIBRIUM_XTOL,
                          RM_BRENT_RTOL);
    return 1;
}

int rm_equilibrium_start(const RmMesh* M, double phi_p, double w_p, double tau_load,
                         RmWheel* wheel, RmText* err)
{
    double w_w = w_p * M->g.ratio;
    memset(wheel, 0, sizeof *wheel);
    wheel->diss = rm_resting_dissipation(M);
    if (tau_load == 0.0) {
        wheel->phi = wheel_angle(M, RM_DRIVE, phi_p, 0.0);
        wheel->w = w_w;
        return 1;
    }
    RmFail f;
    Residual r;
    r.M = M;
    r.f = &f;
    rm_pair_cache_init(&r.cache);
    r.flank = tau_load > 0.0 ? RM_DRIVE : RM_COAST;
    r.phi_p = phi_p;
    r.w_p = w_p;
    r.w_w = w_w;
    r.tau_load = tau_load;
    double delta = 0.0;
    if (setjmp(f.jb) != 0) {
        rm_refusal_text(err, f.code, f.values);
        return 0;
    }
    if (!balance(&r, &delta, err)) return 0;
    wheel->phi = wheel_angle(M, r.flank, phi_p, delta);
    wheel->w = w_w;
    wheel->flank = r.flank;
    return 1;
}

int rm_free_start(const RmMesh* M, double phi_start, double w_start, double phi_p, double w_p,
                  double tau_load, RmWheel* wheel, RmText* err)
{
    memset(wheel, 0, sizeof *wheel);
    wheel->diss = rm_resting_dissipation(M);
    wheel->phi = phi_start;
    wheel->w = w_start;
    wheel->flank = rm_contact_flank(M, phi_p, w_p, 0.0, tau_load, wheel);
    double depth = rm_max(rm_penetration(M, RM_DRIVE, phi_p, phi_start),
                          rm_penetration(M, RM_COAST, phi_p, phi_start));
    if (depth > MAX_INITIAL_PENETRATION) {
        double half = M->g.half_backlash / M->arm_wheel;
        rm_printf(err, "parameter 'wheel.phi_start' = %r rad puts the flanks %.4r mm into each "
                       "other at pinion.phi = %r rad; allowed: within the backlash, "
                       "|wheel.phi_start - %.6r pinion.phi| <= %.4r rad (plus %.6r um), or "
                       "init.in_contact = true",
                  phi_start, depth * 1e3, phi_p, M->g.ratio, half,
                  MAX_INITIAL_PENETRATION * 1e6);
        return 0;
    }
    return 1;
}
