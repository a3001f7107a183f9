/*
 * rattle_kernel.c - compiled twin of the pure-Python wheel stepper of drive_rattle.
 *
 * This file is a line-by-line port of
 *   drive_rattle/stepper.py     WheelStepper.step, _StepRun (free flight, RK4 contact substeps,
 *                               breakpoint splitting, release location, peak tracking, guards)
 *   drive_rattle/mesh.py        MeshModel._loads / torques / stiffness_sum / penetration ...
 *   drive_rattle/geometry.py    pairs_at_roll, next_breakpoint, normal_radii, flank_roll
 *   drive_rattle/hertz.py       stiffness, contact_radius, apparent_area,
 *                               energy_balance_delta_max
 *   drive_rattle/lubrication.py film_thickness, asperity_area, dry_fraction, friction_force
 *   drive_rattle/roots.py       brent, first_crossing
 *   drive_rattle/interface.py   mesh_outputs
 * that reproduces the Python results BIT FOR BIT (docs/kernel.md).  The Python code is the
 * reference: every expression below performs the same IEEE operations in the same order as
 * the Python line it ports (Python evaluates a + b + c as (a + b) + c, x ** y is pow(x, y),
 * math.sqrt is sqrt, an int operand is converted to double first).  Do not "simplify" an
 * expression here (x*sqrt(x) for x**1.5, fmax for max(), hoisting a product, ...): a one-ulp
 * difference changes the impact sequence of the chaotic rattle motion.
 *
 * Python's max(a, b) returns a unless b > a (so max(nan, x) is nan, max(x, nan) is x and
 * max(-0.0, 0.0) is -0.0); PY_MAX reproduces that, fmax would not.
 *
 * Build (kernel.compile_kernel does this):
 *   gcc -std=c99 -O2 -fno-fast-math -ffp-contract=off -fPIC -shared -o _rattle_kernel.so \
 *       rattle_kernel.c -lm
 * -ffp-contract=off is required: a fused multiply-add rounds once instead of twice.
 *
 * The geometry and the derived constants are computed once in Python (kernel.pack_model) and
 * passed as a flat array of doubles (layout: enum below, mirrored in kernel.py MODEL_FIELDS).
 * The state is an array of 8 doubles mirroring stepper.WheelState (flank and the counters
 * are integers stored exactly in doubles, int64 inside).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define EXPORT __attribute__((visibility("default")))

/* Bump together with kernel.py ABI_VERSION whenever a layout below changes. */
#define RK_ABI_VERSION 1
#define RK_MAGIC 7261747465.0 /* "rattle" */

#define PI 3.141592653589793 /* math.pi */
#define DRIVE 1
#define COAST (-1)
#define N_SLOTS 8 /* parameters.MAX_PAIR_SLOTS, checked against the model array */
/* Largest |pair number| handled: pair numbers are exact integers in doubles below 2**53. */
#define PAIR_NUMBER_LIMIT 4503599627370496.0 /* 2**52 */
/* Consecutive main-loop iterations without progress in time before the step is refused
 * (the Python loop would not terminate). */
#define STALL_LIMIT 1000000

/* ------------------------------------------------------------------ layouts */
enum {
    M_MAGIC, M_ABI, M_SIZE,
    /* geometry.HelicalPairGeometry */
    M_RB_PINION, M_FLANK_PHASE, M_BASE_PITCH, M_LINE_SPAN, M_S_START, M_S_END,
    M_LINE_LENGTH, M_NORMAL_FACTOR, M_HALF_BACKLASH, M_N_BREAKPOINTS,
    M_BP0, M_BP1, M_BP2, M_BP3,
    /* mesh.MeshModel */
    M_E_STAR, M_ARM_WHEEL, M_ARM_PINION,
    /* parameters.MeshParameters */
    M_J_WHEEL, M_R_Y, M_LENGTH_WEIGHTING, M_DAMPING, M_FRICTION_ENABLED, M_FRICTION_FORM,
    M_SHEAR_SPEED, M_TAU_S, M_ETA, M_SIGMA, M_GAMMA, M_DENSITY, M_H_MAX, M_H_COMM_MAX, M_M_N,
    /* module constants */
    M_PEN_MODULES, M_PEN_LIMIT, M_BP_TOL, M_GRAZING_SAMPLES, M_BRENT_MAX_ITER, M_BRENT_RTOL,
    M_RELEASE_XTOL, M_MAX_PAIR_SLOTS, M_LAMBDA_BOUNDARY, M_LAMBDA_FULL_FILM, M_SUM_MODE,
    M_COUNT
};

enum { S_PHI, S_W, S_FLANK, S_V_DRIVE, S_V_COAST, S_V_LAST, S_N_DRIVE, S_N_COAST, S_COUNT };

enum {
    R_TAU_WHEEL, R_TAU_PINION, R_W_PEAK, R_DELTA_PEAK, R_ONSETS_DRIVE, R_ONSETS_COAST,
    R_RHS_EVALUATIONS, R_EVENTS, R_PINION_PHI, R_PINION_W, R_COUNT
};

