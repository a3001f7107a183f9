/*
 * contact.c - the load-approach laws of a tooth pair and the contact's dissipation (paper
 * eq. 1, 2, 7, 8; Johnson, Contact Mechanics, 1985, sections 4.2, 13.4; Palmgren 1959;
 * Greenwood and Tripp 1970; Hunt and Crossley 1975).
 *
 * Two Hertz point-contact laws of the form W = K delta^(3/2) for the contact of radii r_x
 * (across the contact line) and r_y (along it):
 *  - law 0, exact elliptical Hertz contact: the ellipse's axis ratio q = b/a from the
 *    curvature ratio through complete elliptic integrals, and K, the semi-major axis a and the
 *    area pi a b from q.  It depends on the radii only through rho = R/r >= 1, so a pair's
 *    range of rho is fitted once as Chebyshev series in ln rho, accurate to rounding (checked
 *    between the nodes), evaluated with Clenshaw's recurrence;
 *  - law 1, the paper's equivalent sphere (eq. 2), K = 4/3 E* (r_x r_y)^(1/4), with Johnson's
 *    approximate ellipse sqrt(ab) = (3 W sqrt(r_x r_y) / (4 E*))^(1/3), a/b = (R/r)^(2/3).
 * Palmgren's empirical line-contact law for unmodified flanks, delta = C_P (W/E*)^0.9 L^-0.8
 * (L the engaged contact line's length; Palmgren, Ball and Roller Bearing Engineering, 1959),
 * i.e. W = K delta^(10/9) with K = E* (L^0.8 / C_P)^(10/9).
 * Roughness: the Greenwood-Tripp asperity layer (its pressure K' E* F_5/2(h/sigma) with the
 * fit F_5/2 = c (4 - h/sigma)^n) integrated over the pair's rigid nominal gap -- an ellipsoid
 * (r_x, r_y) or a cylinder (r_x, length L) -- gives W = W_r (delta_a/sigma)^(1/q) from first
 * asperity contact; it is taken in series with the smooth law (the same load on both):
 * delta = (W/K)^(1/p) + sigma (W/W_r)^q, solved for W by Newton's method.
 * The teeth's compliance c_t (compliance.c) is a linear spring in series with either:
 * delta = (W/K)^(1/p) [+ sigma (W/W_r)^q] + c_t W.
 * Dissipation: Hunt-Crossley, W = K delta^(3/2) (1 + d d(delta)/dt), with d set exactly from a
 * coefficient of restitution (docs/model.md section 3.3).
 */
#include <float.h>
#include <stdlib.h>

#include "rm_private.h"

/* Relative accuracy a fitted series must reach between its nodes. */
#define CHEBYSHEV_TOLERANCE 1e-13
/* Curvature ratio below which an ellipse counts as a circle. */
#define CIRCLE_RATIO (1.0 + 1e-9)
/* The arithmetic-geometric mean: relative convergence and its iteration cap. */
#define AGM_TOLERANCE 1e-16
#define AGM_MAX_ITERATIONS 60
/* Brent's absolute tolerances on ln(q) and on the Hunt-Crossley factor d v, and on e. */
#define ROOT_XTOL 1e-15
#define RESTITUTION_XTOL 1e-16

double rm_effective_modulus(double E1, double nu1, double E2, double nu2)
{
    /* Johnson's contact modulus, 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2; the paper prints 2/(...)
     * (the "reduced modulus" E' = 2E*), which with K = 4/3 E* sqrt(R) would double K */
    return 1.0 / ((1.0 - nu1 * nu1) / E1 + (1.0 - nu2 * nu2) / E2);
}

/* The root of fn in [a, b] by Brent's method: 1, or 0 with the refusal. */
static int solve(RmRootFn fn, void* ctx, double a, double b, double xtol, double* root,
                 RmText* err)
{
    RmFail f;
    double fa = fn(ctx, a);
    double fb = fn(ctx, b);
    if (setjmp(f.jb) != 0) {
        rm_refusal_text(err, f.code, f.values);
        return 0;
    }
    *root = rm_brent(&f, fn, ctx, a, b, fa, fb, xtol, RM_BRENT_RTOL);
    return 1;
}

/* Complete elliptic integrals for the ellipse of axis ratio q = b/a (modulus
 * e = sqrt(1 - q^2)): K(e) and S with E(e) = K (1 - S), by the arithmetic-geometric mean
 * (Abramowitz and Stegun 17.6), S = sum 2^(n-1) c_n^2 so that K - E = K S cancels nothing. */
