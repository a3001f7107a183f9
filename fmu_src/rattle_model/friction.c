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

/* The least sliding speed [m/s] over which the friction of a sticking pair turns from one
 * direction to the other: a creep speed far below the mesh's sliding speeds (0.1-1 m/s) and
 * the rattle's approach speeds (mm/s).  The stepper widens it where the regularized
 * friction's time scale J v / (F rho_w^2) would be shorter than its substeps resolve
 * (docs/model.md section 5). */
const double RM_STICK_SPEED = 1e-6;

/* The central film thickness of the loaded pair as an isothermal, fully flooded
 * elastohydrodynamic point contact (Hamrock and Dowson, J. Lubr. Technol. 99, 1977):
 *   h_c / r_x = 2.69 U^0.67 G^0.53 Wd^-0.067 (1 - 0.61 exp(-0.73 k)),
 *   U = eta |u| / (E' r_x),  G = alpha E',  Wd = W / (E' r_x^2),  k = 1.03 (r_y / r_x)^0.64,
 * E' = 2 E*, r_x the radius in the rolling direction (across the contact line).  Fitted for
 * k of 1 to 8; the crowned flanks' k ~ 100 takes the fit's long-contact limit (the bracket
 * -> 1).  The film the entrainment builds in a loaded pair, which the eq. 11 reading of the
 * paper (rigid gap plus the impact's delta_max) leaves out; with alpha = 0 (G = 0) it is 0. */
double rm_ehl_central_film(double u, double W, double r_x, double r_y, double E_star,
                           double eta, double alpha)
{
    double E2 = 2.0 * E_star;
    double U = eta * fabs(u) / (E2 * r_x);
    double G = alpha * E2;
    double Wd = W / (E2 * r_x * r_x);
    double k = 1.03 * rm_pow(r_y / r_x, 0.64);
    return r_x * 2.69 * rm_pow(U, 0.67) * rm_pow(G, 0.53) * rm_pow(Wd, -0.067)
           * (1.0 - 0.61 * exp(-0.73 * k));
}

/* The shear stress of the film in the viscous term of eq. (12), at the pair's mean Hertz
 * pressure p, shear speed U and film thickness h > 0:
 *   law 0 (the paper): Newtonian and isoviscous, eta |U| / h;
 *   law 1: piezoviscous after Barus (1893), eta(p) = eta exp(alpha p), bounded by the limiting
 *     shear stress tau_L = tau_L0 + gamma_L p in Bair and Winer's (1979) form
 *     tau = tau_L (1 - exp(-eta(p) |U| / (h tau_L))): eta(p) |U| / h at low shear, tau_L at
 *     high.  Written as -tau_L expm1(-x) with x from its logarithm, so that an overflowing
 *     exp(alpha p) gives tau_L, not inf * 0. */
double rm_viscous_stress(int law, double eta, double alpha, double tau_limit_0,
                         double tau_limit_slope, double p, double U, double h)
{
    if (law != RM_VISCOUS_BARUS_LIMITED) return eta * fabs(U) / h;
    double shear = fabs(U);
    if (shear == 0.0) return 0.0;
    double tau_L = tau_limit_0 + tau_limit_slope * p;
    double x = exp(alpha * p + log(eta * shear / (h * tau_L)));
    return -tau_L * expm1(-x);
}

/* The magnitude of the flank friction force [N], eq. (12) in the chosen reading, with
 * tau_viscous the film's shear stress (rm_viscous_stress):
 *   form 0 (load sharing, default): psi A_e tau_s + (1 - psi) A tau_viscous -- boundary shear
 *     on the real asperity area of eq. (13), viscous shear of the film on the apparent area;
 *   form 1 (apparent area): A (psi tau_s + (1 - psi) tau_viscous);
 *   form 2 (as printed): A_e (psi tau_s + (1 - psi) tau_viscous).
 * The viscous stress is evaluated only where psi < 1, which implies h > sigma > 0 (else it is
 * 0).  The form is checked with the parameters (an unknown one gives no friction). */
double rm_friction_force(int form, double psi, double A_e, double A, double tau_s,
                         double tau_viscous)
{
    double viscous = tau_viscous;
    switch (form) {
    case RM_FORM_LOAD_SHARING: return psi * A_e * tau_s + (1.0 - psi) * A * viscous;
    case RM_FORM_APPARENT_AREA: return A * (psi * tau_s + (1.0 - psi) * viscous);
    case RM_FORM_AS_PRINTED: return A_e * (psi * tau_s + (1.0 - psi) * viscous);
    default: return 0.0;
    }
}

/* The friction direction of a pair that sticks (its friction could hold the sliding speed at
 * zero; stepper.c decides): v_s / v clamped to [-1, 1] with v its stick speed, so that the
 * friction turns continuously instead of chattering between +F and -F (the regularization of
 * Karnopp-type stick-slip models), and its power -F |v_s| min(1, |v_s| / v) never creates
 * energy. */
double rm_stick_direction(double v_s, double v)
{
    double x = v_s / v;
    return x > 1.0 ? 1.0 : (x < -1.0 ? -1.0 : x);
}
