/*
 * rm_private.h - what the files of the model library share, by physical job:
 *
 *   text.c          message text: the formatter (numbers as the shortest text that reads
 *                   back exactly, whatever the locale)
 *   refusals.c      the wording of every refusal the physics reports as a code
 *   maths.c         x ** y through libm's pow (rm_pow)
 *   roots.c         Brent's method, exact quadratic crossings, Chebyshev series
 *   geometry.c      the helical involute pair and its tooth pairs (paper eq. 3-6)
 *   contact.c       the load-approach laws of a tooth pair: Hertz point contact (exact
 *                   ellipse, eq. 2), Palmgren's line contact, the Greenwood-Tripp asperity
 *                   layer and the teeth's compliance in series; eq. 7-8, Hunt-Crossley
 *   compliance.c    the teeth's compliance: bending, shear and compression of both teeth and
 *                   their gear bodies, per pair over its engaged contact line
 *   friction.c      film, regime and flank friction (eq. 11-17)
 *   dissipation.c   the contact's dissipation set at each onset: the squeeze-film (Stokes
 *                   number) impact law, the squeeze films after a sticking impact, the mesh
 *                   damping ratio
 *   pairs.c         the tooth pairs in the zone of action with their laws' coefficients,
 *                   cached per step (what mesh.c and dissipation.c both read)
 *   mesh.c          the mesh model: loads and torques of every pair (eq. 1-2, 10-17)
 *   stepper.c       the wheel's equation of motion (eq. 10) over one communication step
 *   start.c         the start solutions: static flank equilibrium, free start
 *   driveline.c     input-shaft kinematics and the output shaft
 *   speed_table.c   reading a measured speed table
 *   unit.c          the unit: variables, phases, checks, save/restore (rattle_model.h)
 *   record.c        the unit's state as a versioned binary record: writer, reader, checks
 *   boundary.c      the inputs a master holds, or did not exchange during initialization
 *   unit_mesh.c     GearMeshRattle: parameters to model, held inputs, outputs
 *   unit_driveline.c  Driveline: the same for the driveline
 *   system.c        the two units coupled in a compiled loop (the co-simulation's numbers)
 *   probe.c         the laws at given arguments for the tests (rm_probe.h; test builds only)
 *   rm_tables.c     GENERATED from the Python specs: the variables of both units
 *
 * Numbers: every expression keeps the IEEE operations of the reference results (docs/model.md:
 * "Reproducible numbers"): no -ffast-math, no contraction (-ffp-contract=off), x ** y through
 * libm's pow (rm_pow), max(a, b) as "b > a ? b : a".  A one-ulp change changes the impact
 * sequence of the chaotic rattle motion, so do not "simplify" an expression here.
 */
#ifndef RM_PRIVATE_H
#define RM_PRIVATE_H

#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif
#if defined(__FAST_MATH__)
#error "the rattle model must not be compiled with -ffast-math: it keeps IEEE arithmetic"
#endif

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include "rattle_model.h"
#include "rm_portable.h" /* UTF-8 and files, shared with the FMI faces */
#include "rm_tables.h"

#define RM_PI 3.141592653589793

/* Internal to the library's binary: never exported to a host (nor interposed by a namesake). */
#if (defined(__GNUC__) || defined(__clang__)) && !defined(_WIN32)
#define RM_INTERNAL __attribute__((visibility("hidden")))
#else
#define RM_INTERNAL
#endif

/* ------------------------------------------------------------------ text (text.c) */
/* A growable UTF-8 string; on allocation failure it keeps what it has and sets `failed`. */
typedef struct {
    char* data;
    size_t len, cap;
    int failed;
} RmText;

RM_INTERNAL void rm_text_init(RmText* t);
RM_INTERNAL void rm_text_free(RmText* t);
RM_INTERNAL void rm_text_clear(RmText* t);
RM_INTERNAL const char* rm_text_str(const RmText* t); /* "" when empty */
RM_INTERNAL void rm_puts(RmText* t, const char* s);
RM_INTERNAL void rm_putn(RmText* t, const char* s, size_t n);
/* The library's formatter, the same in every locale: printf's %s, %c, %d, %i, %u, %x, %X (flags,
 * width, precision, '*', h, l, ll, z) and %%, and its own conversions:
 *   %r    a double as the shortest text that reads back to it (0.1, 1e-05, 2.5e+16, nan, inf:
 *         the digits Python's repr() chooses, in C's %g form);
 *   %.Nr  a double with N significant digits, in C's %g form;
 *   %q    a string in single quotes, bytes that are not printable as \xNN: two arguments, the
 *         const char* and its length (size_t).
 * printf's %f, %e, %g and %a are not among them: a conversion it does not know ends the text
 * there, visibly.  A message is one call at its check:
 *     rm_printf(err, "parameter 'gear.b' = %r gives ... eps_gamma = %.4r", b, eps_gamma);
 * rm_printf appends to t; rm_format writes at most size bytes with the NUL into buf and returns
 * the length of the whole text.  No compiler checks these formats' arguments: a %r takes a
 * double (not an int), a %q a size_t length. */
RM_INTERNAL void rm_printf(RmText* t, const char* fmt, ...);
RM_INTERNAL void rm_vprintf(RmText* t, const char* fmt, va_list ap);
RM_INTERNAL size_t rm_format(char* buf, size_t size, const char* fmt, ...);
/* Locale-independent strtod of a whole string (surrounding blanks allowed); 1 on success. */
RM_INTERNAL int rm_parse_number(const char* text, size_t n, double* out);

/* ------------------------------------------------------------------ failures */
/* A refusal inside the physics: its code and the numbers its message quotes, then a longjmp
 * back to the entry point (stepper.c, the start and the probes), which leaves its state
 * unchanged.  refusals.c words them (rm_refusal_text). */
/* The work budget of a communication step per 1e-4 s of it (stepper.c, where it is chosen;
 * refusals.c words it): substeps and evaluations of the mesh's loads. */