static void elliptic_integrals(double q, double* K, double* S_out)
{
    double a = 1.0, b = q;
    double c = sqrt((1.0 - q) * (1.0 + q));
    double S = 0.5 * c * c;
    double weight = 0.5;
    for (int it = 0; it < AGM_MAX_ITERATIONS; it++) {
        if (a - b <= AGM_TOLERANCE * a) break;
        c = 0.5 * (a - b);
        double na = 0.5 * (a + b), nb = sqrt(a * b);
        a = na;
        b = nb;
        weight *= 2.0;
        S += weight * c * c;
    }
    *K = RM_PI / (2.0 * a);
    *S_out = S;
}

/* R/r of the ellipse with axis ratio q: ((a/b)^2 E - K) / (K - E) = (e^2 - S) / (q^2 S). */
static double curvature_ratio(double q)
{
    double K, S;
    elliptic_integrals(q, &K, &S);
    double e2 = (1.0 - q) * (1.0 + q);
    return (e2 - S) / (q * q * S);
}

static double ellipse_residual(void* ctx, double y) /* y = ln q */
{
    double target = *(const double*)ctx;
    return log(curvature_ratio(exp(y))) - target;
}

/* The exact elliptical contact for rho = R/r >= 1 (Johnson section 4.2): q solves R/r above;
 * a^3 = 3 W R K S / (pi E* e^2); the approach delta = 3 W K(e) / (2 pi a E*) gives
 * K_H = (2 sqrt(2) pi / 3) E* sqrt(R) sqrt(S) / (K e).  For rho -> 1 the sphere:
 * K_H = 4/3 E* sqrt(R), a = (3 W R / (4 E*))^(1/3). */
int rm_exact_ellipse(double rho, RmEllipse* out, RmText* err)
{
    if (!(rho >= 1.0)) {
        rm_printf(err, "radius ratio rho = %r must be >= 1 (larger over smaller)", rho);
        return 0;
    }
    if (rho <= CIRCLE_RATIO) {
        double third = rm_pow(3.0 / 4.0, 1.0 / 3.0);
        out->q = 1.0;
        out->kappa = 4.0 / 3.0;
        out->alpha = third;
        out->zeta = RM_PI * third * third;
        return 1;
    }
    double target = log(rho);
    double y_lo = -1.0;
    while (ellipse_residual(&target, y_lo) < 0.0) {
        y_lo *= 2.0;
        if (y_lo < -200.0) {
            rm_printf(err, "radius ratio rho = %r too large for an elliptical contact", rho);
            return 0;
        }
    }
    double y_hi = -1e-9;
    double y;
    if (ellipse_residual(&target, y_hi) < 0.0) {
        if (!solve(ellipse_residual, &target, y_lo, y_hi, ROOT_XTOL, &y, err)) return 0;
    }
    else
        y = y_hi;
    double q = exp(y);
    double K, S;
    elliptic_integrals(q, &K, &S);
    double e2 = (1.0 - q) * (1.0 + q);
    double e = sqrt(e2);
    double kappa = (2.0 * sqrt(2.0) * RM_PI / 3.0) * sqrt(S) / (K * e);
    double alpha = rm_pow(3.0 * K * S / (RM_PI * e2), 1.0 / 3.0);
    out->q = q;
    out->kappa = kappa;
    out->alpha = alpha;
    out->zeta = RM_PI * q * alpha * alpha;
    return 1;
}

/* The fit's memo of x -> exact_ellipse(exp(x)) (the nodes repeat between fits). */
typedef struct {
    int n, cap;
    double* x;
    RmEllipse* e;
} EllipseCache;

static int cached_ellipse(EllipseCache* c, double x, RmEllipse* out, RmText* err)
{
    for (int k = 0; k < c->n; k++)
        if (c->x[k] == x) {
            *out = c->e[k];
            return 1;
        }
    if (!rm_exact_ellipse(exp(x), out, err)) return 0;
    if (c->n == c->cap) {
        int cap = c->cap ? 2 * c->cap : 64;
        double* nx = realloc(c->x, (size_t)cap * sizeof *nx);
        if (nx == NULL) return 1; /* not memoized: computed again when asked */
        c->x = nx;
        RmEllipse* ne = realloc(c->e, (size_t)cap * sizeof *ne);
        if (ne == NULL) return 1;
        c->e = ne;
        c->cap = cap;
    }
    c->x[c->n] = x;
    c->e[c->n] = *out;
    c->n++;
    return 1;
}

static double ellipse_field(const RmEllipse* e, int i)
{
    return i == 1 ? e->kappa : (i == 2 ? e->alpha : e->zeta);
}

/* Coefficients of the Chebyshev interpolant of field i on [lo, hi] at the n Chebyshev points
 * of the first kind (roots.c's rm_chebyshev_node and rm_chebyshev_coefficients). */
