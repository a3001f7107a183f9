/*
 * unit_driveline.c - the Driveline unit: its parameters to the input-shaft kinematics and the
 * output shaft (the speed table read once per file name), the start behind the wheel, how it
 * reads held inputs and a first step on other inputs than initialization's, the outputs, its
 * record (which carries the speed table: a restored state reads no file).
 *
 * Held inputs: when the master holds wheel.phi and wheel.w (set neither since the last step,
 * or set the last step's values again), the wheel runs on at constant speed from where the
 * last step left it (inputs.continue_when_held).  A first step on another wheel than
 * initialization's starts the output shaft anew in steady state behind it
 * (init.settle_first_step), with a warning.
 */
#include <stdlib.h>
#include <string.h>

#include "rm_private.h"

#define R(vr) (values[vr].r)
#define I(vr) (values[vr].i)
#define B(vr) (values[vr].i != 0)

#define GROUP_ALL 1u
/* The most rows a speed-table file can hold (each row at least "0,0\n"): a saved table of
 * more rows came from no file. */
#define MAX_TABLE_ROWS (RM_MAX_SPEED_TABLE_BYTES / 4u)

typedef struct {
    RmDriveline d;
    RmBoundary boundary;
    double wheel_end[2]; /* where a held wheel runs on from: the last step's end */
} DrivelineModel;

/* The speed table read at the last build, by the parameter's value. */
typedef struct {
    char* name;
    size_t n;
    double *times, *speeds;
} TableCache;

static void free_cache(RmUnit* u)
{
    TableCache* c = u->cache;
    if (c != NULL) {
        free(c->name);
        free(c->times);
        free(c->speeds);
        free(c);
    }
    u->cache = NULL;
}

static void free_model(void* model)
{
    DrivelineModel* m = model;
    if (m == NULL) return;
    rm_driveline_release(&m->d);
    free(m);
}

/* The driveline of the current parameters: shaft, engine orders, the start time. */
static DrivelineModel* new_model(const RmUnit* u, double t_start)
{
    static const unsigned ORDER[RM_N_ENGINE_ORDERS] = {
        RM_DRIVELINE_ENGINE_ORDER_1, RM_DRIVELINE_ENGINE_ORDER_2, RM_DRIVELINE_ENGINE_ORDER_3,
        RM_DRIVELINE_ENGINE_ORDER_4};
    static const unsigned AMPLITUDE[RM_N_ENGINE_ORDERS] = {
        RM_DRIVELINE_ENGINE_AMPLITUDE_1, RM_DRIVELINE_ENGINE_AMPLITUDE_2,
        RM_DRIVELINE_ENGINE_AMPLITUDE_3, RM_DRIVELINE_ENGINE_AMPLITUDE_4};
    static const unsigned PHASE[RM_N_ENGINE_ORDERS] = {
        RM_DRIVELINE_ENGINE_PHASE_1, RM_DRIVELINE_ENGINE_PHASE_2, RM_DRIVELINE_ENGINE_PHASE_3,
        RM_DRIVELINE_ENGINE_PHASE_4};
    const RmValue* values = u->values;
    DrivelineModel* m = calloc(1, sizeof *m);
    if (m == NULL) return NULL;
    RmDriveline* d = &m->d;
    d->p.k = R(RM_DRIVELINE_SHAFT_K);
    d->p.c = R(RM_DRIVELINE_SHAFT_C);
    d->p.J = R(RM_DRIVELINE_VEHICLE_J);
    d->p.drag = R(RM_DRIVELINE_VEHICLE_DRAG);
    d->p.drag_viscous = R(RM_DRIVELINE_VEHICLE_DRAG_VISCOUS);
    d->p.model = (int)values[RM_DRIVELINE_VEHICLE_MODEL].i;
    d->p.h_max = R(RM_DRIVELINE_SOLVER_H_MAX);
    d->p.h_comm_max = R(RM_DRIVELINE_SOLVER_H_COMM_MAX);
    d->w_mean = R(RM_DRIVELINE_ENGINE_W_MEAN);
    d->phi_0 = R(RM_DRIVELINE_PINION_PHI_START);
    d->t_start = t_start;
    d->a_over_step = B(RM_DRIVELINE_PINION_A_OVER_STEP);
    /* the active engine orders: a slot with zero amplitude is off */
    d->n_terms = 0;
    for (int k = 0; k < RM_N_ENGINE_ORDERS; k++) {
        if (R(AMPLITUDE[k]) != 0.0) {
            d->A[d->n_terms] = R(AMPLITUDE[k]);
            d->W[d->n_terms] = R(ORDER[k]) * d->w_mean;
            d->ph[d->n_terms] = R(PHASE[k]);
            d->n_terms++;
        }
    }
    return m;
}

