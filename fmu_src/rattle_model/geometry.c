/*
 * geometry.c - the helical involute pair and the tooth pairs in its zone of action (paper
 * eq. 3-6, read as docs/model.md section 2 says).
 *
 * Conventions:
 *  - each gear's angle is positive in its own forward direction; phi_p = phi_w = 0 puts the
 *    pinion tooth centreline on the line of centres, centred in the wheel's tooth space;
 *  - s is the roll coordinate along a transverse line of action from the pinion's base-circle
 *    tangent point: at a contact s is the pinion's roll length rho_p (its involute radius of
 *    curvature) and L - s the wheel's, L = a sin(alpha_t) (eq. 5);
 *  - flank +1 is the drive flank (pinion leads), -1 the coast flank;
 *  - a helical pair touches along a contact line spanning w = b tan(beta_b) of roll; it is in
 *    the zone of action while that span overlaps the path of contact [s_start, s_end];
 *  - contact.geometry 0 (crowned, RM_LAYOUT_CROWNED): the flanks are lead-crowned
 *    (contact.crowning C_b, along the normal): a pair touches at the lowest point of its
 *    engaged contact line -- its face centre s_n while that lies in the path, else the end of
 *    the path nearest to it, with the crown offset g = C_b (d / (w/2))^2 at roll distance d
 *    from the face centre;
 *  - contact.geometry 1 and 2 (RM_LAYOUT_PAPER, RM_LAYOUT_LINE): unmodified flanks, every pair
 *    in the zone touches at the shared rigid approach (no offset), represented by the centre
 *    of its engaged contact line [max(s_n - w/2, s_start), min(s_n + w/2, s_end)] and that
 *    line's length (a roll distance d along the line is d / sin(beta_b) of line; a spur pair's
 *    line is the face width b).
 */
#include "rm_private.h"

/* x % w of doubles with the sign of w (floored modulo). */
static double floored_mod(double v, double w)
{
    double mod = fmod(v, w);
    if (mod != 0.0) {
        if ((w < 0.0) != (mod < 0.0)) mod += w;
    }
    else
        mod = copysign(0.0, w);
    return mod;
}

/* The radius of a gear at the point of roll length rho from its base circle (eq. 4 as
 * printed: the radius of the point). */
static double point_radius(double r_base, double rho) { return sqrt(r_base * r_base + rho * rho); }

/* The gear pair's validity, once its geometry is computed: no undercut (a rack cutter whose
 * dedendum matches the addendum h_a m_n), no tip interference, eps_alpha >= 1, eq. 6's radii
 * where the layout uses them, and the pair slots: 1, or 0 with the refusal. */
