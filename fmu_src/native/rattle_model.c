/*
 * rattle_model.c - the units of the native drive-rattle FMUs, transcribed from the Python
 * that runs inside the pythonfmu FMUs:
 *
 *   GearMeshRattle (RN_UNIT_MESH): drive_rattle/geometry.py (HelicalPairGeometry and its
 *     validity checks), hertz.py (effective_modulus, the exact elliptical contact by the
 *     arithmetic-geometric mean and Brent's method, its Chebyshev fit ContactLaw._fit,
 *     hunt_crossley_factor), mesh.py (MeshModel: arms, normal mass, damping factor),
 *     stepper.py (WheelStepper: the equilibrium start and the free start's checks),
 *     kernel_layout.pack_model (the model array of rattle_kernel.c), and
 *     drive_rattle_fmi/boundary.py (MeshInputReading: held inputs, first-step settling).
 *     Stepping and the outputs are rattle_kernel.c's rk_step and rk_outputs.
 *   Driveline (RN_UNIT_DRIVELINE): drive_rattle/driveline.py (engine orders, the speed table
 *     read once with its checks, the output shaft: RK4 or its exact solution) and
 *     boundary.py (DrivelineInputReading).
 *
 * Every expression performs the IEEE operations of the Python line it ports, in the same
 * order, with the same libm functions (x ** y is pow, Python's max(a, b) is "b > a ? b : a",
 * a % b is Python's float modulo), so that on the same C library the models, and hence every
 * output, are the Python ones bit for bit (docs/kernel.md: "Keeping the numbers identical").
 * Build without contraction: -ffp-contract=off (the pragmas below ask for it where the
 * compiler honours them).
 */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif
#if defined(__FAST_MATH__)
#error "rattle_model.c must not be compiled with -ffast-math: it reproduces IEEE arithmetic"
#endif
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rattle_kernel_layout.h"
#include "rattle_native.h"

/* rattle_kernel.c */
int rk_step(const double* model, double* state, const double* inputs, double* result,
            double* err_values);
int rk_outputs(const double* model, const double* state, const double* last, double* out,
               double* err_values);
int rk_mesh_torques(const double* model, double flank, double phi_p, double w_p, double phi_w,
                    double w_w, double v_impact, double* out, double* err_values);

#define PI 3.141592653589793 /* math.pi */

/* ------------------------------------------------------------------ Python semantics */
static double py_max(double a, double b) { return b > a ? b : a; } /* max(a, b) */

static void put_tuple(RnText* t, const double* v, int n)
{
    rn_puts(t, "(");
    for (int k = 0; k < n; k++) {
        if (k) rn_puts(t, ", ");
        rn_put_repr(t, v[k]);
    }
    rn_puts(t, n == 1 ? ",)" : ")");
}

/* The value of a Real / Integer / Boolean variable. */
#define R(vr) (values[vr].r)
#define I(vr) (values[vr].i)
#define B(vr) (values[vr].i != 0)

void rn_error_init(RnError* e)
{
    e->set = 0;
    e->type = NULL;
    rn_text_init(&e->text);
}

void rn_error_free(RnError* e) { rn_text_free(&e->text); }

void rn_error_clear(RnError* e)
{
    e->set = 0;
    e->type = NULL;
    rn_text_clear(&e->text);
}

RnText* rn_error_value(RnError* e)
{
    rn_error_clear(e);
    e->set = 1;
    return &e->text;
}

RnText* rn_error_other(RnError* e, const char* type)
{
    rn_error_clear(e);
    e->set = 1;
    e->type = type;
    return &e->text;
}

/* The settling warning of boundary._InputReading._settled_warning. */
static void settled_warning(RnInstance* inst, const char* const* names, const char* const* units,
                            const double* given, const double* initial, int n, const char* what)
{
    RnText t;
    rn_text_init(&t);
    rn_puts(&t, "doStep at the first step: the inputs (");
    for (int k = 0; k < n; k++) {
        if (k) rn_puts(&t, ", ");
        rn_printf(&t, "%s = ", names[k]);
        rn_put_repr(&t, given[k]);
        rn_printf(&t, " %s", units[k]);
    }
    rn_puts(&t, ") differ from those at the end of initialization ");
    put_tuple(&t, initial, n);
    rn_printf(&t, ": %s (init.settle_first_step; a master that exchanges no values during "
                  "initialization)", what);
    rn_report(inst, fmi2Warning, rn_text_str(&t));
    rn_text_free(&t);
}

/* ------------------------------------------------------------------ snapshot checks */
/* snapshots.check_fields: kinds "f" (finite float), "f+" (>= 0), "n" (integer in
 * [0, 2^53]), "flank" (-1, 0, 1), "any"; a kind starting with '=' is a scalar entry. */
typedef struct {
    const char* key;
    const char* kinds[9];
    int count; /* entries of a list; 0: a scalar ("=" kind) or "any" */
} FieldLayout;

static void put_sorted_keys(RnText* t, const RnJson* obj)
{
    /* sorted(dict): the keys in code-point order */
    size_t n = obj->n;
    const char** keys = malloc((n ? n : 1) * sizeof *keys);
    if (keys == NULL) return;
    for (size_t k = 0; k < n; k++) keys[k] = obj->keys[k];
    for (size_t a = 1; a < n; a++)
        for (size_t b = a; b > 0 && strcmp(keys[b - 1], keys[b]) > 0; b--) {
            const char* x = keys[b];
            keys[b] = keys[b - 1];
            keys[b - 1] = x;
        }
    rn_puts(t, "[");
    for (size_t k = 0; k < n; k++) {
        if (k) rn_puts(t, ", ");
        rn_put_repr_str(t, keys[k]);
    }
    rn_puts(t, "]");
    free(keys);
}

static int kind_ok(const char* kind, const RnJson* item)
{
    if (kind[0] == '=') kind++;
    if (strcmp(kind, "f") == 0) return rn_json_is_finite_float(item);
    if (strcmp(kind, "f+") == 0) return rn_json_is_finite_float(item) && item->f >= 0.0;
    if (strcmp(kind, "n") == 0)
        return item->kind == RJ_INT && item->i >= 0 && item->i <= RN_MAX_STATE_INTEGER;
    if (strcmp(kind, "flank") == 0)
        return item->kind == RJ_INT && item->i >= -1 && item->i <= 1;
    return 1;
}

static const char* kind_wanted(const char* kind)
{
    if (kind[0] == '=') kind++;
    if (strcmp(kind, "f") == 0) return "a finite float";
    if (strcmp(kind, "f+") == 0) return "a finite float >= 0";
    if (strcmp(kind, "n") == 0) return "an integer in [0, 2^53]";
    return "-1, 0 or 1";
}

/* 1 if `snapshot` is a dict with exactly the keys of `layout` (n entries, given in sorted
 * order in `sorted_names` for the message) and every entry of the kinds given; 0 with the
 * ValueError otherwise. */
static int check_snapshot_fields(const RnJson* snapshot, const FieldLayout* layout, int n,
                                 const char* sorted_names, RnError* err)
{
    int keys_ok = snapshot->kind == RJ_OBJECT && snapshot->n == (size_t)n;
    for (int k = 0; keys_ok && k < n; k++)
        if (rn_json_get(snapshot, layout[k].key) == NULL) keys_ok = 0;
    if (!keys_ok) {
        RnText* t = rn_error_value(err);
        rn_puts(t, "model snapshot has entries ");
        if (snapshot->kind == RJ_OBJECT)
            put_sorted_keys(t, snapshot);
        else
            rn_puts(t, rn_json_type_name(snapshot));
        rn_printf(t, ", expected %s", sorted_names);
        return 0;
    }
    for (int k = 0; k < n; k++) {
        const FieldLayout* f = &layout[k];
        const RnJson* value = rn_json_get(snapshot, f->key);
        if (strcmp(f->kinds[0], "any") == 0) continue;
        int scalar = f->kinds[0][0] == '=';
        if (!scalar && !(value->kind == RJ_ARRAY && value->n == (size_t)f->count)) {
            RnText* t = rn_error_value(err);
            rn_printf(t, "model snapshot '%s' = ", f->key);
            rn_json_short_repr(t, value);
            rn_printf(t, ": expected a list of %d values", f->count);
            return 0;
        }
        int items = scalar ? 1 : f->count;
        for (int i = 0; i < items; i++) {
            const RnJson* item = scalar ? value : &value->items[i];
            const char* kind = f->kinds[scalar ? 0 : i];
            if (!kind_ok(kind, item)) {
                RnText* t = rn_error_value(err);
                if (scalar)
                    rn_printf(t, "model snapshot %s = ", f->key);
                else
                    rn_printf(t, "model snapshot %s[%d] = ", f->key, i);
                rn_json_short_repr(t, item);
                rn_printf(t, ": expected %s", kind_wanted(kind));
                return 0;
            }
        }
    }
    return 1;
}

/* boundary._InputReading: the state of how the unit reads its inputs (n_start START_INPUTS,
 * n_motion MOTION_INPUTS; the Driveline adds wheel_end). */
typedef struct {
    double initial_inputs[3];
    int first_step;
    int has_last_motion;
    double last_motion[3];
} Boundary;

static void boundary_snapshot(const Boundary* b, int n_start, int n_motion, RnText* j)
{
    rn_puts(j, "\"first_step\": ");
    rn_puts(j, b->first_step ? "true" : "false");
    rn_puts(j, ", \"initial_inputs\": [");
    for (int k = 0; k < n_start; k++) {
        if (k) rn_puts(j, ", ");
        rn_json_put_float(j, b->initial_inputs[k]);
    }
    rn_puts(j, "], \"last_motion\": ");
    if (!b->has_last_motion)
        rn_puts(j, "null");
    else {
        rn_puts(j, "[");
        for (int k = 0; k < n_motion; k++) {
            if (k) rn_puts(j, ", ");
            rn_json_put_float(j, b->last_motion[k]);
        }
        rn_puts(j, "]");
    }
}

/* _InputReading._restore_boundary */
static int boundary_restore(Boundary* b, const RnJson* state, int n_start, int n_motion,
                            int driveline, double* wheel_end, RnError* err)
{
    static const char* const F[9] = {"f", "f", "f", "f", "f", "f", "f", "f", "f"};
    FieldLayout layout[4];
    int n = 3;
    layout[0].key = "initial_inputs";
    layout[0].count = n_start;
    memcpy(layout[0].kinds, F, sizeof F);
    layout[1].key = "first_step";
    layout[1].count = 0;
    layout[1].kinds[0] = "any";
    layout[2].key = "last_motion";
    layout[2].count = 0;
    layout[2].kinds[0] = "any";
    if (driveline) {
        layout[3].key = "wheel_end";
        layout[3].count = 2;
        memcpy(layout[3].kinds, F, sizeof F);
        n = 4;
    }
    if (!check_snapshot_fields(state, layout, n,
                               driveline ? "['first_step', 'initial_inputs', 'last_motion', "
                                           "'wheel_end']"
                                         : "['first_step', 'initial_inputs', 'last_motion']",
                               err))
        return 0;
    const RnJson* first = rn_json_get(state, "first_step");
    if (first->kind != RJ_TRUE && first->kind != RJ_FALSE) {
        RnText* t = rn_error_value(err);
        rn_puts(t, "model snapshot first_step = ");
        rn_json_repr(t, first);
        rn_puts(t, ": expected a boolean");
        return 0;
    }
    const RnJson* last = rn_json_get(state, "last_motion");
    if (last->kind != RJ_NULL) {
        FieldLayout lm;
        lm.key = "last_motion";
        lm.count = n_motion;
        memcpy(lm.kinds, F, sizeof F);
        /* check_snapshot_fields({"last_motion": last}, ...): only the entry's own checks */
        RnJson wrapper;
        char* key = "last_motion";
        memset(&wrapper, 0, sizeof wrapper);
        wrapper.kind = RJ_OBJECT;
        wrapper.n = 1;
        wrapper.items = (RnJson*)last;
        wrapper.keys = &key;
        if (!check_snapshot_fields(&wrapper, &lm, 1, "['last_motion']", err)) return 0;
    }
    const RnJson* init = rn_json_get(state, "initial_inputs");
    for (int k = 0; k < n_start; k++) b->initial_inputs[k] = init->items[k].f;
    b->first_step = first->kind == RJ_TRUE;
    b->has_last_motion = last->kind != RJ_NULL;
    for (int k = 0; b->has_last_motion && k < n_motion; k++) b->last_motion[k] = last->items[k].f;
    if (driveline) {
        const RnJson* end = rn_json_get(state, "wheel_end");
        wheel_end[0] = end->items[0].f;
        wheel_end[1] = end->items[1].f;
    }
    return 1;
}

/* HeldInputTracking._motion_held: no motion input set since the last step, or all set to
 * exactly the values of the last step. */