#define RM_WORK_SUBSTEPS 10000
#define RM_WORK_EVALUATIONS 20000
enum {
    RM_FAIL_NONE = 0,
    RM_FAIL_DIVERGED,     /* wheel angle, speed */
    RM_FAIL_PENETRATION,  /* depth, limit */
    RM_FAIL_TOO_STIFF,    /* fastest rate, the budget's substeps, h */
    RM_FAIL_NO_BRACKET,   /* a, f(a), b, f(b) */
    RM_FAIL_MATH,         /* which (RM_MATH_...), x, y */
    RM_FAIL_TOO_MANY_PAIRS, /* limit */
    RM_FAIL_PAIR_RANGE,   /* roll coordinate, pair number */
    RM_FAIL_NO_PROGRESS,  /* time */
    RM_FAIL_SUBSTEPS,     /* h, substeps, the budget's substeps */
    RM_FAIL_PAIR_LEFT,    /* (a pair left the zone of action while its event was located) */
    RM_FAIL_WORK          /* time, the budget's substeps and evaluations, h */
};
enum { RM_MATH_POW, RM_MATH_SQRT, RM_MATH_LOG, RM_MATH_EXP, RM_MATH_FLOOR, RM_MATH_CEIL,
       RM_MATH_INT };

typedef struct {
    jmp_buf jb;
    int code;
    double values[4];
} RmFail;

#if defined(__GNUC__) || defined(__clang__)
#define RM_NORETURN __attribute__((noreturn))
#else
#define RM_NORETURN
#endif
RM_INTERNAL void rm_fail(RmFail* f, int code, double v0, double v1, double v2, double v3)
    RM_NORETURN;
/* The message of a failure (refusals.c). */
RM_INTERNAL void rm_refusal_text(RmText* t, int code, const double* values);

/* x ** y through libm's pow, called through a volatile pointer so that the compiler cannot
 * fold a constant exponent (pow(x, 2.0) into x * x rounds differently in rare cases)
 * (maths.c). */
RM_INTERNAL double rm_pow(double x, double y);

/* The library calls of the physics, refused where their result is not a real number the
 * integration can go on with (a negative or non-finite argument from diverging inputs). */
static inline double rm_pow_checked(RmFail* f, double x, double y)
{
    double r = rm_pow(x, y);
    if (x < 0.0 || (isinf(r) && isfinite(x))) rm_fail(f, RM_FAIL_MATH, RM_MATH_POW, x, y, 0.0);
    return r;
}

static inline double rm_sqrt_checked(RmFail* f, double x)
{
    if (x < 0.0) rm_fail(f, RM_FAIL_MATH, RM_MATH_SQRT, x, 0.0, 0.0);
    return sqrt(x);
}

static inline double rm_log_checked(RmFail* f, double x)
{
    if (x <= 0.0) rm_fail(f, RM_FAIL_MATH, RM_MATH_LOG, x, 0.0, 0.0);
    return log(x);
}

static inline double rm_exp_checked(RmFail* f, double x)
{
    double r = exp(x);
    if (isinf(r) && isfinite(x)) rm_fail(f, RM_FAIL_MATH, RM_MATH_EXP, x, 0.0, 0.0);
    return r;
}

static inline double rm_floor_checked(RmFail* f, double x)
{
    if (!isfinite(x)) rm_fail(f, RM_FAIL_MATH, RM_MATH_FLOOR, x, 0.0, 0.0);
    return floor(x);
}

static inline double rm_ceil_checked(RmFail* f, double x)
{
    if (!isfinite(x)) rm_fail(f, RM_FAIL_MATH, RM_MATH_CEIL, x, 0.0, 0.0);
    return ceil(x);
}

/* max(a, b) that returns a unless b > a (a NaN in a stays; fmax would drop it). */
static inline double rm_max(double a, double b) { return b > a ? b : a; }
static inline double rm_min(double a, double b) { return b < a ? b : a; }

/* ------------------------------------------------------------------ roots.c */
/* Brent's method: its iteration cap and the usual relative tolerance (four units of roundoff). */
#define RM_BRENT_MAX_ITERATIONS 200
#define RM_BRENT_RTOL (4.0 * 2.220446049250313e-16)

typedef double (*RmRootFn)(void* ctx, double x);
/* The root of fn in [a, b] given f(a) = fa and f(b) = fb of different signs (or one zero), to
 * xtol + rtol |x|; RM_FAIL_NO_BRACKET otherwise. */
RM_INTERNAL double rm_brent(RmFail* f, RmRootFn fn, void* ctx, double a, double b, double fa,
                            double fb, double xtol, double rtol);
/* The smallest t in [0, t_max] where c0 + c1 t + c2 t^2 crosses zero upwards (rising) or
 * downwards: 1 and *out, or 0. */
RM_INTERNAL int rm_first_crossing(double c0, double c1, double c2, double t_max, int rising,
                                  double* out);

/* Chebyshev series (the laws tabulated once per parameter set): the k-th of the n Chebyshev
 * points of the first kind on [lo, hi]; the coefficients of the interpolant through values
 * at those n points (c_0 halved, ready for rm_chebyshev_value); and the series
 * sum_j c_j T_j(t) at t in [-1, 1] by Clenshaw's recurrence. */
#define RM_MAX_CHEBYSHEV_TERMS 32
RM_INTERNAL double rm_chebyshev_node(double lo, double hi, int k, int n);
RM_INTERNAL void rm_chebyshev_coefficients(const double* values, int n, double* coeffs);
/* The n coefficients of the derivative d/dt of the series c (its last one 0). */
RM_INTERNAL void rm_chebyshev_derivative(const double* c, int n, double* d);
static inline double rm_chebyshev_value(const double* c, int n, double t)
{
    double b1 = 0.0, b2 = 0.0;
    int j = n - 1;
    while (j > 0) {
        double next = 2.0 * t * b1 - b2 + c[j];
        b2 = b1;
        b1 = next;
        j -= 1;
    }
    return t * b1 - b2 + c[0];
}

/* Quintic Hermite interpolation on a grid of step h: the value at the fraction t in [0, 1] of
 * the step between the nodes a0 and a1, each {value, first, second derivative}. */
