/*
 * rattle_kernel.c - compiled twin of the pure-Python wheel stepper of drive_rattle.
 *
 * This file is a line-by-line port of
 *   drive_rattle/stepper.py     WheelStepper.step, contact_flank and _StepRun (free flight,
 *                               RK4 contact substeps split at breakpoints and subdivided from
 *                               the contact's time scales, release, friction-reversal and
 *                               pair-engagement location, peak tracking, rattle index, guards)
 *                               and WheelStepper.outputs (the values of interface.MESH_OUTPUTS)
 *   drive_rattle/mesh.py        MeshModel._loads / torques / static_force / contact_rates /
 *                               energy_balance_delta_max / penetration / approach_rate ...
 *   drive_rattle/geometry.py    pairs_at_roll, next_breakpoint, normal_radii, flank_roll
 *   drive_rattle/hertz.py       ContactLaw.coefficients (Chebyshev series, Clenshaw), film_delta_max
 *   drive_rattle/lubrication.py film_thickness, asperity_area, dry_fraction, friction_force
 *   drive_rattle/roots.py       brent, first_crossing
 * that reproduces the Python results BIT FOR BIT (docs/kernel.md).  The Python code is the
 * reference: every expression below performs the same IEEE operations in the same order as
 * the Python line it ports (Python evaluates a + b + c as (a + b) + c, x ** y is pow(x, y),
 * math.sqrt is sqrt, math.log is log, math.exp is exp, an int operand is converted to double
 * first).  Do not "simplify" an expression here (x*sqrt(x) for x**1.5, fmax for max(),
 * hoisting a product, ...): a one-ulp difference changes the impact sequence of the chaotic
 * rattle motion.
 *
 * Python's max(a, b) returns a unless b > a (so max(nan, x) is nan, max(x, nan) is x and
 * max(-0.0, 0.0) is -0.0); py_max reproduces that, fmax would not.
 *
 * Build (drive_rattle_build.kernel.compile_kernel does this):
 *   gcc -std=c99 -O2 -fno-fast-math -ffp-contract=off -fPIC -shared -o _rattle_kernel.so \
 *       rattle_kernel.c -lm
 * -ffp-contract=off is required: a fused multiply-add rounds once instead of twice.
 *
 * The layouts of the arrays shared with Python (model, state, result, outputs, inputs), the
 * return codes and the codes of flanks, laws and friction forms come from
 * rattle_kernel_layout.h, which drive_rattle/kernel_layout.py generates; RK_LAYOUT_HASH
 * identifies that layout.  The geometry, the contact law's Chebyshev series and the module
 * constants are computed once in Python (kernel_layout.pack_model) and passed in the model
 * array: nothing is derived again here.
 *
 * Refusals: where the Python step raises, rk_step returns a code (RK_ERR_...), leaves state
 * and result unchanged and passes the numbers the refusal needs in err_values: those its
 * message quotes (RK_ERR_DIVERGED, _PENETRATION, _TOO_STIFF, _NO_BRACKET, ...), or, where
 * Python fails inside a library call (math.sqrt, math.log, math.exp, math.floor, math.ceil,
 * int(), **, a comparison with None: RK_ERR_LIBRARY), which call (RK_CALL_...) with its
 * arguments.  This file holds no message text: kernel.py raises the exception Python raises,
 * from the functions the Python core raises from, or by making the same library call.
 */
#include <math.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>

#include "rattle_kernel_layout.h"

#define EXPORT __attribute__((visibility("default")))

#define PI 3.141592653589793 /* math.pi */
#define N_SLOTS RK_N_SLOTS

/* The pair block of the outputs is contiguous: out[O_PAIR_0_W + k] is pair[k].W. */
typedef char pair_outputs_are_contiguous[O_PAIR_7_W - O_PAIR_0_W == N_SLOTS - 1 ? 1 : -1];

/* ------------------------------------------------------------------ model and state */
typedef struct {
    double rb_pinion, flank_phase, base_pitch, line_span, s_start, s_end, line_length;
    double normal_factor, half_backlash, crown_factor;
    int n_bp;
    double bp[RK_MAX_BREAKPOINTS];
    double cos_alpha_t, sin_alpha_t, sin_beta_b;
    double E_star, arm_wheel, arm_pinion, normal_mass, damping;
    int64_t law;
    double law_E_star, r_y, t_mid, t_scale;
    int n_cheb;
    const double *kappa, *alpha, *zeta; /* into the model array */
    double J, tau_s, eta, sigma, gamma, density, h_max, h_comm_max, rattle_time;
    int friction_enabled;
    int64_t friction_form, shear_speed;
    double pen_limit, bp_tol, brent_rtol, event_xtol, engagement_min_fraction;
    int64_t grazing_samples, brent_max_iter, max_contact_substeps;
    double lambda_boundary, lambda_full_film, contact_rate_safety, grid_slack;
    double sqrt_gamma_sigma; /* math.sqrt(gamma / sigma), the same value every call */
} Model;

typedef struct {
    double phi, w;
    int64_t flank;
    double v_drive, v_coast, v_last;
    int64_t n_drive, n_coast;
    double rattle_index;
} State;

/* Error exit: the code and the values of the refusal, then longjmp back to the entry point. */
typedef struct {
    jmp_buf jb;
    int code;
    double values[RK_ERROR_VALUES];
} Fail;

static void fail(Fail* f, int code, double v0, double v1, double v2, double v3)
{
    f->code = code;
    f->values[0] = v0;
    f->values[1] = v1;
    f->values[2] = v2;
    f->values[3] = v3;
    longjmp(f->jb, 1);
}

/* A library call that raises in Python: which one (RK_CALL_...) and its arguments. */
static void fail_call(Fail* f, int call, double x, double y)
{
    fail(f, RK_ERR_LIBRARY, (double)call, x, y, 0.0);
}

/* ------------------------------------------------------------------ Python semantics */
/* max(a, b): a unless b > a. */
static inline double py_max(double a, double b) { return b > a ? b : a; }

/* x ** y for the exponents used (1/3, 2/3): CPython's float_pow calls pow(x, y) for a
 * positive finite base and raises OverflowError when a finite base gives an infinite
 * result; a negative base with a fractional exponent gives a complex number in Python, which
 * the kernel does not follow (never reached: the bases are stiffnesses, loads and lengths). */
static inline double py_pow(Fail* f, double x, double y)
{
    double r = pow(x, y);
    if (x < 0.0 || (isinf(r) && isfinite(x)))
        fail_call(f, RK_CALL_POW, x, y);
    return r;
}

/* math.sqrt / math.log / math.exp where CPython raises a domain or range error. */
static inline double py_sqrt(Fail* f, double x)
{
    if (x < 0.0)
        fail_call(f, RK_CALL_SQRT, x, 0.0);
    return sqrt(x);
}

static inline double py_log(Fail* f, double x)
{
    if (x <= 0.0)
        fail_call(f, RK_CALL_LOG, x, 0.0);
    return log(x);
}

static inline double py_exp(Fail* f, double x)
{
    double r = exp(x);
    if (isinf(r) && isfinite(x))
        fail_call(f, RK_CALL_EXP, x, 0.0);
    return r;
}

/* math.floor / math.ceil return ints (CPython raises for a float that is not finite).  The
 * pair and breakpoint arithmetic keeps the integer in a double: float(int(floor(x)) + 1)
 * equals floor(x) + 1.0 for every finite x (both are the correctly rounded exact sum). */
static inline double py_floor(Fail* f, double x)
{
    if (!isfinite(x))
        fail_call(f, RK_CALL_FLOOR, x, 0.0);
    return floor(x);
}

static inline double py_ceil(Fail* f, double x)
{
    if (!isfinite(x))
        fail_call(f, RK_CALL_CEIL, x, 0.0);
    return ceil(x);
}

/* ------------------------------------------------------------------ unpacking */
/* Returns RK_ERR_OK, RK_ERR_LAYOUT (an array of another layout) or RK_ERR_MODEL_VALUES
 * (counts out of the kernel's range, passed in err_values). */