static int motion_held(const RnInstance* inst, const Boundary* b, const unsigned* vrs, int n)
{
    if (!inst->motion_set) return 1;
    if (!b->has_last_motion) return 0;
    for (int k = 0; k < n; k++)
        if (!(inst->values[vrs[k]].r == b->last_motion[k])) return 0;
    return 1;
}

static void motion_step_done(RnInstance* inst, Boundary* b, const unsigned* vrs, int n)
{
    for (int k = 0; k < n; k++) b->last_motion[k] = inst->values[vrs[k]].r;
    b->has_last_motion = 1;
    inst->motion_set = 0;
}

static int first_step_differs(const Boundary* b, int settle, const double* values, int n)
{
    if (!b->first_step || !settle) return 0;
    for (int k = 0; k < n; k++)
        if (values[k] != b->initial_inputs[k]) return 1;
    return 0;
}

#if defined(RN_UNIT_MESH)

/* ================================================================== GearMeshRattle */
static const unsigned MOTION_VRS[3] = {RN_VR_PINION_PHI, RN_VR_PINION_W, RN_VR_PINION_A};
static const unsigned START_VRS[3] = {RN_VR_PINION_PHI, RN_VR_PINION_W, RN_VR_WHEEL_TAU_LOAD};
static const char* const START_NAMES[3] = {"pinion.phi", "pinion.w", "wheel.tau_load"};

int rn_unit_is_motion_input(unsigned vr)
{
    return vr == RN_VR_PINION_PHI || vr == RN_VR_PINION_W || vr == RN_VR_PINION_A;
}

/* ------------------------------------------------------------------ Python semantics */
static double py_min(double a, double b) { return b < a ? b : a; } /* min(a, b) */

/* x ** y as CPython computes it: libm's pow.  Called through a volatile pointer so that the
 * compiler cannot fold a constant exponent (pow(x, 2.0) into x * x, which rounds differently
 * from glibc's pow in rare cases: found by tests/native's hypothesis test of the model array). */
static double py_pow(double x, double y)
{
    double (*volatile libm_pow)(double, double) = pow;
    return libm_pow(x, y);
}

/* math.degrees(x): x * (180 / pi), as CPython computes it */
static double py_degrees(double x) { return x * (180.0 / PI); }

/* a % b of floats (CPython's float_rem) */
static double py_mod(double v, double w)
{
    double mod = fmod(v, w);
    if (mod != 0.0) {
        if ((w < 0.0) != (mod < 0.0)) mod += w;
    }
    else
        mod = copysign(0.0, w);
    return mod;
}

/* roots.brent, the kernel's (rk_brent); fa/fb computed when not given.  0 with the ValueError
 * in err if [a, b] does not bracket a root. */
typedef double (*RootFn)(void* ctx, double x);
int rk_brent(RootFn fn, void* ctx, double a, double b, double fa, double fb, double xtol,
             double rtol, int64_t max_iter, double* root, double* err_values);
static void kernel_refusal(int code, const double* v, RnError* err);