static inline double rm_quintic_hermite(double t, double h, const double* a0, const double* a1)
{
    double t2 = t * t, t3 = t2 * t, t4 = t3 * t, t5 = t4 * t, hh = h * h;
    return (1.0 - 10.0 * t3 + 15.0 * t4 - 6.0 * t5) * a0[0]
           + (t - 6.0 * t3 + 8.0 * t4 - 3.0 * t5) * h * a0[1]
           + (0.5 * t2 - 1.5 * t3 + 1.5 * t4 - 0.5 * t5) * hh * a0[2]
           + (10.0 * t3 - 15.0 * t4 + 6.0 * t5) * a1[0]
           + (-4.0 * t3 + 7.0 * t4 - 3.0 * t5) * h * a1[1]
           + (0.5 * t3 - t4 + 0.5 * t5) * hh * a1[2];
}

/* ------------------------------------------------------------------ geometry.c */
#define RM_DRIVE 1
#define RM_COAST (-1)
/* Roll distance [m] under which a breakpoint counts as reached. */
#define RM_BREAKPOINT_TOLERANCE 1e-12
/* Tooth pairs held per roll coordinate, and the largest |pair number| (exact in a double). */
#define RM_MAX_PAIRS 16
#define RM_PAIR_NUMBER_LIMIT 4503599627370496.0 /* 2^52 */

/* contact.geometry: which pairs carry load and where (docs/model.md section 2). */
#define RM_LAYOUT_CROWNED 0 /* each pair at the lowest point of its line, crown offset */
#define RM_LAYOUT_PAPER 1   /* every pair in the zone, no offset, ellipsoid at eq. 6's r_y */
#define RM_LAYOUT_LINE 2    /* every pair in the zone along its engaged contact line */

/* The parameters the geometry reads. */
typedef struct {
    int z_pinion, z_wheel, layout;
    double m_n, alpha_n, beta, addendum, b, backlash, crowning;
} RmGearParams;

typedef struct {
    double ratio, alpha_t, beta_b, m_t, r_pinion, r_wheel, centre_distance, rb_pinion,
        rb_wheel, ra_pinion, ra_wheel, line_length, s_start, s_end, s_pitch, base_pitch,
        eps_alpha, eps_beta, eps_gamma, line_span, crowning, crown_factor, r_y, normal_factor,
        cos_alpha_t, sin_alpha_t, sin_beta_b, half_backlash, flank_phase, face_width;
    int layout;
    int n_bp;
    double bp[4]; /* roll breakpoints modulo the base pitch, sorted */
} RmGeometry;

/* The pair's geometry from its parameters, with its validity checks (undercut, tip
 * interference, contact ratio, pair slots): 1, or 0 with the refusal in err. */
RM_INTERNAL int rm_geometry(const RmGearParams* p, RmGeometry* g, RmText* err);
/* r_x = r_p r_w / (r_p + r_w) of the normal-plane radii at roll coordinate s (eq. 3-5). */
RM_INTERNAL double rm_radius_x(const RmGeometry* g, double s);
/* r_y of eq. 6 at roll coordinate s: the gears' radii at the contact point, the wheel's
 * taken as concave, R_p R_w / (R_w - R_p) (docs/model.md section 2). */
RM_INTERNAL double rm_radius_y_eq6(const RmGeometry* g, double s);
/* Bounds of |ln(r_y / r_x)| over the contact points of the path of contact, r_y the contact
 * law's (RM_LAYOUT_CROWNED) or eq. 6's (RM_LAYOUT_PAPER). */
RM_INTERNAL void rm_radius_ratio_range(const RmGeometry* g, double r_y, double* lo, double* hi);

static inline double rm_flank_roll(const RmGeometry* g, int flank, double phi_p)
{
    return g->flank_phase + (double)flank * g->rb_pinion * phi_p;
}

/* The tooth pairs in the zone of action at roll coordinate u, with the load-approach law's
 * coefficients at each pair's contact (filled on first use by pairs.c) and, per impact speed,
 * the eq. 7 delta_max.  `member` is the roll coordinate at which the pairs in the zone were
 * decided (u, or for the layouts without crown offsets the middle of the stepper's substep,
 * whose force jumps when a pair enters or leaves). */
typedef struct {
    double u, member;
    int n;
    int64_t slot[RM_MAX_PAIRS];
    double s[RM_MAX_PAIRS], offset[RM_MAX_PAIRS], dg[RM_MAX_PAIRS], length[RM_MAX_PAIRS];
    int coefficients_ok[RM_MAX_PAIRS];
    double r_x[RM_MAX_PAIRS], r_y[RM_MAX_PAIRS], K[RM_MAX_PAIRS], ka[RM_MAX_PAIRS],
        kz[RM_MAX_PAIRS], W_r[RM_MAX_PAIRS], c_t[RM_MAX_PAIRS];
    double d_max_v;
    int d_max_ok[RM_MAX_PAIRS];
    double d_max[RM_MAX_PAIRS];
} RmPairSet;

/* The pairs at roll coordinate u (positions), in the zone of action at roll coordinate
 * `member` (RM_LAYOUT_PAPER and RM_LAYOUT_LINE; the crowned layout decides at u). */
RM_INTERNAL void rm_pair_set_build(const RmGeometry* g, RmFail* f, double u, double member,
                                   RmPairSet* ps);
/* The first roll breakpoint between u_a and u_b in the direction of travel: 1 and *out. */
RM_INTERNAL int rm_next_breakpoint(const RmGeometry* g, RmFail* f, double u_a, double u_b,
                                   double* out);

/* ------------------------------------------------------------------ contact.c */
#define RM_LAW_EXACT 0
#define RM_LAW_EQUIVALENT_SPHERE 1

typedef struct {
    double q, kappa, alpha, zeta;
} RmEllipse;

typedef struct {
    int law;
    double E_star, r_y, x_lo, x_hi, t_mid, t_scale;
    int terms;
    double kappa[RM_MAX_CHEBYSHEV_TERMS], alpha[RM_MAX_CHEBYSHEV_TERMS],
        zeta[RM_MAX_CHEBYSHEV_TERMS];
} RmContactLaw;

RM_INTERNAL double rm_effective_modulus(double E1, double nu1, double E2, double nu2);
RM_INTERNAL int rm_exact_ellipse(double rho, RmEllipse* out, RmText* err);
RM_INTERNAL int rm_contact_law_build(int law, double E_star, double r_y, double x_lo,
                                     double x_hi, RmContactLaw* c, RmText* err);