enum {
    O_TAU_WHEEL, O_TAU_PINION, O_PHI, O_W, O_W_NOW, O_W_PEAK, O_F, O_DELTA, O_DELTA_PEAK,
    O_V_IMPACT, O_H, O_LAMBDA, O_PSI, O_N_CONTACT, O_IMPACTS_DRIVE, O_IMPACTS_COAST, O_PAIR0,
    O_COUNT = O_PAIR0 + N_SLOTS
};

typedef struct {
    double rb_pinion, flank_phase, base_pitch, line_span, s_start, s_end, line_length;
    double normal_factor, half_backlash;
    int n_bp;
    double bp[4];
    double E_star, arm_wheel, arm_pinion;
    double J, r_y, damping, tau_s, eta, sigma, gamma, density, h_max, h_comm_max, m_n;
    int length_weighting, friction_enabled;
    int64_t friction_form, shear_speed;
    double pen_modules, pen_limit, bp_tol, brent_rtol, release_xtol;
    int64_t grazing_samples, brent_max_iter;
    double lambda_boundary, lambda_full_film;
    int sum_mode; /* 0: left-to-right float sum (Python <= 3.11), 1: Neumaier (>= 3.12) */
    double sqrt_gamma_sigma; /* math.sqrt(gamma / sigma), the same value every call */
} Model;

typedef struct {
    double phi, w;
    int64_t flank;
    double v_drive, v_coast, v_last;
    int64_t n_drive, n_coast;
} State;

/* Error exit: the message goes to err, then longjmp back to the entry point. */
typedef struct {
    jmp_buf jb;
    char* err;
    int errlen;
} Fail;

static void fail(Fail* f, const char* fmt, ...)
{
    if (f->err != NULL && f->errlen > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(f->err, (size_t)f->errlen, fmt, ap);
        va_end(ap);
    }
    longjmp(f->jb, 1);
}

static void set_err(char* err, int errlen, const char* fmt, ...)
{
    if (err != NULL && errlen > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, (size_t)errlen, fmt, ap);
        va_end(ap);
    }
}

/* ------------------------------------------------------------------ Python semantics */
/* For messages: printf writes a NaN with its sign bit as "-nan", Python's repr as "nan". */
static inline double unsigned_nan(double x) { return isnan(x) ? fabs(x) : x; }

/* max(a, b): a unless b > a. */
static inline double py_max(double a, double b) { return b > a ? b : a; }

/* x ** y for the exponents used (0.5, 1/3, 1.5): CPython's float_pow calls pow(x, y) for a
 * positive base; a finite base with an infinite result raises OverflowError; a negative base
 * with a fractional exponent gives a complex number (never reached: the bases are
 * penetrations, loads and lengths > 0). */
static inline double py_pow(Fail* f, double x, double y)
{
    if (x < 0.0)
        fail(f, "negative number %.17g raised to the fractional power %.17g", x, y);
    double r = pow(x, y);
    if (isinf(r) && isfinite(x))
        fail(f, "math range error: %.17g ** %.17g overflows", x, y);
    return r;
}

/* math.floor / math.ceil return ints; NaN raises ValueError, an infinity OverflowError.  The
 * pair and breakpoint arithmetic keeps the integer in a double: float(int(floor(x)) + 1)
 * equals floor(x) + 1.0 for every finite x (both are the correctly rounded exact sum). */
static inline double py_floor(Fail* f, double x)
{
    if (!isfinite(x))
        fail(f, "cannot convert float %.17g to integer (math.floor)", x);
    return floor(x);
}

static inline double py_ceil(Fail* f, double x)
{
    if (!isfinite(x))
        fail(f, "cannot convert float %.17g to integer (math.ceil)", x);
    return ceil(x);
}