static int geometry_valid(const RmGearParams* p, const RmGeometry* g, RmText* err)
{
    double m_n = p->m_n, alpha_n = p->alpha_n, beta = p->beta;
    double addendum = p->addendum, b = p->b;
    double sin2 = rm_pow(sin(g->alpha_t), 2.0);
    double z_min = 2.0 * addendum * cos(beta) / sin2;
    const char* names[2] = {"gear.z_pinion", "gear.z_wheel"};
    int zs[2] = {p->z_pinion, p->z_wheel};
    for (int k = 0; k < 2; k++) {
        if ((double)zs[k] < z_min) {
            rm_printf(err, "parameter '%s' = %d undercuts with gear.alpha_n = %.4r deg and "
                           "gear.beta = %.4r deg; allowed: %s >= %r (2 cos(beta)/sin^2(alpha_t) * "
                           "gear.h_a = %.4r)",
                      names[k], zs[k], alpha_n * (180.0 / RM_PI), beta * (180.0 / RM_PI),
                      names[k], ceil(z_min - 1e-9), z_min);
            return 0;
        }
    }
    if (g->s_start <= 0.0 || g->s_end >= g->line_length) {
        rm_printf(err, "tip interference: the path of contact leaves the line of action (s_start "
                       "= %.4r m, s_end = %.4r m, line length %.4r m) for gear.z_pinion = %d, "
                       "gear.z_wheel = %d; allowed: 0 < s_start < s_end < line length",
                  g->s_start, g->s_end, g->line_length, zs[0], zs[1]);
        return 0;
    }
    if (g->eps_alpha < 1.0) {
        rm_printf(err, "transverse contact ratio eps_alpha = %.5r below 1 for gear.z_pinion = %d, "
                       "gear.z_wheel = %d, gear.h_a = %.4r, gear.alpha_n = %.4r deg, gear.beta = "
                       "%.4r deg; allowed: eps_alpha >= 1",
                  g->eps_alpha, zs[0], zs[1], addendum, alpha_n * (180.0 / RM_PI),
                  beta * (180.0 / RM_PI));
        return 0;
    }
    if (g->layout == RM_LAYOUT_PAPER) {
        /* eq. 6 needs the wheel's radius at the contact point to exceed the pinion's; their
         * difference falls along the path (R_p grows with s, R_w shrinks), least at s_end */
        double R_p = point_radius(g->rb_pinion, g->s_end);
        double R_w = point_radius(g->rb_wheel, g->line_length - g->s_end);
        if (!(R_w > R_p)) {
            rm_printf(err, "parameter 'contact.geometry' = %d (the paper's eq. 6, r_y = R_p R_w / "
                           "(R_w - R_p)) needs the wheel's radius at every contact point larger "
                           "than the pinion's; with gear.z_pinion = %d, gear.z_wheel = %d it is "
                           "%.6r mm against %.6r mm at the pinion tip; allowed: contact.geometry "
                           "= 0 or 2, or a wheel with more teeth",
                      p->layout, zs[0], zs[1], R_w * 1e3, R_p * 1e3);
            return 0;
        }
    }
    double max_pairs = floor(g->eps_gamma) + 1.0;
    if (max_pairs > RM_MAX_PAIR_SLOTS) {
        double b_max = (RM_MAX_PAIR_SLOTS - g->eps_alpha) * RM_PI * m_n / rm_max(sin(beta), 1e-300);
        rm_printf(err, "parameter 'gear.b' = %r gives a total contact ratio eps_gamma = %.4r, "
                       "needing %r pair slots; at most %d are available; allowed: gear.b < %.4r m",
                  b, g->eps_gamma, max_pairs, RM_MAX_PAIR_SLOTS, b_max);
        return 0;
    }
    return 1;
}

/* The breakpoints of the pair set (RmGeometry.bp, .n_bp). */
static void set_breakpoints(RmGeometry* g)
{
    /* roll coordinates (mod the base pitch) of a pair's face centre where the pair enters or
     * leaves the zone (s_start - w/2, s_end + w/2) or its contact point starts or stops
     * following the face centre (s_start, s_end; crowned), or an end of its engaged line
     * starts or stops following the path's end (s_start + w/2, s_end - w/2; unmodified
     * flanks): distinct values, sorted */
    double half = 0.5 * g->line_span;
    double raw[4] = {g->s_start - half, g->s_start, g->s_end, g->s_end + half};
    if (g->layout != RM_LAYOUT_CROWNED) {
        raw[1] = g->s_start + half;
        raw[2] = g->s_end - half;
    }
    int n = 0;
    for (int k = 0; k < 4; k++) {
        int seen = 0;
        for (int m = 0; m < k; m++)
            if (raw[m] == raw[k]) seen = 1;
        if (!seen) g->bp[n++] = floored_mod(raw[k], g->base_pitch);
    }
    for (int a = 1; a < n; a++)
        for (int c = a; c > 0 && g->bp[c] < g->bp[c - 1]; c--) {
            double x = g->bp[c];
            g->bp[c] = g->bp[c - 1];
            g->bp[c - 1] = x;
        }
    g->n_bp = n;
}

