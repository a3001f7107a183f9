/*
 * mesh.c - the mesh model: Hertzian normal force and flank friction of every tooth pair in
 * contact, and the torques they put on the wheel and the pinion (paper eq. 1-2, 10-17 as read
 * in docs/model.md).
 *
 * The rigid-body approach along the tooth normal is common to the pairs of a flank:
 *     x     = cos(beta_b) (rb_p phi_p - rb_w phi_w)        (> 0 when the pinion leads)
 *     delta = flank x - backlash / 2                       (penetration; < 0 is a gap)
 * Each pair touches at its own point with its own crown offset g_i (geometry.c; zero on
 * unmodified flanks), so its penetration is delta_i = delta - g_i, and it carries the load of
 * its load-approach law (contact.c) with the contact's dissipation (dissipation.c) on its own
 * penetration rate: Hunt-Crossley,
 *     W_i = W(delta_i) (1 + d d(delta_i)/dt),   W_i >= 0,
 * or a viscous damping c_i (squeeze film after a sticking impact, mesh damping ratio),
 *     W_i = W(delta_i) + c_i d(delta_i)/dt,    W_i >= 0,
 * W(delta) = K_i delta^(3/2) for smooth point contacts, K_i from the contact law at the pair's
 * radii, in series with the teeth's compliance c_i (compliance.c): delta = x + c_i W(x).  The
 * dissipation acts on the pair's whole approach delta_i (the mesh damping of gear dynamics),
 * the film's thickness (eq. 11) on the flanks' own approach x.  Torques (each gear positive forward), F_i the
 * pair's friction force and sgn_i the sign of its sliding speed:
 *     wheel:   tau_w = sum_i  flank W_i cos(beta_b) rb_w + sgn_i F_i rho_w,i
 *     pinion:  tau_p = sum_i -flank W_i cos(beta_b) rb_p - sgn_i F_i rho_p,i
 */
#include "rm_private.h"

int rm_mesh_build(const RmMeshParams* p, RmMesh* m, RmText* err)
{
    m->p = *p;
    if (!rm_geometry(&p->gear, &m->g, err)) return 0;
    if (!rm_tooth_compliance_build(p, &m->g, &m->tooth, err)) return 0;
    /* the EHL film is Hamrock and Dowson's point-contact film (friction.c): a line contact's
     * film follows another law, not in this model */
    if (m->g.layout == RM_LAYOUT_LINE && p->film == RM_FILM_EHL) {
        rm_printf(err, "parameter 'contact.geometry' = %d (line contact of unmodified flanks) "
                       "with lubricant.film = 1 (EHL film): the film law is derived for point "
                       "contacts; allowed: contact.geometry = 0 or 1 with it, or "
                       "lubricant.film = 0 with the line contact", p->gear.layout);
        return 0;
    }
    m->E_star = rm_effective_modulus(p->E_pinion, p->nu_pinion, p->E_wheel, p->nu_wheel);
    double x_lo, x_hi;
    if (m->g.layout == RM_LAYOUT_LINE) { /* Palmgren's law: no elliptical contact to tabulate */
        if (!rm_contact_law_build(RM_LAW_EQUIVALENT_SPHERE, m->E_star, m->g.r_y, 0.0, 0.0,
                                  &m->law, err))
            return 0;
    }
    else {
        rm_radius_ratio_range(&m->g, m->g.r_y, &x_lo, &x_hi);
        if (!rm_contact_law_build(p->hertz_law, m->E_star, m->g.r_y, x_lo, x_hi, &m->law, err))
            return 0;
    }
    rm_approach_law_build(&m->approach, m->g.layout == RM_LAYOUT_LINE, p->roughness != 0,
                          m->E_star, p->sigma, p->gamma, p->asperity_density);
    m->damping = 0.0;
    if (p->dissipation == RM_DISSIPATION_RESTITUTION) {
        if (!rm_hunt_crossley_factor(p->restitution, p->restitution_speed, &m->damping, err))
            return 0;
    }
    else if (p->dissipation == RM_DISSIPATION_FACTOR)
        m->damping = p->damping;
    /* the squeeze-film law divides by St and realizes e(v) through a Hunt-Crossley factor of
     * e in (0, 1]: e_dry > 0 and the film's viscosity, fraction and roughness are positive
     * (their ranges) */
    /* arms of the normal force about each axis: cos(beta_b) times the base radius */
    m->arm_wheel = m->g.normal_factor * m->g.rb_wheel;
    m->arm_pinion = m->g.normal_factor * m->g.rb_pinion;
    /* the wheel's effective mass along the tooth normal (energy-consistent) */
    m->normal_mass = p->J_wheel / rm_pow(m->arm_wheel, 2.0);
    m->pen_limit = RM_MAX_PENETRATION_MODULES * p->gear.m_n;
    m->sqrt_gamma_sigma = sqrt(p->gamma / p->sigma);
    return 1;
}