RM_INTERNAL void rm_contact_law_at(const RmContactLaw* c, RmFail* f, double r_x, double* K,
                                   double* R, double* ka, double* kz);
/* The same at the radii (r_x, r_y) of a pair whose r_y is its own (eq. 6). */
RM_INTERNAL void rm_contact_law_at_radii(const RmContactLaw* c, RmFail* f, double r_x,
                                         double r_y, double* K, double* R, double* ka,
                                         double* kz);
RM_INTERNAL double rm_film_delta_max(RmFail* f, double v, double K, double r_x, double ka,
                                     double density);
RM_INTERNAL int rm_hunt_crossley_restitution(double alpha, double* e, RmText* err);

/* The grid of the root of the teeth's series law with Hertz: e in [0, 2] in steps of 1/256. */
#define RM_TOOTH_ROOT_POINTS 512
#define RM_TOOTH_ROOT_STEP (1.0 / 256.0)
/* The load-approach law of one tooth pair: the smooth bulk law W = K pen^p -- Hertz point
 * contact (p = 3/2, K from the contact law) or Palmgren's line contact (p = 10/9, K from the
 * engaged contact line's length) -- optionally in series with the Greenwood-Tripp asperity
 * layer, whose approach is sigma (W / W_r)^q (W_r the pair's asperity load scale). */
typedef struct {
    int line, rough;
    double E_star, sigma;
    double exponent;          /* p of the bulk law */
    double palmgren;          /* Palmgren's constant made dimensionless, C_P */
    double asperity_pressure; /* K' E* c of the Greenwood-Tripp fit [Pa] */
    double rough_exponent;    /* q of the asperity layer */
    double line_beta;         /* B(1/2, n + 1) of the rough line contact */
    /* the root f of f^2 + e f^3 = 1 and its first two derivatives in e at
     * e = k RM_TOOTH_ROOT_STEP (Hertz with the teeth in series, contact.c) */
    double tooth_root[RM_TOOTH_ROOT_POINTS + 1][3];
} RmApproachLaw;

RM_INTERNAL void rm_approach_law_build(RmApproachLaw* a, int line, int rough, double E_star,
                                       double sigma, double gamma, double asperity_density);
/* K of a line contact of length L (W = K pen^(10/9)) and its area coefficient
 * (A = kz W^(1/2)) at the radius r_x. */
RM_INTERNAL double rm_line_coefficient(const RmApproachLaw* a, RmFail* f, double length);
RM_INTERNAL double rm_line_area_coefficient(const RmApproachLaw* a, RmFail* f, double r_x,
                                            double length);
/* W_r of the asperity layer of a point contact (radii r_x, r_y) or a line contact (r_x,
 * length). */
RM_INTERNAL double rm_asperity_scale(const RmApproachLaw* a, RmFail* f, double r_x, double r_y,
                                     double length);
/* The elastic load W [N] of a pair at approach pen > 0, its law in series with the teeth's
 * compliance c_t [m/N] (0: rigid teeth; infinite: no contact line, no load), and (surface not
 * NULL) the part of pen the flanks' surfaces take, pen - c_t W. */
RM_INTERNAL double rm_approach_force(const RmApproachLaw* a, RmFail* f, double K, double W_r,
                                     double c_t, double pen, double* surface);
/* Its stiffness dW/d(pen) [N/m] and, for the Hunt-Crossley factor d, its damping
 * d W [N.s/m]. */
RM_INTERNAL void rm_approach_rates(const RmApproachLaw* a, RmFail* f, double K, double W_r,
                                   double c_t, double pen, double d, double* k, double* c);
/* The elastic energy integral_0^pen W [J]. */
RM_INTERNAL double rm_approach_energy(const RmApproachLaw* a, RmFail* f, double K, double W_r,
                                      double c_t, double pen);
/* The apparent contact area [m^2] at load W: kz W^(2/3) (point) or kz W^(1/2) (line). */
RM_INTERNAL double rm_approach_area(const RmApproachLaw* a, RmFail* f, double kz, double W);
/* eq. 7's delta_max of the pair's smooth law for the impact speed v (the film estimate). */
RM_INTERNAL double rm_approach_film_delta_max(const RmApproachLaw* a, RmFail* f, double v,
                                              double K, double r_x, double ka, double length,
                                              double density);
RM_INTERNAL int rm_hunt_crossley_factor(double e, double v, double* d, RmText* err);

/* ------------------------------------------------------------------ compliance.c */
/* tooth.compliance */
#define RM_TOOTH_NONE 0
#define RM_TOOTH_WEBER_SAINSOT 1

/* The teeth's stiffness per unit length of contact line, 1/q(s) [N/m^2] of both teeth at the
 * contact's roll coordinate s: a Chebyshev series over the path of contact (of at most
 * RM_MAX_TOOTH_TERMS terms: 20 for the reference pair, 40 where a tooth is nearly pointed at
 * the tip), evaluated as quintic Hermite pieces on a grid of at most RM_MAX_TOOTH_GRID steps
 * (its values and two derivatives at the nodes). */
#define RM_MAX_TOOTH_TERMS 64
#define RM_MAX_TOOTH_GRID 1024
typedef struct {
    int on, terms, steps;
    double t_mid, t_scale, lo, h, inv_h;
    double k[RM_MAX_TOOTH_TERMS];
    double grid[RM_MAX_TOOTH_GRID + 1][3];
    double pitch; /* q at the pitch point [m^2/N] */
} RmToothCompliance;

typedef struct RmMeshParams RmMeshParams;
/* The teeth's compliance of the parameters (nothing to build with tooth.compliance = 0): 1, or
 * 0 with the refusal. */
RM_INTERNAL int rm_tooth_compliance_build(const RmMeshParams* p, const RmGeometry* g,
                                          RmToothCompliance* c, RmText* err);
/* c_t = q(s) / length [m/N] of a pair touching at s over an engaged contact line of `length`:
 * 0 with rigid teeth, infinite for no line. */