int rm_geometry(const RmGearParams* p, RmGeometry* g, RmText* err)
{
    double zp = (double)p->z_pinion, zw = (double)p->z_wheel;
    double m_n = p->m_n, alpha_n = p->alpha_n, beta = p->beta;
    double addendum = p->addendum, b = p->b;
    g->ratio = zp / zw; /* wheel speed / pinion speed in rigid mesh */
    /* transverse pressure angle and base helix angle (MODEL_NOTES section 4) */
    g->alpha_t = atan(tan(alpha_n) / cos(beta));
    g->beta_b = asin(sin(beta) * cos(alpha_n));
    g->m_t = m_n / cos(beta);
    /* pitch, base and tip radii; addendum h_a m_n, no profile shift */
    g->r_pinion = 0.5 * zp * g->m_t;
    g->r_wheel = 0.5 * zw * g->m_t;
    g->centre_distance = g->r_pinion + g->r_wheel;
    g->rb_pinion = g->r_pinion * cos(g->alpha_t);
    g->rb_wheel = g->r_wheel * cos(g->alpha_t);
    g->ra_pinion = g->r_pinion + addendum * m_n;
    g->ra_wheel = g->r_wheel + addendum * m_n;
    /* line of action between the base tangent points, and the path of contact on it (eq. 5) */
    g->line_length = g->centre_distance * sin(g->alpha_t);
    g->s_start = g->line_length - sqrt(rm_pow(g->ra_wheel, 2.0) - rm_pow(g->rb_wheel, 2.0));
    g->s_end = sqrt(rm_pow(g->ra_pinion, 2.0) - rm_pow(g->rb_pinion, 2.0));
    g->s_pitch = g->rb_pinion * tan(g->alpha_t);
    g->base_pitch = 2.0 * RM_PI * g->rb_pinion / zp; /* transverse, p_bt */
    g->eps_alpha = (g->s_end - g->s_start) / g->base_pitch;
    g->eps_beta = b * sin(beta) / (RM_PI * m_n);
    g->eps_gamma = g->eps_alpha + g->eps_beta;
    /* transverse extent of one contact line across the face (eps_beta p_bt); a span below
     * the roll resolution is a spur pair's */
    g->line_span = b * tan(g->beta_b);
    if (g->line_span < RM_BREAKPOINT_TOLERANCE) g->line_span = 0.0;
    /* lead crowning: gap g = crown_factor d^2 at roll distance d from the face centre (C_b at
     * d = w/2), and the flank radius along the contact line it implies (eq. 6 read as
     * crowning): a distance l along the line is l sin(beta_b) of roll, and the face end lies
     * at l = b / (2 cos beta_b), so r_y = (b / (2 cos beta_b))^2 / (2 C_b) */
    g->crowning = p->crowning;
    double half_span = 0.5 * g->line_span;
    g->crown_factor = half_span > 0.0 ? g->crowning / (half_span * half_span) : 0.0;
    double half_line = 0.5 * b / cos(g->beta_b);
    g->r_y = half_line * half_line / (2.0 * g->crowning);
    /* rigid-body kinematics onto the tooth normal: delta = cos(beta_b)(rb_p phi_p - rb_w phi_w) */
    g->normal_factor = cos(g->beta_b);
    g->cos_alpha_t = cos(g->alpha_t);
    g->sin_alpha_t = sin(g->alpha_t);
    g->sin_beta_b = sin(g->beta_b);
    g->half_backlash = 0.5 * p->backlash;
    g->layout = p->layout;
    g->face_width = b;
    /* roll coordinate of pair 0 at phi_p = 0: the flank a quarter base pitch ahead of the
     * pitch point, both flanks */
    g->flank_phase = g->s_pitch + 0.25 * g->base_pitch;

    if (!geometry_valid(p, g, err)) return 0;
    set_breakpoints(g);
    return 1;
}

/* Principal radii in the normal plane at roll coordinate s (eq. 3-5 as read in MODEL_NOTES
 * section 2): the involute radius of curvature is the roll length, and a helicoid's
 * normal-section radius the transverse one over cos(beta_b). */
double rm_radius_x(const RmGeometry* g, double s)
{
    double c = g->normal_factor;
    double rp = s / c;
    double rw = (g->line_length - s) / c;
    return rp * rw / (rp + rw);
}

/* eq. 6 read with the gears' radii at the contact point (eq. 4's sqrt(R_b^2 + rho^2)): the
 * wheel's radius counted concave, 1/r_y = 1/R_p - 1/R_w.  The printed R_p - R_w in the
 * denominator would make r_y negative for a wheel larger than the pinion. */
double rm_radius_y_eq6(const RmGeometry* g, double s)
{
    double R_p = point_radius(g->rb_pinion, s);
    double R_w = point_radius(g->rb_wheel, g->line_length - s);
    if (R_w == R_p) return INFINITY; /* equal radii (reported by rm_describe, refused in use) */
    return R_p * R_w / (R_w - R_p);
}

/* Samples of ln(r_y(s) / r_x(s)) along the path for RM_LAYOUT_PAPER, and the relative margin
 * the range is widened by: the function is smooth (its second derivative bounds the error
 * between samples far below the margin). */
#define EQ6_RANGE_SAMPLES 256
#define EQ6_RANGE_MARGIN 0.01

/* Bounds of ln(R/r), R and r the larger and smaller of r_x and r_y, over the contact points
 * the path of contact allows. */