/* ------------------------------------------------------------------ the pair cache */
/* eq. 7 delta_max of pair i (coefficients computed) for the impact speed v. */
static inline double pair_d_max(const RmMesh* M, RmFail* f, RmPairSet* ps, int i, double v)
{
    if (!(v == ps->d_max_v)) {
        for (int k = 0; k < ps->n; k++) ps->d_max_ok[k] = 0;
        ps->d_max_v = v;
    }
    if (!ps->d_max_ok[i] || v != v) {
        ps->d_max[i] = rm_approach_film_delta_max(&M->approach, f, v, ps->K[i], ps->r_x[i],
                                                  ps->ka[i], ps->length[i], M->p.density);
        ps->d_max_ok[i] = 1;
    }
    return ps->d_max[i];
}

/* The rate [m/s] at which a pair's crown offset grows: dg/ds_n times the roll speed of its
 * face centre, flank rb_p w_p. */
static inline double pair_rate(const RmMesh* M, int flank, double w_p, double dg)
{
    return dg * ((double)flank * M->g.rb_pinion * w_p);
}

/* ------------------------------------------------------------------ loads */
void rm_mesh_loads(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank, double phi_p,
                   double w_p, double phi_w, double w_w, double v_impact,
                   RmContactDissipation diss, const double* signs, const double* stick_speeds,
                   int detail, RmLoads* out, double* pairs, size_t capacity)
{
    const RmMeshParams* p = &M->p;
    double delta = rm_penetration(M, flank, phi_p, phi_w);
    out->delta = delta;
    out->tau_w = out->tau_p = out->W = out->F = 0.0;
    out->n_pairs = 0;
    if (detail) {
        out->n_loaded = 0;
        out->top_W = out->top_h = out->top_lam = out->top_psi = 0.0;
        for (int k = 0; k < RM_MAX_PAIR_SLOTS; k++) out->forces[k] = 0.0;
    }
    if (delta <= 0.0) return;
    double delta_dot = rm_approach_rate(M, flank, w_p, w_w);
    double damping = diss.d;
    double E_star = M->E_star;
    double tau_w = 0.0, tau_p = 0.0, W_sum = 0.0, F_net = 0.0;
    RmPairSet* ps = rm_pairs_at(M, f, cache, rm_flank_roll(&M->g, flank, phi_p));
    double ratio_scale = rm_ratio_scale(M, f, ps, delta);
    int viscous = diss.film || ratio_scale > 0.0;
    for (int i = 0; i < ps->n; i++) {
        int64_t slot = ps->slot[i];
        double s = ps->s[i];
        double pen = delta - ps->offset[i];
        double W = 0.0, F = 0.0, v_s = 0.0, u = 0.0, h = 0.0, lam = 0.0, psi = 0.0, d_max = 0.0;
        if (pen <= 0.0) {
            if (detail) out->forces[slot] = 0.0;
            if (pairs != NULL && (size_t)out->n_pairs < capacity) {
                rm_pair_coefficients(M, f, ps, i);
                double* row = pairs + RM_PAIR_DETAIL * (size_t)out->n_pairs;
                for (int k = 0; k < RM_PAIR_DETAIL; k++) row[k] = 0.0;
                row[0] = (double)slot;
                row[1] = s;
                row[2] = ps->offset[i];
                row[3] = ps->r_x[i];
                row[4] = ps->K[i];
                row[5] = pen;
                out->n_pairs++;
            }
            continue;
        }
        rm_pair_coefficients(M, f, ps, i);
        double K = ps->K[i];
        double surface; /* the flanks' own approach: pen less the teeth's deflection */
        W = rm_approach_force(&M->approach, f, K, ps->W_r[i], ps->c_t[i], pen, &surface);
        if (damping > 0.0) {
            W *= 1.0 + damping * (delta_dot - pair_rate(M, flank, w_p, ps->dg[i]));
            if (W < 0.0) W = 0.0; /* the flanks never pull on each other */
        }
        else if (viscous) {
            double k_i = 0.0, c_i;
            if (ratio_scale > 0.0)
                rm_approach_rates(&M->approach, f, K, ps->W_r[i], ps->c_t[i], pen, 0.0, &k_i,
                                  &c_i);
            double c = rm_pair_viscous_damping(M, diss.film, ps->r_x[i], ps->r_y[i],
                                               ps->length[i], k_i, ratio_scale, pen);
            W += c * (delta_dot - pair_rate(M, flank, w_p, ps->dg[i]));
            if (W < 0.0) W = 0.0;
        }
        tau_w += (double)flank * W * M->arm_wheel;
        tau_p -= (double)flank * W * M->arm_pinion;
        W_sum += W;
        double rho_p = s, rho_w = M->g.line_length - s;
        v_s = w_p * rho_p - w_w * rho_w;       /* sliding speed, changes sign at the pitch point */
        u = 0.5 * (w_p * rho_p + w_w * rho_w); /* entrainment (mean rolling) speed, eq. 16-17 */
        if ((p->friction_enabled || detail) && W > 0.0) {
            double A_e = 3.2 * W / E_star * M->sqrt_gamma_sigma; /* eq. 13 */
            double A = rm_approach_area(&M->approach, f, ps->kz[i], W);
            d_max = pair_d_max(M, f, ps, i, v_impact);
            h = -surface + d_max; /* eq. 11: rigid gap plus the eq. 7 delta_max, >= 0 */
            if (!(h > 0.0)) h = 0.0;
            if (p->film == RM_FILM_EHL)
                h = rm_max(h, rm_ehl_central_film(u, W, ps->r_x[i], ps->r_y[i], E_star, p->eta,
                                                  p->alpha_pv));
            lam = h / p->sigma;
            psi = rm_dry_fraction(lam);
            if (p->friction_enabled) {
                double U = p->shear_speed == 0 ? u : v_s;
                double tau_v = psi < 1.0 ? rm_viscous_stress(p->viscous_law, p->eta, p->alpha_pv,
                                                             p->tau_limit_0, p->tau_limit_slope,
                                                             W / A, U, h)
                                         : 0.0;
                F = rm_friction_force(p->friction_form, psi, A_e, A, p->tau_s, tau_v);
                double sgn;
                if (signs != NULL) {
                    sgn = signs[slot];
                    if (sgn == RM_FRICTION_STICKING)
                        sgn = rm_stick_direction(v_s, stick_speeds[slot]);
                }
                else if (v_s > 0.0)
                    sgn = 1.0;
                else if (v_s < 0.0)
                    sgn = -1.0;
                else
                    sgn = 0.0;
                if (sgn != 0.0) {
                    tau_w += sgn * F * rho_w;
                    tau_p -= sgn * F * rho_p;
                    F_net += sgn * F;
                }
            }
        }
        if (detail) {
            /* the loaded pairs (W > 0), the most loaded one (the first of equal maxima), the
             * force per slot (a later pair in the same slot overwrites) */
            if (W > 0.0) {
                if (out->n_loaded == 0 || W > out->top_W) {
                    out->top_W = W;
                    out->top_h = h;
                    out->top_lam = lam;
                    out->top_psi = psi;
                }
                out->n_loaded++;
            }
            out->forces[slot] = W;
        }
        if (pairs != NULL && (size_t)out->n_pairs < capacity) {
            double* row = pairs + RM_PAIR_DETAIL * (size_t)out->n_pairs;
            double values[RM_PAIR_DETAIL] = {(double)slot, s, ps->offset[i], ps->r_x[i], K, pen,
                                             W, F, v_s, u, h, lam, psi, d_max};
            for (int k = 0; k < RM_PAIR_DETAIL; k++) row[k] = values[k];
            out->n_pairs++;
        }
    }
    out->tau_w = tau_w;
    out->tau_p = tau_p;
    out->W = W_sum;
    out->F = F_net;
}