static int unpack_model(const double* a, Model* m, double* err_values)
{
    if (a == NULL || a[M_MAGIC] != RK_MAGIC || a[M_LAYOUT_HASH] != (double)RK_LAYOUT_HASH
        || a[M_SIZE] != (double)M_COUNT)
        return RK_ERR_LAYOUT;
    m->rb_pinion = a[M_RB_PINION];
    m->flank_phase = a[M_FLANK_PHASE];
    m->base_pitch = a[M_BASE_PITCH];
    m->line_span = a[M_LINE_SPAN];
    m->s_start = a[M_S_START];
    m->s_end = a[M_S_END];
    m->line_length = a[M_LINE_LENGTH];
    m->normal_factor = a[M_NORMAL_FACTOR];
    m->half_backlash = a[M_HALF_BACKLASH];
    m->crown_factor = a[M_CROWN_FACTOR];
    m->n_bp = (int)a[M_N_BREAKPOINTS];
    m->n_cheb = (int)a[M_CHEBYSHEV_TERMS];
    m->law = (int64_t)a[M_LAW];
    if (m->n_bp < 0 || m->n_bp > M_BREAKPOINTS_LENGTH || m->n_cheb < 0
        || m->n_cheb > M_KAPPA_LENGTH || (m->law == RK_LAW_EXACT && m->n_cheb < 1)) {
        if (err_values != NULL) {
            err_values[0] = (double)m->n_bp;
            err_values[1] = (double)m->n_cheb;
            err_values[2] = (double)m->law;
            err_values[3] = 0.0;
        }
        return RK_ERR_MODEL_VALUES;
    }
    for (int i = 0; i < RK_MAX_BREAKPOINTS; i++)
        m->bp[i] = a[M_BREAKPOINTS + i];
    m->cos_alpha_t = a[M_COS_ALPHA_T];
    m->sin_alpha_t = a[M_SIN_ALPHA_T];
    m->sin_beta_b = a[M_SIN_BETA_B];
    m->E_star = a[M_E_STAR];
    m->arm_wheel = a[M_ARM_WHEEL];
    m->arm_pinion = a[M_ARM_PINION];
    m->normal_mass = a[M_NORMAL_MASS];
    m->damping = a[M_DAMPING];
    m->law_E_star = a[M_LAW_E_STAR];
    m->r_y = a[M_R_Y];
    m->t_mid = a[M_T_MID];
    m->t_scale = a[M_T_SCALE];
    m->kappa = a + M_KAPPA;
    m->alpha = a + M_ALPHA;
    m->zeta = a + M_ZETA;
    m->J = a[M_J_WHEEL];
    m->friction_enabled = a[M_FRICTION_ENABLED] != 0.0;
    m->friction_form = (int64_t)a[M_FRICTION_FORM];
    m->shear_speed = (int64_t)a[M_SHEAR_SPEED];
    m->tau_s = a[M_TAU_S];
    m->eta = a[M_ETA];
    m->sigma = a[M_SIGMA];
    m->gamma = a[M_GAMMA];
    m->density = a[M_DENSITY];
    m->h_max = a[M_H_MAX];
    m->h_comm_max = a[M_H_COMM_MAX];
    m->rattle_time = a[M_RATTLE_TIME];
    m->pen_limit = a[M_PENETRATION_LIMIT];
    m->bp_tol = a[M_BREAKPOINT_TOLERANCE];
    m->grazing_samples = (int64_t)a[M_GRAZING_SAMPLES];
    m->brent_max_iter = (int64_t)a[M_BRENT_MAX_ITERATIONS];
    m->brent_rtol = a[M_BRENT_RTOL];
    m->event_xtol = a[M_EVENT_XTOL];
    m->engagement_min_fraction = a[M_ENGAGEMENT_MIN_FRACTION];
    m->lambda_boundary = a[M_LAMBDA_BOUNDARY];
    m->lambda_full_film = a[M_LAMBDA_FULL_FILM];
    m->contact_rate_safety = a[M_CONTACT_RATE_SAFETY];
    m->max_contact_substeps = (int64_t)a[M_MAX_CONTACT_SUBSTEPS];
    m->grid_slack = a[M_GRID_SLACK];
    m->sqrt_gamma_sigma = sqrt(m->gamma / m->sigma);
    return RK_ERR_OK;
}

static void unpack_state(const double* a, State* s)
{
    s->phi = a[S_PHI];
    s->w = a[S_W];
    s->flank = (int64_t)a[S_FLANK];
    s->v_drive = a[S_V_IMPACT_DRIVE];
    s->v_coast = a[S_V_IMPACT_COAST];
    s->v_last = a[S_V_IMPACT_LAST];
    s->n_drive = (int64_t)a[S_IMPACTS_DRIVE];
    s->n_coast = (int64_t)a[S_IMPACTS_COAST];
    s->rattle_index = a[S_RATTLE_INDEX];
}

static void pack_state(const State* s, double* a)
{
    a[S_PHI] = s->phi;
    a[S_W] = s->w;
    a[S_FLANK] = (double)s->flank;
    a[S_V_IMPACT_DRIVE] = s->v_drive;
    a[S_V_IMPACT_COAST] = s->v_coast;
    a[S_V_IMPACT_LAST] = s->v_last;
    a[S_IMPACTS_DRIVE] = (double)s->n_drive;
    a[S_IMPACTS_COAST] = (double)s->n_coast;
    a[S_RATTLE_INDEX] = s->rattle_index;
}

/* ------------------------------------------------------------------ roots.py */
/* first_crossing: smallest t in [0, t_max] where c0 + c1 t + c2 t^2 crosses zero upwards
 * (rising) or downwards; returns 1 and *out, or 0 for None. */
static int first_crossing(double c0, double c1, double c2, double t_max, int rising,
                          double* out)
{
    double sign = rising ? 1.0 : -1.0;
    if (c0 == 0.0 && (sign * c1 > 0.0 || (c1 == 0.0 && sign * c2 > 0.0))) {
        *out = 0.0;
        return 1;
    }
    double roots[2];
    int n = 0;
    if (c2 == 0.0) {
        if (c1 != 0.0)
            roots[n++] = -c0 / c1;
    }
    else {
        double disc = c1 * c1 - 4.0 * c2 * c0;
        if (disc >= 0.0) {
            double sq = sqrt(disc);
            double qq = -0.5 * (c1 + copysign(sq, c1));
            if (qq != 0.0) {
                roots[n++] = qq / c2;
                roots[n++] = c0 / qq;
            }
            else {
                roots[n++] = 0.0;
            }
        }
    }
    int found = 0;
    double best = 0.0;
    for (int i = 0; i < n; i++) {
        double t = roots[i];
        if (0.0 < t && t <= t_max) {
            double slope = c1 + 2.0 * c2 * t;
            int right_way = rising ? (slope > 0.0) : (slope < 0.0);
            if (right_way && (!found || t < best)) {
                best = t;
                found = 1;
            }
        }
    }
    if (found)
        *out = best;
    return found;
}

typedef double (*RootFn)(void* ctx, double x);

/* roots.brent with fa and fb given. */
static double brent(Fail* f, RootFn fn, void* ctx, double a, double b, double fa, double fb,
                    double xtol, double rtol, int64_t max_iter)
{
    if (fa == 0.0)
        return a;
    if (fb == 0.0)
        return b;
    if ((fa > 0.0) == (fb > 0.0))
        fail(f, RK_ERR_NO_BRACKET, a, fa, b, fb);
    double c = a, fc = fa;
    double d = b - a, e = b - a;
    for (int64_t it = 0; it < max_iter; it++) {
        if ((fb > 0.0) == (fc > 0.0)) {
            c = a;
            fc = fa;
            d = e = b - a;
        }
        if (fabs(fc) < fabs(fb)) {
            /* a, fa, b, fb, c, fc = b, fb, c, fc, b, fb */
            double na = b, nfa = fb, nb = c, nfb = fc;
            a = na;
            fa = nfa;
            b = nb;
            fb = nfb;
            c = na;
            fc = nfa;
        }
        double tol = 2.0 * rtol * fabs(b) + 0.5 * xtol;
        double m = 0.5 * (c - b);
        if (fabs(m) <= tol || fb == 0.0)
            return b;
        if (fabs(e) >= tol && fabs(fa) > fabs(fb)) {
            double s = fb / fa;
            double p, q;
            if (a == c) { /* secant */
                p = 2.0 * m * s;
                q = 1.0 - s;
            }
            else { /* inverse quadratic interpolation */
                q = fa / fc;
                double r = fb / fc;
                p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0));
                q = (q - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if (p > 0.0)
                q = -q;
            else
                p = -p;
            double lim1 = 3.0 * m * q - fabs(tol * q);
            double lim2 = fabs(e * q);
            double lim = lim2 < lim1 ? lim2 : lim1; /* min(lim1, lim2) */
            if (2.0 * p < lim) {
                e = d;
                d = p / q;
            }
            else {
                d = e = m;
            }
        }
        else {
            d = e = m;
        }
        a = b;
        fa = fb;
        b += fabs(d) > tol ? d : copysign(tol, m);
        fb = fn(ctx, b);
    }
    return b;
}