void rm_radius_ratio_range(const RmGeometry* g, double r_y_law, double* lo, double* hi)
{
    if (g->layout == RM_LAYOUT_PAPER) {
        double v_lo = 0.0, v_hi = 0.0, prev = 0.0;
        int crosses = 0;
        for (int k = 0; k <= EQ6_RANGE_SAMPLES; k++) {
            double s = g->s_start + (g->s_end - g->s_start) * (double)k / EQ6_RANGE_SAMPLES;
            double v = log(rm_radius_y_eq6(g, s) / rm_radius_x(g, s));
            if (k == 0 || v < v_lo) v_lo = v;
            if (k == 0 || v > v_hi) v_hi = v;
            if (k > 0 && (v > 0.0) != (prev > 0.0)) crosses = 1;
            prev = v;
        }
        double margin = EQ6_RANGE_MARGIN * (v_hi - v_lo);
        v_lo -= margin;
        v_hi += margin;
        /* |ln(rho)|: through zero when the ratio crosses 1 */
        double a = fabs(v_lo), b = fabs(v_hi);
        *lo = (crosses || (v_lo <= 0.0 && 0.0 <= v_hi)) ? 0.0 : rm_min(a, b);
        *hi = rm_max(a, b);
        return;
    }
    double samples[3] = {g->s_start, g->s_end, 0.0};
    int n = 2;
    double mid = 0.5 * g->line_length; /* r_x(s) = s (L - s) / (L cos beta_b) peaks there */
    if (g->s_start < mid && mid < g->s_end) samples[n++] = mid;
    double r_x[3];
    for (int k = 0; k < n; k++) r_x[k] = rm_radius_x(g, samples[k]);
    double r_lo = r_x[0], r_hi = r_x[0];
    for (int k = 1; k < n; k++) {
        if (r_x[k] < r_lo) r_lo = r_x[k];
        if (r_x[k] > r_hi) r_hi = r_x[k];
    }
    double cand[3] = {fabs(log(r_y_law / r_lo)), fabs(log(r_y_law / r_hi)), 0.0};
    int m = 2;
    if (r_lo <= r_y_law && r_y_law <= r_hi) cand[m++] = 0.0;
    double c_lo = cand[0], c_hi = cand[0];
    for (int k = 1; k < m; k++) {
        if (cand[k] < c_lo) c_lo = cand[k];
        if (cand[k] > c_hi) c_hi = cand[k];
    }
    *lo = c_lo;
    *hi = c_hi;
}

static void pair_set_add(RmFail* f, RmPairSet* ps, double n, double s, double g, double dg,
                         double length)
{
    if (ps->n == RM_MAX_PAIRS) rm_fail(f, RM_FAIL_TOO_MANY_PAIRS, RM_MAX_PAIRS, 0.0, 0.0, 0.0);
    int i = ps->n++;
    int64_t k = (int64_t)n % RM_MAX_PAIR_SLOTS; /* the slot: pair number mod slots, >= 0 */
    ps->slot[i] = k < 0 ? k + RM_MAX_PAIR_SLOTS : k;
    ps->s[i] = s;
    ps->offset[i] = g;
    ps->dg[i] = dg;
    ps->length[i] = length;
    ps->coefficients_ok[i] = 0;
    ps->d_max_ok[i] = 0;
}

/* The pairs of the unmodified flanks (RM_LAYOUT_PAPER, RM_LAYOUT_LINE) at roll coordinate u,
 * those in the zone at `member`: per pair the centre of its engaged contact line and the
 * line's length (zero where the positions at u put the line outside the path: a pair the
 * stepper holds in the zone over a substep that ends where it enters or leaves). */
static void unmodified_pairs(const RmGeometry* g, RmFail* f, double u, double member,
                             RmPairSet* ps)
{
    double pb = g->base_pitch;
    double half = 0.5 * g->line_span;
    double s0 = g->s_start, s1 = g->s_end;
    double n_lo = rm_floor_checked(f, (member - s1 - half) / pb) + 1.0;
    double n_hi = rm_ceil_checked(f, (member - s0 + half) / pb) - 1.0;
    if (!(fabs(n_lo) < RM_PAIR_NUMBER_LIMIT && fabs(n_hi) < RM_PAIR_NUMBER_LIMIT))
        rm_fail(f, RM_FAIL_PAIR_RANGE, member, n_lo, 0.0, 0.0);
    for (double n = n_lo; n <= n_hi; n += 1.0) {
        double c = member - n * pb; /* the face centre at `member`: in the zone? */
        int inside = half > 0.0 ? (c + half > s0 && c - half < s1) : (s0 < c && c < s1);
        if (!inside) continue;
        double s = u - n * pb; /* the face centre at u */
        double a = rm_max(s - half, s0), b = rm_min(s + half, s1);
        double length;
        if (half > 0.0)
            length = b > a ? (b - a) / g->sin_beta_b : 0.0;
        else
            length = s0 < s && s < s1 ? g->face_width : 0.0;
        /* the centre of the engaged line, kept inside the path */
        double mid = rm_min(rm_max(0.5 * (a + b), s0), s1);
        pair_set_add(f, ps, n, mid, 0.0, 0.0, length);
    }
}

