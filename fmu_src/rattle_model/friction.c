/*
 * friction.c - regime of lubrication and flank friction (paper eq. 12-17, read as
 * docs/model.md section 4 says).  The film of eq. 11 and the asperity area of eq. 13 are
 * evaluated per pair by the mesh model (mesh.c).
 */
#include "rm_private.h"

/* The proportion psi of the load carried by asperity (boundary) contact, eq. (12)-(15) read
 * continuously: 1 for lambda <= 1 (boundary), 0 for lambda >= 3 (full film), linear between.
 * The paper's psi = A_e/A in the mixed regime jumps at both limits (to A_e/A ~ 0.03 at
 * lambda = 1+, which cut the friction 38-fold); the linear share joins the boundary and
 * full-film readings of every friction form continuously. */
double rm_dry_fraction(double lam)
{
    if (lam <= RM_LAMBDA_BOUNDARY) return 1.0;
    if (lam >= RM_LAMBDA_FULL_FILM) return 0.0;
    return (RM_LAMBDA_FULL_FILM - lam) / (RM_LAMBDA_FULL_FILM - RM_LAMBDA_BOUNDARY);
}

/* The magnitude of the flank friction force [N], eq. (12) in the chosen reading:
 *   form 0 (load sharing, default): psi A_e tau_s + (1 - psi) A eta U / h -- boundary shear on
 *     the real asperity area of eq. (13), viscous shear of the film on the apparent area;
 *   form 1 (apparent area): A (psi tau_s + (1 - psi) eta U / h);
 *   form 2 (as printed): A_e (psi tau_s + (1 - psi) eta U / h).
 * The viscous term is evaluated only where psi < 1, which implies h > sigma > 0.  The form is
 * checked with the parameters (an unknown one gives no friction). */
double rm_friction_force(int form, double psi, double A_e, double A, double tau_s, double eta,
                         double U, double h)
{
    double viscous = psi < 1.0 ? eta * fabs(U) / h : 0.0;
    switch (form) {
    case RM_FORM_LOAD_SHARING: return psi * A_e * tau_s + (1.0 - psi) * A * viscous;
    case RM_FORM_APPARENT_AREA: return A * (psi * tau_s + (1.0 - psi) * viscous);
    case RM_FORM_AS_PRINTED: return A_e * (psi * tau_s + (1.0 - psi) * viscous);
    default: return 0.0;
    }
}