RM_INTERNAL double rm_tooth_pair_compliance(const RmToothCompliance* c, double s,
                                            double length);

/* ------------------------------------------------------------------ friction.c */
#define RM_FORM_LOAD_SHARING 0
#define RM_FORM_APPARENT_AREA 1
#define RM_FORM_AS_PRINTED 2
/* Film parameters of the boundary (psi = 1) and full-film (psi = 0) limits. */
#define RM_LAMBDA_BOUNDARY 1.0
#define RM_LAMBDA_FULL_FILM 3.0

/* lubricant.film */
#define RM_FILM_EQ11 0
#define RM_FILM_EHL 1
/* friction.viscous_law */
#define RM_VISCOUS_NEWTONIAN 0
#define RM_VISCOUS_BARUS_LIMITED 1
/* A friction direction (rm_mesh_loads' signs) meaning: the regularized direction
 * clamp(v_s / v, -1, 1) of a pair whose friction sticks, v its stick speed (stepper.c). */
#define RM_FRICTION_STICKING 2.0
/* The least sliding speed [m/s] over which a sticking pair's friction turns (friction.c). */
RM_INTERNAL extern const double RM_STICK_SPEED;

RM_INTERNAL double rm_dry_fraction(double lam);
/* The central film thickness [m] of a loaded elliptical EHL contact (Hamrock and Dowson
 * 1977): entrainment speed u [m/s], load W > 0 [N], radii r_x (rolling direction) and r_y
 * [m], contact modulus E* [Pa], viscosity eta [Pa.s] and pressure-viscosity coefficient
 * alpha [1/Pa]. */
RM_INTERNAL double rm_ehl_central_film(double u, double W, double r_x, double r_y,
                                       double E_star, double eta, double alpha);
/* The shear stress [Pa] of the film in the viscous term, friction.viscous_law `law`, at the
 * pair's mean Hertz pressure p [Pa], shear speed U [m/s] and film thickness h > 0 [m]. */
RM_INTERNAL double rm_viscous_stress(int law, double eta, double alpha, double tau_limit_0,
                                     double tau_limit_slope, double p, double U, double h);
RM_INTERNAL double rm_friction_force(int form, double psi, double A_e, double A, double tau_s,
                                     double tau_viscous);
/* The regularized friction direction of a sticking pair at sliding speed v_s, turning over
 * the stick speed v. */
RM_INTERNAL double rm_stick_direction(double v_s, double v);

/* ------------------------------------------------------------------ mesh.c */
#define RM_DISSIPATION_NONE 0
#define RM_DISSIPATION_RESTITUTION 1
#define RM_DISSIPATION_FACTOR 2
#define RM_DISSIPATION_SQUEEZE 3
#define RM_DISSIPATION_RATIO 4

/* The parameters of the mesh model (GearMeshRattle's, SI). */
struct RmMeshParams {
    RmGearParams gear;
    double E_pinion, nu_pinion, E_wheel, nu_wheel, density, J_wheel;
    int hertz_law, dissipation, roughness;
    double restitution, restitution_speed, damping, asperity_density;
    double stokes_critical, restitution_dry, squeeze_fraction, damping_ratio;
    int tooth_compliance;
    double body_ratio_pinion, body_ratio_wheel;
    int friction_enabled, friction_form, shear_speed, viscous_law, film;
    double tau_s, eta, alpha_pv, tau_limit_0, tau_limit_slope, sigma, gamma, rattle_time, h_max,
        h_comm_max;
};

/* The dissipation of the contact in progress, set at its onset (dissipation.c): the
 * Hunt-Crossley factor d [s/m] on each pair's penetration rate, or (film) the pairs' squeeze
 * films damping it, as after an impact that did not rebound (the squeeze-film law). */
typedef struct {
    double d;
    int film;
} RmContactDissipation;

/* The mesh model: everything the stepper reads, built once per parameter set. */
typedef struct {
    RmMeshParams p;
    RmGeometry g;
    RmContactLaw law;
    RmApproachLaw approach;
    RmToothCompliance tooth;
    double E_star, arm_wheel, arm_pinion, normal_mass, damping;
    double pen_limit;        /* largest penetration a step may reach [m] */
    double sqrt_gamma_sigma; /* sqrt(gamma / sigma) of eq. 13 */
} RmMesh;

RM_INTERNAL int rm_mesh_build(const RmMeshParams* p, RmMesh* m, RmText* err);

static inline double rm_penetration(const RmMesh* M, int flank, double phi_p, double phi_w)
{
    return (double)flank * (M->arm_pinion * phi_p - M->arm_wheel * phi_w) - M->g.half_backlash;
}

static inline double rm_approach_rate(const RmMesh* M, int flank, double w_p, double w_w)
{
    return (double)flank * (M->arm_pinion * w_p - M->arm_wheel * w_w);
}

static inline double rm_sliding_speed(const RmMesh* M, double s, double w_p, double w_w)
{
    return w_p * s - w_w * (M->g.line_length - s);
}

#define RM_PAIR_CACHE 6
typedef struct {
    int n_used, next;
    double member; /* the roll coordinate deciding the pairs in the zone (NAN: each u) */
    RmPairSet set[RM_PAIR_CACHE];
} RmPairCache;

/* pairs.c: an empty cache; the pair set at u; the coefficients of pair i (once per set). */
RM_INTERNAL void rm_pair_cache_init(RmPairCache* c);
/* The pair set at roll coordinate u, from the cache or built into it (valid until the next
 * call); in the zone at c->member when that is set, else at u. */
RM_INTERNAL RmPairSet* rm_pairs_at(const RmMesh* M, RmFail* f, RmPairCache* c, double u);
RM_INTERNAL void rm_pair_coefficients(const RmMesh* M, RmFail* f, RmPairSet* ps, int i);

/* Largest penetration a step may reach, as a fraction of the normal module (mesh.c's
 * pen_limit; refusals.c quotes it): far beyond it the Hertz contact of the flanks' surfaces is
 * no longer a model of anything (the default pair reaches about 1e-3 of the module in
 * rattle). */
#define RM_MAX_PENETRATION_MODULES 0.05