/* ------------------------------------------------------------------ model */
static int unpack_model(const double* a, Model* m, char* err, int errlen)
{
    if (a == NULL || a[M_MAGIC] != RK_MAGIC || a[M_ABI] != (double)RK_ABI_VERSION
        || a[M_SIZE] != (double)M_COUNT) {
        set_err(err, errlen,
                "rattle kernel: model array layout mismatch (kernel ABI %d with %d fields; "
                "rebuild _rattle_kernel.so from the sources of this version)",
                RK_ABI_VERSION, (int)M_COUNT);
        return 0;
    }
    if (a[M_MAX_PAIR_SLOTS] != (double)N_SLOTS) {
        set_err(err, errlen, "rattle kernel: MAX_PAIR_SLOTS = %g, the kernel has %d",
                a[M_MAX_PAIR_SLOTS], N_SLOTS);
        return 0;
    }
    m->rb_pinion = a[M_RB_PINION];
    m->flank_phase = a[M_FLANK_PHASE];
    m->base_pitch = a[M_BASE_PITCH];
    m->line_span = a[M_LINE_SPAN];
    m->s_start = a[M_S_START];
    m->s_end = a[M_S_END];
    m->line_length = a[M_LINE_LENGTH];
    m->normal_factor = a[M_NORMAL_FACTOR];
    m->half_backlash = a[M_HALF_BACKLASH];
    m->n_bp = (int)a[M_N_BREAKPOINTS];
    if (m->n_bp < 0 || m->n_bp > 4) {
        set_err(err, errlen, "rattle kernel: %d breakpoints (at most 4)", m->n_bp);
        return 0;
    }
    for (int i = 0; i < 4; i++)
        m->bp[i] = a[M_BP0 + i];
    m->E_star = a[M_E_STAR];
    m->arm_wheel = a[M_ARM_WHEEL];
    m->arm_pinion = a[M_ARM_PINION];
    m->J = a[M_J_WHEEL];
    m->r_y = a[M_R_Y];
    m->length_weighting = a[M_LENGTH_WEIGHTING] != 0.0;
    m->damping = a[M_DAMPING];
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
    m->m_n = a[M_M_N];
    m->pen_modules = a[M_PEN_MODULES];
    m->pen_limit = a[M_PEN_LIMIT];
    m->bp_tol = a[M_BP_TOL];
    m->grazing_samples = (int64_t)a[M_GRAZING_SAMPLES];
    m->brent_max_iter = (int64_t)a[M_BRENT_MAX_ITER];
    m->brent_rtol = a[M_BRENT_RTOL];
    m->release_xtol = a[M_RELEASE_XTOL];
    m->lambda_boundary = a[M_LAMBDA_BOUNDARY];
    m->lambda_full_film = a[M_LAMBDA_FULL_FILM];
    m->sum_mode = (int)a[M_SUM_MODE];
    m->sqrt_gamma_sigma = sqrt(m->gamma / m->sigma);
    return 1;
}

static void unpack_state(const double* a, State* s)
{
    s->phi = a[S_PHI];
    s->w = a[S_W];
    s->flank = (int64_t)a[S_FLANK];
    s->v_drive = a[S_V_DRIVE];
    s->v_coast = a[S_V_COAST];
    s->v_last = a[S_V_LAST];
    s->n_drive = (int64_t)a[S_N_DRIVE];
    s->n_coast = (int64_t)a[S_N_COAST];
}

static void pack_state(const State* s, double* a)
{
    a[S_PHI] = s->phi;
    a[S_W] = s->w;
    a[S_FLANK] = (double)s->flank;
    a[S_V_DRIVE] = s->v_drive;
    a[S_V_COAST] = s->v_coast;
    a[S_V_LAST] = s->v_last;
    a[S_N_DRIVE] = (double)s->n_drive;
    a[S_N_COAST] = (double)s->n_coast;
}

/* ------------------------------------------------------------------ roots.py */
/* first_crossing: smallest t in (0, t_max] where c0 + c1 t + c2 t^2 crosses zero upwards
 * (rising) or downwards; returns 1 and *out, or 0 for None. */