static int chebyshev_fit(EllipseCache* cache, int i, double lo, double hi, int terms,
                         double* coeffs, RmText* err)
{
    int n = terms;
    double values[RM_MAX_CHEBYSHEV_TERMS];
    for (int k = 0; k < n; k++) {
        RmEllipse e;
        if (!cached_ellipse(cache, rm_chebyshev_node(lo, hi, k, n), &e, err)) return 0;
        values[k] = ellipse_field(&e, i);
    }
    rm_chebyshev_coefficients(values, n, coeffs);
    return 1;
}

int rm_contact_law_build(int law, double E_star, double r_y, double x_lo, double x_hi,
                         RmContactLaw* c, RmText* err)
{
    c->law = law;
    c->E_star = E_star;
    c->r_y = r_y;
    c->x_lo = x_lo;
    c->x_hi = x_hi;
    c->terms = 0;
    c->t_mid = 0.5 * (x_lo + x_hi);
    double half = 0.5 * (x_hi - x_lo);
    c->t_scale = half > 0.0 ? 1.0 / half : 0.0;
    if (law == RM_LAW_EQUIVALENT_SPHERE) return 1;
    if (law != RM_LAW_EXACT) {
        rm_printf(err, "contact law %d unknown; allowed: 0, 1", law);
        return 0;
    }
    double lo = x_lo, hi = x_hi;
    if (hi - lo < 1e-12) { /* a single ratio: constant series */
        RmEllipse e;
        if (!rm_exact_ellipse(exp(lo), &e, err)) return 0;
        c->kappa[0] = e.kappa;
        c->alpha[0] = e.alpha;
        c->zeta[0] = e.zeta;
        c->terms = 1;
        return 1;
    }
    EllipseCache cache = {0, 0, NULL, NULL};
    double checks[23];
    for (int k = 0; k < 23; k++) checks[k] = lo + (hi - lo) * ((double)k + 0.5) / 23.0;
    double worst = 0.0;
    int ok = 0, failed = 0;
    for (int terms = 8; terms <= RM_MAX_CHEBYSHEV_TERMS && !ok && !failed; terms += 4) {
        double* fits[3] = {c->kappa, c->alpha, c->zeta};
        for (int i = 1; i <= 3 && !failed; i++)
            if (!chebyshev_fit(&cache, i, lo, hi, terms, fits[i - 1], err)) failed = 1;
        worst = 0.0;
        for (int k = 0; k < 23 && !failed; k++) {
            double x = checks[k];
            double t = (x - c->t_mid) * c->t_scale;
            RmEllipse e;
            if (!cached_ellipse(&cache, x, &e, err)) {
                failed = 1;
                break;
            }
            for (int i = 1; i <= 3; i++) {
                double exact = ellipse_field(&e, i);
                worst = rm_max(worst,
                               fabs(rm_chebyshev_value(fits[i - 1], terms, t) - exact) / exact);
            }
        }
        if (!failed && worst <= CHEBYSHEV_TOLERANCE) {
            c->terms = terms;
            ok = 1;
        }
    }
    free(cache.x);
    free(cache.e);
    if (!ok && !failed) {
        rm_printf(err, "parameter 'contact.hertz_law' = 0 (exact elliptical Hertz contact): the "
                       "exact Hertz law cannot be tabulated for ln(R/r) in [%.4r, %.4r] to %.6r "
                       "(reached %.3r); allowed for this geometry: contact.hertz_law = 1 "
                       "(equivalent sphere)", lo, hi, CHEBYSHEV_TOLERANCE, worst);
    }
    return ok;
}

/* The law at the contact radius r_x: the stiffness non-linearity K [N/m^1.5], the larger
 * radius R [m] and the coefficients of the semi-major axis a = ka W^(1/3) [m] and of the
 * area A = kz W^(2/3) [m^2]. */
void rm_contact_law_at(const RmContactLaw* c, RmFail* f, double r_x, double* K, double* R,
                       double* ka, double* kz)
{
    rm_contact_law_at_radii(c, f, r_x, c->r_y, K, R, ka, kz);
}