/* The length of the engaged contact line of a pair whose face centre is at roll coordinate s
 * (in the zone of action): [max(s - w/2, s_start), min(s + w/2, s_end)] over sin(beta_b), or
 * the face width of a spur pair. */
static double engaged_length(const RmGeometry* g, double s)
{
    double half = 0.5 * g->line_span;
    if (!(half > 0.0)) return g->face_width;
    double a = rm_max(s - half, g->s_start), b = rm_min(s + half, g->s_end);
    return b > a ? (b - a) / g->sin_beta_b : 0.0;
}

/* The pairs at roll coordinate u of pair 0's face centre: pair n sits at s_n = u - n p_bt.
 * Per pair: its slot (pair number mod RM_MAX_PAIR_SLOTS, so a slot follows one pair through
 * its passage), the roll coordinate s of its contact point, the crown offset g there (the
 * pair touches when the flank's penetration exceeds it), dg = dg/ds_n, and the length of its
 * engaged contact line (over which its teeth bend, compliance.c). */
void rm_pair_set_build(const RmGeometry* g, RmFail* f, double u, double member, RmPairSet* ps)
{
    double pb = g->base_pitch;
    double half = 0.5 * g->line_span;
    double s0 = g->s_start, s1 = g->s_end;
    double k = g->crown_factor;
    double n_lo = rm_floor_checked(f, (u - s1 - half) / pb) + 1.0;
    double n_hi = rm_ceil_checked(f, (u - s0 + half) / pb) - 1.0;
    if (!(fabs(n_lo) < RM_PAIR_NUMBER_LIMIT && fabs(n_hi) < RM_PAIR_NUMBER_LIMIT))
        rm_fail(f, RM_FAIL_PAIR_RANGE, u, n_lo, 0.0, 0.0);
    ps->u = u;
    ps->member = member;
    ps->n = 0;
    ps->d_max_v = 0.0;
    if (g->layout != RM_LAYOUT_CROWNED) {
        unmodified_pairs(g, f, u, member, ps);
        return;
    }
    for (double n = n_lo; n <= n_hi; n += 1.0) {
        double s = u - n * pb; /* roll coordinate of the pair's face centre */
        if (half > 0.0) {
            if (s + half > s0 && s - half < s1) {
                double length = engaged_length(g, s);
                if (s < s0) {
                    double d = s0 - s;
                    pair_set_add(f, ps, n, s0, k * d * d, -2.0 * k * d, length);
                }
                else if (s > s1) {
                    double d = s - s1;
                    pair_set_add(f, ps, n, s1, k * d * d, 2.0 * k * d, length);
                }
                else {
                    pair_set_add(f, ps, n, s, 0.0, 0.0, length);
                }
            }
        }
        else if (s0 < s && s < s1) {
            pair_set_add(f, ps, n, s, 0.0, 0.0, g->face_width);
        }
    }
}

/* The first breakpoint between u_a and u_b in the direction of travel; breakpoints within
 * RM_BREAKPOINT_TOLERANCE of u_a are behind (the previous substep ended on them). */
int rm_next_breakpoint(const RmGeometry* g, RmFail* f, double u_a, double u_b, double* out)
{
    if (u_a == u_b) return 0;
    double pb = g->base_pitch;
    double tol = RM_BREAKPOINT_TOLERANCE;
    int found = 0;
    double best = 0.0;
    if (u_b > u_a) {
        for (int i = 0; i < g->n_bp; i++) {
            double bp = g->bp[i];
            double v = bp + (rm_floor_checked(f, (u_a + tol - bp) / pb) + 1.0) * pb;
            if (v < u_b && (!found || v < best)) {
                best = v;
                found = 1;
            }
        }
    }
    else {
        for (int i = 0; i < g->n_bp; i++) {
            double bp = g->bp[i];
            double v = bp + (rm_ceil_checked(f, (u_a - tol - bp) / pb) - 1.0) * pb;
            if (v > u_b && (!found || v > best)) {
                best = v;
                found = 1;
            }
        }
    }
    if (found) *out = best;
    return found;
}