static int brent(RootFn f, void* ctx, double a, double b, const double* fa_given,
                 const double* fb_given, double xtol, double rtol, double* root, RnError* err)
{
    double fa = fa_given == NULL ? f(ctx, a) : *fa_given;
    double fb = fb_given == NULL ? f(ctx, b) : *fb_given;
    double err_values[RK_ERROR_VALUES];
    int code = rk_brent(f, ctx, a, b, fa, fb, xtol, rtol, RN_ROOTS_MAX_ITERATIONS, root,
                        err_values);
    if (code != RK_ERR_OK) {
        kernel_refusal(code, err_values, err);
        return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------ geometry.py */
typedef struct {
    double ratio, alpha_t, beta_b, m_t, r_pinion, r_wheel, centre_distance, rb_pinion,
        rb_wheel, ra_pinion, ra_wheel, line_length, s_start, s_end, s_pitch, base_pitch,
        eps_alpha, eps_beta, eps_gamma, line_span, crowning, crown_factor, r_y, normal_factor,
        cos_alpha_t, sin_alpha_t, sin_beta_b, half_backlash, flank_phase;
    int n_bp;
    double bp[4];
} Geometry;

/* HelicalPairGeometry.__init__ (with _check when `check`); 0 with the ValueError. */
static int geometry(const RnValue* values, Geometry* g, RnError* err)
{
    double zp = (double)I(RN_VR_GEAR_Z_PINION), zw = (double)I(RN_VR_GEAR_Z_WHEEL);
    double m_n = R(RN_VR_GEAR_M_N), alpha_n = R(RN_VR_GEAR_ALPHA_N), beta = R(RN_VR_GEAR_BETA);
    double addendum = R(RN_VR_GEAR_H_A), b = R(RN_VR_GEAR_B);
    g->ratio = zp / zw;
    g->alpha_t = atan(tan(alpha_n) / cos(beta));
    g->beta_b = asin(sin(beta) * cos(alpha_n));
    g->m_t = m_n / cos(beta);
    g->r_pinion = 0.5 * zp * g->m_t;
    g->r_wheel = 0.5 * zw * g->m_t;
    g->centre_distance = g->r_pinion + g->r_wheel;
    g->rb_pinion = g->r_pinion * cos(g->alpha_t);
    g->rb_wheel = g->r_wheel * cos(g->alpha_t);
    g->ra_pinion = g->r_pinion + addendum * m_n;
    g->ra_wheel = g->r_wheel + addendum * m_n;
    g->line_length = g->centre_distance * sin(g->alpha_t);
    g->s_start = g->line_length - sqrt(py_pow(g->ra_wheel, 2.0) - py_pow(g->rb_wheel, 2.0));
    g->s_end = sqrt(py_pow(g->ra_pinion, 2.0) - py_pow(g->rb_pinion, 2.0));
    g->s_pitch = g->rb_pinion * tan(g->alpha_t);
    g->base_pitch = 2.0 * PI * g->rb_pinion / zp;
    g->eps_alpha = (g->s_end - g->s_start) / g->base_pitch;
    g->eps_beta = b * sin(beta) / (PI * m_n);
    g->eps_gamma = g->eps_alpha + g->eps_beta;
    g->line_span = b * tan(g->beta_b);
    if (g->line_span < RN_BREAKPOINT_TOLERANCE) g->line_span = 0.0;
    g->crowning = R(RN_VR_CONTACT_CROWNING);
    double half_span = 0.5 * g->line_span;
    g->crown_factor = half_span > 0.0 ? g->crowning / (half_span * half_span) : 0.0;
    double half_line = 0.5 * b / cos(g->beta_b);
    g->r_y = half_line * half_line / (2.0 * g->crowning);
    g->normal_factor = cos(g->beta_b);
    g->cos_alpha_t = cos(g->alpha_t);
    g->sin_alpha_t = sin(g->alpha_t);
    g->sin_beta_b = sin(g->beta_b);
    g->half_backlash = 0.5 * R(RN_VR_GEAR_BACKLASH);
    g->flank_phase = g->s_pitch + 0.25 * g->base_pitch;

    /* _check */
    double sin2 = py_pow(sin(g->alpha_t), 2.0);
    double z_min = 2.0 * addendum * cos(beta) / sin2;
    const char* names[2] = {"gear.z_pinion", "gear.z_wheel"};
    long long zs[2] = {I(RN_VR_GEAR_Z_PINION), I(RN_VR_GEAR_Z_WHEEL)};
    for (int k = 0; k < 2; k++) {
        if ((double)zs[k] < z_min) {
            RnText* t = rn_error_value(err);
            rn_printf(t, "parameter '%s' = %lld undercuts with gear.alpha_n = ", names[k], zs[k]);
            rn_put_g(t, py_degrees(alpha_n), 4);
            rn_puts(t, " deg and gear.beta = ");
            rn_put_g(t, py_degrees(beta), 4);
            rn_printf(t, " deg; allowed: %s >= %.0f (2 cos(beta)/sin^2(alpha_t) * gear.h_a = ",
                      names[k], ceil(z_min - 1e-9));
            rn_put_g(t, z_min, 4);
            rn_puts(t, ")");
            return 0;
        }
    }
    if (g->s_start <= 0.0 || g->s_end >= g->line_length) {
        RnText* t = rn_error_value(err);
        rn_puts(t, "tip interference: the path of contact leaves the line of action (s_start = ");
        rn_put_g(t, g->s_start, 4);
        rn_puts(t, " m, s_end = ");
        rn_put_g(t, g->s_end, 4);
        rn_puts(t, " m, line length ");
        rn_put_g(t, g->line_length, 4);
        rn_printf(t, " m) for gear.z_pinion = %lld, gear.z_wheel = %lld; allowed: 0 < s_start "
                     "< s_end < line length", zs[0], zs[1]);
        return 0;
    }
    if (g->eps_alpha < 1.0) {
        RnText* t = rn_error_value(err);
        rn_puts(t, "transverse contact ratio eps_alpha = ");
        rn_put_f(t, g->eps_alpha, 4);
        rn_printf(t, " below 1 for gear.z_pinion = %lld, gear.z_wheel = %lld, gear.h_a = ", zs[0],
                  zs[1]);
        rn_put_g(t, addendum, 4);
        rn_puts(t, ", gear.alpha_n = ");
        rn_put_g(t, py_degrees(alpha_n), 4);
        rn_puts(t, " deg, gear.beta = ");
        rn_put_g(t, py_degrees(beta), 4);
        rn_puts(t, " deg; allowed: eps_alpha >= 1");
        return 0;
    }
    double max_pairs = floor(g->eps_gamma) + 1.0;
    if (max_pairs > RN_MAX_PAIR_SLOTS) {
        double b_max = (RN_MAX_PAIR_SLOTS - g->eps_alpha) * PI * m_n / py_max(sin(beta), 1e-300);
        RnText* t = rn_error_value(err);
        rn_puts(t, "parameter 'gear.b' = ");
        rn_put_repr(t, b);
        rn_puts(t, " gives a total contact ratio eps_gamma = ");
        rn_put_g(t, g->eps_gamma, 4);
        rn_printf(t, ", needing %.0f pair slots; at most %d are available; allowed: gear.b < ",
                  max_pairs, RN_MAX_PAIR_SLOTS);
        rn_put_g(t, b_max, 4);
        rn_puts(t, " m");
        return 0;
    }

    /* _roll_breakpoints: sorted(v % base_pitch for v in {the four, as a set}) */
    double half = 0.5 * g->line_span;
    double raw[4] = {g->s_start - half, g->s_start, g->s_end, g->s_end + half};
    int n = 0;
    for (int k = 0; k < 4; k++) {
        int seen = 0;
        for (int m = 0; m < k; m++)
            if (raw[m] == raw[k]) seen = 1;
        if (!seen) g->bp[n++] = py_mod(raw[k], g->base_pitch);
    }
    for (int a = 1; a < n; a++)
        for (int c = a; c > 0 && g->bp[c] < g->bp[c - 1]; c--) {
            double x = g->bp[c];
            g->bp[c] = g->bp[c - 1];
            g->bp[c - 1] = x;
        }
    g->n_bp = n;
    return 1;
}

int rn_unit_check_combination(const RnValue* values, RnError* err)
{
    Geometry g;
    return geometry(values, &g, err);
}

/* normal_radii(s)[2] */
static double radius_x(const Geometry* g, double s)
{
    double c = g->normal_factor;
    double rp = s / c;
    double rw = (g->line_length - s) / c;
    return rp * rw / (rp + rw);
}

/* radius_ratio_range */
static void radius_ratio_range(const Geometry* g, double* lo, double* hi)
{
    double samples[3] = {g->s_start, g->s_end, 0.0};
    int n = 2;
    double mid = 0.5 * g->line_length;
    if (g->s_start < mid && mid < g->s_end) samples[n++] = mid;
    double r_x[3];
    for (int k = 0; k < n; k++) r_x[k] = radius_x(g, samples[k]);
    double r_lo = r_x[0], r_hi = r_x[0];
    for (int k = 1; k < n; k++) {
        if (r_x[k] < r_lo) r_lo = r_x[k];
        if (r_x[k] > r_hi) r_hi = r_x[k];
    }
    double cand[3] = {fabs(log(g->r_y / r_lo)), fabs(log(g->r_y / r_hi)), 0.0};
    int m = 2;
    if (r_lo <= g->r_y && g->r_y <= r_hi) cand[m++] = 0.0;
    double c_lo = cand[0], c_hi = cand[0];
    for (int k = 1; k < m; k++) {
        if (cand[k] < c_lo) c_lo = cand[k];
        if (cand[k] > c_hi) c_hi = cand[k];
    }
    *lo = c_lo;
    *hi = c_hi;
}

/* ------------------------------------------------------------------ hertz.py */
/* elliptic_integrals(q): K(e) and S, E = K (1 - S) */
static void elliptic_integrals(double q, double* K, double* S_out)
{
    double a = 1.0, b = q;
    double c = sqrt((1.0 - q) * (1.0 + q));
    double S = 0.5 * c * c;
    double weight = 0.5;
    for (int it = 0; it < RN_AGM_MAX_ITERATIONS; it++) {
        if (a - b <= RN_AGM_TOLERANCE * a) break;
        c = 0.5 * (a - b);
        double na = 0.5 * (a + b), nb = sqrt(a * b);
        a = na;
        b = nb;
        weight *= 2.0;
        S += weight * c * c;
    }
    *K = PI / (2.0 * a);
    *S_out = S;
}

static double curvature_ratio(double q)
{
    double K, S;
    elliptic_integrals(q, &K, &S);
    double e2 = (1.0 - q) * (1.0 + q);
    return (e2 - S) / (q * q * S);
}

typedef struct {
    double q, kappa, alpha, zeta;
} Ellipse;

static double ellipse_residual(void* ctx, double y)
{
    double target = *(const double*)ctx;
    return log(curvature_ratio(exp(y))) - target;
}

/* exact_ellipse(rho) */
static int exact_ellipse(double rho, Ellipse* out, RnError* err)
{
    if (!(rho >= 1.0)) {
        RnText* t = rn_error_value(err);
        rn_puts(t, "radius ratio rho = ");
        rn_put_repr(t, rho);
        rn_puts(t, " must be >= 1 (larger over smaller)");
        return 0;
    }
    if (rho <= RN_CIRCLE_RATIO) {
        double third = py_pow(3.0 / 4.0, 1.0 / 3.0);
        out->q = 1.0;
        out->kappa = 4.0 / 3.0;
        out->alpha = third;
        out->zeta = PI * third * third;
        return 1;
    }
    double target = log(rho);
    double y_lo = -1.0;
    while (ellipse_residual(&target, y_lo) < 0.0) {
        y_lo *= 2.0;
        if (y_lo < -200.0) {
            RnText* t = rn_error_value(err);
            rn_puts(t, "radius ratio rho = ");
            rn_put_repr(t, rho);
            rn_puts(t, " too large for an elliptical contact");
            return 0;
        }
    }
    double y_hi = -1e-9;
    double y;
    if (ellipse_residual(&target, y_hi) < 0.0) {
        if (!brent(ellipse_residual, &target, y_lo, y_hi, NULL, NULL, RN_HERTZ_ROOT_XTOL,
                   RN_BRENT_RTOL, &y,
                   err))
            return 0;
    }
    else
        y = y_hi;
    double q = exp(y);
    double K, S;
    elliptic_integrals(q, &K, &S);
    double e2 = (1.0 - q) * (1.0 + q);
    double e = sqrt(e2);
    double kappa = (2.0 * sqrt(2.0) * PI / 3.0) * sqrt(S) / (K * e);
    double alpha = py_pow(3.0 * K * S / (PI * e2), 1.0 / 3.0);
    out->q = q;
    out->kappa = kappa;
    out->alpha = alpha;
    out->zeta = PI * q * alpha * alpha;
    return 1;
}

/* The memo of ContactLaw._fit (x -> exact_ellipse(exp(x))): values are what a call gives. */
typedef struct {
    int n, cap;
    double* x;
    Ellipse* e;
} EllipseCache;

static int cached_ellipse(EllipseCache* c, double x, Ellipse* out, RnError* err)
{
    for (int k = 0; k < c->n; k++)
        if (c->x[k] == x) {
            *out = c->e[k];
            return 1;
        }
    if (!exact_ellipse(exp(x), out, err)) return 0;
    if (c->n == c->cap) {
        int cap = c->cap ? 2 * c->cap : 64;
        double* nx = realloc(c->x, (size_t)cap * sizeof *nx);
        if (nx == NULL) return 1;
        c->x = nx;
        Ellipse* ne = realloc(c->e, (size_t)cap * sizeof *ne);
        if (ne == NULL) return 1;
        c->e = ne;
        c->cap = cap;
    }
    c->x[c->n] = x;
    c->e[c->n] = *out;
    c->n++;
    return 1;
}

static double ellipse_field(const Ellipse* e, int i)
{
    return i == 1 ? e->kappa : (i == 2 ? e->alpha : e->zeta);
}

/* chebyshev_fit of ellipse field i on [lo, hi] with `terms` coefficients */
static int chebyshev_fit(EllipseCache* cache, int i, double lo, double hi, int terms,
                         double* coeffs, RnError* err)
{
    int n = terms;
    double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
    double values[RN_MAX_CHEBYSHEV_TERMS];
    for (int k = 0; k < n; k++) {
        Ellipse e;
        if (!cached_ellipse(cache, mid + half * cos(PI * ((double)k + 0.5) / (double)n), &e, err))
            return 0;
        values[k] = ellipse_field(&e, i);
    }
    for (int j = 0; j < n; j++) {
        double acc = 0.0;
        for (int k = 0; k < n; k++)
            acc += values[k] * cos(PI * (double)j * ((double)k + 0.5) / (double)n);
        coeffs[j] = 2.0 * acc / (double)n;
    }
    coeffs[0] *= 0.5;
    return 1;
}

static double chebyshev_value(const double* c, int n, double t)
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

typedef struct {
    int law;
    double E_star, r_y, x_lo, x_hi, t_mid, t_scale;
    int terms;
    double kappa[RN_MAX_CHEBYSHEV_TERMS], alpha[RN_MAX_CHEBYSHEV_TERMS],
        zeta[RN_MAX_CHEBYSHEV_TERMS];
} ContactLaw;

/* ContactLaw.__init__ with _fit */
static int contact_law(int law, double E_star, double r_y, double x_lo, double x_hi,
                       ContactLaw* c, RnError* err)
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
    if (law == RN_LAW_EQUIVALENT_SPHERE) return 1;
    if (law != RN_LAW_EXACT) {
        RnText* t = rn_error_value(err);
        rn_printf(t, "contact law %d unknown; allowed: 0, 1", law);
        return 0;
    }
    double lo = x_lo, hi = x_hi;
    if (hi - lo < 1e-12) {
        Ellipse e;
        if (!exact_ellipse(exp(lo), &e, err)) return 0;
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
    int ok = 0;
    for (int terms = 8; terms <= RN_MAX_CHEBYSHEV_TERMS; terms += 4) {
        double* fits[3] = {c->kappa, c->alpha, c->zeta};
        for (int i = 1; i <= 3; i++)
            if (!chebyshev_fit(&cache, i, lo, hi, terms, fits[i - 1], err)) goto done;
        worst = 0.0;
        for (int k = 0; k < 23; k++) {
            double x = checks[k];
            double t = (x - c->t_mid) * c->t_scale;
            Ellipse e;
            if (!cached_ellipse(&cache, x, &e, err)) goto done;
            for (int i = 1; i <= 3; i++) {
                double exact = ellipse_field(&e, i);
                worst = py_max(worst, fabs(chebyshev_value(fits[i - 1], terms, t) - exact) / exact);
            }
        }
        if (worst <= RN_CHEBYSHEV_TOLERANCE) {
            c->terms = terms;
            ok = 1;
            goto done;
        }
    }
    {
        RnText* t = rn_error_value(err);
        rn_puts(t, "the exact Hertz law cannot be tabulated for ln(R/r) in [");
        rn_put_g(t, lo, 4);
        rn_puts(t, ", ");
        rn_put_g(t, hi, 4);
        rn_puts(t, "] to ");
        rn_put_g(t, RN_CHEBYSHEV_TOLERANCE, 6);
        rn_puts(t, " (reached ");
        rn_put_g(t, worst, 3);
        rn_puts(t, "); use contact.hertz_law = 1");
    }
done:
    free(cache.x);
    free(cache.e);
    return ok;
}

/* _hunt_crossley_balance */
static double hc_balance(double alpha, double e)
{
    return alpha - log1p(alpha) + alpha * e + log1p(-alpha * e);
}

static double hc_balance_fn(void* ctx, double e) { return hc_balance(*(const double*)ctx, e); }

/* hunt_crossley_restitution(alpha) */
static double hc_restitution(double alpha, RnError* err, int* ok)
{
    if (!(alpha >= 0.0 && isfinite(alpha))) {
        RnText* t = rn_error_value(err);
        rn_puts(t, "alpha = d v = ");
        rn_put_repr(t, alpha);
        rn_puts(t, " must be finite and >= 0");
        *ok = 0;
        return 0.0;
    }
    if (alpha == 0.0) return 1.0;
    double hi = py_min(1.0, 1.0 / alpha) * (1.0 - 1e-15);
    if (hc_balance(alpha, hi) >= 0.0) return hi;
    double root;
    if (!brent(hc_balance_fn, &alpha, 0.0, hi, NULL, NULL, RN_RESTITUTION_XTOL, RN_BRENT_RTOL,
               &root, err)) {
        *ok = 0;
        return 0.0;
    }
    return root;
}

typedef struct {
    double e;
    RnError* err;
    int ok;
} HcCtx;

static double hc_factor_fn(void* vctx, double a)
{
    HcCtx* c = vctx;
    int ok = 1;
    double r = hc_restitution(a, c->err, &ok);
    if (!ok) c->ok = 0;
    return r - c->e;
}

/* hunt_crossley_factor(e, v) */
static int hunt_crossley_factor(double e, double v, double* out, RnError* err)
{
    if (!(0.0 < e && e <= 1.0) || !(v > 0.0)) {
        RnText* t = rn_error_value(err);
        rn_puts(t, "restitution e = ");
        rn_put_repr(t, e);
        rn_puts(t, " must be in (0, 1] and speed v = ");
        rn_put_repr(t, v);
        rn_puts(t, " > 0");
        return 0;
    }
    if (e == 1.0) {
        *out = 0.0;
        return 1;
    }
    double hi = 1.0;
    int ok = 1;
    while (hc_restitution(hi, err, &ok) > e) {
        if (!ok) return 0;
        hi *= 2.0;
    }
    if (!ok) return 0;
    HcCtx ctx = {e, err, 1};
    double alpha;
    if (!brent(hc_factor_fn, &ctx, 0.0, hi, NULL, NULL, RN_HERTZ_ROOT_XTOL, RN_BRENT_RTOL,
               &alpha, err)
        || !ctx.ok)
        return 0;
    *out = alpha / v;
    return 1;
}

/* ------------------------------------------------------------------ the model array */
typedef struct {
    double model[M_COUNT]; /* kernel_layout.pack_model of the parameters */
    double state[S_COUNT];
    double last[R_COUNT]; /* the last step's aggregates and, in R_PINION_*, the pinion */
    Boundary boundary;
} MeshModel;

/* MeshModel(params) and the model array of kernel_layout.pack_model. */
static int pack_model(const RnValue* values, double* M, RnError* err)
{
    Geometry g;
    if (!geometry(values, &g, err)) return 0;
    double nu1 = R(RN_VR_MATERIAL_NU_PINION), nu2 = R(RN_VR_MATERIAL_NU_WHEEL);
    double E1 = R(RN_VR_MATERIAL_E_PINION), E2 = R(RN_VR_MATERIAL_E_WHEEL);
    double E_star = 1.0 / ((1.0 - nu1 * nu1) / E1 + (1.0 - nu2 * nu2) / E2);
    double x_lo, x_hi;
    radius_ratio_range(&g, &x_lo, &x_hi);
    ContactLaw law;
    if (!contact_law((int)I(RN_VR_CONTACT_HERTZ_LAW), E_star, g.r_y, x_lo, x_hi, &law, err))
        return 0;
    double damping = 0.0; /* mesh.damping_factor */
    long long dissipation = I(RN_VR_CONTACT_DISSIPATION);
    if (dissipation == RN_DISSIPATION_RESTITUTION) {
        if (!hunt_crossley_factor(R(RN_VR_CONTACT_RESTITUTION), R(RN_VR_CONTACT_RESTITUTION_SPEED),
                                  &damping, err))
            return 0;
    }
    else if (dissipation == RN_DISSIPATION_FACTOR)
        damping = R(RN_VR_CONTACT_DAMPING);
    double arm_wheel = g.normal_factor * g.rb_wheel;
    double arm_pinion = g.normal_factor * g.rb_pinion;
    double normal_mass = R(RN_VR_WHEEL_J) / py_pow(arm_wheel, 2.0);

    for (int k = 0; k < M_COUNT; k++) M[k] = 0.0;
    M[M_MAGIC] = RK_MAGIC;
    M[M_LAYOUT_HASH] = (double)RK_LAYOUT_HASH;
    M[M_SIZE] = (double)M_COUNT;
    M[M_RB_PINION] = g.rb_pinion;
    M[M_FLANK_PHASE] = g.flank_phase;
    M[M_BASE_PITCH] = g.base_pitch;
    M[M_LINE_SPAN] = g.line_span;
    M[M_S_START] = g.s_start;
    M[M_S_END] = g.s_end;
    M[M_LINE_LENGTH] = g.line_length;
    M[M_NORMAL_FACTOR] = g.normal_factor;
    M[M_HALF_BACKLASH] = g.half_backlash;
    M[M_CROWN_FACTOR] = g.crown_factor;
    M[M_N_BREAKPOINTS] = (double)g.n_bp;
    for (int k = 0; k < g.n_bp; k++) M[M_BREAKPOINTS + k] = g.bp[k];
    M[M_COS_ALPHA_T] = g.cos_alpha_t;
    M[M_SIN_ALPHA_T] = g.sin_alpha_t;
    M[M_SIN_BETA_B] = g.sin_beta_b;
    M[M_E_STAR] = E_star;
    M[M_ARM_WHEEL] = arm_wheel;
    M[M_ARM_PINION] = arm_pinion;
    M[M_NORMAL_MASS] = normal_mass;
    M[M_DAMPING] = damping;
    M[M_LAW] = (double)law.law;
    M[M_LAW_E_STAR] = law.E_star;
    M[M_R_Y] = law.r_y;
    M[M_T_MID] = law.t_mid;
    M[M_T_SCALE] = law.t_scale;
    M[M_CHEBYSHEV_TERMS] = (double)law.terms;
    for (int k = 0; k < law.terms; k++) {
        M[M_KAPPA + k] = law.kappa[k];
        M[M_ALPHA + k] = law.alpha[k];
        M[M_ZETA + k] = law.zeta[k];
    }
    M[M_J_WHEEL] = R(RN_VR_WHEEL_J);
    M[M_FRICTION_ENABLED] = B(RN_VR_FRICTION_ENABLED) ? 1.0 : 0.0;
    M[M_FRICTION_FORM] = (double)I(RN_VR_FRICTION_FORM);
    M[M_SHEAR_SPEED] = (double)I(RN_VR_FRICTION_SHEAR_SPEED);
    M[M_TAU_S] = R(RN_VR_FRICTION_TAU_S);
    M[M_ETA] = R(RN_VR_LUBRICANT_ETA);
    M[M_SIGMA] = R(RN_VR_SURFACE_SIGMA);
    M[M_GAMMA] = R(RN_VR_SURFACE_GAMMA);
    M[M_DENSITY] = R(RN_VR_MATERIAL_RHO);
    M[M_H_MAX] = R(RN_VR_SOLVER_H_MAX);
    M[M_H_COMM_MAX] = R(RN_VR_SOLVER_H_COMM_MAX);
    M[M_RATTLE_TIME] = R(RN_VR_RATTLE_TIME_CONSTANT);
    M[M_PENETRATION_LIMIT] = RN_MAX_PENETRATION_MODULES * R(RN_VR_GEAR_M_N);
    M[M_BREAKPOINT_TOLERANCE] = RN_BREAKPOINT_TOLERANCE;
    M[M_GRAZING_SAMPLES] = (double)RN_GRAZING_SAMPLES;
    M[M_BRENT_MAX_ITERATIONS] = (double)RN_ROOTS_MAX_ITERATIONS;
    M[M_BRENT_RTOL] = RN_EVENT_RTOL;
    M[M_EVENT_XTOL] = RN_EVENT_XTOL;
    M[M_ENGAGEMENT_MIN_FRACTION] = RN_ENGAGEMENT_MIN_FRACTION;
    M[M_LAMBDA_BOUNDARY] = RN_LAMBDA_BOUNDARY;
    M[M_LAMBDA_FULL_FILM] = RN_LAMBDA_FULL_FILM;
    M[M_CONTACT_RATE_SAFETY] = RN_CONTACT_RATE_SAFETY;
    M[M_MAX_CONTACT_SUBSTEPS] = (double)RN_MAX_CONTACT_SUBSTEPS;
    M[M_GRID_SLACK] = RN_GRID_SLACK;
    return 1;
}

/* The model array of the last parameter set, kept: the contact law's fit is the costly part
 * of a build, and initialization mode rebuilds on every read after a set. */
typedef struct {
    int valid;
    RnValue params[RN_N_PARAMETERS];
    double model[M_COUNT];
} ModelCache;

static int same_parameters(const RnValue* a, const RnValue* b)
{
    for (int k = 0; k < RN_N_PARAMETERS; k++) {
        int fmi_type = RN_VARIABLES[k].fmi_type;
        if (fmi_type == RN_REAL) {
            if (memcmp(&a[k].r, &b[k].r, sizeof(double)) != 0) return 0;
        }
        else if (fmi_type == RN_STRING) {
            if (strcmp(a[k].s ? a[k].s : "", b[k].s ? b[k].s : "") != 0) return 0;
        }
        else if (a[k].i != b[k].i)
            return 0;
    }
    return 1;
}

static int cached_pack_model(RnInstance* inst, const RnValue* values, double* M, RnError* err)
{
    ModelCache* c = inst->unit_cache;
    if (c != NULL && c->valid && same_parameters(c->params, values)) {
        memcpy(M, c->model, sizeof c->model);
        return 1;
    }
    if (!pack_model(values, M, err)) return 0;
    if (c == NULL) c = inst->unit_cache = calloc(1, sizeof *c);
    if (c != NULL) {
        for (int k = 0; k < RN_N_PARAMETERS; k++) c->params[k] = values[k];
        for (int k = 0; k < RN_N_PARAMETERS; k++) c->params[k].s = NULL; /* no strings here */
        memcpy(c->model, M, sizeof c->model);
        c->valid = 1;
    }
    return 1;
}

void rn_unit_free_cache(RnInstance* inst)
{
    free(inst->unit_cache);
    inst->unit_cache = NULL;
}

/* ------------------------------------------------------------------ stepper.py */
static double penetration(const double* M, double flank, double phi_p, double phi_w)
{
    return flank * (M[M_ARM_PINION] * phi_p - M[M_ARM_WHEEL] * phi_w) - M[M_HALF_BACKLASH];
}

static double approach_rate(const double* M, double flank, double w_p, double w_w)
{
    return flank * (M[M_ARM_PINION] * w_p - M[M_ARM_WHEEL] * w_w);
}

/* WheelStepper._wheel_angle */
static double wheel_angle(const double* M, double flank, double phi_p, double delta)
{
    double x = flank * (M[M_HALF_BACKLASH] + delta);
    return (M[M_ARM_PINION] * phi_p - x) / M[M_ARM_WHEEL];
}

/* A failed kernel call as the Python core raises it: kernel.refusal, transcribed (the codes
 * and their numbers are kernel_layout.ERROR_CODES; the texts are those of the Python functions
 * named).  The "input" code is the caller's: it knows the step's inputs. */
static void kernel_refusal(int code, const double* v, RnError* err)
{
    RnText* t;
    switch (code) {
    case RK_ERR_DIVERGED: /* stepper.diverged_error */
        t = rn_error_value(err);
        rn_puts(t, "the step diverged (wheel angle ");
        rn_put_repr(t, v[0]);
        rn_puts(t, " rad, speed ");
        rn_put_repr(t, v[1]);
        rn_puts(t, " rad/s); the inputs or parameters are beyond what the integrator resolves "
                   "(reduce solver.h_max or the communication step)");
        return;
    case RK_ERR_PENETRATION: /* stepper.penetration_error */
        t = rn_error_value(err);
        rn_puts(t, "the flanks would penetrate ");
        rn_put_g(t, v[0] * 1e3, 4);
        rn_puts(t, " mm in this step, beyond the validity of the Hertz contact (allowed: ");
        rn_put_g(t, v[1] * 1e3, 4);
        rn_puts(t, " mm = ");
        rn_put_repr(t, RN_MAX_PENETRATION_MODULES);
        rn_puts(t, " gear.m_n); the inputs drive the teeth into each other far harder than any "
                   "transmission (check wheel.tau_load and the pinion kinematics, or reduce the "
                   "communication step)");
        return;
    case RK_ERR_TOO_STIFF: /* stepper.stiffness_error */
        t = rn_error_value(err);
        rn_puts(t, "the contact is too stiff to resolve: its fastest time scale ");
        rn_put_g(t, 1.0 / v[0], 3);
        rn_puts(t, " s (stiffness ");
        rn_put_g(t, v[1], 4);
        rn_puts(t, " N/m, damping ");
        rn_put_g(t, v[2], 4);
        rn_puts(t, " N.s/m on the wheel's normal mass ");
        rn_put_g(t, v[3], 4);
        rn_printf(t, " kg) needs more than %d substeps in this step; reduce the communication "
                     "step, the impact speed (inputs) or contact.damping, or raise wheel.J",
                  RN_MAX_CONTACT_SUBSTEPS);
        return;
    case RK_ERR_NO_BRACKET: /* roots.bracket_error */
        t = rn_error_value(err);
        rn_puts(t, "brent: f(");
        rn_put_repr(t, v[0]);
        rn_puts(t, ") = ");
        rn_put_repr(t, v[1]);
        rn_puts(t, " and f(");
        rn_put_repr(t, v[2]);
        rn_puts(t, ") = ");
        rn_put_repr(t, v[3]);
        rn_puts(t, " do not bracket a root");
        return;
    case RK_ERR_FRICTION_FORM: /* lubrication.unknown_form_error */
        rn_printf(rn_error_value(err), "friction form %lld unknown; allowed: %d, %d, %d",
                  (long long)v[0], RK_FORM_LOAD_SHARING, RK_FORM_APPARENT_AREA,
                  RK_FORM_AS_PRINTED);
        return;
    case RK_ERR_LIBRARY: /* the exception of the library call, as CPython words it */
        switch ((int)v[0]) {
        case RK_CALL_POW:
            if (v[1] < 0.0) { /* Python gives a complex number: never reached (bases > 0) */
                t = rn_error_value(err);
                rn_puts(t, "rattle kernel: pow(");
                rn_put_repr(t, v[1]);
                rn_puts(t, ", ");
                rn_put_repr(t, v[2]);
                rn_puts(t, ") is a complex number, not a real number the kernel can go on with");
            }
            else
                rn_puts(rn_error_other(err, "OverflowError"),
                        "(34, 'Numerical result out of range')");
            return;
        case RK_CALL_SQRT:
        case RK_CALL_LOG:
            rn_puts(rn_error_value(err), "math domain error");
            return;
        case RK_CALL_EXP:
            rn_puts(rn_error_other(err, "OverflowError"), "math range error");
            return;
        case RK_CALL_FLOOR:
        case RK_CALL_CEIL:
        case RK_CALL_INT:
            if (isnan(v[1]))
                rn_puts(rn_error_value(err), "cannot convert float NaN to integer");
            else
                rn_puts(rn_error_other(err, "OverflowError"),
                        "cannot convert float infinity to integer");
            return;
        case RK_CALL_NONE_GT:
            rn_puts(rn_error_other(err, "TypeError"),
                    "'>' not supported between instances of 'NoneType' and 'float'");
            return;
        default:
            break;
        }
        break;
    case RK_ERR_TOO_MANY_PAIRS:
        rn_printf(rn_error_value(err), "more than %d tooth pairs in the zone of action",
                  (int)v[0]);
        return;
    case RK_ERR_PAIR_NUMBER_RANGE:
        t = rn_error_value(err);
        rn_puts(t, "roll coordinate ");
        rn_put_repr(t, v[0]);
        rn_puts(t, " m beyond the kernel's range (pair number ");
        rn_put_repr(t, v[1]);
        rn_puts(t, "; |pinion angle| too large)");
        return;
    case RK_ERR_NO_PROGRESS:
        t = rn_error_value(err);
        rn_puts(t, "the step makes no progress at t = ");
        rn_put_repr(t, v[0]);
        rn_puts(t, " s (the integrator is stuck; reduce solver.h_max or the communication "
                   "step)");
        return;
    case RK_ERR_SUBSTEP_COUNT:
        t = rn_error_value(err);
        rn_puts(t, "step size h = ");
        rn_put_repr(t, v[0]);
        rn_puts(t, " s needs ");
        rn_put_repr(t, v[1]);
        rn_puts(t, " substeps");
        return;
    case RK_ERR_LAYOUT:
        rn_printf(rn_error_other(err, "RuntimeError"),
                  "rattle kernel: model array layout mismatch (kernel layout %llu with %d "
                  "fields; rebuild the FMU from the sources of this version)",
                  (unsigned long long)RK_LAYOUT_HASH, (int)M_COUNT);
        return;
    case RK_ERR_MODEL_VALUES:
        rn_printf(rn_error_other(err, "RuntimeError"),
                  "rattle kernel: %d breakpoints, %d Chebyshev terms, law %d: beyond the "
                  "kernel's arrays", (int)v[0], (int)v[1], (int)v[2]);
        return;
    default:
        break;
    }
    t = rn_error_other(err, "RuntimeError");
    rn_printf(t, "rattle kernel: return code %d with ", code);
    put_tuple(t, v, RK_ERROR_VALUES);
}

typedef struct {
    const double* M;
    double flank, phi_p, w_p, w_w, tau_load;
    int code;
    double err_values[RK_ERROR_VALUES];
} Residual;

/* residual(delta) of equilibrium_state: the mesh torque on the wheel minus the load */
static double equilibrium_residual(void* vctx, double delta)
{
    Residual* r = vctx;
    double out[3];
    if (r->code != RK_ERR_OK) return NAN;
    double phi_w = wheel_angle(r->M, r->flank, r->phi_p, delta);
    int code = rk_mesh_torques(r->M, r->flank, r->phi_p, r->w_p, phi_w, r->w_w, 0.0, out,
                               r->err_values);
    if (code != RK_ERR_OK) {
        r->code = code;
        return NAN;
    }
    return out[0] - r->tau_load;
}

/* WheelStepper.equilibrium_state: the wheel at the rigid speed ratio, resting on the flank
 * that carries tau_load with the penetration at which the mesh torque balances it. */
static int equilibrium_state(const RnValue* values, const double* M, double phi_p, double w_p,
                             double tau_load, double* state, RnError* err)
{
    double ratio = (double)I(RN_VR_GEAR_Z_PINION) / (double)I(RN_VR_GEAR_Z_WHEEL);
    double w_w = w_p * ratio;
    for (int k = 0; k < S_COUNT; k++) state[k] = 0.0;
    if (tau_load == 0.0) {
        state[S_PHI] = wheel_angle(M, RK_DRIVE, phi_p, 0.0);
        state[S_W] = w_w;
        state[S_FLANK] = 0.0;
        return 1;
    }
    double flank = tau_load > 0.0 ? RK_DRIVE : RK_COAST;
    Residual r = {M, flank, phi_p, w_p, w_w, tau_load, RK_ERR_OK, {0.0}};
    double hi = 1e-9;
    double r_hi = equilibrium_residual(&r, hi);
    while ((r_hi > 0.0) != (flank == RK_DRIVE) || r_hi == 0.0) {
        if (r.code != RK_ERR_OK) break;
        hi *= 2.0;
        if (hi > 1e-2) {
            RnText* t = rn_error_value(err);
            rn_puts(t, "no static flank equilibrium for wheel.tau_load = ");
            rn_put_repr(t, tau_load);
            rn_puts(t, " N.m: the mesh torque does not reach it within 10 mm penetration "
                       "(friction dominates the normal force?); set init.in_contact = false");
            return 0;
        }
        r_hi = equilibrium_residual(&r, hi);
    }
    double delta = 0.0;
    if (r.code == RK_ERR_OK) {
        double r_0 = equilibrium_residual(&r, 0.0);
        if ((r_0 >= 0.0) == (flank == RK_DRIVE))
            delta = 0.0;
        else if (!brent(equilibrium_residual, &r, 0.0, hi, &r_0, &r_hi, RN_EQUILIBRIUM_XTOL,
                        RN_BRENT_RTOL,
                        &delta, err)) {
            if (r.code == RK_ERR_OK) return 0;
        }
    }
    if (r.code != RK_ERR_OK) {
        kernel_refusal(r.code, r.err_values, err);
        return 0;
    }
    state[S_PHI] = wheel_angle(M, flank, phi_p, delta);
    state[S_W] = w_w;
    state[S_FLANK] = flank;
    return 1;
}

/* WheelStepper.contact_flank for a state with flank 0 */
static double contact_flank(const double* M, double phi_p, double w_p, double a_p,
                            double tau_load, const double* st)
{
    double accel_w = -tau_load / M[M_J_WHEEL];
    double order[3] = {st[S_FLANK], RK_DRIVE, RK_COAST};
    for (int i = 0; i < 3; i++) {
        double flank = order[i];
        if (flank == 0.0) continue;
        double pen = penetration(M, flank, phi_p, st[S_PHI]);
        if (pen > 0.0) return flank;
        if (pen == 0.0) {
            double rate = approach_rate(M, flank, w_p, st[S_W]);
            if (rate > 0.0) return flank;
            if (rate == 0.0 && approach_rate(M, flank, a_p, accel_w) > 0.0) return flank;
        }
    }
    return 0.0;
}

void* rn_unit_build(RnInstance* inst, const RnValue* values, RnError* err)
{
    MeshModel* m = calloc(1, sizeof *m);
    if (m == NULL) {
        rn_puts(rn_error_other(err, "MemoryError"), "");
        return NULL;
    }
    double phi_p = R(RN_VR_PINION_PHI), w_p = R(RN_VR_PINION_W), tau_load = R(RN_VR_WHEEL_TAU_LOAD);
    if (!cached_pack_model(inst, values, m->model, err)) goto fail;
    if (B(RN_VR_INIT_IN_CONTACT)) {
        if (!equilibrium_state(values, m->model, phi_p, w_p, tau_load, m->state, err)) goto fail;
    }
    else {
        double phi_start = R(RN_VR_WHEEL_PHI_START);
        m->state[S_PHI] = phi_start;
        m->state[S_W] = R(RN_VR_WHEEL_W_START);
        m->state[S_FLANK] = contact_flank(m->model, phi_p, w_p, 0.0, tau_load, m->state);
        double depth = py_max(penetration(m->model, RK_DRIVE, phi_p, phi_start),
                              penetration(m->model, RK_COAST, phi_p, phi_start));
        if (depth > RN_MAX_INITIAL_PENETRATION) {
            double ratio = (double)I(RN_VR_GEAR_Z_PINION) / (double)I(RN_VR_GEAR_Z_WHEEL);
            double half = m->model[M_HALF_BACKLASH] / m->model[M_ARM_WHEEL];
            RnText* t = rn_error_value(err);
            rn_puts(t, "parameter 'wheel.phi_start' = ");
            rn_put_repr(t, phi_start);
            rn_puts(t, " rad puts the flanks ");
            rn_put_g(t, depth * 1e3, 4);
            rn_puts(t, " mm into each other at pinion.phi = ");
            rn_put_repr(t, phi_p);
            rn_puts(t, " rad; allowed: within the backlash, |wheel.phi_start - ");
            rn_put_g(t, ratio, 6);
            rn_puts(t, " pinion.phi| <= ");
            rn_put_g(t, half, 4);
            rn_puts(t, " rad (plus ");
            rn_put_g(t, RN_MAX_INITIAL_PENETRATION * 1e6, 6);
            rn_puts(t, " um), or init.in_contact = true");
            goto fail;
        }
    }
    m->last[R_PINION_PHI] = phi_p;
    m->last[R_PINION_W] = w_p;
    /* _InputReading._started */
    for (int k = 0; k < 3; k++) m->boundary.initial_inputs[k] = values[START_VRS[k]].r;
    m->boundary.first_step = 1;
    m->boundary.has_last_motion = 0;
    return m;
fail:
    free(m);
    return NULL;
}

void rn_unit_free(void* model) { free(model); }

/* CompiledWheelStepper.step: the kernel, and its refusals as Python raises them. */
static int kernel_step(MeshModel* m, double h, double phi_p, double w_p, double a_p,
                       double tau_load, RnError* err)
{
    double inputs[I_COUNT], result[R_COUNT], err_values[RK_ERROR_VALUES], state[S_COUNT];
    inputs[I_H] = h;
    inputs[I_PHI_P] = phi_p;
    inputs[I_W_P] = w_p;
    inputs[I_A_P] = a_p;
    inputs[I_TAU_LOAD] = tau_load;
    memcpy(state, m->state, sizeof state);
    int code = rk_step(m->model, state, inputs, result, err_values);
    if (code == RK_ERR_OK) {
        memcpy(m->state, state, sizeof state);
        memcpy(m->last, result, sizeof result);
        return 1;
    }
    if (code == RK_ERR_INPUT) {
        /* _check_finite (the unit checked its inputs), then check_step_size */
        RnText* t = rn_error_value(err);
        double h_max = m->model[M_H_COMM_MAX];
        if (!(h > 0.0 && isfinite(h))) {
            rn_puts(t, "step size h = ");
            rn_put_repr(t, h);
            rn_puts(t, " s is invalid; allowed: finite and > 0");
        }
        else {
            rn_puts(t, "step size h = ");
            rn_put_repr(t, h);
            rn_puts(t, " s exceeds solver.h_comm_max = ");
            rn_put_repr(t, h_max);
            rn_puts(t, " s; allowed: (0, ");
            rn_put_repr(t, h_max);
            rn_puts(t, "] s");
        }
        return 0;
    }
    kernel_refusal(code, err_values, err);
    return 0;
}

/* MeshInputReading._step */
int rn_unit_step(RnInstance* inst, double t, double h, RnError* err)
{
    MeshModel* m = inst->model;
    const RnValue* values = inst->values;
    double phi_p = R(RN_VR_PINION_PHI), w_p = R(RN_VR_PINION_W), a_p = R(RN_VR_PINION_A);
    double tau_load = R(RN_VR_WHEEL_TAU_LOAD);
    (void)t;
    if (B(RN_VR_INPUTS_CONTINUE_WHEN_HELD) && motion_held(inst, &m->boundary, MOTION_VRS, 3)) {
        phi_p = m->last[R_PINION_PHI];
        w_p = m->last[R_PINION_W];
        a_p = 0.0;
    }
    int settled = 0;
    double saved_state[S_COUNT], saved_pinion[2];
    double used[3] = {phi_p, w_p, tau_load};
    if (B(RN_VR_INIT_IN_CONTACT)
        && first_step_differs(&m->boundary, B(RN_VR_INIT_SETTLE_FIRST_STEP), used, 3)) {
        double settled_state[S_COUNT];
        if (!equilibrium_state(values, m->model, phi_p, w_p, tau_load, settled_state, err))
            return 0;
        memcpy(saved_state, m->state, sizeof saved_state);
        saved_pinion[0] = m->last[R_PINION_PHI];
        saved_pinion[1] = m->last[R_PINION_W];
        memcpy(m->state, settled_state, sizeof settled_state);
        m->last[R_PINION_PHI] = phi_p;
        m->last[R_PINION_W] = w_p;
        settled = 1;
    }
    if (!kernel_step(m, h, phi_p, w_p, a_p, tau_load, err)) {
        if (settled) { /* a rejected step leaves the unit as it was */
            memcpy(m->state, saved_state, sizeof saved_state);
            m->last[R_PINION_PHI] = saved_pinion[0];
            m->last[R_PINION_W] = saved_pinion[1];
        }
        double advised = RN_DEFAULT_STEP_SIZE;
        if (err->type == NULL && h > advised
            && strstr(rn_text_str(&err->text), "h_comm_max") == NULL) {
            RnText* txt = &err->text;
            rn_puts(txt, ". The communication step ");
            rn_put_repr(txt, h);
            rn_puts(txt, " s is ");
            rn_put_g(txt, h / advised, 3);
            rn_puts(txt, " times the default experiment's: use ");
            rn_put_repr(txt, advised);
            rn_puts(txt, " s (docs/tools.md: accuracy against the step)");
        }
        return 0;
    }
    m->boundary.first_step = 0;
    motion_step_done(inst, &m->boundary, MOTION_VRS, 3);
    if (settled) {
        static const char* const units[3] = {"rad", "rad/s", "N.m"};
        settled_warning(inst, START_NAMES, units, used, m->boundary.initial_inputs, 3,
                        "the wheel was settled in the flank equilibrium for them first");
    }
    return 1;
}

int rn_unit_outputs(void* model, unsigned groups, RnValue* out, RnError* err)
{
    MeshModel* m = model;
    const double* st = m->state;
    if (groups & RN_GROUP_LOADS) {
        double o[O_COUNT], err_values[RK_ERROR_VALUES];
        int code = rk_outputs(m->model, m->state, m->last, o, err_values);
        if (code != RK_ERR_OK) {
            kernel_refusal(code, err_values, err);
            return 0;
        }
        for (int k = 0; k < O_COUNT; k++) {
            unsigned vr = RN_OUTPUT_VR[k];
            if (RN_VARIABLES[vr].fmi_type == RN_INTEGER)
                out[vr].i = (int64_t)o[k];
            else
                out[vr].r = o[k];
        }
        return 1;
    }
    /* interface.mesh_outputs, the entries that need no mesh loads */
    if (groups & RN_GROUP_QUICK) {
        out[RN_VR_WHEEL_PHI].r = st[S_PHI];
        out[RN_VR_WHEEL_W].r = st[S_W];
    }
    if (groups & RN_GROUP_STATE) {
        const double* M = m->model;
        double v = st[S_V_IMPACT_LAST];
        out[RN_VR_WHEEL_TAU_MESH].r = m->last[R_TAU_WHEEL_MEAN];
        out[RN_VR_PINION_TAU_MESH].r = m->last[R_TAU_PINION_MEAN];
        out[RN_VR_MESH_W_PEAK].r = m->last[R_W_PEAK];
        out[RN_VR_MESH_DELTA_PEAK].r = m->last[R_DELTA_PEAK];
        out[RN_VR_MESH_V_IMPACT].r = v;
        out[RN_VR_MESH_IMPACTS_DRIVE].i = (int64_t)st[S_IMPACTS_DRIVE];
        out[RN_VR_MESH_IMPACTS_COAST].i = (int64_t)st[S_IMPACTS_COAST];
        out[RN_VR_MESH_TRANSMISSION_ERROR].r =
            penetration(M, RK_DRIVE, m->last[R_PINION_PHI], st[S_PHI]) + M[M_HALF_BACKLASH];
        out[RN_VR_MESH_IMPACT_ENERGY].r = 0.5 * M[M_NORMAL_MASS] * v * v;
        out[RN_VR_MESH_RATTLE_INDEX].r = st[S_RATTLE_INDEX];
    }
    return 1;
}

/* GearMeshRattle._model_state, as json.dumps(sort_keys=True) writes it */
void rn_unit_snapshot(const void* model, RnText* j)
{
    const MeshModel* m = model;
    const double* st = m->state;
    rn_puts(j, "{\"fmi\": {");
    boundary_snapshot(&m->boundary, 3, 3, j);
    rn_puts(j, "}, \"last\": [");
    rn_json_put_float(j, m->last[R_TAU_WHEEL_MEAN]);
    rn_puts(j, ", ");
    rn_json_put_float(j, m->last[R_TAU_PINION_MEAN]);
    rn_puts(j, ", ");
    rn_json_put_float(j, m->last[R_W_PEAK]);
    rn_puts(j, ", ");
    rn_json_put_float(j, m->last[R_DELTA_PEAK]);
    rn_printf(j, ", %lld, %lld], \"pinion\": [", (long long)m->last[R_ONSETS_DRIVE],
              (long long)m->last[R_ONSETS_COAST]);
    rn_json_put_float(j, m->last[R_PINION_PHI]);
    rn_puts(j, ", ");
    rn_json_put_float(j, m->last[R_PINION_W]);
    rn_puts(j, "], \"wheel\": [");
    rn_json_put_float(j, st[S_PHI]);
    rn_puts(j, ", ");
    rn_json_put_float(j, st[S_W]);
    rn_printf(j, ", %lld, ", (long long)st[S_FLANK]);
    rn_json_put_float(j, st[S_V_IMPACT_DRIVE]);
    rn_puts(j, ", ");
    rn_json_put_float(j, st[S_V_IMPACT_COAST]);
    rn_puts(j, ", ");
    rn_json_put_float(j, st[S_V_IMPACT_LAST]);
    rn_printf(j, ", %lld, %lld, ", (long long)st[S_IMPACTS_DRIVE], (long long)st[S_IMPACTS_COAST]);
    rn_json_put_float(j, st[S_RATTLE_INDEX]);
    rn_puts(j, "]}");
}

/* GearMeshRattle._model_from_snapshot */
void* rn_unit_restore(RnInstance* inst, const RnValue* values, double start_time,
                      const RnJson* snapshot, RnError* err)
{
    static const FieldLayout LAYOUT[4] = {
        {"wheel", {"f", "f", "flank", "f", "f", "f", "n", "n", "f+"}, 9},
        {"pinion", {"f", "f"}, 2},
        {"last", {"f", "f", "f+", "f+", "n", "n"}, 6},
        {"fmi", {"any"}, 0},
    };
    (void)start_time;
    if (!check_snapshot_fields(snapshot, LAYOUT, 4, "['fmi', 'last', 'pinion', 'wheel']", err))
        return NULL;
    MeshModel* m = calloc(1, sizeof *m);
    if (m == NULL) {
        rn_puts(rn_error_other(err, "MemoryError"), "");
        return NULL;
    }
    const RnJson* wheel = rn_json_get(snapshot, "wheel");
    const RnJson* pinion = rn_json_get(snapshot, "pinion");
    const RnJson* last = rn_json_get(snapshot, "last");
    static const int STATE_INDEX[9] = {S_PHI, S_W, S_FLANK, S_V_IMPACT_DRIVE, S_V_IMPACT_COAST,
                                       S_V_IMPACT_LAST, S_IMPACTS_DRIVE, S_IMPACTS_COAST,
                                       S_RATTLE_INDEX};
    for (int k = 0; k < 9; k++) {
        const RnJson* v = &wheel->items[k];
        m->state[STATE_INDEX[k]] = v->kind == RJ_INT ? (double)v->i : v->f;
    }
    m->last[R_PINION_PHI] = pinion->items[0].f;
    m->last[R_PINION_W] = pinion->items[1].f;
    m->last[R_TAU_WHEEL_MEAN] = last->items[0].f;
    m->last[R_TAU_PINION_MEAN] = last->items[1].f;
    m->last[R_W_PEAK] = last->items[2].f;
    m->last[R_DELTA_PEAK] = last->items[3].f;
    m->last[R_ONSETS_DRIVE] = (double)last->items[4].i;
    m->last[R_ONSETS_COAST] = (double)last->items[5].i;
    if (!cached_pack_model(inst, values, m->model, err)
        || !boundary_restore(&m->boundary, rn_json_get(snapshot, "fmi"), 3, 3, 0, NULL, err)) {
        free(m);
        return NULL;
    }
    return m;
}

/* Exported for the tests (tests/native): the model array the unit builds for the parameter
 * values of `values_in` (one double per parameter in value-reference order, Integer and
 * Boolean as numbers), as kernel_layout.pack_model gives it in Python.  Returns M_COUNT, or
 * 0 with the message in err. */
FMI2_Export int rattle_native_pack_model(const double* values_in, double* out, char* err,
                                         int errlen)
{
    RnValue values[RN_N_VARIABLES];
    RnError e;
    memset(values, 0, sizeof values);
    for (int k = 0; k < RN_N_PARAMETERS; k++) {
        values[k].r = values_in[k];
        values[k].i = (int64_t)values_in[k];
    }
    rn_error_init(&e);
    int ok = pack_model(values, out, &e);
    if (!ok && err != NULL && errlen > 0) snprintf(err, (size_t)errlen, "%s", rn_text_str(&e.text));
    rn_error_free(&e);
    return ok ? M_COUNT : 0;
}

#elif defined(RN_UNIT_DRIVELINE)
/* ================================================================== Driveline */
static const unsigned MOTION_VRS[2] = {RN_VR_WHEEL_PHI, RN_VR_WHEEL_W};
static const char* const START_NAMES[2] = {"wheel.phi", "wheel.w"};

int rn_unit_is_motion_input(unsigned vr) { return vr == RN_VR_WHEEL_PHI || vr == RN_VR_WHEEL_W; }

typedef struct {
    double k, c, J, drag, drag_viscous, h_max, h_comm_max;
} ShaftParams;

typedef struct {
    ShaftParams p;
    /* kinematics: engine orders or the speed table */
    double w_mean, phi_0, t_start;
    int n_terms;
    double A[RN_N_ORDERS], W[RN_N_ORDERS], ph[RN_N_ORDERS];
    int a_over_step;
    size_t n_table; /* 0: engine orders */
    double *times, *speeds, *angles;
    /* output shaft */
    double shaft_phi, shaft_w, tau_load;
    double time, last_step;
    Boundary boundary;
    double wheel_end[2];
} DrivelineModel;

/* The speed table read at the last build, by parameter value (Driveline._speed_table). */
typedef struct {
    char* name;
    size_t n;
    double *times, *speeds;
} TableCache;

void rn_unit_free_cache(RnInstance* inst)
{
    TableCache* c = inst->unit_cache;
    if (c != NULL) {
        free(c->name);
        free(c->times);
        free(c->speeds);
        free(c);
    }
    inst->unit_cache = NULL;
}

int rn_unit_check_combination(const RnValue* values, RnError* err)
{
    (void)values;
    (void)err;
    return 1;
}

static ShaftParams shaft_params(const RnValue* values)
{
    ShaftParams p;
    p.k = R(RN_VR_SHAFT_K);
    p.c = R(RN_VR_SHAFT_C);
    p.J = R(RN_VR_VEHICLE_J);
    p.drag = R(RN_VR_VEHICLE_DRAG);
    p.drag_viscous = R(RN_VR_VEHICLE_DRAG_VISCOUS);
    p.h_max = R(RN_VR_SOLVER_H_MAX);
    p.h_comm_max = R(RN_VR_SOLVER_H_COMM_MAX);
    return p;
}

/* EngineOrderKinematics / SpeedTableKinematics: (phi, w, a) at t */
static void kinematics(const DrivelineModel* d, double t, double* out)
{
    if (d->n_table == 0) {
        double tau = t - d->t_start;
        double phi = d->phi_0 + d->w_mean * tau;
        double w = d->w_mean, a = 0.0;
        for (int k = 0; k < d->n_terms; k++) {
            double A = d->A[k], W = d->W[k], ph = d->ph[k];
            double arg = W * tau + ph;
            phi -= A / (W * W) * (cos(arg) - cos(ph));
            w += A / W * sin(arg);
            a += A * cos(arg);
        }
        out[0] = phi;
        out[1] = w;
        out[2] = a;
        return;
    }
    const double *ts = d->times, *ws = d->speeds;
    size_t n = d->n_table;
    if (t <= ts[0]) {
        out[0] = d->phi_0 + ws[0] * (t - ts[0]);
        out[1] = ws[0];
        out[2] = 0.0;
        return;
    }
    if (t >= ts[n - 1]) {
        out[0] = d->angles[n - 1] + ws[n - 1] * (t - ts[n - 1]);
        out[1] = ws[n - 1];
        out[2] = 0.0;
        return;
    }
    /* bisect_right(ts, t) - 1 */
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (t < ts[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    size_t i = lo - 1;
    double dt = t - ts[i];
    double a = (ws[i + 1] - ws[i]) / (ts[i + 1] - ts[i]);
    out[0] = d->angles[i] + ws[i] * dt + 0.5 * a * dt * dt;
    out[1] = ws[i] + a * dt;
    out[2] = a;
}

/* OutputShaft.torque */
static double shaft_torque(const ShaftParams* p, double phi_w, double w_w, double phi_v,
                           double w_v)
{
    return p->k * (phi_w - phi_v) + p->c * (w_w - w_v);
}

/* OutputShaft.__init__: steady state behind the wheel */
static void shaft_start(DrivelineModel* d, double phi_w, double w_w)
{
    const ShaftParams* p = &d->p;
    double steady = p->drag + p->drag_viscous * w_w;
    d->shaft_phi = phi_w - steady / p->k;
    d->shaft_w = w_w;
    d->tau_load = shaft_torque(p, phi_w, w_w, d->shaft_phi, d->shaft_w);
}

static double shaft_acc(const ShaftParams* p, double phi_w, double w_w, double t, double phi_v,
                        double w_v)
{
    double tau = p->k * (phi_w + w_w * t - phi_v) + p->c * (w_w - w_v);
    return (tau - p->drag - p->drag_viscous * w_v) / p->J;
}

/* OutputShaft._rk4 */
static void shaft_rk4(const DrivelineModel* d, double h, double n, double phi_w, double w_w,
                      double* phi_out, double* w_out)
{
    const ShaftParams* p = &d->p;
    double dt = h / n;
    double phi = d->shaft_phi, w = d->shaft_w;
    for (double j = 0.0; j < n; j += 1.0) {
        double t = h * j / n;
        double a1 = shaft_acc(p, phi_w, w_w, t, phi, w);
        double a2 = shaft_acc(p, phi_w, w_w, t + 0.5 * dt, phi + 0.5 * dt * w, w + 0.5 * dt * a1);
        double a3 = shaft_acc(p, phi_w, w_w, t + 0.5 * dt, phi + 0.5 * dt * (w + 0.5 * dt * a1),
                              w + 0.5 * dt * a2);
        double a4 = shaft_acc(p, phi_w, w_w, t + dt, phi + dt * (w + 0.5 * dt * a2), w + dt * a3);
        phi += dt * (w + dt / 6.0 * (a1 + a2 + a3));
        w += dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    }
    *phi_out = phi;
    *w_out = w;
}

/* OutputShaft._exact */
static void shaft_exact(const DrivelineModel* d, double h, double phi_w, double w_w,
                        double* phi_out, double* w_out)
{
    const ShaftParams* p = &d->p;
    double g = (p->c + p->drag_viscous) / p->J;
    double dd = p->k / p->J;
    double offset = (p->drag + p->drag_viscous * w_w) / p->k;
    double e0 = d->shaft_phi - (phi_w - offset);
    double f0 = d->shaft_w - w_w;
    double s = -0.5 * g;
    double q2 = 0.25 * g * g - dd;
    double x2 = fabs(q2) * h * h;
    double m11, m12, m21, m22;
    if (x2 < 1e-6) {
        double es = exp(s * h);
        double ch = 1.0 + 0.5 * q2 * h * h * (1.0 + q2 * h * h / 12.0);
        double sh = h * (1.0 + q2 * h * h / 6.0 * (1.0 + q2 * h * h / 20.0));
        m11 = es * (ch - s * sh);
        m12 = es * sh;
        m21 = -dd * es * sh;
        m22 = es * (ch + (-g - s) * sh);
    }
    else if (q2 < 0.0) {
        double wd = sqrt(-q2);
        double es = exp(s * h);
        double c = es * cos(wd * h), sn = es * sin(wd * h) / wd;
        m11 = c - s * sn;
        m12 = sn;
        m21 = -dd * sn;
        m22 = c + (-g - s) * sn;
    }
    else {
        double l2 = s - sqrt(q2);
        double l1 = dd / l2;
        double e1 = exp(l1 * h), e2 = exp(l2 * h);
        double span = l1 - l2;
        m11 = (l1 * e2 - l2 * e1) / span;
        m12 = (e1 - e2) / span;
        m21 = -dd * (e1 - e2) / span;
        m22 = (l1 * e1 - l2 * e2) / span;
    }
    double e1h = m11 * e0 + m12 * f0;
    double f1h = m21 * e0 + m22 * f0;
    *phi_out = phi_w + w_w * h - offset + e1h;
    *w_out = w_w + f1h;
}

/* Driveline.step (check_step_size, then OutputShaft.step); 0 with the ValueError. */
static int driveline_step(DrivelineModel* d, double t, double h, double phi_w, double w_w,
                          RnError* err)
{
    const ShaftParams* p = &d->p;
    if (!(h > 0.0 && isfinite(h))) {
        RnText* e = rn_error_value(err);
        rn_puts(e, "step size h = ");
        rn_put_repr(e, h);
        rn_puts(e, " s is invalid; allowed: finite and > 0");
        return 0;
    }
    if (h > p->h_comm_max) {
        RnText* e = rn_error_value(err);
        rn_puts(e, "step size h = ");
        rn_put_repr(e, h);
        rn_puts(e, " s exceeds solver.h_comm_max = ");
        rn_put_repr(e, p->h_comm_max);
        rn_puts(e, " s; allowed: (0, ");
        rn_put_repr(e, p->h_comm_max);
        rn_puts(e, "] s");
        return 0;
    }
    double n = py_max(1.0, ceil(h / p->h_max * (1.0 - 1e-12)));
    double dt = h / n;
    double bound = (p->c + p->drag_viscous) / p->J + sqrt(p->k / p->J);
    double phi, w;
    if (dt * bound > RN_RK4_MAX_STEP_SCALE)
        shaft_exact(d, h, phi_w, w_w, &phi, &w);
    else
        shaft_rk4(d, h, n, phi_w, w_w, &phi, &w);
    if (!(isfinite(phi) && isfinite(w))) {
        rn_puts(rn_error_value(err), "output shaft diverged: reduce solver.h_max");
        return 0;
    }
    d->shaft_phi = phi;
    d->shaft_w = w;
    d->tau_load = shaft_torque(p, phi_w + w_w * h, w_w, phi, w);
    d->time = t + h;
    d->last_step = h;
    return 1;
}

/* The rows of text.splitlines() (\n, \r\n, \r, \v, \f, \x1c-\x1e, \x85, \u2028, \u2029):
 * the end of the line starting at *pos, and the start of the next. */
static size_t line_end(const char* s, size_t n, size_t pos, size_t* next)
{
    size_t i = pos;
    while (i < n) {
        unsigned char c = (unsigned char)s[i];
        if (c == '\n' || c == '\v' || c == '\f' || (c >= 0x1C && c <= 0x1E)) {
            *next = i + 1;
            return i;
        }
        if (c == '\r') {
            *next = (i + 1 < n && s[i + 1] == '\n') ? i + 2 : i + 1;
            return i;
        }
        if (c == 0xC2 && i + 1 < n && (unsigned char)s[i + 1] == 0x85) {
            *next = i + 2;
            return i;
        }
        if (c == 0xE2 && i + 2 < n && (unsigned char)s[i + 1] == 0x80
            && ((unsigned char)s[i + 2] == 0xA8 || (unsigned char)s[i + 2] == 0xA9)) {
            *next = i + 3;
            return i;
        }
        i++;
    }
    *next = n;
    return n;
}

/* One row of csv.reader (excel dialect: ',' separates, '"' quotes, '""' in quotes is '"',
 * text after a closing quote joins the field) of the line s[0:n]; the fields into `fields`
 * (each NUL-terminated, in order), their count returned. */
static int csv_row(const char* s, size_t n, RnText* fields, int max_fields)
{
    int count = 0;
    size_t i = 0;
    if (n == 0) return 0;
    for (;;) {
        RnText* f = &fields[count < max_fields ? count : max_fields - 1];
        if (count < max_fields) rn_text_clear(f);
        rn_putn(f, "", 0);
        int quoted = 0;
        if (i < n && s[i] == '"') {
            quoted = 1;
            i++;
        }
        while (i < n) {
            char c = s[i];
            if (quoted) {
                if (c == '"') {
                    if (i + 1 < n && s[i + 1] == '"') {
                        rn_putn(f, "\"", 1);
                        i += 2;
                        continue;
                    }
                    quoted = 0;
                    i++;
                    continue;
                }
                rn_putn(f, &c, 1);
                i++;
                continue;
            }
            if (c == ',') break;
            rn_putn(f, &c, 1);
            i++;
        }
        count++;
        if (i < n && s[i] == ',') {
            i++;
            if (i == n) { /* a trailing ',' ends the row with an empty field */
                RnText* last = &fields[count < max_fields ? count : max_fields - 1];
                if (count < max_fields) rn_text_clear(last);
                rn_putn(last, "", 0);
                count++;
                return count;
            }
            continue;
        }
        return count;
    }
}

static int is_blank(const char* s)
{
    for (; *s != '\0'; s++)
        if (!(*s == ' ' || (*s >= 0x09 && *s <= 0x0D) || (*s >= 0x1C && *s <= 0x1F))) return 0;
    return 1;
}

#define CSV_FIELDS 64

/* read_speed_table(path): (times, speeds) with driveline.py's checks and messages. */
static int read_speed_table(const char* path, size_t* n_out, double** times_out,
                            double** speeds_out, RnError* err)
{
    size_t n = 0;
    char* raw = rn_read_bounded_file(path, RN_MAX_SPEED_TABLE_BYTES, "engine.speed_table", &n,
                                     rn_error_value(err));
    if (raw == NULL) return 0;
    rn_error_clear(err);
    size_t bad = rattle_utf8_error_at_n(raw, n);
    if (bad != (size_t)-1) {
        RnText* t = rn_error_value(err);
        RnText shown;
        rn_text_init(&shown);
        size_t len = strlen(path), chars = rn_utf8_length(path, len);
        if (chars <= 80)
            rn_puts(&shown, path);
        else {
            size_t k = 0, count = 0;
            while (k < len) {
                if (((unsigned char)path[k] & 0xC0) != 0x80) {
                    if (count == 80) break;
                    count++;
                }
                k++;
            }
            rn_putn(&shown, path, k);
            rn_printf(&shown, "... (%zu characters)", chars);
        }
        rn_puts(t, "speed table ");
        rn_put_repr_str(t, rn_text_str(&shown));
        rn_printf(t, " is not UTF-8 text (byte %zu); allowed: a CSV file of time [s], speed "
                     "[rad/s]", bad);
        rn_text_free(&shown);
        free(raw);
        return 0;
    }
    if (memchr(raw, '\0', n) != NULL) { /* csv.reader refuses NUL */
        rn_puts(rn_error_other(err, "_csv.Error"), "line contains NUL");
        free(raw);
        return 0;
    }
    size_t cap = 1024, count = 0;
    double* times = malloc(cap * sizeof *times);
    double* speeds = malloc(cap * sizeof *speeds);
    RnText fields[CSV_FIELDS];
    for (int k = 0; k < CSV_FIELDS; k++) rn_text_init(&fields[k]);
    int ok = times != NULL && speeds != NULL;
    size_t pos = 0, row_number = 0;
    if (!ok) rn_puts(rn_error_other(err, "MemoryError"), "");
    while (ok && pos < n) {
        size_t next;
        size_t end = line_end(raw, n, pos, &next);
        row_number++;
        int nf = csv_row(raw + pos, end - pos, fields, CSV_FIELDS);
        pos = next;
        RnText joined;
        rn_text_init(&joined);
        for (int k = 0; k < nf && k < CSV_FIELDS; k++) rn_puts(&joined, rn_text_str(&fields[k]));
        int blank = nf == 0 || is_blank(rn_text_str(&joined));
        rn_text_free(&joined);
        if (blank) continue;
        double t = 0.0, w = 0.0;
        int parsed = nf >= 2
                     && rn_parse_python_float(fields[0].data, fields[0].len, &t)
                     && rn_parse_python_float(fields[1].data, fields[1].len, &w);
        if (!parsed) {
            if (row_number == 1) continue; /* header */
            RnText* e = rn_error_value(err);
            rn_puts(e, "speed table ");
            rn_put_repr_str(e, path);
            rn_printf(e, " row %zu = [", row_number);
            for (int k = 0; k < nf && k < CSV_FIELDS; k++) {
                if (k) rn_puts(e, ", ");
                rn_put_repr_strn(e, fields[k].data, fields[k].len);
            }
            rn_puts(e, "]: expected two numbers (time [s], speed [rad/s])");
            ok = 0;
            break;
        }
        if (!(isfinite(t) && isfinite(w))) {
            RnText* e = rn_error_value(err);
            rn_puts(e, "speed table ");
            rn_put_repr_str(e, path);
            rn_printf(e, " row %zu has a non-finite value", row_number);
            ok = 0;
            break;
        }
        if (count > 0 && t <= times[count - 1]) {
            RnText* e = rn_error_value(err);
            rn_puts(e, "speed table ");
            rn_put_repr_str(e, path);
            rn_printf(e, " row %zu: time ", row_number);
            rn_put_repr(e, t);
            rn_puts(e, " s does not increase");
            ok = 0;
            break;
        }
        if (count == cap) {
            cap *= 2;
            double* nt = realloc(times, cap * sizeof *nt);
            if (nt != NULL) times = nt;
            double* ns = realloc(speeds, cap * sizeof *ns);
            if (ns != NULL) speeds = ns;
            if (nt == NULL || ns == NULL) {
                rn_puts(rn_error_other(err, "MemoryError"), "");
                ok = 0;
                break;
            }
        }
        times[count] = t;
        speeds[count] = w;
        count++;
    }
    for (int k = 0; k < CSV_FIELDS; k++) rn_text_free(&fields[k]);
    free(raw);
    if (ok && count < 2) {
        RnText* e = rn_error_value(err);
        rn_puts(e, "speed table ");
        rn_put_repr_str(e, path);
        rn_puts(e, " needs at least two rows");
        ok = 0;
    }
    if (!ok) {
        free(times);
        free(speeds);
        return 0;
    }
    *n_out = count;
    *times_out = times;
    *speeds_out = speeds;
    return 1;
}

/* SpeedTableKinematics._setup: the angle at each sample (trapezoids) */
static int table_kinematics(DrivelineModel* d, size_t n, const double* times,
                            const double* speeds)
{
    d->times = malloc(n * sizeof *d->times);
    d->speeds = malloc(n * sizeof *d->speeds);
    d->angles = malloc(n * sizeof *d->angles);
    if (d->times == NULL || d->speeds == NULL || d->angles == NULL) return 0;
    memcpy(d->times, times, n * sizeof *times);
    memcpy(d->speeds, speeds, n * sizeof *speeds);
    d->n_table = n;
    d->angles[0] = d->phi_0;
    for (size_t i = 1; i < n; i++) {
        double dt = times[i] - times[i - 1];
        d->angles[i] = d->angles[i - 1] + 0.5 * dt * (speeds[i] + speeds[i - 1]);
    }
    return 1;
}

static void engine_orders(DrivelineModel* d, const RnValue* values)
{
    static const unsigned ORDER[RN_N_ORDERS] = RN_VR_ENGINE_ORDERS;
    static const unsigned AMPLITUDE[RN_N_ORDERS] = RN_VR_ENGINE_AMPLITUDES;
    static const unsigned PHASE[RN_N_ORDERS] = RN_VR_ENGINE_PHASES;
    d->n_terms = 0;
    for (int k = 0; k < RN_N_ORDERS; k++) {
        if (R(AMPLITUDE[k]) != 0.0) {
            d->A[d->n_terms] = R(AMPLITUDE[k]);
            d->W[d->n_terms] = R(ORDER[k]) * d->w_mean;
            d->ph[d->n_terms] = R(PHASE[k]);
            d->n_terms++;
        }
    }
}

static DrivelineModel* new_driveline(const RnValue* values, double t_start)
{
    DrivelineModel* d = calloc(1, sizeof *d);
    if (d == NULL) return NULL;
    d->p = shaft_params(values);
    d->w_mean = R(RN_VR_ENGINE_W_MEAN);
    d->phi_0 = R(RN_VR_PINION_PHI_START);
    d->t_start = t_start;
    d->a_over_step = B(RN_VR_PINION_A_OVER_STEP);
    engine_orders(d, values);
    return d;
}

void rn_unit_free(void* model)
{
    DrivelineModel* d = model;
    if (d == NULL) return;
    free(d->times);
    free(d->speeds);
    free(d->angles);
    free(d);
}

/* The file the speed-table parameter names (resolve_speed_table), as str(Path) writes it. */
static void resolve_speed_table(const RnInstance* inst, const char* name, RnText* out)
{
    RnText rel;
    rn_text_init(&rel);
    rn_path_normalise(&rel, name);
    if (!rattle_path_is_absolute(name) && inst->resources != NULL) {
        RnText joined;
        rn_text_init(&joined);
        rn_puts(&joined, inst->resources);
#if defined(_WIN32)
        rn_puts(&joined, "\\");
#else
        rn_puts(&joined, "/");
#endif
        rn_puts(&joined, rn_text_str(&rel));
        if (rn_path_exists(rn_text_str(&joined))) {
            rn_text_clear(out);
            rn_path_normalise(out, rn_text_str(&joined));
            rn_text_free(&joined);
            rn_text_free(&rel);
            return;
        }
        rn_text_free(&joined);
    }
    rn_text_clear(out);
    rn_puts(out, rn_text_str(&rel));
    rn_text_free(&rel);
}

void* rn_unit_build(RnInstance* inst, const RnValue* values, RnError* err)
{
    DrivelineModel* d = new_driveline(values, inst->start_time);
    if (d == NULL) {
        rn_puts(rn_error_other(err, "MemoryError"), "");
        return NULL;
    }
    const char* name = values[RN_VR_ENGINE_SPEED_TABLE].s;
    if (name != NULL && name[0] != '\0') {
        TableCache* c = inst->unit_cache;
        if (c == NULL || strcmp(c->name, name) != 0) {
            RnText path;
            size_t n;
            double *times, *speeds;
            rn_text_init(&path);
            resolve_speed_table(inst, name, &path);
            int ok = read_speed_table(rn_text_str(&path), &n, &times, &speeds, err);
            rn_text_free(&path);
            if (!ok) {
                rn_unit_free(d);
                return NULL;
            }
            rn_unit_free_cache(inst);
            c = calloc(1, sizeof *c);
            if (c != NULL) c->name = malloc(strlen(name) + 1);
            if (c == NULL || c->name == NULL) {
                free(c);
                free(times);
                free(speeds);
                rn_unit_free(d);
                rn_puts(rn_error_other(err, "MemoryError"), "");
                return NULL;
            }
            strcpy(c->name, name);
            c->n = n;
            c->times = times;
            c->speeds = speeds;
            inst->unit_cache = c;
        }
        if (!table_kinematics(d, c->n, c->times, c->speeds)) {
            rn_unit_free(d);
            rn_puts(rn_error_other(err, "MemoryError"), "");
            return NULL;
        }
    }
    double phi_w = R(RN_VR_WHEEL_PHI), w_w = R(RN_VR_WHEEL_W);
    shaft_start(d, phi_w, w_w);
    d->time = inst->start_time;
    d->last_step = 0.0;
    /* DrivelineInputReading._started */
    d->wheel_end[0] = phi_w;
    d->wheel_end[1] = w_w;
    d->boundary.initial_inputs[0] = phi_w;
    d->boundary.initial_inputs[1] = w_w;
    d->boundary.first_step = 1;
    d->boundary.has_last_motion = 0;
    return d;
}

/* DrivelineInputReading._step */
int rn_unit_step(RnInstance* inst, double t, double h, RnError* err)
{
    DrivelineModel* d = inst->model;
    const RnValue* values = inst->values;
    double phi_w = R(RN_VR_WHEEL_PHI), w_w = R(RN_VR_WHEEL_W);
    if (B(RN_VR_INPUTS_CONTINUE_WHEN_HELD) && motion_held(inst, &d->boundary, MOTION_VRS, 2)) {
        phi_w = d->wheel_end[0];
        w_w = d->wheel_end[1];
    }
    double used[2] = {phi_w, w_w};
    int settled = 0;
    double saved[3] = {d->shaft_phi, d->shaft_w, d->tau_load};
    if (first_step_differs(&d->boundary, B(RN_VR_INIT_SETTLE_FIRST_STEP), used, 2)) {
        shaft_start(d, phi_w, w_w);
        settled = 1;
    }
    if (!driveline_step(d, t, h, phi_w, w_w, err)) {
        if (settled) {
            d->shaft_phi = saved[0];
            d->shaft_w = saved[1];
            d->tau_load = saved[2];
        }
        return 0;
    }
    d->wheel_end[0] = phi_w + w_w * h;
    d->wheel_end[1] = w_w;
    d->boundary.first_step = 0;
    motion_step_done(inst, &d->boundary, MOTION_VRS, 2);
    if (settled) {
        static const char* const units[2] = {"rad", "rad/s"};
        settled_warning(inst, START_NAMES, units, used, d->boundary.initial_inputs, 2,
                        "the output shaft was started anew in steady state behind them");
    }
    return 1;
}

/* Driveline.outputs */
int rn_unit_outputs(void* model, unsigned groups, RnValue* out, RnError* err)
{
    DrivelineModel* d = model;
    double k[3];
    (void)err;
    if (!(groups & (RN_GROUP_QUICK | RN_GROUP_STATE | RN_GROUP_LOADS))) return 1;
    kinematics(d, d->time, k);
    double a = k[2];
    double h = d->last_step;
    if (d->a_over_step && h > 0.0) {
        double later[3];
        kinematics(d, d->time + h, later);
        a = (later[1] - k[1]) / h;
    }
    out[RN_VR_PINION_PHI].r = k[0];
    out[RN_VR_PINION_W].r = k[1];
    out[RN_VR_PINION_A].r = a;
    out[RN_VR_WHEEL_TAU_LOAD].r = d->tau_load;
    out[RN_VR_VEHICLE_W].r = d->shaft_w;
    return 1;
}

void rn_unit_snapshot(const void* model, RnText* j)
{
    const DrivelineModel* d = model;
    rn_puts(j, "{\"fmi\": {");
    boundary_snapshot(&d->boundary, 2, 2, j);
    rn_puts(j, ", \"wheel_end\": [");
    rn_json_put_float(j, d->wheel_end[0]);
    rn_puts(j, ", ");
    rn_json_put_float(j, d->wheel_end[1]);
    rn_puts(j, "]}, \"last_step\": ");
    rn_json_put_float(j, d->last_step);
    rn_puts(j, ", \"shaft\": [");
    rn_json_put_float(j, d->shaft_phi);
    rn_puts(j, ", ");
    rn_json_put_float(j, d->shaft_w);
    rn_puts(j, ", ");
    rn_json_put_float(j, d->tau_load);
    rn_puts(j, "], \"table\": ");
    if (d->n_table == 0)
        rn_puts(j, "null");
    else {
        rn_puts(j, "[[");
        for (size_t i = 0; i < d->n_table; i++) {
            if (i) rn_puts(j, ", ");
            rn_json_put_float(j, d->times[i]);
        }
        rn_puts(j, "], [");
        for (size_t i = 0; i < d->n_table; i++) {
            if (i) rn_puts(j, ", ");
            rn_json_put_float(j, d->speeds[i]);
        }
        rn_puts(j, "]]");
    }
    rn_puts(j, ", \"time\": ");
    rn_json_put_float(j, d->time);
    rn_puts(j, "}");
}

/* check_speed_table(times, speeds, "the saved speed table") of a restored state */
static int check_saved_table(const RnJson* times, const RnJson* speeds, RnError* err)
{
    static const char source[] = "the saved speed table";
    if (!(times->kind == RJ_ARRAY && speeds->kind == RJ_ARRAY && times->n == speeds->n)) {
        rn_printf(rn_error_value(err), "%s: times and speeds must be two lists of equal length",
                  source);
        return 0;
    }
    if (times->n < 2) {
        rn_printf(rn_error_value(err), "%s needs at least two rows", source);
        return 0;
    }
    for (size_t k = 0; k < times->n; k++) {
        const RnJson* t = &times->items[k];
        const RnJson* w = &speeds->items[k];
        if (!(rn_json_is_finite_float(t) && rn_json_is_finite_float(w))) {
            RnText* e = rn_error_value(err);
            rn_printf(e, "%s row %zu = (", source, k + 1);
            rn_json_repr(e, t);
            rn_puts(e, ", ");
            rn_json_repr(e, w);
            rn_puts(e, "): expected two finite floats");
            return 0;
        }
        if (k > 0 && t->f <= times->items[k - 1].f) {
            RnText* e = rn_error_value(err);
            rn_printf(e, "%s row %zu: time ", source, k + 1);
            rn_put_repr(e, t->f);
            rn_puts(e, " s does not increase");
            return 0;
        }
    }
    return 1;
}

/* Driveline._model_from_snapshot and drive_rattle.driveline.Driveline.from_snapshot */
void* rn_unit_restore(RnInstance* inst, const RnValue* values, double start_time,
                      const RnJson* snapshot, RnError* err)
{
    static const FieldLayout LAYOUT[5] = {
        {"shaft", {"f", "f", "f"}, 3}, {"time", {"=f"}, 0}, {"last_step", {"=f+"}, 0},
        {"table", {"any"}, 0},         {"fmi", {"any"}, 0},
    };
    (void)inst;
    if (!check_snapshot_fields(snapshot, LAYOUT, 5,
                               "['fmi', 'last_step', 'shaft', 'table', 'time']", err))
        return NULL;
    const RnJson* table = rn_json_get(snapshot, "table");
    if (table->kind != RJ_NULL && !(table->kind == RJ_ARRAY && table->n == 2)) {
        /* {str(table)[:60]!r}: str of a str is the string itself, of anything else repr */
        RnText s;
        rn_text_init(&s);
        if (table->kind == RJ_STRING)
            rn_putn(&s, table->s, table->slen);
        else
            rn_json_repr(&s, table);
        size_t k = 0, count = 0;
        while (k < s.len) {
            if (((unsigned char)s.data[k] & 0xC0) != 0x80) {
                if (count == 60) break;
                count++;
            }
            k++;
        }
        RnText* e = rn_error_value(err);
        rn_puts(e, "model snapshot 'table' = ");
        rn_put_repr_strn(e, rn_text_str(&s), k);
        rn_puts(e, ": expected [times, speeds] or null");
        rn_text_free(&s);
        return NULL;
    }
    const char* name = values[RN_VR_ENGINE_SPEED_TABLE].s;
    int uses_table = name != NULL && name[0] != '\0';
    if (uses_table && table->kind == RJ_NULL) {
        rn_puts(rn_error_value(err), "the saved driveline state lacks the speed table that "
                                     "parameter 'engine.speed_table' names");
        return NULL;
    }
    DrivelineModel* d = new_driveline(values, start_time);
    if (d == NULL) {
        rn_puts(rn_error_other(err, "MemoryError"), "");
        return NULL;
    }
    if (uses_table) {
        const RnJson* times = &table->items[0];
        const RnJson* speeds = &table->items[1];
        if (!check_saved_table(times, speeds, err)) {
            rn_unit_free(d);
            return NULL;
        }
        size_t n = times->n;
        double* t = malloc(n * sizeof *t);
        double* w = malloc(n * sizeof *w);
        int ok = t != NULL && w != NULL;
        for (size_t k = 0; ok && k < n; k++) {
            t[k] = times->items[k].f;
            w[k] = speeds->items[k].f;
        }
        ok = ok && table_kinematics(d, n, t, w);
        free(t);
        free(w);
        if (!ok) {
            rn_unit_free(d);
            rn_puts(rn_error_other(err, "MemoryError"), "");
            return NULL;
        }
    }
    const RnJson* shaft = rn_json_get(snapshot, "shaft");
    d->shaft_phi = shaft->items[0].f;
    d->shaft_w = shaft->items[1].f;
    d->tau_load = shaft->items[2].f;
    d->time = rn_json_get(snapshot, "time")->f;
    d->last_step = rn_json_get(snapshot, "last_step")->f;
    if (!boundary_restore(&d->boundary, rn_json_get(snapshot, "fmi"), 2, 2, 1, d->wheel_end,
                          err)) {
        rn_unit_free(d);
        return NULL;
    }
    return d;
}

#else
#error "define RN_UNIT_MESH or RN_UNIT_DRIVELINE (rattle_native_tables.h)"
#endif
