/*
 * compliance.c - the teeth's own compliance, in series with each pair's contact law
 * (docs/model.md section 3.7; tooth.compliance = 1).
 *
 * Only the contact deforms in the paper's equations.  In gear standards and gear dynamics the
 * mesh stiffness at working loads is set by the teeth bending, shearing and compressing and by
 * the gear body under them, in series with the contact's flattening.  Each tooth is taken as
 * the tooth of its virtual spur gear in the normal section (z_n = z / (cos^2 beta_b cos beta),
 * m_n, alpha_n: ISO 6336-1's virtual gear), cut by the ISO 53 basic rack (dedendum 1.25 m_n,
 * tip radius 0.38 m_n), per unit length of contact line.  Loaded at the involute point of
 * roll length rho along its line of action it deflects by q F:
 *
 *  - the tooth as a cantilever of its actual section from the root circle to the load:
 *    bending, shear (factor 1.2) and compression, plane strain (E' = E / (1 - nu^2)), by
 *    Weber's energy method (W. Weber, The deformation of loaded gears and the effect on their
 *    load-carrying capacity, DSIR Sponsored Research 3, 1949; Weber and Banaschek 1953; in
 *    the form of Yang and Lin, J. Mech. Transm. Autom. Des. 109, 1987):
 *        q_beam = int [m^2 / (E' I) + 1.2 cos^2(a1) / (G A) + sin^2(a1) / (E' A)] dy,
 *        m = cos(a1) (y_c - y) - sin(a1) x_c,  I = (2x)^3 / 12,  A = 2x,
 *    over the height y along the tooth centreline, (x, y) the section's half thickness and
 *    height, (x_c, y_c) the load point, a1 the load's angle to the normal of the centreline;
 *    the involute x = R sin(theta), y = R cos(theta), R = r_b sqrt(1 + t^2),
 *    theta = theta_b - (t - atan t) is integrated in t (smooth there), and below the base
 *    circle the tooth keeps its base-circle thickness down to the root circle;
 *  - the gear body under the tooth, held at its bore (Sainsot, Velex and Duverger, J. Mech.
 *    Des. 126, 2004):
 *        q_f = cos^2(a1) / E [L (u_f/S_f)^2 + M (u_f/S_f) + P (1 + Q tan^2(a1))],
 *    u_f the height above the root circle where the load's line crosses the centreline,
 *    S_f = 2 r_f theta_f, each coefficient a fit in theta_f (the tooth's half angle at the root
 *    circle, where the rack's tip radius leaves it) and h = r_f / r_bore
 *    (tooth.body_ratio_*), fitted for 0.01 <= theta_f <= 0.12 (taken at the nearer end
 *    outside) and 1.4 <= h <= 7 (the parameters' range).
 *
 * ISO 6336-1's c' is a fit to measured stiffness that contains the contact's flattening; here
 * the contact is each pair's own law (contact.c), so no Hertz term is added to the teeth.
 * A pair's teeth at its contact point s (roll coordinate; the pinion's normal roll length is
 * s / cos(beta_b), the wheel's (L - s) / cos(beta_b)) have q(s) = q_pinion + q_wheel per unit
 * length of contact line, and the load bends them over the pair's engaged contact line of
 * length L_n: the pair's tooth compliance is c_t = q(s) / L_n [m/N], in series with its
 * contact law (pen = contact approach + c_t W, contact.c).  The teeth's stiffness per unit
 * length 1/q(s) is fitted once per parameter set as a Chebyshev series over the path of
 * contact, and evaluated from a grid of quintic Hermite pieces of that series.
 */
#include "rm_private.h"

/* ISO 53 basic rack profile A: the cutter's addendum (the gear's dedendum) and tip radius,
 * over m_n. */
#define RACK_DEDENDUM 1.25
#define RACK_TIP_RADIUS 0.38
/* Shear correction factor of a rectangular section. */
#define SHEAR_FACTOR 1.2
/* Sainsot, Velex and Duverger (2004), Table 1: A, B, C, D, E, F of L*, M*, P*, Q*, each
 * X = A / theta_f^2 + B h^2 + C h / theta_f + D / theta_f + E h + F. */
static const double SAINSOT[4][6] = {
    {-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045},
    {60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086},
    {-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236},
    {-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904},
};
/* The fit's range of theta_f [rad]. */
#define THETA_F_MIN 0.01
#define THETA_F_MAX 0.12
/* Gauss-Legendre points per panel of the beam integrals, the relative agreement of two
 * successive panel doublings that ends the refinement, and the most panels (the integrand is
 * analytic in t; one panel of 24 points already reaches rounding on the reference pair). */
