/*
 * driveline.c - the simple driveline around the mesh: the input shaft's prescribed kinematics
 * (engine orders or a measured speed table) and the output shaft as a torsional spring-damper
 * to a reflected vehicle inertia with drag.
 *
 * Engine orders (MODEL_NOTES section 3), W_k = order_k w_mean:
 *     a(t)   = sum_k A_k cos(W_k t + p_k)
 *     w(t)   = w_mean + sum_k A_k / W_k sin(W_k t + p_k)
 *     phi(t) = phi_0 + w_mean t - sum_k A_k / W_k^2 (cos(W_k t + p_k) - cos p_k)
 * so the mean speed is exactly w_mean and the three are consistent.  A speed table: speed
 * linear between samples, the angle its exact integral, held constant beyond the table.
 *
 * Output shaft (vehicle.model 0): tau_load = k (phi_w - phi_v) + c (w_w - w_v) resists the
 * wheel;
 *     J_v dw_v/dt = tau_load - drag - drag_viscous w_v.
 * Or (vehicle.model 1, the paper's M_res) a constant load on the wheel, tau_load = drag; the
 * "vehicle" then moves with the wheel (its angle and speed are the wheel's).
 * Within a step the wheel moves at its step-start speed; RK4 on substeps <= h_max, or, where
 * that substep is not small against the shaft's own time scales, the exact solution of the
 * same linear equation, so that every legal parameter set integrates stably.
 */
#include <stdlib.h>
#include <string.h>

#include "rm_private.h"

/* Largest RK4 substep relative to the time scale of the shaft's fastest mode: below it RK4 is
 * accurate to ~1e-9 per substep; above it the shaft is integrated exactly. */
#define RK4_MAX_STEP_SCALE 0.1
/* The grid slack of the substeps (stepper.c's GRID_SLACK). */
#define GRID_SLACK 1e-12

void rm_kinematics(const RmDriveline* d, double t, double* out)
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
    size_t lo = 0, hi = n; /* the last sample at or before t */
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

int rm_use_table(RmDriveline* d, size_t n, const double* times, const double* speeds)
{
    double* t = malloc(n * sizeof *t);
    double* w = malloc(n * sizeof *w);
    double* phi = malloc(n * sizeof *phi);
    if (t == NULL || w == NULL || phi == NULL) {
        free(t);
        free(w);
        free(phi);
        return 0;
    }
    memcpy(t, times, n * sizeof *t);
    memcpy(w, speeds, n * sizeof *w);
    /* the angle at each sample: trapezoids, exact for a piecewise-linear speed */
    phi[0] = d->phi_0;
    for (size_t i = 1; i < n; i++) {
        double dt = times[i] - times[i - 1];
        phi[i] = phi[i - 1] + 0.5 * dt * (speeds[i] + speeds[i - 1]);
    }
    rm_driveline_release(d);
    d->times = t;
    d->speeds = w;
    d->angles = phi;
    d->n_table = n;
    return 1;
}

void rm_driveline_release(RmDriveline* d)
{
    free(d->times);
    free(d->speeds);
    free(d->angles);
    d->times = d->speeds = d->angles = NULL;
    d->n_table = 0;
}

/* "<source> sample k (time t s)": a table's samples counted from 1, header and blank rows of
 * its file not counted (the reader's own messages name the file's rows). */
static void sample_at(RmText* err, const char* source, size_t k, double t)
{
    rm_printf(err, "%s sample %zu (time %r s)", source, k + 1, t);
}

int rm_check_speed_table(size_t n, const double* times, const double* speeds, double phi_0,
                         const char* source, RmText* err)
{
    if (n < 2) {
        rm_printf(err, "%s needs at least two rows", source);
        return 0;
    }
    double angle = phi_0;
    for (size_t k = 0; k < n; k++) {
        if (!(isfinite(times[k]) && isfinite(speeds[k]))) {
            sample_at(err, source, k, times[k]);
            rm_printf(err, ": speed %r rad/s; allowed: finite numbers", speeds[k]);
            return 0;
        }
        if (!(fabs(times[k]) <= RM_MAX_TABLE_TIME)) {
            sample_at(err, source, k, times[k]);
            rm_printf(err, ": the time is out of range; allowed: [%.6r, %.6r] s",
                      -RM_MAX_TABLE_TIME, RM_MAX_TABLE_TIME);
            return 0;
        }
        if (k > 0 && !(times[k] > times[k - 1])) {
            sample_at(err, source, k, times[k]);
            rm_puts(err, ": the time does not increase");
            return 0;
        }
        if (!(fabs(speeds[k]) <= RM_MAX_SPEED)) {
            sample_at(err, source, k, times[k]);
            rm_printf(err, ": speed %r rad/s is out of range; allowed: [%.6r, %.6r] rad/s",
                      speeds[k], -RM_MAX_SPEED, RM_MAX_SPEED);
            return 0;
        }
        if (k > 0) angle += 0.5 * (times[k] - times[k - 1]) * (speeds[k] + speeds[k - 1]);
        if (!(fabs(angle) <= RM_MAX_ANGLE)) {
            sample_at(err, source, k, times[k]);
            rm_printf(err, ": the input-shaft angle reaches %r rad there; allowed: within [%.6r, "
                           "%.6r] rad (a shorter table, or pinion.phi_start nearer 0)",
                      angle, -RM_MAX_ANGLE, RM_MAX_ANGLE);
            return 0;
        }
    }
    return 1;
}