/* roots.brent for callers outside the stepper (the native FMUs' start and contact-law fit,
 * rattle_model.c): RK_ERR_OK with the root in *root, or RK_ERR_NO_BRACKET with (a, fa, b, fb)
 * in err_values. */
EXPORT int rk_brent(RootFn fn, void* ctx, double a, double b, double fa, double fb,
                    double xtol, double rtol, int64_t max_iter, double* root,
                    double* err_values)
{
    Fail f;
    f.code = RK_ERR_OK;
    if (setjmp(f.jb) != 0) {
        for (int i = 0; i < RK_ERROR_VALUES; i++)
            err_values[i] = f.values[i];
        return f.code;
    }
    *root = brent(&f, fn, ctx, a, b, fa, fb, xtol, rtol, max_iter);
    return RK_ERR_OK;
}

/* ------------------------------------------------------------------ hertz.py */
/* chebyshev_value: Clenshaw's recurrence for sum_j c_j T_j(t). */
static inline double chebyshev_value(const double* c, int n, double t)
{
    double b1 = 0.0;
    double b2 = 0.0;
    int j = n - 1;
    while (j > 0) {
        double next = 2.0 * t * b1 - b2 + c[j];
        b2 = b1;
        b1 = next;
        j -= 1;
    }
    return t * b1 - b2 + c[0];
}

/* ContactLaw.coefficients(r_x): K, ka, kz (R is not used by the stepper). */
static void law_coefficients(const Model* M, Fail* f, double r_x, double* K, double* ka, double* kz)
{
    double r_y = M->r_y;
    double E = M->law_E_star;
    if (M->law == RK_LAW_EXACT) {
        double R, rho;
        if (r_y >= r_x) {
            R = r_y;
            rho = r_y / r_x;
        }
        else {
            R = r_x;
            rho = r_x / r_y;
        }
        double t = (py_log(f, rho) - M->t_mid) * M->t_scale;
        *K = E * py_sqrt(f, R) * chebyshev_value(M->kappa, M->n_cheb, t);
        double c = py_pow(f, R / E, 1.0 / 3.0);
        *ka = c * chebyshev_value(M->alpha, M->n_cheb, t);
        *kz = c * c * chebyshev_value(M->zeta, M->n_cheb, t);
        return;
    }
    *K = (4.0 / 3.0) * E * py_sqrt(f, py_sqrt(f, r_x * r_y));
    double g = py_pow(f, 3.0 * py_sqrt(f, r_x * r_y) / (4.0 * E), 1.0 / 3.0);
    double stretch;
    if (r_y >= r_x)
        stretch = py_pow(f, r_y / r_x, 1.0 / 3.0);
    else
        stretch = py_pow(f, r_x / r_y, 1.0 / 3.0);
    *ka = g * stretch;
    *kz = PI * g * g;
}

/* hertz.film_delta_max */
static inline double film_delta_max(Fail* f, double v, double K, double r_x, double ka,
                                    double density)
{
    double C = 2.0 * density * PI * r_x * r_x * ka * py_pow(f, K, 1.0 / 3.0);
    return fabs(v) * py_sqrt(f, 5.0 * C / (4.0 * K));
}

/* ------------------------------------------------------------------ lubrication.py */
static inline double dry_fraction(const Model* M, double lam)
{
    if (lam <= M->lambda_boundary)
        return 1.0;
    if (lam >= M->lambda_full_film)
        return 0.0;
    return (M->lambda_full_film - lam) / (M->lambda_full_film - M->lambda_boundary);
}

static inline double friction_force(const Model* M, Fail* f, double psi, double A_e, double A,
                                    double U, double h)
{
    double viscous = psi < 1.0 ? M->eta * fabs(U) / h : 0.0;
    switch (M->friction_form) {
    case RK_FORM_LOAD_SHARING:
        return psi * A_e * M->tau_s + (1.0 - psi) * A * viscous;
    case RK_FORM_APPARENT_AREA:
        return A * (psi * M->tau_s + (1.0 - psi) * viscous);
    case RK_FORM_AS_PRINTED:
        return A_e * (psi * M->tau_s + (1.0 - psi) * viscous);
    default:
        fail(f, RK_ERR_FRICTION_FORM, (double)M->friction_form, 0.0, 0.0, 0.0);
    }
    return 0.0;
}

/* ------------------------------------------------------------------ geometry.py */
static inline double flank_roll(const Model* M, int64_t flank, double phi_p)
{
    return M->flank_phase + (double)flank * M->rb_pinion * phi_p;
}

/* next_breakpoint: returns 1 and *out, or 0 for None. */
static int next_breakpoint(const Model* M, Fail* f, double u_a, double u_b, double* out)
{
    if (u_a == u_b)
        return 0;
    double pb = M->base_pitch;
    double tol = M->bp_tol;
    int found = 0;
    double best = 0.0;
    if (u_b > u_a) {
        for (int i = 0; i < M->n_bp; i++) {
            double bp = M->bp[i];
            double v = bp + (py_floor(f, (u_a + tol - bp) / pb) + 1.0) * pb;
            if (v < u_b && (!found || v < best)) {
                best = v;
                found = 1;
            }
        }
    }
    else {
        for (int i = 0; i < M->n_bp; i++) {
            double bp = M->bp[i];
            double v = bp + (py_ceil(f, (u_a - tol - bp) / pb) - 1.0) * pb;
            if (v > u_b && (!found || v > best)) {
                best = v;
                found = 1;
            }
        }
    }
    if (found)
        *out = best;
    return found;
}

/* The tooth pairs in the zone of action at roll coordinate u (geometry.pairs_at_roll) with
 * the pure functions of them the stepper needs: the contact law's coefficients at the pair's radius
 * (computed on first use) and, per impact speed, the eq. 7 delta_max.  The integrator
 * evaluates the pairs twice at t + h/2 of each RK4 step and at the start of a substep for the
 * right-hand side, the substep length and the friction directions, so a step keeps a few of
 * these sets: each value is computed by the same expression as without the cache, only fewer
 * times. */
#define PAIR_MAX RK_MAX_PAIRS
typedef struct {
    double u;
    int n;
    int64_t slot[PAIR_MAX];
    double s[PAIR_MAX], offset[PAIR_MAX], dg[PAIR_MAX];
    int coefficients_ok[PAIR_MAX];
    double r_x[PAIR_MAX], K[PAIR_MAX], ka[PAIR_MAX], kz[PAIR_MAX];
    double d_max_v;         /* impact speed of the d_max entries */
    int d_max_ok[PAIR_MAX]; /* d_max[i] computed for d_max_v */
    double d_max[PAIR_MAX];
} PairSet;

static inline void pairset_add(Fail* f, PairSet* ps, double n, double s, double g, double dg)
{
    if (ps->n == PAIR_MAX)
        fail(f, RK_ERR_TOO_MANY_PAIRS, (double)PAIR_MAX, 0.0, 0.0, 0.0);
    int i = ps->n++;
    int64_t k = (int64_t)n % N_SLOTS; /* n % MAX_PAIR_SLOTS (Python: never negative) */
    ps->slot[i] = k < 0 ? k + N_SLOTS : k;
    ps->s[i] = s;
    ps->offset[i] = g;
    ps->dg[i] = dg;
    ps->coefficients_ok[i] = 0;
    ps->d_max_ok[i] = 0;
}

/* geometry.pairs_at_roll */
static void pairset_build(const Model* M, Fail* f, double u, PairSet* ps)
{
    double pb = M->base_pitch;
    double half = 0.5 * M->line_span;
    double s0 = M->s_start, s1 = M->s_end;
    double k = M->crown_factor;
    double n_lo = py_floor(f, (u - s1 - half) / pb) + 1.0;
    double n_hi = py_ceil(f, (u - s0 + half) / pb) - 1.0;
    if (!(fabs(n_lo) < RK_PAIR_NUMBER_LIMIT && fabs(n_hi) < RK_PAIR_NUMBER_LIMIT))
        fail(f, RK_ERR_PAIR_NUMBER_RANGE, u, n_lo, 0.0, 0.0);
    ps->u = u;
    ps->n = 0;
    ps->d_max_v = 0.0;
    for (double n = n_lo; n <= n_hi; n += 1.0) {
        double s = u - n * pb; /* roll coordinate of the pair's face centre */
        if (half > 0.0) {
            if (s + half > s0 && s - half < s1) {
                if (s < s0) {
                    double d = s0 - s;
                    pairset_add(f, ps, n, s0, k * d * d, -2.0 * k * d);
                }
                else if (s > s1) {
                    double d = s - s1;
                    pairset_add(f, ps, n, s1, k * d * d, 2.0 * k * d);
                }
                else {
                    pairset_add(f, ps, n, s, 0.0, 0.0);
                }
            }
        }
        else if (s0 < s && s < s1) {
            pairset_add(f, ps, n, s, 0.0, 0.0);
        }
    }
}

