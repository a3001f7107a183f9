/*
 * dissipation.c - the dissipation of a contact, set at its onset (docs/model.md section 3.3):
 *
 *  - Hunt-Crossley (contact.dissipation 1, 2): one factor d for every contact (mesh.c builds it,
 *    from a restitution or given);
 *  - the squeeze-film impact law (3): a lubricated impact loses its approach speed in the oil
 *    film; its coefficient of restitution rises with the Stokes number St = m v / (6 pi eta A)
 *    from zero (no rebound) below a critical St_c to the dry restitution at large St (Davis,
 *    Rager and Good, J. Fluid Mech. 468, 2002; Gondret, Lance and Petit, Phys. Fluids 14,
 *    2002; the form e = e_dry (1 - St_c/St) of Mueller and Huang, Phys. Rev. E 93, 2016, and of
 *    lubrication theory).  Each impact's e(v) is realized exactly by the Hunt-Crossley factor
 *    that gives it at the impact's own speed (contact.c: e depends on d v alone); an impact
 *    below the critical Stokes number does not rebound: the stepper takes its approach speed
 *    away (all its kinetic energy on the tooth normal is lost in the film) and the contact goes
 *    on damped by the pairs' squeeze films at the roughness gap;
 *  - the mesh damping ratio (4): a viscous damping c = 2 zeta sqrt(k m_n) on the contact's
 *    linearized stiffness k = dW/d(delta), shared by the pairs in proportion to their
 *    stiffness (Kahraman and Singh, J. Sound Vib. 142, 1990; Oezgueven and Houser, J. Sound
 *    Vib. 121, 1988).
 */
#include "rm_private.h"

/* An impact whose law gives a restitution below this is taken as not rebounding: the
 * Hunt-Crossley factor for e -> 0 grows as 1/(e v) (a rebound of e v creeping out over a time
 * of order delta_max / (e v)); below 5e-4 the realized restitution (0) differs from the law
 * by less than that. */
#define STICK_RESTITUTION 5e-4

/* The squeeze-film area of a pair.  The rigid paraboloidal gap h = h0 + x^2/(2 r_x) +
 * y^2/(2 r_y) closing at the rate -dh0/dt carries the Reynolds pressure
 * p = 6 eta (-dh0/dt) R_e / h^2, R_e = r_x r_y / (r_x + r_y) (it satisfies
 * div(h^3 grad p) = 12 eta dh0/dt exactly and vanishes far away), whose resultant is
 * F = 12 pi eta (-dh0/dt) R_e sqrt(r_x r_y) / h0 = 6 pi eta A (-dh0/dt) / h0 with
 * A = 2 (r_x r_y)^(3/2) / (r_x + r_y): the sphere's a^2 = R^2 for r_x = r_y = R (Reynolds'
 * squeeze film, e.g. Hamrock, Schmid and Jacobson, Fundamentals of Fluid Film Lubrication,
 * 2004), 2 sqrt(r_x^3 r_y) for the elongated contact of crowned teeth. */
double rm_squeeze_pair_area(double r_x, double r_y)
{
    double g = sqrt(r_x * r_y);
    return 2.0 * (r_x * r_y) * g / (r_x + r_y);
}

/* The squeeze-film area of an unmodified pair in line contact (contact.geometry 2), as the
 * point contacts' law uses it.  A cylinder of radius R and length L at the gap
 * h = h0 + x^2/(2R) closing at the rate -dh0/dt carries the same Reynolds pressure
 * p = 6 eta R (-dh0/dt) / h^2 (d/dx(h^3 dp/dx) = 12 eta dh0/dt), whose resultant is
 * F = 3 sqrt(2) pi eta L R^(3/2) (-dh0/dt) / h0^(3/2): from the film's edge down to the
 * roughness h_c = sigma the approach loses m dv = 6 sqrt(2) pi eta phi L R^(3/2) / sqrt(sigma)
 * (the edge's h0 drops out), where a point contact loses 6 pi eta phi A ln(h0/h_c) =
 * 6 pi eta phi A St_c.  So a line pair enters the law e = e_dry (1 - St_c/St) with the area
 * A = sqrt(2) L R^(3/2) / (St_c sqrt(sigma)): its critical speed does not depend on St_c (0
 * without a film loss, St_c = 0). */
static double line_pair_area(const RmMeshParams* p, double r_x, double length)
{
    if (!(p->stokes_critical > 0.0)) return 0.0;
    return sqrt(2.0) * length * r_x * sqrt(r_x) / (p->stokes_critical * sqrt(p->sigma));
}

/* The pairs of `flank` whose crown offset is within the roughness of the first-touching pair's
 * (the smallest) touch first and squeeze their films down to it; the others keep a gap of at
 * least the difference.  (Unmodified flanks: every pair in the zone, at its line's area for
 * contact.geometry 2.)  Measured from the smallest offset, not from zero: where no pair's face
 * centre lies in the path of contact the first pair touches at an offset above zero, and
 * counting from zero could leave no film at all (St infinite, the dry restitution). */
double rm_squeeze_area(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank, double phi_p)
{
    RmPairSet* ps = rm_pairs_at(M, f, cache, rm_flank_roll(&M->g, flank, phi_p));
    double first = INFINITY, area = 0.0;
    for (int i = 0; i < ps->n; i++) first = rm_min(first, ps->offset[i]);
    for (int i = 0; i < ps->n; i++) {
        if (!(ps->offset[i] < first + M->p.sigma)) continue;
        rm_pair_coefficients(M, f, ps, i);
        area += M->g.layout == RM_LAYOUT_LINE
                    ? line_pair_area(&M->p, ps->r_x[i], ps->length[i])
                    : rm_squeeze_pair_area(ps->r_x[i], ps->r_y[i]); /* the crown's or eq. 6's */
    }
    return area;
}