/* The total normal force of `flank` at penetration delta without dissipation:
 * sum_i W_i(delta - g_i) over the pairs that touch. */
double rm_static_force(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank, double phi_p,
                       double delta)
{
    RmPairSet* ps = rm_pairs_at(M, f, cache, rm_flank_roll(&M->g, flank, phi_p));
    double total = 0.0;
    for (int i = 0; i < ps->n; i++) {
        double d = delta - ps->offset[i];
        if (d > 0.0) {
            rm_pair_coefficients(M, f, ps, i);
            total += rm_approach_force(&M->approach, f, ps->K[i], ps->W_r[i], ps->c_t[i], d,
                                       NULL);
        }
    }
    return total;
}

/* The contact's stiffness dW/d(delta) [N/m] and damping dW/d(delta_dot) [N.s/m] summed over
 * the touching pairs at penetration delta and rate delta_dot: they set its time scales
 * sqrt(m/k) and m/c. */
void rm_contact_rates(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank, double phi_p,
                      double w_p, double delta, double delta_dot, RmContactDissipation diss,
                      double* k, double* c)
{
    double d = diss.d;
    double k_sum = 0.0, c_sum = 0.0;
    RmPairSet* ps = rm_pairs_at(M, f, cache, rm_flank_roll(&M->g, flank, phi_p));
    double ratio_scale = rm_ratio_scale(M, f, ps, delta);
    for (int i = 0; i < ps->n; i++) {
        double pen = delta - ps->offset[i];
        if (pen > 0.0) {
            rm_pair_coefficients(M, f, ps, i);
            double k_i, c_i;
            rm_approach_rates(&M->approach, f, ps->K[i], ps->W_r[i], ps->c_t[i], pen, d, &k_i,
                              &c_i);
            double factor = 1.0 + d * (delta_dot - pair_rate(M, flank, w_p, ps->dg[i]));
            if (factor > 0.0) k_sum += k_i * factor;
            c_sum += c_i;
            if (d == 0.0) { /* the viscous dampings (none with Hunt-Crossley) */
                double c_v = rm_pair_viscous_damping(M, diss.film, ps->r_x[i], ps->r_y[i],
                                                     ps->length[i], k_i, ratio_scale, pen);
                c_sum += c_v;
                /* a film still engaging adds c_v rate / pen to the stiffness */
                if (diss.film && pen < rm_film_engagement_width(&M->p))
                    k_sum += c_v / pen
                             * fabs(delta_dot - pair_rate(M, flank, w_p, ps->dg[i]));
            }
        }
    }
    *k = k_sum;
    *c = c_sum;
}

/* The largest eq. (7)-(8) delta_max over the pairs of `flank` for an impact at v_impact. */
double rm_energy_balance_delta_max(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank,
                                   double phi_p, double v_impact)
{
    RmPairSet* ps = rm_pairs_at(M, f, cache, rm_flank_roll(&M->g, flank, phi_p));
    double out = 0.0;
    for (int i = 0; i < ps->n; i++) {
        rm_pair_coefficients(M, f, ps, i);
        double d = rm_approach_film_delta_max(&M->approach, f, v_impact, ps->K[i], ps->r_x[i],
                                              ps->ka[i], ps->length[i], M->p.density);
        if (d > out) out = d;
    }
    return out;
}