/* The loads of one flank. */
typedef struct {
    double delta, tau_w, tau_p, W, F;
    /* with detail: */
    int64_t n_loaded;
    double top_W, top_h, top_lam, top_psi;
    double forces[RM_MAX_PAIR_SLOTS];
    int n_pairs; /* rows written to the per-pair detail (probes) */
} RmLoads;

/* Per-pair detail of the loads (probes): slot, s, offset, r_x, K, delta, W, F, v_s, u, h,
 * lambda, psi, delta_max. */
#define RM_PAIR_DETAIL 14
/* Per-pair law detail (rm_probe_pair_laws): slot, s, length, r_x, r_y, K, ka, kz, W_r, c_t. */
#define RM_PAIR_LAW_DETAIL 10

RM_INTERNAL void rm_mesh_loads(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank,
                               double phi_p, double w_p, double phi_w, double w_w,
                               double v_impact, RmContactDissipation diss, const double* signs,
                               const double* stick_speeds, int detail, RmLoads* out,
                               double* pairs, size_t capacity);
RM_INTERNAL double rm_static_force(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank,
                                   double phi_p, double delta);
RM_INTERNAL void rm_contact_rates(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank,
                                  double phi_p, double w_p, double delta, double delta_dot,
                                  RmContactDissipation diss, double* k, double* c);
RM_INTERNAL double rm_energy_balance_delta_max(const RmMesh* M, RmFail* f, RmPairCache* cache,
                                               int flank, double phi_p, double v_impact);

/* ------------------------------------------------------------------ stepper.c */
/* The cumulative onset counters stop at 2^53 (285,000 years at 1,000 onsets/s): every count
 * stays exact as a double in a host language, and every state the unit saves it restores
 * (unit_mesh.c refuses saved counts above this). */
#define RM_COUNT_MAX ((int64_t)1 << 53)

/* The wheel's state and the contact bookkeeping (SI). */
typedef struct {
    double phi, w;
    int flank; /* in contact: +1 drive, -1 coast, 0 none */
    double v_drive, v_coast, v_last; /* approach speed at the last onset of each flank, any */
    int64_t n_drive, n_coast;        /* cumulative onsets, saturating at RM_COUNT_MAX */
    double rattle_index;             /* exponentially averaged impact energy per second [W] */
    RmContactDissipation diss;       /* of the contact in progress (or the last one) */
} RmWheel;

/* ------------------------------------------------------------------ dissipation.c */
/* The squeeze-film area [m^2] of a pair of radii r_x, r_y: F = 6 pi eta A (-dh/dt) / h. */
RM_INTERNAL double rm_squeeze_pair_area(double r_x, double r_y);
/* The squeeze-film area of `flank` at the pinion angle phi_p: the pairs that touch first. */
RM_INTERNAL double rm_squeeze_area(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank,
                                   double phi_p);
/* The squeeze-film law's restitution at Stokes number St: e_dry (1 - St_c/St), 0 below. */
RM_INTERNAL double rm_squeeze_restitution(const RmMeshParams* p, double St);
/* The Stokes number of an impact at normal speed v on the squeeze-film area A. */
RM_INTERNAL double rm_stokes_number(const RmMesh* M, double v, double area);
/* The dissipation of a contact starting on `flank` at phi_p with approach speed v: 1 when
 * the impact does not rebound (the squeeze-film law below its critical Stokes number; the
 * stepper then takes the approach speed away), else 0. */
RM_INTERNAL int rm_onset_dissipation(const RmMesh* M, RmFail* f, RmPairCache* cache, int flank,
                                     double phi_p, double v, RmContactDissipation* out);
/* The dissipation of a contact at rest (a start in contact, or no impact speed). */
RM_INTERNAL RmContactDissipation rm_resting_dissipation(const RmMesh* M);
/* The viscous damping [N.s/m] on a touching pair's penetration rate (radii r_x, r_y, contact
 * line length, linearized stiffness k_i = dW_i/d(pen), penetration pen > 0): its squeeze film
 * in the film state (a point contact's, or a line's for contact.geometry 2, engaged over the
 * first RM_FILM_ENGAGEMENT sigma of the pair's penetration), or its share of the mesh damping
 * ratio's 2 zeta sqrt(k m) (scale from rm_ratio_scale); 0 otherwise. */
RM_INTERNAL double rm_pair_viscous_damping(const RmMesh* M, int film, double r_x, double r_y,
                                           double length, double k_i, double ratio_scale,
                                           double pen);
/* The penetration over which a pair's squeeze-film damping engages: RM_FILM_ENGAGEMENT of the
 * composite roughness sigma, rm_film_engagement_width [m]. */
RM_INTERNAL extern const double RM_FILM_ENGAGEMENT;
RM_INTERNAL double rm_film_engagement_width(const RmMeshParams* p);
/* 2 zeta sqrt(m_n / k) over the touching pairs of a pair set at the flank penetration delta
 * (0 without the mesh damping ratio or without a touching pair). */
RM_INTERNAL double rm_ratio_scale(const RmMesh* M, RmFail* f, RmPairSet* ps, double delta);

/* The aggregates of the last step, and the pinion at its end. */
typedef struct {
    double tau_wheel_mean, tau_pinion_mean, W_peak, delta_peak;
    int64_t onsets_drive, onsets_coast;
    double pinion_phi, pinion_w;
} RmLast;

/* The cost counters and the located events of a step. */
typedef struct {
    int64_t rhs_evaluations, contact_substeps;
    size_t n_events, total_events;
    RmEvent events[RM_MAX_EVENTS];
} RmStepLog;

/* One communication step of the wheel from `wheel` under the pinion's Taylor polynomial
 * (phi_p, w_p, a_p) and the held load tau_load: RM_FAIL_NONE with the new wheel and last,
 * or the failure's code with its numbers in values (wheel and last untouched). */
RM_INTERNAL int rm_wheel_step(const RmMesh* M, RmWheel* wheel, RmLast* last, double h,
                              double phi_p, double w_p, double a_p, double tau_load,
                              RmStepLog* log, double* values);

/* ------------------------------------------------------------------ start.c */
RM_INTERNAL int rm_contact_flank(const RmMesh* M, double phi_p, double w_p, double a_p,
                                 double tau_load, const RmWheel* st);