void rm_contact_law_at_radii(const RmContactLaw* c, RmFail* f, double r_x, double r_y,
                             double* K, double* R, double* ka, double* kz)
{
    double E = c->E_star;
    if (c->law == RM_LAW_EXACT) {
        double rho;
        if (r_y >= r_x) {
            *R = r_y;
            rho = r_y / r_x;
        }
        else {
            *R = r_x;
            rho = r_x / r_y;
        }
        double t = (rm_log_checked(f, rho) - c->t_mid) * c->t_scale;
        *K = E * rm_sqrt_checked(f, *R) * rm_chebyshev_value(c->kappa, c->terms, t);
        double cr = rm_pow_checked(f, *R / E, 1.0 / 3.0);
        *ka = cr * rm_chebyshev_value(c->alpha, c->terms, t);
        *kz = cr * cr * rm_chebyshev_value(c->zeta, c->terms, t);
        return;
    }
    /* equivalent sphere (eq. 2) with Johnson's approximate ellipse, a along the larger radius */
    *K = (4.0 / 3.0) * E * rm_sqrt_checked(f, rm_sqrt_checked(f, r_x * r_y));
    double g = rm_pow_checked(f, 3.0 * rm_sqrt_checked(f, r_x * r_y) / (4.0 * E), 1.0 / 3.0);
    double stretch;
    if (r_y >= r_x) {
        *R = r_y;
        stretch = rm_pow_checked(f, r_y / r_x, 1.0 / 3.0);
    }
    else {
        *R = r_x;
        stretch = rm_pow_checked(f, r_x / r_y, 1.0 / 3.0);
    }
    *ka = g * stretch;
    *kz = RM_PI * g * g;
}

/* delta_max of eq. (7)-(8): the equivalent ellipsoid of mass m = rho pi r_x^2 l, l = 2a its
 * contact ellipse's long diameter at the peak load W = K delta_max^(3/2), striking at v:
 * 1/2 m v^2 = 2/5 K delta_max^(5/2).  With a = ka W^(1/3), m = C sqrt(delta_max) where
 * C = 2 rho pi r_x^2 ka K^(1/3), and the balance has the closed form
 * delta_max = |v| sqrt(5 C / (4 K)). */
double rm_film_delta_max(RmFail* f, double v, double K, double r_x, double ka, double density)
{
    double C = 2.0 * density * RM_PI * r_x * r_x * ka * rm_pow_checked(f, K, 1.0 / 3.0);
    return fabs(v) * rm_sqrt_checked(f, 5.0 * C / (4.0 * K));
}

/* ---------------------------------------------------------- the pair's load-approach law */
/* Palmgren's line contact of steel (A. Palmgren, Ball and Roller Bearing Engineering, 3rd ed.,
 * 1959; quoted in T. A. Harris, Rolling Bearing Analysis): delta = 3.84e-5 mm (Q / N)^0.9
 * (l / mm)^-0.8, the approach of a roller of effective length l and a raceway under the load
 * Q.  Made dimensionless with the contact modulus of bearing steel (taken as E = 207 GPa,
 * nu = 0.3) and scaled with (W/E*)^0.9 for other moduli, as dimensions require:
 * delta = C_P (W/E*)^0.9 L^-0.8, C_P = 3.84e-8 m (1e-3 m)^0.8 E*_steel^0.9. */
#define PALMGREN_APPROACH 3.84e-8  /* m, at Q = 1 N and l = 1 mm */
#define PALMGREN_LENGTH 1e-3       /* m */
#define PALMGREN_LOAD_EXPONENT 0.9
#define PALMGREN_LENGTH_EXPONENT 0.8
#define PALMGREN_STEEL_MODULUS (207e9 / (1.0 - 0.3 * 0.3) * 0.5) /* E* of steel on steel [Pa] */
/* Greenwood and Tripp (1970), in the form Gohar and Rahnejat (Fundamentals of Tribology,
 * 2008) and the paper's group use: asperity pressure p = K' E* F_5/2(h/sigma),
 * K' = (16 sqrt(2) / 15) pi (eta gamma sigma)^2 sqrt(sigma / gamma), with the fit
 * F_5/2(lambda) = 4.4086e-5 (4 - lambda)^6.804 for lambda < 4 (0 beyond: first asperity
 * contact at four sigma). */
#define GT_FIT_COEFFICIENT 4.4086e-5
#define GT_FIT_EXPONENT 6.804
/* Newton's method on the series law (it converges from above, monotonically): the iteration
 * cap (never reached: a few iterations reach rounding). */
#define SERIES_MAX_ITERATIONS 100
/* Newton's method on the teeth's series law converges quadratically, its error after a step of
 * relative size r about r^2: past a step of 1e-8 the next is below rounding. */
#define SERIES_STEP_TOLERANCE 1e-8