static const char* table_name(const RmUnit* u)
{
    const char* name = u->values[RM_DRIVELINE_ENGINE_SPEED_TABLE].s;
    return name != NULL ? name : "";
}

/* The speed table the parameter names, read once per name: 1, or 0 with the refusal. */
static int read_table(RmUnit* u, const TableCache** out, RmText* err)
{
    const char* name = table_name(u);
    TableCache* c = u->cache;
    if (c != NULL && strcmp(c->name, name) == 0) {
        *out = c;
        return 1;
    }
    RmText path;
    rm_text_init(&path);
    rm_resolve_speed_table(u->resources, name, &path);
    size_t n;
    double *times, *speeds;
    int ok = !path.failed && rm_read_speed_table(rm_text_str(&path), &n, &times, &speeds, err);
    rm_text_free(&path);
    if (!ok) return 0;
    free_cache(u);
    c = calloc(1, sizeof *c);
    if (c != NULL) c->name = malloc(strlen(name) + 1);
    if (c == NULL || c->name == NULL) {
        free(c);
        free(times);
        free(speeds);
        rm_printf(err, "out of memory");
        return 0;
    }
    strcpy(c->name, name);
    c->n = n;
    c->times = times;
    c->speeds = speeds;
    u->cache = c;
    *out = c;
    return 1;
}

/* The kinematics and the shaft started behind the wheel at (phi_w, w_w). */
static DrivelineModel* started(RmUnit* u, double t_start, double phi_w, double w_w, RmText* err)
{
    const TableCache* table = NULL;
    if (table_name(u)[0] != '\0') {
        if (!read_table(u, &table, err)) return NULL;
        RmText source;
        rm_text_init(&source);
        rm_printf(&source, "speed table %q", table->name, strlen(table->name));
        int ok = rm_check_speed_table(table->n, table->times, table->speeds,
                                      u->values[RM_DRIVELINE_PINION_PHI_START].r,
                                      rm_text_str(&source), err);
        rm_text_free(&source);
        if (!ok) return NULL;
    }
    DrivelineModel* m = new_model(u, t_start);
    if (m == NULL || (table != NULL && !rm_use_table(&m->d, table->n, table->times, table->speeds))) {
        free_model(m);
        rm_printf(err, "out of memory");
        return NULL;
    }
    rm_shaft_start(&m->d, phi_w, w_w);
    m->d.time = t_start;
    m->d.last_step = 0.0;
    m->wheel_end[0] = phi_w;
    m->wheel_end[1] = w_w;
    return m;
}

static void* build(RmUnit* u, RmText* err)
{
    const RmValue* values = u->values;
    DrivelineModel* m = started(u, u->start_time, R(RM_DRIVELINE_WHEEL_PHI), R(RM_DRIVELINE_WHEEL_W),
                                err);
    if (m != NULL) rm_boundary_start(u, &m->boundary);
    return m;
}

/* The outputs of the driveline in `m`. */
static void driveline_outputs(const DrivelineModel* m, double* out)
{
    const RmDriveline* d = &m->d;
    double k[3];
    rm_kinematics(d, d->time, k);
    double a = k[2];
    double h = d->last_step;
    /* pinion.a_over_step: the mean acceleration over the coming step (taken as long as the
     * last one), so that the mesh moves the pinion at exactly its speed at the next
     * communication point: the pinion speed it sees is continuous */
    if (d->a_over_step && h > 0.0) {
        double later[3];
        rm_kinematics(d, d->time + h, later);
        a = (later[1] - k[1]) / h;
    }
    out[0] = k[0];
    out[1] = k[1];
    out[2] = a;
    out[3] = d->tau_load;
    out[4] = d->shaft_w;
}

static void store_outputs(const double* out, RmValue* values)
{
    values[RM_DRIVELINE_PINION_PHI].r = out[0];
    values[RM_DRIVELINE_PINION_W].r = out[1];
    values[RM_DRIVELINE_PINION_A].r = out[2];
    values[RM_DRIVELINE_WHEEL_TAU_LOAD].r = out[3];
    values[RM_DRIVELINE_VEHICLE_W].r = out[4];
}

int rm_driveline_start_outputs(RmUnit* u, double start_time, double phi_w, double w_w,
                               double* out, RmText* err)
{
    DrivelineModel* m = started(u, start_time, phi_w, w_w, err);
    if (m == NULL) return 0;
    driveline_outputs(m, out);
    free_model(m);
    return 1;
}