/* The wheel at the rigid speed ratio resting on the flank that carries tau_load (static
 * equilibrium): 1, or 0 with the refusal. */
RM_INTERNAL int rm_equilibrium_start(const RmMesh* M, double phi_p, double w_p,
                                     double tau_load, RmWheel* wheel, RmText* err);
/* The wheel at (phi_start, w_start) against the pinion: 1, or 0 if that puts the flanks into
 * each other. */
RM_INTERNAL int rm_free_start(const RmMesh* M, double phi_start, double w_start, double phi_p,
                              double w_p, double tau_load, RmWheel* wheel, RmText* err);

/* ------------------------------------------------------------------ driveline.c */
#define RM_N_ORDERS 4

/* vehicle.model: the output shaft to the reflected vehicle, or a constant load on the wheel */
enum { RM_VEHICLE_SHAFT = 0, RM_VEHICLE_CONSTANT_LOAD = 1 };

typedef struct {
    double k, c, J, drag, drag_viscous, h_max, h_comm_max;
    int model; /* RM_VEHICLE_SHAFT or RM_VEHICLE_CONSTANT_LOAD */
} RmShaftParams;

typedef struct {
    RmShaftParams p;
    /* input-shaft kinematics: engine orders, or the speed table when n_table > 0 */
    double w_mean, phi_0, t_start;
    int n_terms;
    double A[RM_N_ORDERS], W[RM_N_ORDERS], ph[RM_N_ORDERS];
    int a_over_step;
    size_t n_table;
    double *times, *speeds, *angles;
    /* output shaft */
    double shaft_phi, shaft_w, tau_load;
    double time, last_step;
} RmDriveline;

/* (phi, w, a) of the input shaft at t. */
RM_INTERNAL void rm_kinematics(const RmDriveline* d, double t, double* out);
/* The speed table (n rows) as the kinematics: 1, or 0 when out of memory. */
RM_INTERNAL int rm_use_table(RmDriveline* d, size_t n, const double* times,
                             const double* speeds);
RM_INTERNAL void rm_driveline_release(RmDriveline* d);
/* The output shaft in steady state behind the wheel at (phi_w, w_w). */
RM_INTERNAL void rm_shaft_start(RmDriveline* d, double phi_w, double w_w);
/* One step of the output shaft from t by h with the wheel's step-start angle and speed: 1, or
 * 0 with the refusal (nothing changed). */
RM_INTERNAL int rm_driveline_step(RmDriveline* d, double t, double h, double phi_w,
                                  double w_w, RmText* err);
/* A table of n rows: at least two, finite, times increasing, speeds and the angles they
 * integrate to (from phi_0) within the inputs' ranges: 1, else 0 with the refusal naming
 * `source`. */
RM_INTERNAL int rm_check_speed_table(size_t n, const double* times, const double* speeds,
                                     double phi_0, const char* source, RmText* err);

/* ------------------------------------------------------------------ speed_table.c */
#define RM_MAX_SPEED_TABLE_BYTES (4u * 1024u * 1024u)
/* The largest |time| [s] of a speed table's row: beyond every time a unit reaches (start
 * times within +-1e9 s, runs of at most 4e9 s), and small enough that no span of the table
 * overflows. */
#define RM_MAX_TABLE_TIME 1e10
#define RM_MAX_PATH_BYTES 4096
/* The file a speed-table parameter names: a relative path in `resources` first (when it
 * exists there), else as given. */
RM_INTERNAL void rm_resolve_speed_table(const char* resources, const char* name, RmText* out);
/* The rows of the CSV file at path: 1 with n, times, speeds (malloc'ed), or 0 with the
 * refusal. */
RM_INTERNAL int rm_read_speed_table(const char* path, size_t* n, double** times,
                                    double** speeds, RmText* err);

/* ------------------------------------------------------------------ the unit (unit.c) */
/* A stored value: Real in r, Integer and Boolean in i, String in s (UTF-8, owned). */
typedef struct {
    double r;
    int64_t i;
    char* s;
} RmValue;

/* A binary record being written or read (little-endian, explicit fields). */
typedef struct {
    unsigned char* data;
    size_t len, cap;
    int failed;
} RmWriter;
typedef struct {
    const unsigned char* data;
    size_t len, pos;
    int failed;
} RmReader;
RM_INTERNAL void rm_write_u32(RmWriter* w, uint32_t x);
RM_INTERNAL void rm_write_i64(RmWriter* w, int64_t x);
RM_INTERNAL void rm_write_f64(RmWriter* w, double x);
RM_INTERNAL void rm_write_bytes(RmWriter* w, const void* p, size_t n);
RM_INTERNAL uint32_t rm_read_u32(RmReader* r);
RM_INTERNAL int64_t rm_read_i64(RmReader* r);
RM_INTERNAL double rm_read_f64(RmReader* r);
RM_INTERNAL const unsigned char* rm_read_bytes(RmReader* r, size_t n);

/* How a unit reads inputs a master holds or did not exchange during initialization (the
 * boundary of the unit): the inputs at the end of initialization, whether the first step is
 * still to come, and the motion inputs of the last step. */
typedef struct {
    double initial_inputs[4];
    int first_step;
    int has_last_motion;
    double last_motion[4];
} RmBoundary;

typedef struct RmUnitClass RmUnitClass;

struct RmUnit {
    const RmUnitClass* cls;
    int kind;
    int phase;
    double start_time, time;
    size_t n_variables;
    const RmVariable* variables;
    size_t first_input, first_output; /* the table's order: parameters, inputs, outputs */
    RmValue* values;
    char* resources;
    void* model;            /* the unit's model, NULL before initialization has ended */
    void* cache;            /* the unit's own cache (built models, the speed table read) */
    unsigned stale;         /* output groups out of date since the last step */
    int provisional_valid;  /* outputs of initialization mode computed */
    RmValue* provisional;   /* ... here */
    int motion_set;         /* a motion input was set since the last step */
    int status;             /* of the current call */
    RmText message;
    RmLogger logger;
    void* logger_env;
};