static double shaft_torque(const RmShaftParams* p, double phi_w, double w_w, double phi_v,
                           double w_v)
{
    return p->k * (phi_w - phi_v) + p->c * (w_w - w_v);
}

void rm_shaft_start(RmDriveline* d, double phi_w, double w_w)
{
    const RmShaftParams* p = &d->p;
    if (p->model == RM_VEHICLE_CONSTANT_LOAD) {
        d->shaft_phi = phi_w;
        d->shaft_w = w_w;
        d->tau_load = p->drag;
        return;
    }
    /* steady state: the vehicle at the wheel speed, the shaft wound up by the drag */
    double steady = p->drag + p->drag_viscous * w_w;
    d->shaft_phi = phi_w - steady / p->k;
    d->shaft_w = w_w;
    d->tau_load = shaft_torque(p, phi_w, w_w, d->shaft_phi, d->shaft_w);
}

static double shaft_acc(const RmShaftParams* p, double phi_w, double w_w, double t,
                        double phi_v, double w_v)
{
    double tau = p->k * (phi_w + w_w * t - phi_v) + p->c * (w_w - w_v);
    return (tau - p->drag - p->drag_viscous * w_v) / p->J;
}

static void shaft_rk4(const RmDriveline* d, double h, double n, double phi_w, double w_w,
                      double* phi_out, double* w_out)
{
    const RmShaftParams* p = &d->p;
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

/* The exact solution over h of the shaft's linear equation.  With the wheel at
 * phi_w + w_w t, x_p(t) = phi_w + w_w t - (drag + drag_viscous w_w)/k, w_p = w_w solves it
 * (the steadily wound shaft); the deviation e = (phi_v - x_p, w_v - w_w) obeys e' = A e with
 * A = [[0, 1], [-k/J, -(c + drag_viscous)/J]], so e(h) = exp(A h) e(0), evaluated from the
 * eigenvalues of A without overflow (both have non-positive real parts). */
static void shaft_exact(const RmDriveline* d, double h, double phi_w, double w_w,
                        double* phi_out, double* w_out)
{
    const RmShaftParams* p = &d->p;
    double g = (p->c + p->drag_viscous) / p->J; /* -trace(A) >= 0 */
    double dd = p->k / p->J;                     /* det(A) > 0 */
    double offset = (p->drag + p->drag_viscous * w_w) / p->k;
    double e0 = d->shaft_phi - (phi_w - offset);
    double f0 = d->shaft_w - w_w;
    double s = -0.5 * g;
    double q2 = 0.25 * g * g - dd;
    double x2 = fabs(q2) * h * h;
    double m11, m12, m21, m22;
    if (x2 < 1e-6) { /* near critical damping: series of cosh(qh), sinh(qh)/q in q^2 h^2 */
        double es = exp(s * h);
        double ch = 1.0 + 0.5 * q2 * h * h * (1.0 + q2 * h * h / 12.0);
        double sh = h * (1.0 + q2 * h * h / 6.0 * (1.0 + q2 * h * h / 20.0));
        m11 = es * (ch - s * sh);
        m12 = es * sh;
        m21 = -dd * es * sh;
        m22 = es * (ch + (-g - s) * sh);
    }
    else if (q2 < 0.0) { /* underdamped: exp(sh) (cos(wd h) I + sin(wd h)/wd (A - sI)) */
        double wd = sqrt(-q2);
        double es = exp(s * h);
        double c = es * cos(wd * h), sn = es * sin(wd * h) / wd;
        m11 = c - s * sn;
        m12 = sn;
        m21 = -dd * sn;
        m22 = c + (-g - s) * sn;
    }
    else { /* overdamped: real eigenvalues l2 < l1 < 0, l1 from l1 l2 = det (no cancellation) */
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

int rm_driveline_step(RmDriveline* d, double t, double h, double phi_w, double w_w,
                      RmText* err)
{
    const RmShaftParams* p = &d->p;
    if (p->model == RM_VEHICLE_CONSTANT_LOAD) {
        d->shaft_phi = phi_w + w_w * h;
        d->shaft_w = w_w;
        d->tau_load = p->drag;
        d->time = t + h;
        d->last_step = h;
        return 1;
    }
    double n = rm_max(1.0, ceil(h / p->h_max * (1.0 - GRID_SLACK)));
    double dt = h / n;
    /* an upper bound of the magnitude of the shaft's eigenvalues (at most twice the largest) */
    double bound = (p->c + p->drag_viscous) / p->J + sqrt(p->k / p->J);
    double phi, w;
    if (dt * bound > RK4_MAX_STEP_SCALE)
        shaft_exact(d, h, phi_w, w_w, &phi, &w);
    else
        shaft_rk4(d, h, n, phi_w, w_w, &phi, &w);
    if (!(isfinite(phi) && isfinite(w))) {
        rm_printf(err, "the output shaft diverged (vehicle-side angle %r rad, speed %r rad/s): "
                       "reduce solver.h_max", phi, w);
        return 0;
    }
    d->shaft_phi = phi;
    d->shaft_w = w;
    d->tau_load = shaft_torque(p, phi_w + w_w * h, w_w, phi, w);
    d->time = t + h;
    d->last_step = h;
    return 1;
}