static int first_crossing(double c0, double c1, double c2, double t_max, int rising,
                          double* out)
{
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
        fail(f, "brent: f(%.17g) = %.17g and f(%.17g) = %.17g do not bracket a root", a, fa, b,
             fb);
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

/* ------------------------------------------------------------------ geometry.py */
static inline double flank_roll(const Model* M, int64_t flank, double phi_p)
{
    return M->flank_phase + (double)flank * M->rb_pinion * phi_p;
}

/* Pair numbers n_lo..n_hi of pairs_at_roll(u). */
static void pair_range(const Model* M, Fail* f, double u, double* n_lo, double* n_hi)
{
    double pb = M->base_pitch;
    double half = 0.5 * M->line_span;
    double lo = py_floor(f, (u - M->s_end - half) / pb) + 1.0;
    double hi = py_ceil(f, (u - M->s_start + half) / pb) - 1.0;
    if (!(fabs(lo) < PAIR_NUMBER_LIMIT && fabs(hi) < PAIR_NUMBER_LIMIT))
        fail(f, "roll coordinate %.17g m beyond the kernel's range (pair number %.17g; "
                "|pinion angle| too large)", u, lo);
    *n_lo = lo;
    *n_hi = hi;
}

/* Pair n of pairs_at_roll(u): returns 1 with (slot, s, fraction) when in the zone. */
static inline int pair_at(const Model* M, double u, double n, int64_t* slot, double* s_out,
                          double* frac)
{
    double pb = M->base_pitch;
    double half = 0.5 * M->line_span;
    double s0 = M->s_start, s1 = M->s_end;
    double s = u - n * pb;
    if (half > 0.0) {
        double lo = s - half > s0 ? s - half : s0;
        double hi = s + half < s1 ? s + half : s1;
        if (hi > lo) {
            int64_t k = (int64_t)n % N_SLOTS;
            *slot = k < 0 ? k + N_SLOTS : k;
            *s_out = 0.5 * (lo + hi);
            *frac = (hi - lo) / (2.0 * half);
            return 1;
        }
        return 0;
    }
    if (s0 < s && s < s1) {
        int64_t k = (int64_t)n % N_SLOTS;
        *slot = k < 0 ? k + N_SLOTS : k;
        *s_out = s;
        *frac = 1.0;
        return 1;
    }
    return 0;
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

/* ------------------------------------------------------------------ mesh.py, hertz.py */
static inline double penetration(const Model* M, int64_t flank, double phi_p, double phi_w)
{
    return (double)flank * (M->arm_pinion * phi_p - M->arm_wheel * phi_w) - M->half_backlash;
}

static inline double approach_rate(const Model* M, int64_t flank, double w_p, double w_w)
{
    return (double)flank * (M->arm_pinion * w_p - M->arm_wheel * w_w);
}

/* MeshModel._pair_stiffness: (r_x, K_full, K). */
static inline void pair_stiffness(const Model* M, double s, double fraction, double* r_x,
                                  double* K_full, double* K)
{
    double c = M->normal_factor;
    double rp = s / c;
    double rw = (M->line_length - s) / c;
    double rx = rp * rw / (rp + rw);
    double kf = (4.0 / 3.0) * M->E_star * sqrt(sqrt(rx * M->r_y));
    *r_x = rx;
    *K_full = kf;
    *K = M->length_weighting ? kf * fraction : kf;
}

/* hertz.energy_balance_delta_max */
static inline double energy_balance_delta_max(const Model* M, Fail* f, double v, double K,
                                              double r_x)
{
    double C = 2.0 * M->density * PI * r_x * r_x
               * py_pow(f, 3.0 * K * M->r_y / (4.0 * M->E_star), 1.0 / 3.0);
    return fabs(v) * sqrt(5.0 * C / (4.0 * K));
}

/* lubrication.dry_fraction */
static inline double dry_fraction(const Model* M, double lam, double A_e, double A)
{
    if (lam <= M->lambda_boundary)
        return 1.0;
    if (lam >= M->lambda_full_film || A <= 0.0)
        return 0.0;
    double psi = A_e / A;
    return psi < 1.0 ? psi : 1.0;
}

/* lubrication.friction_force */
static inline double friction_force(const Model* M, Fail* f, double psi, double A_e, double A,
                                    double U, double h)
{
    double viscous = psi < 1.0 ? M->eta * fabs(U) / h : 0.0;
    switch (M->friction_form) {
    case 0:
        return psi * A_e * M->tau_s + (1.0 - psi) * A * viscous;
    case 1:
        return A * (psi * M->tau_s + (1.0 - psi) * viscous);
    case 2:
        return A_e * (psi * M->tau_s + (1.0 - psi) * viscous);
    default:
        fail(f, "friction form %lld unknown; allowed: 0, 1, 2", (long long)M->friction_form);
    }
    return 0.0;
}

/* The tooth pairs in the zone of action at roll coordinate u with their pure functions of
 * (u, parameters): what geometry.pairs_at_roll and MeshModel._pair_stiffness give, plus
 * sqrt(r_x r_y) of hertz.contact_radius and, per impact speed, the eq. 7 delta_max.  The
 * integrator evaluates the right-hand side twice at t + h/2 of each RK4 step and usually at
 * the end of one substep and the start of the next, so a step keeps a few of these sets:
 * each value is computed by the same expression as without the cache, only fewer times. */
#define PAIR_MAX 16
typedef struct {
    double u;
    int n;
    int64_t slot[PAIR_MAX];
    double s[PAIR_MAX], frac[PAIR_MAX], r_x[PAIR_MAX], K_full[PAIR_MAX], K[PAIR_MAX];
    double sqrt_rxry[PAIR_MAX];
    double d_max_v;          /* impact speed of the d_max entries */
    int d_max_ok[PAIR_MAX];  /* d_max[i] computed for d_max_v */
    double d_max[PAIR_MAX];
} PairSet;

static void pairset_build(const Model* M, Fail* f, double u, PairSet* ps)
{
    double n_lo, n_hi;
    pair_range(M, f, u, &n_lo, &n_hi);
    ps->u = u;
    ps->n = 0;
    ps->d_max_v = 0.0;
    for (double n = n_lo; n <= n_hi; n += 1.0) {
        int64_t slot;
        double s, frac;
        if (!pair_at(M, u, n, &slot, &s, &frac))
            continue;
        if (ps->n == PAIR_MAX)
            fail(f, "more than %d tooth pairs in the zone of action", PAIR_MAX);
        int i = ps->n++;
        ps->slot[i] = slot;
        ps->s[i] = s;
        ps->frac[i] = frac;
        pair_stiffness(M, s, frac, &ps->r_x[i], &ps->K_full[i], &ps->K[i]);
        ps->sqrt_rxry[i] = sqrt(ps->r_x[i] * M->r_y);
        ps->d_max_ok[i] = 0;
    }
}

/* hertz.energy_balance_delta_max(v_impact, K_full, r_x, ...) of pair i. */
static inline double pairset_d_max(const Model* M, Fail* f, PairSet* ps, int i, double v)
{
    if (!(v == ps->d_max_v)) {
        for (int k = 0; k < ps->n; k++)
            ps->d_max_ok[k] = 0;
        ps->d_max_v = v;
    }
    if (!ps->d_max_ok[i] || v != v) {
        ps->d_max[i] = energy_balance_delta_max(M, f, v, ps->K_full[i], ps->r_x[i]);
        ps->d_max_ok[i] = 1;
    }
    return ps->d_max[i];
}

#define PAIRSET_CACHE 4
typedef struct {
    int n_used, next;
    PairSet set[PAIRSET_CACHE];
} PairCache;

/* The pair set at roll coordinate u: from the cache (same u, bit for bit: == on doubles, and
 * +0.0/-0.0 give the same pairs) or built into it. */
static PairSet* pairs_cached(const Model* M, Fail* f, PairCache* c, double u)
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

typedef struct {
    double delta, tau_w, tau_p, W, F;
    /* detail (outputs) only */
    int64_t n_loaded;
    double top_W, top_h, top_lam, top_psi;
    double forces[N_SLOTS];
} Loads;

/* MeshModel._loads; detail = 0 is the integrator's path (mesh.torques), 1 the outputs'.
 * cache: the step's pair sets, or NULL. */
static void mesh_loads(const Model* M, Fail* f, PairCache* cache, int64_t flank, double phi_p,
                       double w_p, double phi_w, double w_w, double v_impact, int detail,
                       Loads* out)
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
    double shape = delta * py_pow(f, delta, 0.5);
    if (M->damping > 0.0) {
        shape *= 1.0 + M->damping * delta_dot;
        if (shape < 0.0)
            shape = 0.0;
    }
    double E_star = M->E_star;
    double tau_w = 0.0, tau_p = 0.0, W_sum = 0.0, F_net = 0.0;
    double u_roll = flank_roll(M, flank, phi_p);
    PairSet local;
    PairSet* ps;
    if (cache != NULL) {
        ps = pairs_cached(M, f, cache, u_roll);
    }
    else {
        pairset_build(M, f, u_roll, &local);
        ps = &local;
    }
    for (int i = 0; i < ps->n; i++) {
        double s = ps->s[i];
        double K = ps->K[i];
        double W = K * shape;
        tau_w += (double)flank * W * M->arm_wheel;
        tau_p -= (double)flank * W * M->arm_pinion;
        W_sum += W;
        double F = 0.0;
        double rho_p = s, rho_w = M->line_length - s;
        double v_s = w_p * rho_p - w_w * rho_w;          /* lubrication.sliding_speed */
        double u = 0.5 * (w_p * rho_p + w_w * rho_w);    /* lubrication.entrainment_speed */
        double h = 0.0, lam = 0.0, psi = 0.0;
        if ((M->friction_enabled || detail) && W > 0.0) {
            double A_e = 3.2 * W / E_star * M->sqrt_gamma_sigma; /* asperity_area */
            /* hertz.contact_radius: (3 W sqrt(r_x r_y) / (4 E*)) ** (1/3) */
            double c = py_pow(f, 3.0 * W * ps->sqrt_rxry[i] / (4.0 * E_star), 1.0 / 3.0);
            double A = PI * c * c;                                /* apparent_area */
            double d_max = pairset_d_max(M, f, ps, i, v_impact);
            h = -delta + d_max; /* film_thickness(-delta, d_max) */
            if (!(h > 0.0))
                h = 0.0;
            lam = h / M->sigma;
            psi = dry_fraction(M, lam, A_e, A);
            if (M->friction_enabled) {
                double U = M->shear_speed == 0 ? u : v_s;
                F = friction_force(M, f, psi, A_e, A, U, h);
                if (v_s != 0.0) {
                    double sgn = v_s > 0.0 ? 1.0 : -1.0;
                    tau_w += sgn * F * rho_w;
                    tau_p -= sgn * F * rho_p;
                    F_net += sgn * F;
                }
            }
        }
        if (detail) {
            /* interface.mesh_outputs: loaded pairs (W > 0), the most loaded one (the first
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
            out->forces[ps->slot[i]] = W;
        }
    }
    out->tau_w = tau_w;
    out->tau_p = tau_p;
    out->W = W_sum;
    out->F = F_net;
}

/* MeshModel.stiffness_sum: sum() of the pairs' K, the way the running Python sums floats. */
static double stiffness_sum(const Model* M, Fail* f, int64_t flank, double phi_p)
{
    PairSet ps;
    pairset_build(M, f, flank_roll(M, flank, phi_p), &ps);
    double total = 0.0, comp = 0.0;
    for (int i = 0; i < ps.n; i++) {
        double K = ps.K[i];
        if (M->sum_mode == 0) {
            total += K;
        }
        else { /* CPython >= 3.12: Neumaier's compensated sum */
            double t = total + K;
            if (fabs(total) >= fabs(K))
                comp += (total - t) + K;
            else
                comp += (K - t) + total;
            total = t;
        }
    }
    if (M->sum_mode != 0 && comp != 0.0 && isfinite(comp))
        total += comp;
    return total;
}

/* MeshModel.energy_balance_delta_max (largest over the pairs of the flank). */
static double flank_energy_balance_delta_max(const Model* M, Fail* f, int64_t flank,
                                             double phi_p, double v_impact)
{
    PairSet ps;
    pairset_build(M, f, flank_roll(M, flank, phi_p), &ps);
    double out = 0.0;
    for (int i = 0; i < ps.n; i++) {
        double d = energy_balance_delta_max(M, f, v_impact, ps.K_full[i], ps.r_x[i]);
        out = py_max(out, d);
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
    int64_t onsets_drive, onsets_coast, rhs_evaluations, events;
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

static int64_t flank_in_contact(const Model* M, double phi_p, double phi_w, int64_t current)
{
    if (current != 0 && penetration(M, current, phi_p, phi_w) > 0.0)
        return current;
    if (penetration(M, DRIVE, phi_p, phi_w) > 0.0)
        return DRIVE;
    if (penetration(M, COAST, phi_p, phi_w) > 0.0)
        return COAST;
    return 0;
}

static void onset(Run* r, double t, int64_t flank)
{
    State* st = &r->st;
    double speed = approach_rate(r->M, flank, run_w_p(r, t), st->w);
    r->events++;
    double v = py_max(speed, 0.0);
    st->v_last = v;
    if (flank == DRIVE) {
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
    double c = M->half_backlash;
    double hit_d = 0.0, hit_c = 0.0;
    int has_d = first_crossing(x0 - c, v0, half_acc, span, 1, &hit_d);
    int has_c = first_crossing(-x0 - c, -v0, -half_acc, span, 1, &hit_c);
    double dt;
    int64_t flank;
    if (!has_d && !has_c) {
        dt = span;
        flank = 0;
    }
    else if (!has_c || (has_d && hit_d <= hit_c)) {
        dt = hit_d;
        flank = DRIVE;
    }
    else {
        dt = hit_c;
        flank = COAST;
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
    double v_imp = flank == DRIVE ? st->v_drive : st->v_coast;
    Loads L;
    mesh_loads(r->M, r->f, &r->pairs, flank, run_phi_p(r, t), run_w_p(r, t), phi_w, w_w, v_imp, 0,
               &L);
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

typedef struct {
    Run* r;
    double t;
    const double* k1;
    int64_t flank;
} ReleaseCtx;

/* delta_after of _release_time: penetration after the RK4 step of length dt from t. */
static double delta_after(void* vctx, double dt)
{
    ReleaseCtx* c = (ReleaseCtx*)vctx;
    Run* r = c->r;
    double phi_b, w_b, q;
    rk4(r, c->t, dt, r->st.phi, r->st.w, c->k1, &phi_b, &w_b, &q);
    return penetration(r->M, c->flank, run_phi_p(r, c->t + dt), phi_b);
}

/* _release_time: returns 1 and the offset in (0, h], or 0 for a grazing contact. */
static int release_time(Run* r, double t, double h, double delta_a, double delta_b,
                        const double* k1, double* out)
{
    ReleaseCtx c = {r, t, k1, r->st.flank};
    double lo = 0.0, f_lo = delta_a;
    if (f_lo <= 0.0) {
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
    *out = brent(r->f, delta_after, &c, lo, h, f_lo, delta_b, r->M->release_xtol,
                 r->M->brent_rtol, r->M->brent_max_iter);
    return 1;
}

static void track_peak(Run* r, double t, double h, int64_t flank, double d_a, double phi_a,
                       double w_a, double d_b, double phi_b, double w_b)
{
    (void)phi_a;
    (void)phi_b;
    const Model* M = r->M;
    r->delta_peak = py_max(py_max(r->delta_peak, d_a), d_b);
    double dd_a = approach_rate(M, flank, run_w_p(r, t), w_a) * h;
    double dd_b = approach_rate(M, flank, run_w_p(r, t + h), w_b) * h;
    if (!(dd_a > 0.0 && 0.0 > dd_b))
        return;
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
        double K = stiffness_sum(M, r->f, flank, run_phi_p(r, t + s * h));
        r->W_peak = py_max(r->W_peak, K * py_pow(r->f, d, 1.5));
    }
}

static double contact_substep(Run* r, double t)
{
    const Model* M = r->M;
    State* st = &r->st;
    int64_t flank = st->flank;
    double x = t * (double)r->n_sub / r->H;
    if (!(x > -9.2e18 && x < 9.2e18))
        fail(r->f, "cannot convert float %.17g to integer (substep index)", x);
    int64_t j = (int64_t)x; /* int(): truncation */
    if (r->n_sub - 1 < j)
        j = r->n_sub - 1;
    double t_end = grid(r, j + 1);
    if (t_end <= t)
        t_end = grid(r, j + 2);
    double u_a = flank_roll(M, flank, run_phi_p(r, t));
    double bp;
    if (next_breakpoint(M, r->f, u_a, flank_roll(M, flank, run_phi_p(r, t_end)), &bp)) {
        double k = (double)flank * M->rb_pinion;
        double dt;
        if (first_crossing(u_a - bp, k * run_w_p(r, t), 0.5 * k * r->a_p, t_end - t, bp > u_a,
                           &dt))
            t_end = t + dt;
    }
    double h = t_end - t;
    double k1[3];
    rhs(r, t, st->phi, st->w, k1);
    r->W_peak = py_max(r->W_peak, k1[2]);
    double phi_b, w_b, q;
    rk4(r, t, h, st->phi, st->w, k1, &phi_b, &w_b, &q);
    double delta_a = penetration(M, flank, run_phi_p(r, t), st->phi);
    double delta_b = penetration(M, flank, run_phi_p(r, t_end), phi_b);
    int released = 0;
    if (delta_b <= 0.0) {
        double dt;
        if (release_time(r, t, h, delta_a, delta_b, k1, &dt)) {
            released = 1;
            if (dt < h) {
                h = dt;
                t_end = t + h;
                rk4(r, t, h, st->phi, st->w, k1, &phi_b, &w_b, &q);
            }
            delta_b = 0.0;
        }
    }
    track_peak(r, t, h, flank, delta_a, st->phi, st->w, delta_b, phi_b, w_b);
    st->phi = phi_b;
    st->w = w_b;
    r->int_tau_pinion += q;
    if (released || delta_b <= 0.0) {
        r->events++; /* release */
        st->flank = 0;
    }
    return t_end;
}

/* ------------------------------------------------------------------ entry points */
EXPORT int rk_abi_version(void) { return RK_ABI_VERSION * 1000 + M_COUNT; }

/*
 * WheelStepper.step: advances `state` (S_COUNT doubles) by h under the pinion kinematics and
 * the held load torque.  Returns 0 and writes state and result (R_COUNT doubles) on success;
 * on failure returns non-zero, writes the reason to err and leaves state and result as they
 * were (where the Python stepper raises ValueError).
 */
static int step_impl(const double* model, double* state, double h, double phi_p, double w_p,
                     double a_p, double tau_load, double* result, char* err, int errlen)
{
    Model M;
    if (!unpack_model(model, &M, err, errlen))
        return 1;
    /* _check_finite, then check_step_size */
    const char* names[4] = {"phi_p", "w_p", "a_p", "tau_load"};
    double values[4] = {phi_p, w_p, a_p, tau_load};
    for (int i = 0; i < 4; i++) {
        if (!isfinite(values[i])) {
            set_err(err, errlen, "input %s = %.17g is not a finite number", names[i],
                    unsigned_nan(values[i]));
            return 2;
        }
    }
    if (!(h > 0.0 && isfinite(h))) {
        set_err(err, errlen, "step size h = %.17g s is invalid; allowed: finite and > 0",
                unsigned_nan(h));
        return 3;
    }
    if (h > M.h_comm_max) {
        set_err(err, errlen,
                "step size h = %.17g s exceeds solver.h_comm_max = %.17g s; allowed: "
                "(0, %.17g] s", h, M.h_comm_max, M.h_comm_max);
        return 3;
    }

    Fail f;
    f.err = err;
    f.errlen = errlen;
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
    run.onsets_drive = run.onsets_coast = run.rhs_evaluations = run.events = 0;
    run.pairs.n_used = run.pairs.next = 0;
    if (setjmp(f.jb) != 0)
        return 4;
    {
        double x = py_ceil(&f, h / M.h_max * (1.0 - 1e-12));
        if (!(x < 9.2e18))
            fail(&f, "step size h = %.17g s needs %.17g substeps", h, x);
        run.n_sub = x > 1.0 ? (int64_t)x : 1;
    }

    /* _StepRun.execute */
    State* st = &run.st;
    int64_t flank = flank_in_contact(&M, phi_p, st->phi, st->flank);
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
        else if (++stall > STALL_LIMIT) {
            fail(&f, "the step makes no progress at t = %.17g s (the integrator is stuck; "
                     "reduce solver.h_max or the communication step)", t);
        }
        t = t_new;
    }
    double dw = st->w - w_start;
    double tau_wheel_mean = (run.J * dw + run.tau_load * run.H) / run.H;
    double tau_pinion_mean = run.int_tau_pinion / run.H;
    if (st->flank != 0) {
        run.delta_peak = py_max(run.delta_peak,
                                penetration(&M, st->flank, run_phi_p(&run, run.H), st->phi));
        double k[3];
        rhs(&run, run.H, st->phi, st->w, k);
        run.W_peak = py_max(run.W_peak, k[2]);
    }

    /* WheelStepper.step: divergence and penetration guards */
    if (!(isfinite(st->phi) && isfinite(st->w) && isfinite(tau_pinion_mean)
          && isfinite(run.W_peak))) {
        set_err(err, errlen,
                "the step diverged (wheel angle %.17g rad, speed %.17g rad/s); the inputs or "
                "parameters are beyond what the integrator resolves (reduce solver.h_max or "
                "the communication step)", unsigned_nan(st->phi), unsigned_nan(st->w));
        return 5;
    }
    double phi_end = phi_p + h * (w_p + 0.5 * a_p * h);
    double depth = py_max(py_max(run.delta_peak, penetration(&M, DRIVE, phi_end, st->phi)),
                          penetration(&M, COAST, phi_end, st->phi));
    double limit = M.pen_limit;
    if (depth > limit) {
        set_err(err, errlen,
                "the flanks would penetrate %.4g mm in this step, beyond the validity of the "
                "Hertz contact (allowed: %.4g mm = %g gear.m_n); the inputs drive the teeth "
                "into each other far harder than any transmission (check wheel.tau_load and "
                "the pinion kinematics, or reduce the communication step)",
                depth * 1e3, limit * 1e3, M.pen_modules);
        return 6;
    }

    /* commit */
    pack_state(st, state);
    result[R_TAU_WHEEL] = tau_wheel_mean;
    result[R_TAU_PINION] = tau_pinion_mean;
    result[R_W_PEAK] = run.W_peak;
    result[R_DELTA_PEAK] = run.delta_peak;
    result[R_ONSETS_DRIVE] = (double)run.onsets_drive;
    result[R_ONSETS_COAST] = (double)run.onsets_coast;
    result[R_RHS_EVALUATIONS] = (double)run.rhs_evaluations;
    result[R_EVENTS] = (double)run.events;
    result[R_PINION_PHI] = phi_p + w_p * h + 0.5 * a_p * h * h;
    result[R_PINION_W] = w_p + a_p * h;
    return 0;
}

/*
 * interface.mesh_outputs: the values of MESH_OUTPUTS (O_COUNT doubles, declared order) for
 * the state, the last step's aggregates `last` (the first four result entries of rk_step)
 * and the pinion (phi_p, w_p) at the end of the last step.  Returns 0, or non-zero where the
 * Python function would raise.
 */
static int outputs_impl(const double* model, const double* state, const double* last,
                        double phi_p, double w_p, double* out)
{
    Model M;
    if (!unpack_model(model, &M, NULL, 0))
        return 1;
    Fail f;
    f.err = NULL;
    f.errlen = 0;
    State st;
    unpack_state(state, &st);
    if (setjmp(f.jb) != 0)
        return 2;
    /* WheelStepper.loads_now */
    int64_t flank = st.flank;
    if (flank == 0)
        flank = penetration(&M, DRIVE, phi_p, st.phi) >= penetration(&M, COAST, phi_p, st.phi)
                    ? DRIVE : COAST;
    double v_imp = flank == DRIVE ? st.v_drive : st.v_coast;
    Loads L;
    mesh_loads(&M, &f, NULL, flank, phi_p, w_p, st.phi, st.w, v_imp, 1, &L);
    double h, lam, psi;
    if (L.n_loaded > 0) {
        h = L.top_h;
        lam = L.top_lam;
        psi = L.top_psi;
    }
    else {
        double v = flank > 0 ? st.v_drive : st.v_coast;
        double d_max = flank_energy_balance_delta_max(&M, &f, flank, phi_p, v);
        h = -L.delta + d_max;
        if (!(h > 0.0))
            h = 0.0;
        lam = h / M.sigma;
        psi = dry_fraction(&M, lam, 0.0, 0.0);
    }
    out[O_TAU_WHEEL] = last[R_TAU_WHEEL];
    out[O_TAU_PINION] = last[R_TAU_PINION];
    out[O_PHI] = st.phi;
    out[O_W] = st.w;
    out[O_W_NOW] = L.W;
    out[O_W_PEAK] = last[R_W_PEAK];
    out[O_F] = L.F;
    out[O_DELTA] = L.n_loaded > 0 ? L.delta : 0.0;
    out[O_DELTA_PEAK] = last[R_DELTA_PEAK];
    out[O_V_IMPACT] = st.v_last;
    out[O_H] = h;
    out[O_LAMBDA] = lam;
    out[O_PSI] = psi;
    out[O_N_CONTACT] = (double)L.n_loaded;
    out[O_IMPACTS_DRIVE] = (double)st.n_drive;
    out[O_IMPACTS_COAST] = (double)st.n_coast;
    for (int k = 0; k < N_SLOTS; k++)
        out[O_PAIR0 + k] = L.forces[k];
    return 0;
}

EXPORT int rk_step(const double* model, double* state, double h, double phi_p, double w_p,
                   double a_p, double tau_load, double* result, char* err, int errlen)
{
    return step_impl(model, state, h, phi_p, w_p, a_p, tau_load, result, err, errlen);
}

EXPORT int rk_outputs(const double* model, const double* state, const double* last,
                      double phi_p, double w_p, double* out)
{
    return outputs_impl(model, state, last, phi_p, w_p, out);
}

/*
 * The same two entry points with the scalars in arrays, for a cheaper ctypes call (pointer and
 * int arguments only, no argtypes conversion): inputs = (h, phi_p, w_p, a_p, tau_load);
 * rk_outputs_v reads the pinion from last[R_PINION_PHI], last[R_PINION_W] (the result layout).
 */
EXPORT int rk_step_v(const double* model, double* state, const double* inputs, double* result,
                     char* err, int errlen)
{
    return step_impl(model, state, inputs[0], inputs[1], inputs[2], inputs[3], inputs[4], result,
                     err, errlen);
}

EXPORT int rk_outputs_v(const double* model, const double* state, const double* last,
                        double* out)
{
    return outputs_impl(model, state, last, last[R_PINION_PHI], last[R_PINION_W], out);
}