void rm_approach_law_build(RmApproachLaw* a, int line, int rough, double E_star, double sigma,
                           double gamma, double asperity_density)
{
    double n = GT_FIT_EXPONENT;
    a->line = line;
    a->rough = rough;
    a->E_star = E_star;
    a->sigma = sigma;
    a->exponent = line ? 1.0 / PALMGREN_LOAD_EXPONENT : 1.5;
    a->palmgren = PALMGREN_APPROACH * rm_pow(PALMGREN_LENGTH, PALMGREN_LENGTH_EXPONENT)
                  * rm_pow(PALMGREN_STEEL_MODULUS, PALMGREN_LOAD_EXPONENT);
    double roughness = asperity_density * gamma * sigma;
    double K_prime = (16.0 * sqrt(2.0) / 15.0) * RM_PI * roughness * roughness
                     * sqrt(sigma / gamma);
    a->asperity_pressure = K_prime * E_star * GT_FIT_COEFFICIENT;
    a->rough_exponent = line ? 1.0 / (n + 0.5) : 1.0 / (n + 1.0);
    /* B(1/2, n + 1) = Gamma(1/2) Gamma(n + 1) / Gamma(n + 3/2) (tgamma: lgamma would write
     * the global signgam) */
    a->line_beta = tgamma(0.5) * tgamma(n + 1.0) / tgamma(n + 1.5);
    /* f(e), the root of f^2 + e f^3 = 1 (Newton's method from f = 1, above it, to rounding),
     * and by implicit differentiation f' = -f^2 / D, f'' = -(2 f f' D - f^2 D') / D^2 with
     * D = 2 + 3 e f, D' = 3 f + 3 e f' */
    for (int k = 0; k <= RM_TOOTH_ROOT_POINTS; k++) {
        double e = (double)k * RM_TOOTH_ROOT_STEP, f_k = 1.0;
        for (int it = 0; it < SERIES_MAX_ITERATIONS; it++) {
            double g = f_k * f_k + e * f_k * f_k * f_k - 1.0;
            double next = f_k - g / (2.0 * f_k + 3.0 * e * f_k * f_k);
            if (!(g > 0.0) || !(next < f_k)) break;
            f_k = next;
        }
        double D = 2.0 + 3.0 * e * f_k, d1 = -f_k * f_k / D;
        a->tooth_root[k][0] = f_k;
        a->tooth_root[k][1] = d1;
        a->tooth_root[k][2] = -(2.0 * f_k * d1 * D - f_k * f_k * (3.0 * f_k + 3.0 * e * d1))
                              / (D * D);
    }
}

/* K = E* (L^0.8 / C_P)^(10/9) of Palmgren's law W = K delta^(10/9). */
double rm_line_coefficient(const RmApproachLaw* a, RmFail* f, double length)
{
    double base = rm_pow_checked(f, length, PALMGREN_LENGTH_EXPONENT) / a->palmgren;
    return a->E_star * rm_pow_checked(f, base, a->exponent);
}

/* The line contact's area 2 b L, b = sqrt(4 W r_x / (pi L E*)) its Hertz half-width (Johnson
 * eq. 4.43): A = kz sqrt(W), kz = 4 sqrt(r_x L / (pi E*)). */
double rm_line_area_coefficient(const RmApproachLaw* a, RmFail* f, double r_x, double length)
{
    return 4.0 * rm_sqrt_checked(f, r_x * length / (RM_PI * a->E_star));
}

/* W_r of W = W_r (delta_a / sigma)^(1/q): the asperity pressure P_a ((delta_a - u)/sigma)^n
 * at nominal gap u above the first contact, integrated over the pair's rigid gap,
 *   ellipsoid: dA = 2 pi sqrt(r_x r_y) du, W = 2 pi sqrt(r_x r_y) P_a sigma / (n + 1) t^(n+1);
 *   cylinder:  dA = L sqrt(r_x / (2u)) du,  W = L sqrt(2 r_x sigma) P_a B(1/2, n+1) t^(n+1/2);
 * t = delta_a / sigma. */
double rm_asperity_scale(const RmApproachLaw* a, RmFail* f, double r_x, double r_y,
                         double length)
{
    double P = a->asperity_pressure;
    if (a->line)
        return length * rm_sqrt_checked(f, 2.0 * r_x * a->sigma) * P * a->line_beta;
    return 2.0 * RM_PI * rm_sqrt_checked(f, r_x * r_y) * P * a->sigma / (GT_FIT_EXPONENT + 1.0);
}

/* The series law: W from delta = (W/K)^(1/p) + sigma (W/W_r)^q [+ c_t W] by Newton's method
 * on y = ln W, where the approach is a sum of exponentials (convex, increasing): from the
 * smallest of the one-sided loads (each above the solution) the iterates fall monotonically
 * to it.  *bulk and *layer get the two approaches at the solution (the teeth's is c_t W;
 * c_t = 0: rigid teeth, the two-term law exactly). */