static int step(RmUnit* u, double t, double h, RmText* warning, RmText* err)
{
    DrivelineModel* m = u->model;
    RmDriveline* d = &m->d;
    const RmValue* values = u->values;
    double phi_w = R(RM_DRIVELINE_WHEEL_PHI), w_w = R(RM_DRIVELINE_WHEEL_W);
    if (B(RM_DRIVELINE_INPUTS_CONTINUE_WHEN_HELD) && rm_motion_held(u, &m->boundary)) {
        phi_w = m->wheel_end[0];
        w_w = m->wheel_end[1];
    }
    double used[2] = {phi_w, w_w};
    if (h > d->p.h_comm_max) {
        rm_printf(err, "step size h = %r s exceeds solver.h_comm_max = %r s; allowed: (0, %r] s",
                  h, d->p.h_comm_max, d->p.h_comm_max);
        return 0;
    }
    double saved[3] = {d->shaft_phi, d->shaft_w, d->tau_load};
    double saved_time = d->time, saved_step = d->last_step;
    int settled = rm_first_step_differs(&m->boundary, B(RM_DRIVELINE_INIT_SETTLE_FIRST_STEP), used, 2);
    if (settled) rm_shaft_start(d, phi_w, w_w);
    if (!rm_driveline_step(d, t, h, phi_w, w_w, err)) {
        d->shaft_phi = saved[0]; /* a refused step leaves the unit as it was */
        d->shaft_w = saved[1];
        d->tau_load = saved[2];
        return 0;
    }
    /* the outputs now: checked finite, and kept (the step leaves them computed) */
    double out[5];
    driveline_outputs(m, out);
    for (int k = 0; k < 5; k++) {
        if (!isfinite(out[k])) { /* the kinematics ran off (a table held far beyond its end) */
            rm_printf(err, "the driveline's outputs are not finite at t = %r s (the input-shaft "
                           "angle %r rad); a speed table ends too early for this run",
                      d->time, out[0]);
            d->shaft_phi = saved[0];
            d->shaft_w = saved[1];
            d->tau_load = saved[2];
            d->time = saved_time;
            d->last_step = saved_step;
            return 0;
        }
    }
    store_outputs(out, u->values);
    /* the output shaft moves the wheel at its step-start speed within a step */
    m->wheel_end[0] = phi_w + w_w * h;
    m->wheel_end[1] = w_w;
    rm_motion_step_done(u, &m->boundary);
    if (settled)
        rm_settled_warning(u, &m->boundary, used,
                           "the output shaft was started anew in steady state behind them",
                           warning);
    return 1;
}

static unsigned group_of(unsigned vr)
{
    (void)vr;
    return GROUP_ALL;
}

static int outputs(RmUnit* u, void* model, unsigned groups, RmValue* values, RmText* err)
{
    double out[5];
    (void)u;
    (void)err;
    if (!(groups & GROUP_ALL)) return 1;
    driveline_outputs(model, out);
    store_outputs(out, values);
    return 1;
}

static void save(const void* model, RmWriter* w)
{
    const DrivelineModel* m = model;
    const RmDriveline* d = &m->d;
    rm_write_f64(w, d->shaft_phi);
    rm_write_f64(w, d->shaft_w);
    rm_write_f64(w, d->tau_load);
    rm_write_f64(w, d->time);
    rm_write_f64(w, d->last_step);
    rm_write_i64(w, (int64_t)d->n_table);
    for (size_t i = 0; i < d->n_table; i++) rm_write_f64(w, d->times[i]);
    for (size_t i = 0; i < d->n_table; i++) rm_write_f64(w, d->speeds[i]);
    rm_boundary_save(&RM_DRIVELINE_CLASS, &m->boundary, w);
    rm_write_f64(w, m->wheel_end[0]);
    rm_write_f64(w, m->wheel_end[1]);
}