/* The hooks of a kind of unit (unit_mesh.c, unit_driveline.c). */
struct RmUnitClass {
    int kind;
    /* The inputs whose values the first step compares with initialization's, and the motion
     * inputs a held master leaves unchanged (value references). */
    int n_start, n_motion;
    unsigned start_vr[4], motion_vr[4];
    /* The model for the current values (their ranges checked): the combination checks, the
     * fixed part (kept per parameter set), the start -- a new model, or NULL with the
     * refusal. */
    void* (*build)(RmUnit* u, RmText* err);
    void (*free_model)(void* model);
    void (*free_cache)(RmUnit* u);
    /* The step from t by h with the current inputs: 1 (with a warning, if any, in
     * `warning`), or 0 with the refusal (the model unchanged). */
    int (*step)(RmUnit* u, double t, double h, RmText* warning, RmText* err);
    /* The outputs of the groups asked for into values: 1, or 0 with the refusal.  Asking for
     * complete_group computes every output. */
    int (*outputs)(RmUnit* u, void* model, unsigned groups, RmValue* values, RmText* err);
    unsigned all_groups, complete_group;
    /* The groups a successful step leaves computed (the step wrote them to the values). */
    unsigned fresh_after_step;
    unsigned (*group_of)(unsigned vr);
    /* The model's own record: written, and read back (checked) into a new model for the
     * current values. */
    void (*save)(const void* model, RmWriter* w);
    void* (*restore)(RmUnit* u, RmReader* r, RmText* err);
    /* The events and cost of the last accepted step (NULL: none kept). */
    const RmStepLog* (*step_log)(const void* model);
    /* Derived quantities of the parameters (rm_describe): 1, or 0 with the refusal. */
    int (*describe)(RmUnit* u, const char** names, double* values, size_t capacity,
                    size_t* count, RmText* err);
};

RM_INTERNAL extern const RmUnitClass RM_MESH_CLASS;
RM_INTERNAL extern const RmUnitClass RM_DRIVELINE_CLASS;

/* The current call returns at least `status` with `message` (the first of the highest). */
RM_INTERNAL void rm_report(RmUnit* u, int status, const char* message);
/* ------------------------------------------------------------------ held inputs (boundary.c) */
/* The boundary at the end of initialization, from the current inputs. */
RM_INTERNAL void rm_boundary_start(const RmUnit* u, RmBoundary* b);
/* The master holds the motion inputs: set none since the last step, or set them to exactly
 * the last step's values. */
RM_INTERNAL int rm_motion_held(const RmUnit* u, const RmBoundary* b);
RM_INTERNAL void rm_motion_step_done(RmUnit* u, RmBoundary* b);
/* The first step's inputs differ from initialization's (and settling is asked for). */
RM_INTERNAL int rm_first_step_differs(const RmBoundary* b, int settle, const double* values,
                                      int n);
/* The settling warning of a first step, into t. */
RM_INTERNAL void rm_settled_warning(const RmUnit* u, const RmBoundary* b, const double* given,
                                    const char* what, RmText* t);
RM_INTERNAL void rm_boundary_save(const RmUnitClass* cls, const RmBoundary* b, RmWriter* w);
RM_INTERNAL int rm_boundary_restore(const RmUnitClass* cls, RmBoundary* b, RmReader* r,
                                    RmText* err);
/* 1 with the refusal "the record ends before <what>" when the reader ran past the record's
 * end (a truncated record), else 0. */
RM_INTERNAL int rm_read_ended(const RmReader* r, const char* what, RmText* err);
/* A saved double that must be finite (and >= 0 with nonnegative): 1, or 0 with the refusal
 * naming `what`. */
RM_INTERNAL int rm_read_finite(RmReader* r, const char* what, int nonnegative, double* out,
                               RmText* err);
/* A saved double within [-bound, bound] (in `unit`): what the unit reaches from legal inputs,
 * `why` saying how.  1, or 0 with the refusal naming `what`, the value and the range. */
RM_INTERNAL int rm_read_within(RmReader* r, const char* what, double bound, const char* unit,
                               const char* why, double* out, RmText* err);

/* ------------------------------------------------------------------ the record (record.c) */
/* The header of a unit's record. */
typedef struct {
    uint32_t version, kind, phase, motion_set, n_variables;
    double start_time, time;
} RmRecordHeader;
/* The unit's record (header, parameters and inputs, the model's own fields): 1, or 0 when
 * out of memory. */
RM_INTERNAL int rm_record_write(const RmUnit* u, RmWriter* w);
/* The header: its magic, its length and this version checked.  1, or 0 with the refusal. */
RM_INTERNAL int rm_record_read_header(RmReader* r, RmRecordHeader* h, RmText* err);
/* The parameters and inputs of a unit of these variables into values (Strings malloc'ed, UTF-8
 * checked; Integers 32-bit, Booleans 0 or 1).  1, or 0 with the refusal. */
RM_INTERNAL int rm_record_read_values(RmReader* r, const RmVariable* variables, size_t n,
                                      RmValue* values, RmText* err);

/* The mesh model's parameters from a GearMeshRattle unit's values. */
RM_INTERNAL int rm_mesh_params(const RmValue* values, RmMeshParams* p);
/* The parameters' ranges and choices: 1, or 0 with the refusal. */
RM_INTERNAL int rm_unit_values_valid(RmUnit* u, RmText* err);
/* The coupled start (unit.c) asks the classes: the driveline's outputs at the start for a
 * wheel (pinion.phi, pinion.w, pinion.a, wheel.tau_load, vehicle.w), and the mesh's wheel at
 * the start for its inputs. */
RM_INTERNAL int rm_driveline_start_outputs(RmUnit* u, double start_time, double phi_w,
                                           double w_w, double* out, RmText* err);
RM_INTERNAL int rm_mesh_start_wheel(RmUnit* u, const double* inputs, double* phi, double* w,
                                    RmText* err);
/* A GearMeshRattle unit's mesh model for its current parameters, built once per parameter
 * set (unit_mesh.c): NULL with the refusal.  What the probes (probe.c) evaluate. */
RM_INTERNAL const RmMesh* rm_mesh_configured(RmUnit* u, RmText* err);

#endif