static double series_load(const RmApproachLaw* a, RmFail* f, double K, double W_r, double c_t,
                          double pen, double* bulk, double* layer)
{
    double p = a->exponent, q = a->rough_exponent, sigma = a->sigma;
    double ln_K = rm_log_checked(f, K), ln_r = rm_log_checked(f, W_r);
    double ln_pen = rm_log_checked(f, pen);
    double y = rm_min(ln_K + p * ln_pen, ln_r + (ln_pen - rm_log_checked(f, sigma)) / q);
    if (c_t > 0.0) y = rm_min(y, ln_pen - rm_log_checked(f, c_t));
    double b = rm_exp_checked(f, (y - ln_K) / p), l = sigma * rm_exp_checked(f, q * (y - ln_r));
    double t = c_t > 0.0 ? c_t * rm_exp_checked(f, y) : 0.0;
    for (int it = 0; it < SERIES_MAX_ITERATIONS; it++) {
        double excess = b + l + t - pen; /* (t = +0 adds nothing: the rigid law's numbers) */
        if (!(excess > 0.0)) break;
        double y_new = y - excess / (b / p + q * l + t);
        if (!(y_new < y)) break;
        y = y_new;
        b = rm_exp_checked(f, (y - ln_K) / p);
        l = sigma * rm_exp_checked(f, q * (y - ln_r));
        if (c_t > 0.0) t = c_t * rm_exp_checked(f, y);
    }
    *bulk = b;
    *layer = l;
    return rm_exp_checked(f, y);
}

/* z^n for a small n >= 1 by multiplication. */
static inline double power_n(double z, int n)
{
    double r = z;
    for (int k = 1; k < n; k++) r *= z;
    return r;
}

/* The smooth law W = K x^p in series with the teeth, pen = x + c_t W: W and the contact's
 * approach x.  With x = z^m (m = 2 for Hertz, p = 3/2; m = 9 for Palmgren's p = 10/9) the
 * approach pen = z^m + c_t K z^(m+1) is a polynomial, convex and increasing in z > 0.  For
 * Hertz z = sqrt(pen) f(e), e = c_t K sqrt(pen), f the root of f^2 + e f^3 = 1 -- one function
 * for every pair and load, tabulated once (rm_approach_law_build) and interpolated by quintic
 * Hermite polynomials in e < 2 (to rounding: tests/model/test_compliance.py),
 * with no division or library call but the square root (the law is evaluated per loaded pair
 * at every right-hand side).  Beyond (e >= 2: tens of um of penetration), and for Palmgren's
 * law, Newton's method falls monotonically to the root from the smaller of the one-sided
 * roots pen^(1/m), (pen / (c_t K))^(1/(m+1)), each above it. */
static double tooth_series_load(const RmApproachLaw* a, RmFail* f, double K, double c_t,
                                double pen, double* approach)
{
    int m = a->line ? 9 : 2;
    double C = c_t * K;
    double z;
    if (a->line) {
        z = rm_pow_checked(f, pen, 1.0 / 9.0);
        if (C * z > 1.0) z = rm_min(z, rm_pow_checked(f, pen / C, 0.1));
    }
    else {
        double root = rm_sqrt_checked(f, pen), e = C * root;
        double x = e * (1.0 / RM_TOOTH_ROOT_STEP);
        if (x < (double)RM_TOOTH_ROOT_POINTS) {
            int k = (int)x;
            z = root * rm_quintic_hermite(x - (double)k, RM_TOOTH_ROOT_STEP, a->tooth_root[k],
                                          a->tooth_root[k + 1]);
            *approach = z * z;
            return K * (z * z) * z;
        }
        z = rm_min(root, cbrt(pen / C));
    }
    int lifted = 0;
    for (int it = 0; it < SERIES_MAX_ITERATIONS; it++) {
        double z_m1 = power_n(z, m - 1), z_m = z_m1 * z;
        double excess = z_m + C * z_m * z - pen;
        double z_new = z - excess / ((double)m * z_m1 + (double)(m + 1) * C * z_m);
        if (!(excess > 0.0)) {
            if (!(excess < 0.0) || lifted) break;
            lifted = 1; /* below the root: one step up */
        }
        else if (!(z_new < z))
            break;
        else if (z - z_new <= SERIES_STEP_TOLERANCE * z) { /* the next step is at rounding */
            z = z_new;
            break;
        }
        z = z_new;
    }
    double x = power_n(z, m);
    *approach = x;
    return K * x * z;
}

