/*
 * pairs.c - the tooth pairs in the zone of action at a roll coordinate (geometry.c's pair
 * set), with the radii and the load-approach law's coefficients of each (contact.c,
 * compliance.c), kept in a small cache per step.  What the mesh's loads (mesh.c) and the
 * contact's dissipation (dissipation.c) both read: it is here, below both, so that neither
 * calls the other for it.
 */
#include "rm_private.h"

/* The integrator evaluates the pairs twice at t + h/2 of each RK4 step and at the start of a
 * substep for the right-hand side, the substep length and the friction directions, so a step
 * keeps a few pair sets: each value is computed by the same expression as without the cache,
 * only fewer times. */
void rm_pair_cache_init(RmPairCache* c)
{
    c->n_used = c->next = 0;
    c->member = NAN;
}

RmPairSet* rm_pairs_at(const RmMesh* M, RmFail* f, RmPairCache* c, double u)
{
    double member = isnan(c->member) || M->g.layout == RM_LAYOUT_CROWNED ? u : c->member;
    for (int i = 0; i < c->n_used; i++)
        if (c->set[i].u == u && c->set[i].member == member) return &c->set[i];
    RmPairSet* ps = &c->set[c->next];
    c->next = (c->next + 1) % RM_PAIR_CACHE;
    if (c->n_used < RM_PAIR_CACHE) c->n_used++;
    ps->u = NAN; /* invalid while being built (a failing build longjmps out) */
    rm_pair_set_build(&M->g, f, u, member, ps);
    return ps;
}

/* The radii and the load-approach law's coefficients of pair i: r_x at its contact point, r_y
 * (the crown's, eq. 6's, or none for a line), K of its smooth law, the ellipse's ka and the
 * area coefficient kz, the asperity layer's load scale W_r (rough flanks) and the teeth's
 * compliance c_t over its engaged contact line (0: rigid teeth). */
void rm_pair_coefficients(const RmMesh* M, RmFail* f, RmPairSet* ps, int i)
{
    if (ps->coefficients_ok[i]) return;
    double R;
    const RmApproachLaw* a = &M->approach;
    double r_x = rm_radius_x(&M->g, ps->s[i]);
    ps->r_x[i] = r_x;
    if (M->g.layout == RM_LAYOUT_LINE) {
        double L = ps->length[i];
        ps->r_y[i] = 0.0;
        ps->K[i] = L > 0.0 ? rm_line_coefficient(a, f, L) : 0.0;
        ps->ka[i] = 0.0;
        ps->kz[i] = rm_line_area_coefficient(a, f, r_x, L);
    }
    else if (M->g.layout == RM_LAYOUT_PAPER) {
        ps->r_y[i] = rm_radius_y_eq6(&M->g, ps->s[i]);
        rm_contact_law_at_radii(&M->law, f, r_x, ps->r_y[i], &ps->K[i], &R, &ps->ka[i],
                                &ps->kz[i]);
    }
    else {
        ps->r_y[i] = M->law.r_y;
        rm_contact_law_at(&M->law, f, r_x, &ps->K[i], &R, &ps->ka[i], &ps->kz[i]);
    }
    ps->W_r[i] = a->rough && ps->K[i] > 0.0
                     ? rm_asperity_scale(a, f, r_x, ps->r_y[i], ps->length[i])
                     : 0.0;
    ps->c_t[i] = rm_tooth_pair_compliance(&M->tooth, ps->s[i], ps->length[i]);
    ps->coefficients_ok[i] = 1;
}