/* normal_radii(s)[2] and law.coefficients(r_x) of pair i. */
static inline void pairset_coefficients(const Model* M, Fail* f, PairSet* ps, int i)
{
    if (ps->coefficients_ok[i])
        return;
    double s = ps->s[i];
    double c = M->normal_factor;
    double rp = s / c;
    double rw = (M->line_length - s) / c;
    double r_x = rp * rw / (rp + rw);
    ps->r_x[i] = r_x;
    law_coefficients(M, f, r_x, &ps->K[i], &ps->ka[i], &ps->kz[i]);
    ps->coefficients_ok[i] = 1;
}

/* hertz.film_delta_max(v, K, r_x, ka, density) of pair i (coefficients computed). */
static inline double pairset_d_max(const Model* M, Fail* f, PairSet* ps, int i, double v)
{
    if (!(v == ps->d_max_v)) {
        for (int k = 0; k < ps->n; k++)
            ps->d_max_ok[k] = 0;
        ps->d_max_v = v;
    }
    if (!ps->d_max_ok[i] || v != v) {
        ps->d_max[i] = film_delta_max(f, v, ps->K[i], ps->r_x[i], ps->ka[i], M->density);
        ps->d_max_ok[i] = 1;
    }
    return ps->d_max[i];
}

#define PAIRSET_CACHE 6
typedef struct {
    int n_used, next;
    PairSet set[PAIRSET_CACHE];
} PairCache;

/* The pair set at roll coordinate u: from the cache (same u, bit for bit: == on doubles, and
 * +0.0/-0.0 give the same pairs) or built into it.  The pointer is valid until the next call
 * (a later call may reuse its entry). */
static PairSet* pairs_at(const Model* M, Fail* f, PairCache* c, double u)
{
    for (int i = 0; i < c->n_used; i++)
        if (c->set[i].u == u)
            return &c->set[i];
    PairSet* ps = &c->set[c->next];
    c->next = (c->next + 1) % PAIRSET_CACHE;
    if (c->n_used < PAIRSET_CACHE)
        c->n_used++;
    ps->u = NAN; /* invalid while being built (a failing build longjmps out) */
    pairset_build(M, f, u, ps);
    return ps;
}

/* ------------------------------------------------------------------ mesh.py */
static inline double penetration(const Model* M, int64_t flank, double phi_p, double phi_w)
{
    return (double)flank * (M->arm_pinion * phi_p - M->arm_wheel * phi_w) - M->half_backlash;
}

static inline double approach_rate(const Model* M, int64_t flank, double w_p, double w_w)
{
    return (double)flank * (M->arm_pinion * w_p - M->arm_wheel * w_w);
}

static inline double pair_rate(const Model* M, int64_t flank, double w_p, double dg)
{
    return dg * ((double)flank * M->rb_pinion * w_p);
}

/* lubrication.sliding_speed(w_p, s, w_w, line_length - s) */
static inline double sliding_speed(const Model* M, double s, double w_p, double w_w)
{
    return w_p * s - w_w * (M->line_length - s);
}

typedef struct {
    double delta, tau_w, tau_p, W, F;
    /* detail (outputs) only */
    int64_t n_loaded;
    double top_W, top_h, top_lam, top_psi;
    double forces[N_SLOTS];
} Loads;

/* MeshModel._loads; signs != NULL is the integrator's path (mesh.torques with the substep's
 * friction directions), detail = 1 the outputs' (mesh.loads, signs from the sliding speed). */