/* W = K pen^p of the smooth law (Hertz written as K pen sqrt(pen)). */
static double smooth_load(const RmApproachLaw* a, RmFail* f, double K, double pen)
{
    if (a->line) return K * rm_pow_checked(f, pen, a->exponent);
    return K * (pen * rm_sqrt_checked(f, pen));
}

/* A load below the smallest normal double (2.2e-308 N) is none: a subnormal keeps a few bits
 * at most (the series law's exp() of a log-space sum), and whether a pair counts as loaded --
 * its friction, film and area (mesh.c) -- must not turn on them. */
double rm_approach_force(const RmApproachLaw* a, RmFail* f, double K, double W_r, double c_t,
                         double pen, double* surface)
{
    if (surface != NULL) *surface = pen;
    if (!(K > 0.0 && c_t < INFINITY)) return 0.0; /* a line of zero length */
    double W, x;
    if (!a->rough) {
        if (c_t > 0.0) {
            W = tooth_series_load(a, f, K, c_t, pen, &x);
            if (surface != NULL) *surface = x;
        }
        else
            W = smooth_load(a, f, K, pen);
    }
    else {
        double bulk, layer;
        W = series_load(a, f, K, W_r, c_t, pen, &bulk, &layer);
        if (c_t > 0.0 && surface != NULL) *surface = bulk + layer;
    }
    return W < DBL_MIN ? 0.0 : W;
}

/* dW/d(pen): p W / pen for the smooth law (Hertz: 1.5 K sqrt(pen)); for the series laws the
 * inverse of the compliances' sum, W / (bulk/p + q layer [+ c_t W]), with the teeth
 * 1 / (x / (p W) + c_t). */
void rm_approach_rates(const RmApproachLaw* a, RmFail* f, double K, double W_r, double c_t,
                       double pen, double d, double* k, double* c)
{
    if (!(K > 0.0 && c_t < INFINITY)) {
        *k = *c = 0.0;
        return;
    }
    if (c_t > 0.0 && !a->rough) {
        double x, W = tooth_series_load(a, f, K, c_t, pen, &x);
        *k = W > 0.0 ? W / (x / a->exponent + c_t * W) : 0.0;
        *c = d * W;
        return;
    }
    if (!a->rough && !a->line) {
        double root = rm_sqrt_checked(f, pen);
        *k = 1.5 * K * root;
        *c = K * d * (pen * root);
        return;
    }
    double W, compliance;
    if (a->rough) {
        double bulk, layer;
        W = series_load(a, f, K, W_r, c_t, pen, &bulk, &layer);
        compliance = bulk / a->exponent + a->rough_exponent * layer;
        if (c_t > 0.0) compliance += c_t * W;
    }
    else {
        W = smooth_load(a, f, K, pen);
        compliance = pen / a->exponent;
    }
    *k = W / compliance;
    *c = d * W;
}

/* integral_0^pen W: W pen / (p + 1) for the smooth law; for the series law, with
 * integral_0^W delta dW' = W bulk p/(p+1) + W layer/(q+1),
 * W (bulk + layer) minus that = W bulk / (p + 1) + W layer q / (q + 1); the teeth add their
 * spring's c_t W^2 / 2. */
double rm_approach_energy(const RmApproachLaw* a, RmFail* f, double K, double W_r, double c_t,
                          double pen)
{
    if (!(K > 0.0 && c_t < INFINITY)) return 0.0;
    double p = a->exponent;
    if (!a->rough) {
        if (!(c_t > 0.0)) return smooth_load(a, f, K, pen) * pen / (p + 1.0);
        double x, W = tooth_series_load(a, f, K, c_t, pen, &x);
        return W * x / (p + 1.0) + 0.5 * c_t * W * W;
    }
    double bulk, layer;
    double W = series_load(a, f, K, W_r, c_t, pen, &bulk, &layer);
    double q = a->rough_exponent;
    double energy = W * bulk / (p + 1.0) + W * layer * q / (q + 1.0);
    return c_t > 0.0 ? energy + 0.5 * c_t * W * W : energy;
}

double rm_approach_area(const RmApproachLaw* a, RmFail* f, double kz, double W)
{
    if (a->line) return kz * rm_sqrt_checked(f, W);
    return kz * rm_pow_checked(f, W, 2.0 / 3.0);
}

/* eq. 7 with the pair's smooth law: the ellipsoid's (rm_film_delta_max), or for the line
 * contact the equivalent solid of mass m = rho pi r_x^2 L (its length the contact line's, as
 * eq. 8 takes the footprint's) on W = K delta^(10/9):
 * 1/2 m v^2 = 9/19 K delta^(19/9), delta_max = (19 m v^2 / (18 K))^(9/19). */
