/*
 * rm_probe.h - the model's laws at given arguments, for the tests that hold them against
 * closed forms and the readable equations (tests/oracle).  Test-only (probe.c): in the model
 * library the Python API and the tests load, in no shipped FMU's binary; the Python binding
 * binds them where the library has them (drive_rattle.library).  The unit's parameters are
 * checked first.
 */
#ifndef RM_PROBE_H
#define RM_PROBE_H

#include "rattle_model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Contact law at the contact radius r_x: K [N/m^1.5], R [m], ka, kz (a = ka W^(1/3),
 * A = kz W^(2/3)); crowned flanks (contact.geometry = 0) only, whose pairs share r_y. */
RM_API int rm_probe_contact_law(RmUnit* u, double r_x, double* out4);
/* The exact elliptical contact for the radius ratio rho >= 1: q, kappa, alpha, zeta. */
RM_API int rm_probe_exact_ellipse(RmUnit* u, double rho, double* out4);
/* Hunt-Crossley restitution e(alpha) and the factor d(e, v). */
RM_API int rm_probe_restitution(RmUnit* u, double alpha, double* e);
RM_API int rm_probe_damping_factor(RmUnit* u, double e, double v, double* d);
/* The pairs in the zone of action on `flank` at pinion angle phi_p: per pair (slot, s, g,
 * dg) into out (4 doubles each, at most `capacity` pairs); *count their number. */
RM_API int rm_probe_pairs(RmUnit* u, int flank, double phi_p, double* out, size_t capacity,
                          size_t* count);
/* Mesh loads on `flank`: totals (delta, tau_wheel, tau_pinion, W, F) in totals[5] and per
 * pair (slot, s, offset, r_x, K, delta, W, F, v_s, u, h, lambda, psi, delta_max) in pairs
 * (14 doubles each, at most `capacity`); *count their number. */
RM_API int rm_probe_loads(RmUnit* u, int flank, double phi_p, double w_p, double phi_w,
                          double w_w, double v_impact, double* totals, double* pairs,
                          size_t capacity, size_t* count);
/* The load-approach law's coefficients of the pairs in the zone of action on `flank` at pinion
 * angle phi_p: per pair (slot, s, length of the engaged contact line, r_x, r_y, K, ka, kz, W_r,
 * c_t the teeth's compliance) into out (10 doubles each, at most `capacity` pairs); *count
 * their number. */
RM_API int rm_probe_pair_laws(RmUnit* u, int flank, double phi_p, double* out,
                              size_t capacity, size_t* count);
/* The pair's load-approach law of the unit's parameters (contact.geometry: point or line;
 * contact.roughness) for the coefficients K, W_r, the teeth's compliance c_t [m/N] (0: rigid)
 * and kz at the approach pen > 0: the load W [N], the stiffness dW/d(pen) [N/m], the elastic
 * energy integral_0^pen W [J], the area at W [m^2] and the flanks' own approach pen - c_t W
 * [m], into out5. */
RM_API int rm_probe_approach(RmUnit* u, double K, double W_r, double c_t, double kz,
                             double pen, double* out5);
/* The squeeze-film impact law (contact.dissipation = 3) for an impact on `flank` at pinion
 * angle phi_p with normal speed v: the squeeze-film area A [m^2], the Stokes number, the law's
 * restitution e, and the contact's Hunt-Crossley factor d [s/m] and 1 if the impact does not
 * rebound (else 0) as the onset sets them, into out5.  rm_probe_loads takes the contact's
 * dissipation as such an onset at v_impact sets it. */
RM_API int rm_probe_squeeze(RmUnit* u, int flank, double phi_p, double v, double* out5);

#ifdef __cplusplus
}
#endif

#endif