#define GAUSS_POINTS 24
#define QUADRATURE_TOLERANCE 1e-13
#define MAX_PANELS 64
/* Relative accuracy the Chebyshev series of 1/q(s) must reach between its nodes, far below
 * the model's own; and that of its quintic Hermite grid (evaluated per loaded pair and stage:
 * a few multiply-adds, where the series costs a chain of two per term) against the series at
 * the middle of every step, the grid doubled from GRID_STEPS until it does. */
#define FIT_TOLERANCE 1e-10
#define GRID_TOLERANCE 1e-12
#define GRID_STEPS 64
#define FIT_CHECKS 23

typedef struct {
    double x[GAUSS_POINTS], w[GAUSS_POINTS];
} Gauss;

/* The Gauss-Legendre nodes and weights on [-1, 1]: Newton's method on the Legendre polynomial
 * from the usual cosine estimates. */
static void gauss_legendre(Gauss* q)
{
    int n = GAUSS_POINTS;
    for (int i = 0; i < n; i++) {
        double x = cos(RM_PI * ((double)i + 0.75) / ((double)n + 0.5));
        double dp = 1.0;
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = x;
            for (int k = 2; k <= n; k++) {
                double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / (double)k;
                p0 = p1;
                p1 = p2;
            }
            dp = (double)n * (x * p1 - p0) / (x * x - 1.0);
            double dx = p1 / dp;
            x -= dx;
            if (fabs(dx) <= 1e-16) break;
        }
        q->x[i] = x;
        q->w[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
}

/* The tooth of a virtual spur gear. */
typedef struct {
    double r_base, r_root, theta_base, theta_root, E, E_plane, G;
    double body[4]; /* Sainsot's L*, M*, P*, Q* */
} Tooth;

static void tooth_build(Tooth* t, double z, const RmMeshParams* p, double beta_b, double E,
                        double nu, double body_ratio)
{
    double c = cos(beta_b);
    double z_n = z / (c * c * cos(p->gear.beta));
    double alpha = p->gear.alpha_n, m = p->gear.m_n;
    double r = 0.5 * z_n * m;
    t->r_base = r * cos(alpha);
    t->r_root = r - RACK_DEDENDUM * m;
    t->theta_base = RM_PI / (2.0 * z_n) + (tan(alpha) - alpha);
    /* the cutter's tip radius leaves the root circle at theta_f from the tooth centreline: the
     * cutter tooth's flat tip ends pi m/4 - (h_f - rho) tan(alpha) - rho / cos(alpha) from the
     * space's centre, which lies pi / z_n from the tooth's */
    t->theta_root = (0.5 * RM_PI + 2.0 * (RACK_DEDENDUM - RACK_TIP_RADIUS) * tan(alpha)
                     + 2.0 * RACK_TIP_RADIUS / cos(alpha)) / z_n;
    t->E = E;
    t->E_plane = E / (1.0 - nu * nu);
    t->G = E / (2.0 * (1.0 + nu));
    double th = rm_min(rm_max(t->theta_root, THETA_F_MIN), THETA_F_MAX);
    double h = body_ratio;
    for (int i = 0; i < 4; i++) {
        const double* k = SAINSOT[i];
        t->body[i] = k[0] / (th * th) + k[1] * h * h + k[2] * h / th + k[3] / th + k[4] * h + k[5];
    }
}

/* The involute at t = tan(pressure angle): half thickness x, height y and dy/dt. */
static void involute_point(const Tooth* t, double u, double* x, double* y, double* dy)
{
    double root = sqrt(1.0 + u * u);
    double R = t->r_base * root;
    double theta = t->theta_base - (u - atan(u));
    *x = R * sin(theta);
    *y = R * cos(theta);
    if (dy != NULL) {
        double dR = t->r_base * u / root;
        double dtheta = -u * u / (1.0 + u * u);
        *dy = dR * cos(theta) - R * sin(theta) * dtheta;
    }
}

/* The load point and direction of a tooth loaded at normal roll length rho. */
typedef struct {
    const Tooth* t;
    double x_c, y_c, ca, sa;
} Load;

/* The beam's compliance density per unit height at a section of half thickness x, height y. */
static double beam_density(const Load* L, double x, double y)
{
    const Tooth* t = L->t;
    double arm = L->ca * (L->y_c - y) - L->sa * L->x_c;
    double width = 2.0 * x;
    return arm * arm * 12.0 / (t->E_plane * width * width * width)
           + SHEAR_FACTOR * L->ca * L->ca / (t->G * width) + L->sa * L->sa / (t->E_plane * width);
}

/* The involute part of the beam integral over t in [a, b], in `panels` equal panels. */
static double involute_integral(const Load* L, const Gauss* g, double a, double b, int panels)
{
    double sum = 0.0, span = (b - a) / (double)panels;
    for (int p = 0; p < panels; p++) {
        double lo = a + span * (double)p;
        double mid = lo + 0.5 * span, half = 0.5 * span;
        for (int k = 0; k < GAUSS_POINTS; k++) {
            double x, y, dy;
            involute_point(L->t, mid + half * g->x[k], &x, &y, &dy);
            sum += half * g->w[k] * beam_density(L, x, y) * dy;
        }
    }
    return sum;
}

/* q [m^2/N] of the tooth loaded at normal roll length rho: 1, or 0 with the refusal (a tooth
 * pointed below the load). */
static int tooth_compliance(const Tooth* t, const Gauss* g, double rho, double* out,
                            RmText* err)
{
    double t_c = rho / t->r_base;
    Load L;
    L.t = t;
    involute_point(t, t_c, &L.x_c, &L.y_c, NULL);
    double a1 = atan(t_c) - (t->theta_base - (t_c - atan(t_c)));
    L.ca = cos(a1);
    L.sa = sin(a1);
    if (!(L.x_c > 0.0)) {
        rm_printf(err, "parameter 'tooth.compliance' = 1: the virtual spur tooth (normal section) "
                       "of this pair is pointed below its contact at roll length %.6r mm, where "
                       "its bending is not modelled; allowed: tooth.compliance = 0, or a smaller "
                       "gear.h_a", rho * 1e3);
        return 0;
    }
    double beam = 0.0, t_0 = 0.0;
    if (t->r_root < t->r_base) { /* the base-circle thickness down to the root circle:
                                    a polynomial in y, exact with the Gauss points */
        double x_b, y_b;
        involute_point(t, 0.0, &x_b, &y_b, NULL);
        double y_f = sqrt(t->r_root * t->r_root - x_b * x_b);
        double mid = 0.5 * (y_f + y_b), half = 0.5 * (y_b - y_f);
        for (int k = 0; k < GAUSS_POINTS; k++)
            beam += half * g->w[k] * beam_density(&L, x_b, mid + half * g->x[k]);
    }
    else
        t_0 = sqrt((t->r_root / t->r_base) * (t->r_root / t->r_base) - 1.0);
    int panels = 1;
    double inv = involute_integral(&L, g, t_0, t_c, panels);
    for (;;) {
        double finer = involute_integral(&L, g, t_0, t_c, 2 * panels);
        panels *= 2;
        int done = fabs(finer - inv) <= QUADRATURE_TOLERANCE * fabs(finer);
        inv = finer;
        if (done || panels >= MAX_PANELS) break;
    }
    beam += inv;
    double u_f = L.y_c - L.x_c * tan(a1) - t->r_root;
    double S_f = 2.0 * t->r_root * t->theta_root;
    double ratio = u_f / S_f, ta = tan(a1);
    double body = L.ca * L.ca / t->E
                  * (t->body[0] * ratio * ratio + t->body[1] * ratio
                     + t->body[2] * (1.0 + t->body[3] * ta * ta));
    *out = beam + body;
    if (!(*out > 0.0 && isfinite(*out))) {
        rm_printf(err, "parameter 'tooth.compliance' = 1: the teeth's compliance is not positive "
                       "(q = %r m^2/N) at roll length %.6r mm for this geometry; allowed: "
                       "tooth.compliance = 0", *out, rho * 1e3);
        return 0;
    }
    return 1;
}

typedef struct {
    Tooth pinion, wheel;
    Gauss gauss;
    double line_length, normal_factor;
} PairTeeth;

/* q(s) of both teeth at roll coordinate s. */
static int pair_compliance(const PairTeeth* T, double s, double* out, RmText* err)
{
    double qp, qw;
    if (!tooth_compliance(&T->pinion, &T->gauss, s / T->normal_factor, &qp, err)) return 0;
    if (!tooth_compliance(&T->wheel, &T->gauss, (T->line_length - s) / T->normal_factor, &qw,
                          err))
        return 0;
    *out = qp + qw;
    return 1;
}

/* 1/q(s): the teeth's stiffness per unit length of contact line [N/m^2]. */
static int pair_stiffness(const PairTeeth* T, double s, double* out, RmText* err)
{
    double q;
    if (!pair_compliance(T, s, &q, err)) return 0;
    *out = 1.0 / q;
    return 1;
}

/* The series' quintic Hermite grid over [lo, hi]: 1, or 0 with the refusal. */
static int hermite_grid(RmToothCompliance* c, double lo, double hi, RmText* err)
{
    double d1[RM_MAX_TOOTH_TERMS], d2[RM_MAX_TOOTH_TERMS];
    rm_chebyshev_derivative(c->k, c->terms, d1);
    rm_chebyshev_derivative(d1, c->terms, d2);
    double worst = 0.0;
    for (int steps = GRID_STEPS; steps <= RM_MAX_TOOTH_GRID; steps *= 2) {
        c->steps = steps;
        c->lo = lo;
        c->h = (hi - lo) / (double)steps;
        c->inv_h = (double)steps / (hi - lo);
        for (int k = 0; k <= steps; k++) {
            double t = (lo + c->h * (double)k - c->t_mid) * c->t_scale;
            c->grid[k][0] = rm_chebyshev_value(c->k, c->terms, t);
            c->grid[k][1] = c->t_scale * rm_chebyshev_value(d1, c->terms, t);
            c->grid[k][2] = c->t_scale * c->t_scale * rm_chebyshev_value(d2, c->terms, t);
        }
        worst = 0.0;
        for (int k = 0; k < steps; k++) {
            double t = (lo + c->h * ((double)k + 0.5) - c->t_mid) * c->t_scale;
            double series = rm_chebyshev_value(c->k, c->terms, t);
            double grid = rm_quintic_hermite(0.5, c->h, c->grid[k], c->grid[k + 1]);
            worst = rm_max(worst, fabs(grid - series) / series);
        }
        if (worst <= GRID_TOLERANCE) return 1;
    }
    rm_printf(err, "parameter 'tooth.compliance' = 1: the teeth's compliance along the path of "
                   "contact cannot be tabulated on a grid to %.3r (reached %.3r); allowed: "
                   "tooth.compliance = 0", GRID_TOLERANCE, worst);
    return 0;
}

int rm_tooth_compliance_build(const RmMeshParams* p, const RmGeometry* g, RmToothCompliance* c,
                              RmText* err)
{
    c->on = p->tooth_compliance == RM_TOOTH_WEBER_SAINSOT;
    c->terms = c->steps = 0;
    c->t_mid = c->t_scale = c->pitch = c->lo = c->h = c->inv_h = 0.0;
    if (!c->on) return 1;
    PairTeeth T;
    tooth_build(&T.pinion, (double)p->gear.z_pinion, p, g->beta_b, p->E_pinion, p->nu_pinion,
                p->body_ratio_pinion);
    tooth_build(&T.wheel, (double)p->gear.z_wheel, p, g->beta_b, p->E_wheel, p->nu_wheel,
                p->body_ratio_wheel);
    gauss_legendre(&T.gauss);
    T.line_length = g->line_length;
    T.normal_factor = g->normal_factor;
    double lo = g->s_start, hi = g->s_end;
    c->t_mid = 0.5 * (lo + hi);
    c->t_scale = 1.0 / (0.5 * (hi - lo)); /* s_end > s_start: rm_geometry checked */
    double worst = 0.0;
    for (int terms = 8; terms <= RM_MAX_TOOTH_TERMS; terms += 4) {
        double values[RM_MAX_TOOTH_TERMS];
        for (int k = 0; k < terms; k++)
            if (!pair_stiffness(&T, rm_chebyshev_node(lo, hi, k, terms), &values[k], err))
                return 0;
        rm_chebyshev_coefficients(values, terms, c->k);
        worst = 0.0;
        for (int k = 0; k < FIT_CHECKS; k++) {
            double s = lo + (hi - lo) * ((double)k + 0.5) / (double)FIT_CHECKS, exact;
            if (!pair_stiffness(&T, s, &exact, err)) return 0;
            double fit = rm_chebyshev_value(c->k, terms, (s - c->t_mid) * c->t_scale);
            worst = rm_max(worst, fabs(fit - exact) / exact);
        }
        if (worst <= FIT_TOLERANCE) {
            c->terms = terms;
            return hermite_grid(c, lo, hi, err) && pair_compliance(&T, g->s_pitch, &c->pitch, err);
        }
    }
    rm_printf(err, "parameter 'tooth.compliance' = 1: the teeth's compliance along the path of "
                   "contact cannot be tabulated to %.3r (reached %.3r); allowed: tooth.compliance "
                   "= 0", FIT_TOLERANCE, worst);
    return 0;
}

double rm_tooth_pair_compliance(const RmToothCompliance* c, double s, double length)
{
    if (!c->on) return 0.0;
    if (!(length > 0.0)) return INFINITY; /* no line: the pair carries nothing */
    double x = (s - c->lo) * c->inv_h; /* s in the path of contact: x in [0, steps] */
    if (!(x > 0.0)) x = 0.0; /* (a NaN too) */
    if (x > (double)c->steps) x = (double)c->steps;
    int k = (int)x;
    if (k >= c->steps) k = c->steps - 1;
    double stiffness = rm_quintic_hermite(x - (double)k, c->h, c->grid[k], c->grid[k + 1]);
    return 1.0 / (stiffness * length);
}