double rm_approach_film_delta_max(const RmApproachLaw* a, RmFail* f, double v, double K,
                                  double r_x, double ka, double length, double density)
{
    if (!a->line) return rm_film_delta_max(f, v, K, r_x, ka, density);
    if (!(K > 0.0)) return 0.0;
    double p = a->exponent;
    double m = density * RM_PI * r_x * r_x * length;
    return rm_pow_checked(f, (p + 1.0) * m * v * v / (2.0 * K), 1.0 / (p + 1.0));
}

/* ------------------------------------------------------------------ Hunt-Crossley */
/* x - ln(1 + x) for x > -1.  Near 0 the two terms cancel to x^2/2 (at x = 1e-7, 14 of 16
 * digits lost, which moved the restitution of a near-elastic impact by 2e-10), so there it is
 * the series sum_{k>=2} (-x)^k / k (below 0.1 in magnitude, 22 terms reach the rounding). */
static double x_minus_log1p(double x)
{
    if (!(fabs(x) < 0.1)) return x - log1p(x);
    double power = x * x, sum = 0.0; /* power = x^k */
    for (int k = 2; k <= 23; k++) {
        sum += (k % 2 == 0 ? power : -power) / k;
        power *= x;
    }
    return sum;
}

/* G(alpha, e) = alpha - ln(1 + alpha) + alpha e + ln(1 - alpha e)
 *             = phi(alpha) - phi(-alpha e), phi(x) = x - ln(1 + x): zero on the restitution
 * curve.  With the speed u = d(delta)/dt as variable, m u du = -K delta^n (1 + d u) d delta
 * separates: u/d - ln(1 + d u)/d^2 changes by -(K/m) integral delta^n d delta, which is zero
 * from the onset back to the release, so alpha - ln(1 + alpha) = -alpha e - ln(1 - alpha e)
 * with 0 <= e < 1/alpha (the force never turns tensile). */
static double hc_balance(double alpha, double e)
{
    return x_minus_log1p(alpha) - x_minus_log1p(-alpha * e);
}

static double hc_balance_fn(void* ctx, double e) { return hc_balance(*(const double*)ctx, e); }

/* The coefficient of restitution e of an impact on W = K delta^n (1 + d delta_dot) at
 * approach speed v, alpha = d v >= 0 (any n, K and mass): exact, by Brent's method. */
int rm_hunt_crossley_restitution(double alpha, double* e, RmText* err)
{
    if (!(alpha >= 0.0 && isfinite(alpha))) {
        rm_printf(err, "alpha = d v = %r must be finite and >= 0", alpha);
        return 0;
    }
    if (alpha == 0.0) {
        *e = 1.0;
        return 1;
    }
    /* G falls in e from G(alpha, 0) > 0 towards -inf at e = 1/alpha; at e = 1 it is
     * 2 alpha - 2 artanh(alpha) < 0.  Past alpha ~ 40 the root is 1/alpha to rounding. */
    double hi = rm_min(1.0, 1.0 / alpha) * (1.0 - 1e-15);
    if (hc_balance(alpha, hi) >= 0.0) {
        *e = hi;
        return 1;
    }
    return solve(hc_balance_fn, &alpha, 0.0, hi, RESTITUTION_XTOL, e, err);
}

typedef struct {
    double e;
    RmText* err;
    int ok;
} HcCtx;

static double hc_factor_fn(void* vctx, double a)
{
    HcCtx* c = vctx;
    double r = 0.0;
    if (!rm_hunt_crossley_restitution(a, &r, c->err)) c->ok = 0;
    return r - c->e;
}

/* The Hunt-Crossley factor d [s/m] for which an impact at speed v [m/s] rebounds with the
 * coefficient of restitution e in (0, 1] (e = 1 gives d = 0). */
int rm_hunt_crossley_factor(double e, double v, double* d, RmText* err)
{
    if (!(0.0 < e && e <= 1.0) || !(v > 0.0)) {
        rm_printf(err, "restitution e = %r must be in (0, 1] and speed v = %r > 0", e, v);
        return 0;
    }
    if (e == 1.0) {
        *d = 0.0;
        return 1;
    }
    /* bracket: e(alpha) falls from 1 (alpha = 0) towards 0 and stays below 1/alpha */
    double hi = 1.0, r;
    for (;;) {
        if (!rm_hunt_crossley_restitution(hi, &r, err)) return 0;
        if (!(r > e)) break;
        hi *= 2.0;
    }
    HcCtx ctx = {e, err, 1};
    double alpha;
    if (!solve(hc_factor_fn, &ctx, 0.0, hi, ROOT_XTOL, &alpha, err) || !ctx.ok) return 0;
    *d = alpha / v;
    return 1;
}