static void mesh_loads(const Model* M, Fail* f, PairCache* cache, int64_t flank, double phi_p,
                       double w_p, double phi_w, double w_w, double v_impact,
                       const double* signs, int detail, Loads* out)
{
    double delta = penetration(M, flank, phi_p, phi_w);
    out->delta = delta;
    out->tau_w = out->tau_p = out->W = out->F = 0.0;
    if (detail) {
        out->n_loaded = 0;
        out->top_W = out->top_h = out->top_lam = out->top_psi = 0.0;
        for (int k = 0; k < N_SLOTS; k++)
            out->forces[k] = 0.0;
    }
    if (delta <= 0.0)
        return;
    double delta_dot = approach_rate(M, flank, w_p, w_w);
    double damping = M->damping;
    double E_star = M->E_star;
    double tau_w = 0.0, tau_p = 0.0, W_sum = 0.0, F_net = 0.0;
    PairSet* ps = pairs_at(M, f, cache, flank_roll(M, flank, phi_p));
    for (int i = 0; i < ps->n; i++) {
        int64_t slot = ps->slot[i];
        double s = ps->s[i];
        double pen = delta - ps->offset[i];
        if (pen <= 0.0) {
            if (detail)
                out->forces[slot] = 0.0;
            continue;
        }
        pairset_coefficients(M, f, ps, i);
        double K = ps->K[i];
        double W = K * (pen * py_sqrt(f, pen));
        if (damping > 0.0) {
            W *= 1.0 + damping * (delta_dot - pair_rate(M, flank, w_p, ps->dg[i]));
            if (W < 0.0) /* the flanks never pull on each other */
                W = 0.0;
        }
        tau_w += (double)flank * W * M->arm_wheel;
        tau_p -= (double)flank * W * M->arm_pinion;
        W_sum += W;
        double F = 0.0;
        double rho_p = s, rho_w = M->line_length - s;
        double v_s = w_p * rho_p - w_w * rho_w;       /* lubrication.sliding_speed */
        double u = 0.5 * (w_p * rho_p + w_w * rho_w); /* lubrication.entrainment_speed */
        double h = 0.0, lam = 0.0, psi = 0.0;
        if ((M->friction_enabled || detail) && W > 0.0) {
            double A_e = 3.2 * W / E_star * M->sqrt_gamma_sigma; /* asperity_area */
            double A = ps->kz[i] * py_pow(f, W, 2.0 / 3.0);
            double d_max = pairset_d_max(M, f, ps, i, v_impact);
            h = -pen + d_max; /* film_thickness(-pen, d_max) */
            if (!(h > 0.0))
                h = 0.0;
            lam = h / M->sigma;
            psi = dry_fraction(M, lam);
            if (M->friction_enabled) {
                double U = M->shear_speed == 0 ? u : v_s;
                F = friction_force(M, f, psi, A_e, A, U, h);
                double sgn;
                if (signs != NULL)
                    sgn = signs[slot];
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
            /* WheelStepper.outputs: loaded pairs (W > 0), the most loaded one (the first
             * of equal maxima), pair_forces (a later pair in the same slot overwrites). */
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
    }
    out->tau_w = tau_w;
    out->tau_p = tau_p;
    out->W = W_sum;
    out->F = F_net;
}

/* MeshModel.static_force */
static double static_force(const Model* M, Fail* f, PairCache* cache, int64_t flank,
                           double phi_p, double delta)
{
    PairSet* ps = pairs_at(M, f, cache, flank_roll(M, flank, phi_p));
    double total = 0.0;
    for (int i = 0; i < ps->n; i++) {
        double d = delta - ps->offset[i];
        if (d > 0.0) {
            pairset_coefficients(M, f, ps, i);
            total += ps->K[i] * (d * py_sqrt(f, d));
        }
    }
    return total;
}

/* MeshModel.contact_rates: (k, c). */
static void contact_rates(const Model* M, Fail* f, PairCache* cache, int64_t flank,
                          double phi_p, double w_p, double delta, double delta_dot, double* k,
                          double* c)
{
    double d = M->damping;
    double k_sum = 0.0, c_sum = 0.0;
    PairSet* ps = pairs_at(M, f, cache, flank_roll(M, flank, phi_p));
    for (int i = 0; i < ps->n; i++) {
        double pen = delta - ps->offset[i];
        if (pen > 0.0) {
            pairset_coefficients(M, f, ps, i);
            double K = ps->K[i];
            double root = py_sqrt(f, pen);
            double factor = 1.0 + d * (delta_dot - pair_rate(M, flank, w_p, ps->dg[i]));
            if (factor > 0.0)
                k_sum += 1.5 * K * root * factor;
            c_sum += K * d * (pen * root);
        }
    }
    *k = k_sum;
    *c = c_sum;
}

/* MeshModel.energy_balance_delta_max (largest over the pairs of the flank). */
static double energy_balance_delta_max(const Model* M, Fail* f, PairCache* cache,
                                       int64_t flank, double phi_p, double v_impact)
{
    PairSet* ps = pairs_at(M, f, cache, flank_roll(M, flank, phi_p));
    double out = 0.0;
    for (int i = 0; i < ps->n; i++) {
        pairset_coefficients(M, f, ps, i);
        double d = film_delta_max(f, v_impact, ps->K[i], ps->r_x[i], ps->ka[i], M->density);
        if (d > out)
            out = d;
    }
    return out;
}

/* ------------------------------------------------------------------ stepper.py */
typedef struct {
    const Model* M;
    Fail* f;
    State st;
    double H;
    int64_t n_sub;
    double phi_p0, w_p0, a_p, tau_load, J;
    double W_peak, delta_peak, int_tau_pinion;
    int64_t onsets_drive, onsets_coast, rhs_evaluations, contact_substeps, events;
    /* friction direction of each pair slot on the current substep, and the directions a
     * located reversal prescribes for the substep after it (the dict `reversed`) */
    double signs[N_SLOTS];
    int has_reversed[N_SLOTS];
    double reversed[N_SLOTS];
    double rattle_time, rattle_gain;
    PairCache pairs;
} Run;

static inline double run_phi_p(const Run* r, double t)
{
    return r->phi_p0 + t * (r->w_p0 + 0.5 * r->a_p * t);
}

static inline double run_w_p(const Run* r, double t) { return r->w_p0 + r->a_p * t; }

static inline double grid(const Run* r, int64_t j)
{
    return j >= r->n_sub ? r->H : r->H * (double)j / (double)r->n_sub;
}

/* WheelStepper.contact_flank */
static int64_t contact_flank(const Model* M, double phi_p, double w_p, double a_p,
                             double tau_load, const State* st)
{
    double accel_w = -tau_load / M->J;
    int64_t order[3] = {st->flank, RK_DRIVE, RK_COAST};
    for (int i = 0; i < 3; i++) {
        int64_t flank = order[i];
        if (flank == 0)
            continue;
        double pen = penetration(M, flank, phi_p, st->phi);
        if (pen > 0.0)
            return flank;
        if (pen == 0.0) {
            double rate = approach_rate(M, flank, w_p, st->w);
            if (rate > 0.0)
                return flank;
            if (rate == 0.0 && approach_rate(M, flank, a_p, accel_w) > 0.0)
                return flank;
        }
    }
    return 0;
}

static void onset(Run* r, double t, int64_t flank)
{
    State* st = &r->st;
    double v = approach_rate(r->M, flank, run_w_p(r, t), st->w);
    r->events++;
    if (v < 0.0)
        v = 0.0;
    st->v_last = v;
    /* kinetic energy of the impact on the tooth normal, into the rattle index */
    double energy = 0.5 * r->M->normal_mass * v * v;
    r->rattle_gain += energy / r->rattle_time * py_exp(r->f, -(r->H - t) / r->rattle_time);
    if (flank == RK_DRIVE) {
        st->v_drive = v;
        st->n_drive++;
        r->onsets_drive++;
    }
    else {
        st->v_coast = v;
        st->n_coast++;
        r->onsets_coast++;
    }
}

static double free_flight(Run* r, double t)
{
    const Model* M = r->M;
    State* st = &r->st;
    double a_w = -r->tau_load / r->J;
    double x0 = M->arm_pinion * run_phi_p(r, t) - M->arm_wheel * st->phi;
    double v0 = M->arm_pinion * run_w_p(r, t) - M->arm_wheel * st->w;
    double half_acc = 0.5 * (M->arm_pinion * r->a_p - M->arm_wheel * a_w);
    double span = r->H - t;
    double half_backlash = M->half_backlash;
    double hit_d = 0.0, hit_c = 0.0;
    int has_d = first_crossing(x0 - half_backlash, v0, half_acc, span, 1, &hit_d);
    int has_c = first_crossing(-x0 - half_backlash, -v0, -half_acc, span, 1, &hit_c);
    double dt;
    int64_t flank;
    if (!has_d && !has_c) {
        dt = span;
        flank = 0;
    }
    else if (!has_c || (has_d && hit_d <= hit_c)) {
        dt = hit_d;
        flank = RK_DRIVE;
    }
    else {
        dt = hit_c;
        flank = RK_COAST;
    }
    double t_new = flank == 0 ? r->H : t + dt;
    st->phi += dt * (st->w + 0.5 * a_w * dt);
    st->w += a_w * dt;
    if (flank != 0) {
        st->flank = flank;
        onset(r, t_new, flank);
    }
    return t_new;
}

/* _rhs: (wheel acceleration, mesh torque on the pinion, total normal force) at time t. */
static inline void rhs(Run* r, double t, double phi_w, double w_w, double* out)
{
    const State* st = &r->st;
    int64_t flank = st->flank;
    double v_imp = flank == RK_DRIVE ? st->v_drive : st->v_coast;
    Loads L;
    mesh_loads(r->M, r->f, &r->pairs, flank, run_phi_p(r, t), run_w_p(r, t), phi_w, w_w, v_imp,
               r->signs, 0, &L);
    r->rhs_evaluations++;
    out[0] = (L.tau_w - r->tau_load) / r->J;
    out[1] = L.tau_p;
    out[2] = L.W;
}

static void rk4(Run* r, double t, double h, double phi, double w, const double* k1,
                double* phi_new, double* w_new, double* q)
{
    double a1 = k1[0], p1 = k1[1];
    double k2[3], k3[3], k4[3];
    rhs(r, t + 0.5 * h, phi + 0.5 * h * w, w + 0.5 * h * a1, k2);
    double a2 = k2[0], p2 = k2[1];
    double w2 = w + 0.5 * h * a1;
    rhs(r, t + 0.5 * h, phi + 0.5 * h * w2, w + 0.5 * h * a2, k3);
    double a3 = k3[0], p3 = k3[1];
    double w3 = w + 0.5 * h * a2;
    rhs(r, t + h, phi + h * w3, w + h * a3, k4);
    double a4 = k4[0], p4 = k4[1];
    double w4 = w + h * a3;
    *phi_new = phi + h / 6.0 * (w + 2.0 * w2 + 2.0 * w3 + w4);
    *w_new = w + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    *q = h / 6.0 * (p1 + 2.0 * p2 + 2.0 * p3 + p4);
}

/* _resolved_substep: span divided into equal parts no longer than CONTACT_RATE_SAFETY over
 * the contact's fastest rate. */
static double resolved_substep(Run* r, double t, double span)
{
    const Model* M = r->M;
    State* st = &r->st;
    int64_t flank = st->flank;
    double delta = penetration(M, flank, run_phi_p(r, t), st->phi);
    double rate = approach_rate(M, flank, run_w_p(r, t), st->w);
    double reach = rate > 0.0 ? delta + rate * span : delta;
    double k, c;
    contact_rates(M, r->f, &r->pairs, flank, run_phi_p(r, t), run_w_p(r, t), reach, rate, &k,
                  &c);
    double mass = M->normal_mass;
    double fastest = py_sqrt(r->f, k / mass) + c / mass;
    r->contact_substeps += 1;
    if (fastest * span <= M->contact_rate_safety)
        return span;
    double parts = py_ceil(r->f, fastest * span / M->contact_rate_safety);
    /* contact_substeps + parts > MAX_CONTACT_SUBSTEPS in Python's exact integers: both sides
     * are integers and the sum is exact below 2**53, above which it exceeds the cap anyway */
    if ((double)r->contact_substeps + parts > (double)M->max_contact_substeps)
        fail(r->f, RK_ERR_TOO_STIFF, fastest, k, c, mass);
    return span / parts;
}

/* _friction_directions */
static void friction_directions(Run* r, double t)
{
    const Model* M = r->M;
    State* st = &r->st;
    for (int k = 0; k < N_SLOTS; k++)
        r->signs[k] = 0.0;
    double w_p = run_w_p(r, t);
    PairSet* ps = pairs_at(M, r->f, &r->pairs, flank_roll(M, st->flank, run_phi_p(r, t)));
    for (int i = 0; i < ps->n; i++) {
        int64_t slot = ps->slot[i];
        if (r->has_reversed[slot]) {
            r->signs[slot] = r->reversed[slot];
            continue;
        }
        double v_s = sliding_speed(M, ps->s[i], w_p, st->w);
        r->signs[slot] = v_s > 0.0 ? 1.0 : (v_s < 0.0 ? -1.0 : 0.0);
    }
    for (int k = 0; k < N_SLOTS; k++)
        r->has_reversed[k] = 0;
}

typedef struct {
    Run* r;
    double t;
    const double* k1;
    int64_t flank;
    int64_t slot;
} EventCtx;

/* speed() of _reversal_times: sliding speed of the pair in `slot` at t + dt for wheel speed
 * w (0 when the pair has left the zone). */
static double slot_sliding_speed(EventCtx* c, double dt, double w)
{
    Run* r = c->r;
    PairSet* ps = pairs_at(r->M, r->f, &r->pairs,
                           flank_roll(r->M, c->flank, run_phi_p(r, c->t + dt)));
    for (int i = 0; i < ps->n; i++)
        if (ps->slot[i] == c->slot)
            return sliding_speed(r->M, ps->s[i], run_w_p(r, c->t + dt), w);
    return 0.0;
}

/* slide() of _reversal_times: the sliding speed after the RK4 step of length dt from t. */
static double slide_after(void* vctx, double dt)
{
    EventCtx* c = (EventCtx*)vctx;
    Run* r = c->r;
    double phi_b, w_b, q;
    rk4(r, c->t, dt, r->st.phi, r->st.w, c->k1, &phi_b, &w_b, &q);
    return slot_sliding_speed(c, dt, w_b);
}

/* A located event of one pair slot: a friction reversal or an engagement. */
typedef struct {
    int64_t slot;
    double dt;
} Reversal;

/* _reversal_times: the located reversals (slot, offset) in pair order; returns their count. */
static int reversal_times(Run* r, double t, double h, double w_b, const double* k1,
                          const int* flipped, Reversal* out)
{
    const Model* M = r->M;
    State* st = &r->st;
    int64_t flank = st->flank;
    if (!M->friction_enabled)
        return 0;
    /* the pairs at t + h, copied: locating a reversal evaluates other pair sets */
    PairSet* ps = pairs_at(M, r->f, &r->pairs, flank_roll(M, flank, run_phi_p(r, t + h)));
    int n = ps->n;
    int64_t slots[PAIR_MAX];
    double s_end[PAIR_MAX];
    for (int i = 0; i < n; i++) {
        slots[i] = ps->slot[i];
        s_end[i] = ps->s[i];
    }
    int count = 0;
    for (int i = 0; i < n; i++) {
        int64_t slot = slots[i];
        double sign = r->signs[slot];
        if (flipped[slot] || sign == 0.0
            || sign * sliding_speed(M, s_end[i], run_w_p(r, t + h), w_b) >= 0.0)
            continue;
        EventCtx c = {r, t, k1, flank, slot};
        double f_a = slot_sliding_speed(&c, 0.0, st->w);
        double f_b = slot_sliding_speed(&c, h, w_b);
        if (f_a == 0.0 || (f_a > 0.0) == (f_b > 0.0))
            continue; /* no sign change on the substep's own RK4 path */
        out[count].slot = slot;
        out[count].dt = brent(r->f, slide_after, &c, 0.0, h, f_a, f_b, M->event_xtol,
                              M->brent_rtol, M->brent_max_iter);
        count++;
    }
    return count;
}

/* own_penetration() of _engagement_times: the penetration delta - g of the pair in `slot` at
 * t + dt for wheel angle phi_w.  Python's None (the pair has left the zone) would make
 * roots.brent compare None with 0.0: the TypeError is raised here. */
static double slot_own_penetration(EventCtx* c, double dt, double phi_w, int* found)
{
    Run* r = c->r;
    double phi_p = run_phi_p(r, c->t + dt);
    PairSet* ps = pairs_at(r->M, r->f, &r->pairs, flank_roll(r->M, c->flank, phi_p));
    for (int i = 0; i < ps->n; i++) {
        if (ps->slot[i] == c->slot) {
            *found = 1;
            return penetration(r->M, c->flank, phi_p, phi_w) - ps->offset[i];
        }
    }
    *found = 0;
    return 0.0;
}

/* crossing() of _engagement_times: the pair's own penetration after the RK4 step of length
 * dt from t. */
static double crossing_after(void* vctx, double dt)
{
    EventCtx* c = (EventCtx*)vctx;
    Run* r = c->r;
    double phi_b, w_b, q;
    int found;
    rk4(r, c->t, dt, r->st.phi, r->st.w, c->k1, &phi_b, &w_b, &q);
    double pen = slot_own_penetration(c, dt, phi_b, &found);
    if (!found) /* Python: brent compares the None of own_penetration with 0.0 */
        fail_call(r->f, RK_CALL_NONE_GT, 0.0, 0.0);
    return pen;
}

/* _engagement_times: the located changes of sign of the crowned pairs' own penetrations
 * (slot, offset) in pair order; returns their count. */
static int engagement_times(Run* r, double t, double h, double phi_b, const double* k1,
                            Reversal* out)
{
    const Model* M = r->M;
    State* st = &r->st;
    int64_t flank = st->flank;
    /* the pairs at t, copied: locating a change evaluates other pair sets */
    PairSet* ps = pairs_at(M, r->f, &r->pairs, flank_roll(M, flank, run_phi_p(r, t)));
    int n = ps->n;
    int64_t slots[PAIR_MAX];
    double offsets[PAIR_MAX];
    for (int i = 0; i < n; i++) {
        slots[i] = ps->slot[i];
        offsets[i] = ps->offset[i];
    }
    int count = 0;
    for (int i = 0; i < n; i++) {
        if (offsets[i] == 0.0)
            continue;
        EventCtx c = {r, t, k1, flank, slots[i]};
        int found_a, found_b;
        double f_a = slot_own_penetration(&c, 0.0, st->phi, &found_a);
        double f_b = slot_own_penetration(&c, h, phi_b, &found_b);
        if (!found_a || !found_b || (f_a > 0.0) == (f_b > 0.0))
            continue;
        out[count].slot = slots[i];
        out[count].dt = brent(r->f, crossing_after, &c, 0.0, h, f_a, f_b, M->event_xtol,
                              M->brent_rtol, M->brent_max_iter);
        count++;
    }
    return count;
}

/* delta_after of _release_time: penetration after the RK4 step of length dt from t. */
static double delta_after(void* vctx, double dt)
{
    EventCtx* c = (EventCtx*)vctx;
    Run* r = c->r;
    double phi_b, w_b, q;
    rk4(r, c->t, dt, r->st.phi, r->st.w, c->k1, &phi_b, &w_b, &q);
    return penetration(r->M, c->flank, run_phi_p(r, c->t + dt), phi_b);
}

/* _release_time: returns 1 and the offset in (0, h], or 0 for a grazing contact. */
static int release_time(Run* r, double t, double h, double delta_a, double delta_b,
                        const double* k1, double* out)
{
    EventCtx c = {r, t, k1, r->st.flank, 0};
    double lo = 0.0, f_lo = delta_a;
    if (f_lo <= 0.0) { /* substep starts at the onset: find where it penetrated */
        int found = 0;
        int64_t n = r->M->grazing_samples;
        for (int64_t i = 1; i < n; i++) {
            double s = h * (double)i / (double)n;
            double f_s = delta_after(&c, s);
            if (f_s > 0.0) {
                lo = s;
                f_lo = f_s;
                found = 1;
                break;
            }
        }
        if (!found)
            return 0;
    }
    *out = brent(r->f, delta_after, &c, lo, h, f_lo, delta_b, r->M->event_xtol,
                 r->M->brent_rtol, r->M->brent_max_iter);
    return 1;
}

static void track_peak(Run* r, double t, double h, int64_t flank, double d_a, double w_a,
                       double d_b, double w_b)
{
    const Model* M = r->M;
    r->delta_peak = py_max(py_max(r->delta_peak, d_a), d_b);
    double dd_a = approach_rate(M, flank, run_w_p(r, t), w_a) * h;
    double dd_b = approach_rate(M, flank, run_w_p(r, t + h), w_b) * h;
    if (!(dd_a > 0.0 && 0.0 > dd_b))
        return;
    /* Hermite cubic on s in [0, 1]: derivative is a quadratic; its root where it falls. */
    double A = 6.0 * (d_a - d_b) + 3.0 * (dd_a + dd_b);
    double B = -6.0 * (d_a - d_b) - 4.0 * dd_a - 2.0 * dd_b;
    double s;
    if (!first_crossing(dd_a, B, A, 1.0, 0, &s))
        return;
    double s2 = s * s, s3 = s * s * s;
    double d = ((2.0 * s3 - 3.0 * s2 + 1.0) * d_a + (s3 - 2.0 * s2 + s) * dd_a
                + (-2.0 * s3 + 3.0 * s2) * d_b + (s3 - s2) * dd_b);
    if (d > r->delta_peak) {
        r->delta_peak = d;
        r->W_peak = py_max(r->W_peak,
                           static_force(M, r->f, &r->pairs, flank, run_phi_p(r, t + s * h), d));
    }
}

static double contact_substep(Run* r, double t)
{
    const Model* M = r->M;
    State* st = &r->st;
    int64_t flank = st->flank;
    double x = t * (double)r->n_sub / r->H;
    if (!isfinite(x))
        fail_call(r->f, RK_CALL_INT, x, 0.0);
    int64_t j = (int64_t)x; /* int(): truncation (t < H, so x < n_sub) */
    if (r->n_sub - 1 < j)
        j = r->n_sub - 1;
    double t_end = grid(r, j + 1);
    if (t_end <= t) /* t sits on a grid point within rounding */
        t_end = grid(r, j + 2);
    /* split at the next pair entry/exit so the right-hand side is smooth on the substep */
    double u_a = flank_roll(M, flank, run_phi_p(r, t));
    double bp;
    if (next_breakpoint(M, r->f, u_a, flank_roll(M, flank, run_phi_p(r, t_end)), &bp)) {
        double k = (double)flank * M->rb_pinion;
        double dt;
        if (first_crossing(u_a - bp, k * run_w_p(r, t), 0.5 * k * r->a_p, t_end - t, bp > u_a,
                           &dt))
            t_end = t + dt;
    }
    double h = resolved_substep(r, t, t_end - t);
    t_end = t + h;
    friction_directions(r, t);
    double delta_a = penetration(M, flank, run_phi_p(r, t), st->phi);
    int flipped[N_SLOTS] = {0};
    double k1[3], phi_b, w_b, q, delta_b, dt_event;
    int released, n_rev;
    int64_t reversal;
    Reversal rev[PAIR_MAX];
    for (;;) {
        rhs(r, t, st->phi, st->w, k1);
        rk4(r, t, h, st->phi, st->w, k1, &phi_b, &w_b, &q);
        delta_b = penetration(M, flank, run_phi_p(r, t_end), phi_b);
        released = 0;
        reversal = -1;
        dt_event = h;
        if (delta_b <= 0.0) {
            double dt;
            if (release_time(r, t, h, delta_a, delta_b, k1, &dt)) {
                released = 1;
                dt_event = dt;
            }
        }
        n_rev = reversal_times(r, t, h, w_b, k1, flipped, rev);
        /* a reversal at the substep start to rounding: the pair's friction takes its new
         * direction for the whole substep; redo it */
        int instant = 0;
        for (int i = 0; i < n_rev; i++)
            if (t + rev[i].dt <= t)
                instant = 1;
        if (!instant)
            break;
        for (int i = 0; i < n_rev; i++) {
            if (t + rev[i].dt <= t) {
                r->signs[rev[i].slot] = -r->signs[rev[i].slot];
                flipped[rev[i].slot] = 1;
            }
        }
    }
    r->W_peak = py_max(r->W_peak, k1[2]);
    for (int i = 0; i < n_rev; i++) {
        if (rev[i].dt < dt_event) {
            dt_event = rev[i].dt;
            reversal = rev[i].slot;
            released = 0;
        }
    }
    /* a crowned pair starting or ending to carry load: end the substep there (one located
     * right at the substep start needs no split: ENGAGEMENT_MIN_FRACTION) */
    int64_t engaged = -1;
    Reversal eng[PAIR_MAX];
    int n_eng = engagement_times(r, t, h, phi_b, k1, eng);
    for (int i = 0; i < n_eng; i++) {
        if (eng[i].dt < dt_event && eng[i].dt > r->M->engagement_min_fraction * h) {
            dt_event = eng[i].dt;
            engaged = eng[i].slot;
            reversal = -1;
            released = 0;
        }
    }
    if (dt_event < h) {
        h = dt_event;
        t_end = t + h;
        rk4(r, t, h, st->phi, st->w, k1, &phi_b, &w_b, &q);
    }
    if (released)
        delta_b = 0.0;
    else
        delta_b = penetration(M, flank, run_phi_p(r, t_end), phi_b);
    track_peak(r, t, h, flank, delta_a, st->w, delta_b, w_b);
    st->phi = phi_b;
    st->w = w_b;
    r->int_tau_pinion += q;
    if (reversal >= 0) {
        r->has_reversed[reversal] = 1;
        r->reversed[reversal] = -r->signs[reversal];
        r->events++; /* reversal */
    }
    if (engaged >= 0)
        r->events++; /* pair */
    if (released || delta_b <= 0.0) {
        r->events++; /* release */
        st->flank = 0;
    }
    return t_end;
}

/* ------------------------------------------------------------------ entry points */
/* The layout this library was built for (kernel_layout.LAYOUT_HASH). */
EXPORT unsigned long long rk_layout_hash(void) { return RK_LAYOUT_HASH; }

/*
 * WheelStepper.step: advances `state` (S_COUNT doubles) by inputs[I_H] under the pinion
 * kinematics and the held load torque of `inputs` (I_COUNT doubles).  Returns RK_ERR_OK and
 * writes state and result (R_COUNT doubles) on success; on a refusal returns its code, writes
 * the refusal's numbers to err_values (RK_ERROR_VALUES doubles) and leaves state and result
 * as they were.
 */
EXPORT int rk_step(const double* model, double* state, const double* inputs, double* result,
                   double* err_values)
{
    Model M;
    int unpacked = unpack_model(model, &M, err_values);
    if (unpacked != RK_ERR_OK)
        return unpacked;
    double h = inputs[I_H], phi_p = inputs[I_PHI_P], w_p = inputs[I_W_P];
    double a_p = inputs[I_A_P], tau_load = inputs[I_TAU_LOAD];
    /* _check_finite, then check_step_size: Python words the message */
    if (!(isfinite(phi_p) && isfinite(w_p) && isfinite(a_p) && isfinite(tau_load))
        || !(h > 0.0 && isfinite(h)) || h > M.h_comm_max)
        return RK_ERR_INPUT;

    Fail f;
    f.code = RK_ERR_OK;
    Run run;
    run.M = &M;
    run.f = &f;
    unpack_state(state, &run.st);
    const double w_start = run.st.w;
    run.H = h;
    run.phi_p0 = phi_p;
    run.w_p0 = w_p;
    run.a_p = a_p;
    run.tau_load = tau_load;
    run.J = M.J;
    run.W_peak = run.delta_peak = run.int_tau_pinion = 0.0;
    run.onsets_drive = run.onsets_coast = run.rhs_evaluations = run.contact_substeps = 0;
    run.events = 0;
    for (int k = 0; k < N_SLOTS; k++) {
        run.signs[k] = 0.0;
        run.has_reversed[k] = 0;
        run.reversed[k] = 0.0;
    }
    run.rattle_time = M.rattle_time;
    run.rattle_gain = 0.0;
    run.pairs.n_used = run.pairs.next = 0;
    if (setjmp(f.jb) != 0) {
        if (err_values != NULL)
            for (int i = 0; i < RK_ERROR_VALUES; i++)
                err_values[i] = f.values[i];
        return f.code;
    }
    {
        double x = py_ceil(&f, h / M.h_max * (1.0 - M.grid_slack));
        if (!(x < RK_MAX_GRID_SUBSTEPS))
            fail(&f, RK_ERR_SUBSTEP_COUNT, h, x, 0.0, 0.0);
        run.n_sub = x > 1.0 ? (int64_t)x : 1;
    }

    /* _StepRun.execute */
    State* st = &run.st;
    int64_t flank = contact_flank(&M, phi_p, w_p, a_p, tau_load, st);
    if (flank != st->flank) {
        if (st->flank != 0)
            run.events++; /* release */
        if (flank != 0)
            onset(&run, 0.0, flank);
        st->flank = flank;
    }
    double t = 0.0;
    long stall = 0;
    while (t < run.H) {
        double t_new = st->flank == 0 ? free_flight(&run, t) : contact_substep(&run, t);
        if (t_new > t) {
            stall = 0;
        }
        else if (++stall > RK_STALL_LIMIT) {
            fail(&f, RK_ERR_NO_PROGRESS, t, 0.0, 0.0, 0.0);
        }
        t = t_new;
    }
    /* mean mesh torque from the momentum balance I_w dw = (tau_mesh - tau_load) dt */
    double dw = st->w - w_start;
    double tau_wheel_mean = (run.J * dw + run.tau_load * run.H) / run.H;
    double tau_pinion_mean = run.int_tau_pinion / run.H;
    st->rattle_index = st->rattle_index * py_exp(&f, -run.H / run.rattle_time) + run.rattle_gain;
    if (st->flank != 0) {
        run.delta_peak = py_max(run.delta_peak,
                                penetration(&M, st->flank, run_phi_p(&run, run.H), st->phi));
        double k[3];
        rhs(&run, run.H, st->phi, st->w, k);
        run.W_peak = py_max(run.W_peak, k[2]);
    }

    /* WheelStepper.step: divergence and penetration guards */
    if (!(isfinite(st->phi) && isfinite(st->w) && isfinite(tau_pinion_mean)
          && isfinite(run.W_peak)))
        fail(&f, RK_ERR_DIVERGED, st->phi, st->w, 0.0, 0.0);
    double phi_end = phi_p + h * (w_p + 0.5 * a_p * h);
    double depth = py_max(py_max(run.delta_peak, penetration(&M, RK_DRIVE, phi_end, st->phi)),
                          penetration(&M, RK_COAST, phi_end, st->phi));
    double limit = M.pen_limit;
    if (depth > limit)
        fail(&f, RK_ERR_PENETRATION, depth, limit, 0.0, 0.0);

    /* commit */
    pack_state(st, state);
    result[R_TAU_WHEEL_MEAN] = tau_wheel_mean;
    result[R_TAU_PINION_MEAN] = tau_pinion_mean;
    result[R_W_PEAK] = run.W_peak;
    result[R_DELTA_PEAK] = run.delta_peak;
    result[R_ONSETS_DRIVE] = (double)run.onsets_drive;
    result[R_ONSETS_COAST] = (double)run.onsets_coast;
    result[R_RHS_EVALUATIONS] = (double)run.rhs_evaluations;
    result[R_CONTACT_SUBSTEPS] = (double)run.contact_substeps;
    result[R_EVENT_COUNT] = (double)run.events;
    result[R_PINION_PHI] = phi_p + w_p * h + 0.5 * a_p * h * h;
    result[R_PINION_W] = w_p + a_p * h;
    return RK_ERR_OK;
}

/*
 * WheelStepper.outputs: the values of MESH_OUTPUTS (O_COUNT doubles, declared order) for
 * the state and `last` (R_COUNT doubles: the last step's aggregates and, in R_PINION_PHI and
 * R_PINION_W, the pinion at the end of the last step).  Returns RK_ERR_OK, or the code of
 * the error Python would raise with its numbers in err_values (out is then unspecified).
 */
EXPORT int rk_outputs(const double* model, const double* state, const double* last,
                      double* out, double* err_values)
{
    Model M;
    int unpacked = unpack_model(model, &M, err_values);
    if (unpacked != RK_ERR_OK)
        return unpacked;
    for (int k = 0; k < O_COUNT; k++)
        out[k] = NAN; /* an output this port does not write shows as a difference */
    Fail f;
    f.code = RK_ERR_OK;
    State st;
    unpack_state(state, &st);
    double phi_p = last[R_PINION_PHI], w_p = last[R_PINION_W];
    PairCache cache;
    cache.n_used = cache.next = 0;
    if (setjmp(f.jb) != 0) {
        if (err_values != NULL)
            for (int i = 0; i < RK_ERROR_VALUES; i++)
                err_values[i] = f.values[i];
        return f.code;
    }
    /* WheelStepper.loads_now */
    int64_t flank = st.flank;
    if (flank == 0)
        flank = penetration(&M, RK_DRIVE, phi_p, st.phi)
                        >= penetration(&M, RK_COAST, phi_p, st.phi)
                    ? RK_DRIVE
                    : RK_COAST;
    double v_imp = flank == RK_DRIVE ? st.v_drive : st.v_coast;
    Loads L;
    mesh_loads(&M, &f, &cache, flank, phi_p, w_p, st.phi, st.w, v_imp, NULL, 1, &L);
    double h, lam, psi;
    if (L.n_loaded > 0) {
        h = L.top_h;
        lam = L.top_lam;
        psi = L.top_psi;
    }
    else {
        double v = flank > 0 ? st.v_drive : st.v_coast;
        double d_max = energy_balance_delta_max(&M, &f, &cache, flank, phi_p, v);
        h = -L.delta + d_max; /* film_thickness(-delta, d_max) */
        if (!(h > 0.0))
            h = 0.0;
        lam = h / M.sigma;
        psi = dry_fraction(&M, lam);
    }
    double W = L.W;
    double transverse = W * M.normal_factor;
    out[O_WHEEL_TAU_MESH] = last[R_TAU_WHEEL_MEAN];
    out[O_PINION_TAU_MESH] = last[R_TAU_PINION_MEAN];
    out[O_WHEEL_PHI] = st.phi;
    out[O_WHEEL_W] = st.w;
    out[O_MESH_W] = L.W;
    out[O_MESH_W_PEAK] = last[R_W_PEAK];
    out[O_MESH_F] = L.F;
    out[O_MESH_DELTA] = L.n_loaded > 0 ? L.delta : 0.0;
    out[O_MESH_DELTA_PEAK] = last[R_DELTA_PEAK];
    out[O_MESH_V_IMPACT] = st.v_last;
    out[O_MESH_H] = h;
    out[O_MESH_LAMBDA] = lam;
    out[O_MESH_PSI] = psi;
    out[O_MESH_N_CONTACT] = (double)L.n_loaded;
    out[O_MESH_IMPACTS_DRIVE] = (double)st.n_drive;
    out[O_MESH_IMPACTS_COAST] = (double)st.n_coast;
    out[O_MESH_TRANSMISSION_ERROR] = penetration(&M, RK_DRIVE, phi_p, st.phi) + M.half_backlash;
    out[O_MESH_FORCE_TANGENTIAL] = (double)flank * transverse * M.cos_alpha_t;
    out[O_MESH_FORCE_RADIAL] = transverse * M.sin_alpha_t;
    out[O_MESH_FORCE_AXIAL] = (double)flank * W * M.sin_beta_b;
    out[O_MESH_IMPACT_ENERGY] = 0.5 * M.normal_mass * st.v_last * st.v_last;
    out[O_MESH_RATTLE_INDEX] = st.rattle_index;
    for (int k = 0; k < N_SLOTS; k++)
        out[O_PAIR_0_W + k] = L.forces[k];
    return RK_ERR_OK;
}

/*
 * MeshModel.torques(flank, phi_p, w_p, phi_w, w_w, v_impact) with the friction directions of
 * the sliding speeds (no substep's signs): out[0] the torque on the wheel, out[1] on the
 * pinion, out[2] the total normal force.  The static start equilibrium of the native FMUs
 * (rattle_model.c, WheelStepper.equilibrium_state) solves on it.  Returns RK_ERR_OK, or a
 * code with its numbers in err_values (kernel_layout.ERROR_CODES).
 */
EXPORT int rk_mesh_torques(const double* model, double flank, double phi_p, double w_p,
                           double phi_w, double w_w, double v_impact, double* out,
                           double* err_values)
{
    Model M;
    int unpacked = unpack_model(model, &M, err_values);
    if (unpacked != RK_ERR_OK)
        return unpacked;
    Fail f;
    f.code = RK_ERR_OK;
    PairCache cache;
    cache.n_used = cache.next = 0;
    if (setjmp(f.jb) != 0) {
        if (err_values != NULL)
            for (int i = 0; i < RK_ERROR_VALUES; i++)
                err_values[i] = f.values[i];
        return f.code;
    }
    Loads L;
    mesh_loads(&M, &f, &cache, (int64_t)flank, phi_p, w_p, phi_w, w_w, v_impact, NULL, 0, &L);
    out[0] = L.tau_w;
    out[1] = L.tau_p;
    out[2] = L.W;
    return RK_ERR_OK;
}