/* St = m_n v / (6 pi eta phi A): the wheel's normal mass against the kinematic pinion, the
 * starved film's fraction phi (contact.squeeze_fraction) of the flooded squeeze force. */
double rm_stokes_number(const RmMesh* M, double v, double area)
{
    const RmMeshParams* p = &M->p;
    return M->normal_mass * v / (6.0 * RM_PI * p->eta * p->squeeze_fraction * area);
}

/* e(St) = e_dry (1 - St_c / St) above the critical Stokes number, 0 at and below it.  With the
 * approach slowed by the film, m dv = 6 pi eta A dh / h from the film's edge h_0 down to the
 * roughness h_c, an impact keeps v (1 - St_c/St) with St_c = ln(h_0/h_c) and then rebounds
 * with e_dry; measured restitutions of wet impacts fall linearly in 1/St in this way (Mueller
 * and Huang 2016), with St_c of order 10 for spheres in a liquid (Gondret et al. 2002). */
double rm_squeeze_restitution(const RmMeshParams* p, double St)
{
    if (!(St > p->stokes_critical)) return 0.0;
    return p->restitution_dry * (1.0 - p->stokes_critical / St);
}

RmContactDissipation rm_resting_dissipation(const RmMesh* M)
{
    RmContactDissipation out;
    out.d = M->damping;
    out.film = M->p.dissipation == RM_DISSIPATION_SQUEEZE;
    return out;
}

int rm_onset_dissipation(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank,
                         double phi_p, double v, RmContactDissipation* out)
{
    *out = rm_resting_dissipation(M);
    if (M->p.dissipation != RM_DISSIPATION_SQUEEZE) return 0;
    if (!(v > 0.0)) return 1; /* no approach: at rest on the film */
    double area = rm_squeeze_area(M, f, cache, flank, phi_p);
    double e = rm_squeeze_restitution(&M->p, rm_stokes_number(M, v, area));
    if (!(e >= STICK_RESTITUTION)) return 1;
    RmText err;
    rm_text_init(&err);
    double d = 0.0;
    int ok = rm_hunt_crossley_factor(e, v, &d, &err);
    rm_text_free(&err);
    if (!ok) rm_fail(f, RM_FAIL_NO_BRACKET, e, v, 0.0, 0.0);
    out->d = d;
    out->film = 0;
    return 0;
}

double rm_ratio_scale(const RmMesh* M, RmFail* f, RmPairSet* ps, double delta)
{
    if (M->p.dissipation != RM_DISSIPATION_RATIO || !(M->p.damping_ratio > 0.0)) return 0.0;
    double k = 0.0;
    for (int i = 0; i < ps->n; i++) {
        double pen = delta - ps->offset[i];
        if (pen > 0.0) {
            rm_pair_coefficients(M, f, ps, i);
            double k_i, c_i;
            rm_approach_rates(&M->approach, f, ps->K[i], ps->W_r[i], ps->c_t[i], pen, 0.0, &k_i,
                              &c_i);
            k += k_i;
        }
    }
    if (!(k > 0.0)) return 0.0;
    return 2.0 * M->p.damping_ratio * rm_sqrt_checked(f, M->normal_mass / k);
}

/* A pair's film damping engages linearly over its first RM_FILM_ENGAGEMENT sigma of
 * penetration (4 nm at the default roughness, against the 30-110 nm the default pair carries
 * its loads at) instead of at once: a pair that starts to carry load while the contact is in
 * the film state would otherwise add c times its approach rate as a step in the force, and
 * whether the located engagement counts the pair at the substep's start turns on the sign of a
 * penetration of a few ulps -- the outputs jumped by 5e-5 of the load under perturbations of
 * the inputs in their last bit (tests/model/test_conditioning.py).  A numerical
 * regularization, not a film law: a pair's film before its asperities touch is not modelled. */
const double RM_FILM_ENGAGEMENT = 0.01;

double rm_film_engagement_width(const RmMeshParams* p) { return RM_FILM_ENGAGEMENT * p->sigma; }

/* Film state: the pair's squeeze film at the roughness gap h_c = sigma, c = 6 pi eta phi A / h_c
 * (the film that stopped the impact goes on damping the contact's normal motion).  Mesh
 * damping ratio: the pair's share k_i / k of 2 zeta sqrt(k m_n), k_i = dW_i/d(pen) its
 * linearized stiffness from its load-approach law (3/2 K pen^(1/2) for smooth Hertz) -- so
 * small oscillations about any loaded state have the damping ratio zeta, and a single Hertz
 * impact's restitution depends on zeta alone, not on its speed. */
double rm_pair_viscous_damping(const RmMesh* M, int film, double r_x, double r_y,
                               double length, double k_i, double ratio_scale, double pen)
{
    const RmMeshParams* p = &M->p;
    if (film) {
        double scale = 6.0 * RM_PI * p->eta * p->squeeze_fraction;
        double engaged = rm_min(1.0, pen / rm_film_engagement_width(p));
        if (M->g.layout == RM_LAYOUT_LINE) /* 3 sqrt(2) pi eta phi L R^(3/2) / sigma^(3/2) */
            return engaged * 0.5 * sqrt(2.0) * scale * length * r_x * sqrt(r_x)
                   / (p->sigma * sqrt(p->sigma));
        return engaged * scale * rm_squeeze_pair_area(r_x, r_y) / p->sigma;
    }
    if (ratio_scale > 0.0) return ratio_scale * k_i;
    return 0.0;
}