static void* restore(RmUnit* u, RmReader* r, RmText* err)
{
    DrivelineModel* m = new_model(u, u->start_time);
    if (m == NULL) {
        rm_printf(err, "out of memory");
        return NULL;
    }
    RmDriveline* d = &m->d;
    int ok = rm_read_finite(r, "the vehicle-side shaft angle", 0, &d->shaft_phi, err)
             && rm_read_finite(r, "the vehicle-side shaft speed", 0, &d->shaft_w, err)
             && rm_read_finite(r, "the shaft torque", 0, &d->tau_load, err)
             && rm_read_finite(r, "the driveline's time", 0, &d->time, err)
             && rm_read_finite(r, "the last communication step", 1, &d->last_step, err);
    if (ok && d->last_step > d->p.h_comm_max) {
        rm_printf(err, "the last communication step = %r s: expected within [0, solver.h_comm_max "
                       "= %r] s (a step the unit accepted)", d->last_step, d->p.h_comm_max);
        ok = 0;
    }
    if (ok && d->time != u->time) {
        rm_printf(err, "the driveline's time %r s differs from the state's time %r s",
                  d->time, u->time);
        ok = 0;
    }
    int64_t n = ok ? rm_read_i64(r) : 0;
    int uses_table = table_name(u)[0] != '\0';
    if (ok && rm_read_ended(r, "the saved speed table's length", err)) ok = 0;
    if (ok && (n < 0 || n > (int64_t)MAX_TABLE_ROWS)) {
        rm_printf(err, "the saved speed table's length = %lld rows: expected an integer in [0, "
                       "%lu] (what a table file of at most %u bytes can hold)", (long long)n,
                  (unsigned long)MAX_TABLE_ROWS, RM_MAX_SPEED_TABLE_BYTES);
        ok = 0;
    }
    if (ok && (uint64_t)n > (r->len - r->pos) / 16) {
        rm_printf(err, "the record ends before the end of the saved speed table (%lld rows of "
                       "16 bytes, %zu bytes left)", (long long)n, r->len - r->pos);
        ok = 0;
    }
    if (ok && uses_table != (n > 0)) {
        rm_printf(err, "the saved driveline state %s",
                  uses_table ? "lacks the speed table that parameter 'engine.speed_table' names"
                             : "has a speed table, but parameter 'engine.speed_table' names none");
        ok = 0;
    }
    if (ok && n > 0) {
        size_t rows = (size_t)n;
        double* t = malloc(rows * sizeof *t);
        double* w = malloc(rows * sizeof *w);
        ok = t != NULL && w != NULL;
        if (!ok) rm_printf(err, "out of memory");
        for (size_t i = 0; ok && i < rows; i++) t[i] = rm_read_f64(r);
        for (size_t i = 0; ok && i < rows; i++) w[i] = rm_read_f64(r);
        ok = ok && rm_check_speed_table(rows, t, w, d->phi_0, "the saved speed table", err);
        if (ok && !rm_use_table(d, rows, t, w)) {
            rm_printf(err, "out of memory");
            ok = 0;
        }
        free(t);
        free(w);
    }
    ok = ok && rm_boundary_restore(&RM_DRIVELINE_CLASS, &m->boundary, r, err)
         && rm_read_finite(r, "the wheel's angle at the last step's end", 0, &m->wheel_end[0], err)
         && rm_read_within(r, "the wheel's speed at the last step's end",
                           rm_max(fabs(u->variables[RM_DRIVELINE_WHEEL_W].min),
                                  fabs(u->variables[RM_DRIVELINE_WHEEL_W].max)),
                           "rad/s", "input wheel.w's range: a held wheel keeps its speed",
                           &m->wheel_end[1], err);
    if (!ok) {
        free_model(m);
        return NULL;
    }
    return m;
}

static const RmStepLog* step_log(const void* model)
{
    (void)model;
    return NULL;
}

static int describe(RmUnit* u, const char** names, double* values_out, size_t capacity,
                    size_t* count, RmText* err)
{
    const RmValue* values = u->values;
    const TableCache* table = NULL;
    if (table_name(u)[0] != '\0' && !read_table(u, &table, err)) return 0;
    double k = R(RM_DRIVELINE_SHAFT_K), c = R(RM_DRIVELINE_SHAFT_C), J = R(RM_DRIVELINE_VEHICLE_J);
    /* the vehicle mode against a wheel held fixed: the shaft and the reflected inertia */
    double omega = sqrt(k / J);
    double zeta = (c + R(RM_DRIVELINE_VEHICLE_DRAG_VISCOUS)) / (2.0 * sqrt(k * J));
    const char* n[] = {"vehicle_mode_frequency", "vehicle_mode_damping_ratio",
                       "vehicle_mode_decay_time", "speed_table_rows"};
    double v[] = {omega / (2.0 * RM_PI), zeta, zeta > 0.0 ? 1.0 / (zeta * omega) : INFINITY,
                  table != NULL ? (double)table->n : 0.0};
    size_t total = sizeof v / sizeof v[0];
    for (size_t i = 0; i < total && i < capacity; i++) {
        names[i] = n[i];
        values_out[i] = v[i];
    }
    *count = total;
    return 1;
}

const RmUnitClass RM_DRIVELINE_CLASS = {
    RM_DRIVELINE,
    2,
    2,
    {RM_DRIVELINE_WHEEL_PHI, RM_DRIVELINE_WHEEL_W, 0, 0},
    {RM_DRIVELINE_WHEEL_PHI, RM_DRIVELINE_WHEEL_W, 0, 0},
    build,
    free_model,
    free_cache,
    step,
    outputs,
    GROUP_ALL,
    GROUP_ALL,
    GROUP_ALL,
    group_of,
    save,
    restore,
    step_log,
    describe,
};
