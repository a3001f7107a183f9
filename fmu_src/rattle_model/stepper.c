/*
 * stepper.c - the wheel's equation of motion (paper eq. 10, I_w phi_w'' = mesh torque - M_res)
 * over one communication step, with located contact events.
 *
 * Inside a step the pinion follows the Taylor polynomial of its step-start inputs,
 *     phi_p(t) = phi_p0 + w_p0 t + a_p t^2 / 2,
 * and the load torque is held.  The wheel alternates between two modes:
 *  - free flight (no flank in contact): the wheel's acceleration is constant, so the normal
 *    approach is a quadratic in time and the next contact onset its exact root;
 *  - contact on one flank: classical RK4 on substeps of a fixed grid t_j = j H / n
 *    (n = ceil(H / h_max)), split wherever a pair enters or leaves the zone of action or its
 *    contact point changes its law of motion (kinematic, exact), subdivided where the
 *    contact's own time scales (sqrt(m/k), m/c) are shorter than the grid, and ended at the
 *    release or at a friction reversal (a pair's sliding speed changing sign at the pitch
 *    point), both located by Brent's method on the RK4 step from the substep start, so that
 *    the events are consistent with the integrator.  Between reversals each pair's friction
 *    keeps its direction, so the right-hand side is smooth on every substep.
 * Each onset sets the contact's dissipation from its approach speed (dissipation.c); an
 * impact that does not rebound (the squeeze-film law below its critical Stokes number) loses
 * its approach speed at once.  A pair whose friction would hold its sliding speed at zero
 * (Filippov's sliding condition: either direction of the friction drives the sliding speed
 * back through zero) sticks: its friction turns continuously over RM_STICK_SPEED instead of
 * chattering between the directions.
 * A flank exactly touching and moving into contact -- or at rest and accelerated into it --
 * is an onset (exact touch).  Every time inside the step is a grid point or a located event
 * offset from one; no time is accumulated.  A refused step changes nothing.
 */
#include <string.h>

#include "rm_private.h"

/* Samples used to find a positive penetration inside a substep that starts at an onset and
 * ends separated: a grazing contact shorter than one substep. */
#define GRAZING_SAMPLES 8
/* Largest product of a contact substep and the contact's fastest rate sqrt(k/m) + c/m.  RK4
 * is stable to about 2.8 on both the imaginary and the negative real axis; 0.25 keeps a
 * single impact's restitution within 1e-4 of the closed form from 1 mm/s to 0.5 m/s at any
 * legal damping, and leaves the default grid (10 us) untouched at the default pair's rattle
 * speeds below ~20 mm/s. */
#define CONTACT_RATE_SAFETY 0.25
/* The same for the rough flanks' series law (contact.roughness = 1), whose stiffness changes
 * by orders of magnitude within an impact (W ~ delta^7.8 at first asperity contact, the bulk
 * law beyond): at 0.25 RK4 gained up to 3.4e-4 of a 1 m/s impact's energy, at 1/16 less than
 * 2e-5 (tests/model/test_properties.py).  At rattle speeds the substep grid binds first. */
#define CONTACT_RATE_SAFETY_ROUGH 0.0625
/* With the teeth in series (tooth.compliance = 1, smooth laws) the contact's elastic rate
 * sqrt(k/m) (with sticking friction's) and its damping rate c/m are held apart, each to its
 * own bound.  Elastic: at 0.25 an undamped 0.5 m/s impact lost 1.03e-4 of its speed, at 0.125
 * at most 2.3e-5 from 0.1 to 1 m/s (tests/model/test_closed_forms.py,
 * tests/model/test_properties.py). */
#define CONTACT_RATE_SAFETY_TEETH 0.125
/* Damping: an overdamped contact's fast mode decays at c/m, where RK4 is stable to
 * h c/m = 2.78, and its motion follows the slow mode k/c.  With the teeth 16 % of the paper
 * scenario's drive impacts come just above the squeeze-film law's critical speed (0.1 % with
 * rigid teeth), whose small restitution e is realized by the Hunt-Crossley factor
 * d = alpha(e)/v ~ 1/(e v) (up to 1e6 s/m), heavily overdamping the contact for as long as it
 * stays loaded: held to 0.25 on sqrt(k/m) + c/m they took 2.7 times the substeps of the rigid
 * model.  At 2 every restitution closed form and the squeeze-film law still hold within their
 * tolerances at every damping tested (tests/model/test_closed_forms.py, test_dissipation.py,
 * test_properties.py). */
#define CONTACT_DAMPING_SAFETY_TEETH 2.0
/* xtol [s] and rtol of Brent's method for the release, friction reversals and engagements. */
#define EVENT_XTOL 1e-15
#define EVENT_RTOL RM_BRENT_RTOL
/* Relative slack of the substep grid: a step that is a whole multiple of solver.h_max to
 * rounding gets n grid substeps, not n + 1. */
#define GRID_SLACK 1e-12
/* A crowned pair's engagement located in the first this fraction of a substep does not end
 * the substep: RK4's error from a kink that close to its start is negligible (it scales with
 * the kink's offset to the power 2.5), and splitting there would let a pair hovering at its
 * offset end substep after substep a few femtoseconds long. */
#define ENGAGEMENT_MIN_FRACTION 1e-3
/* A contact substep that would end within this fraction of the grid spacing of its start (an
 * onset located on a grid point to rounding: its time carries the rounding of the quadratic
 * root, up to ~1e-7 of the spacing late in a long run at a slow approach) is merged into the
 * next grid substep: a substep of a few ulps integrates nothing and its end state is the
 * onset's to rounding. */
#define MERGE_FRACTION 1e-6
/* Main-loop iterations without progress in time before a step is refused, and the largest
 * number of grid substeps (an int64). */
#define STALL_LIMIT 1000000
#define MAX_GRID_SUBSTEPS 9.2e18
/* Roll distance [m] of the forward difference that gives a contact point's roll rate (its
 * roll coordinate is piecewise linear in the roll). */
#define ROLL_STEP 1e-9

typedef struct {
    const RmMesh* M;
    RmFail* f;
    RmWheel st;
    double H;
    int64_t n_sub;
    double phi_p0, w_p0, a_p, tau_load, J;
    double W_peak, delta_peak, int_tau_pinion;
    int64_t onsets_drive, onsets_coast;
    RmStepLog* log;
    /* the friction direction of each pair slot on the current substep, and the directions a
     * located reversal prescribes for the substep after it */
    double signs[RM_MAX_PAIR_SLOTS];
    double stick_speeds[RM_MAX_PAIR_SLOTS]; /* of the pairs whose friction sticks */
    int has_reversed[RM_MAX_PAIR_SLOTS];
    double reversed[RM_MAX_PAIR_SLOTS];
    double rattle_time, rattle_gain;
    RmPairCache pairs;
} Run;

static inline double run_phi_p(const Run* r, double t)
{
    return r->phi_p0 + t * (r->w_p0 + 0.5 * r->a_p * t);
}

static inline double run_w_p(const Run* r, double t) { return r->w_p0 + r->a_p * t; }

/* The time of grid point j (exactly H at j = n). */
static inline double grid(const Run* r, int64_t j)
{
    return j >= r->n_sub ? r->H : r->H * (double)j / (double)r->n_sub;
}

/* A located event: its normal approach speed at the event, recorded in the log. */
static double event(Run* r, double t, int kind, int flank)
{
    double speed = rm_approach_rate(r->M, flank, run_w_p(r, t), r->st.w);
    RmStepLog* log = r->log;
    if (log->n_events < RM_MAX_EVENTS) {
        RmEvent* e = &log->events[log->n_events++];
        e->time = t;
        e->kind = kind;
        e->flank = flank;
        e->speed = speed;
    }
    log->total_events++;
    return speed;
}

/* An impact that does not rebound: the wheel takes the pinion's speed on the tooth normal at
 * once (its approach speed, and the kinetic energy 1/2 m_n v^2 on the normal, lost in the
 * film); the impulse's reaction enters the pinion's torque. */
static void stick(Run* r, double t)
{
    const RmMesh* M = r->M;
    RmWheel* st = &r->st;
    double w_old = st->w;
    st->w = M->arm_pinion * run_w_p(r, t) / M->arm_wheel;
    r->int_tau_pinion -= r->J * (st->w - w_old) * M->arm_pinion / M->arm_wheel;
}

static void onset(Run* r, double t, int flank)
{
    RmWheel* st = &r->st;
    double v = event(r, t, RM_EVENT_ONSET, flank);
    /* the contact's dissipation from this impact (dissipation.c) */
    if (rm_onset_dissipation(r->M, r->f, &r->pairs, flank, run_phi_p(r, t), v, &st->diss)
        && v > 0.0)
        stick(r, t);
    if (v < 0.0) v = 0.0;
    st->v_last = v;
    /* the kinetic energy of the impact on the tooth normal, into the rattle index (an
     * exponential average: each impact adds E / tau, decayed to the step end) */
    double energy = 0.5 * r->M->normal_mass * v * v;
    r->rattle_gain += energy / r->rattle_time * rm_exp_checked(r->f, -(r->H - t) / r->rattle_time);
    if (flank == RM_DRIVE) {
        st->v_drive = v;
        if (st->n_drive < RM_COUNT_MAX) st->n_drive++;
        r->onsets_drive++;
    }
    else {
        st->v_coast = v;
        if (st->n_coast < RM_COUNT_MAX) st->n_coast++;
        r->onsets_coast++;
    }
}

/* The first onset in free flight of a flank whose penetration is c0 + c1 t + c2 t^2: its
 * upward crossing of zero, or t = 0 when the flank already penetrates (a rounding-level
 * positive value: with no backlash the other flank's penetration is minus the released
 * one's) and moves into contact -- approaching, or at rest and accelerated into it.  A
 * penetrating flank that recedes is the one just released (rounding again): no onset. */
static int flight_onset(double c0, double c1, double c2, double span, double* out)
{
    if (c0 > 0.0 && (c1 > 0.0 || (c1 == 0.0 && c2 > 0.0))) {
        *out = 0.0;
        return 1;
    }
    return rm_first_crossing(c0, c1, c2, span, 1, out);
}

/* Exact motion under the held load until the next onset or the step end. */
static double free_flight(Run* r, double t)
{
    const RmMesh* M = r->M;
    RmWheel* st = &r->st;
    double a_w = -r->tau_load / r->J;
    double x0 = M->arm_pinion * run_phi_p(r, t) - M->arm_wheel * st->phi;
    double v0 = M->arm_pinion * run_w_p(r, t) - M->arm_wheel * st->w;
    double half_acc = 0.5 * (M->arm_pinion * r->a_p - M->arm_wheel * a_w);
    double span = r->H - t;
    double half_backlash = M->g.half_backlash;
    double hit_d = 0.0, hit_c = 0.0;
    int has_d = flight_onset(x0 - half_backlash, v0, half_acc, span, &hit_d);
    int has_c = flight_onset(-x0 - half_backlash, -v0, -half_acc, span, &hit_c);
    double dt;
    int flank;
    if (!has_d && !has_c) {
        dt = span;
        flank = 0;
    }
    else if (!has_c || (has_d && hit_d <= hit_c)) {
        dt = hit_d;
        flank = RM_DRIVE;
    }
    else {
        dt = hit_c;
        flank = RM_COAST;
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

/* (wheel acceleration, mesh torque on the pinion, total normal force) at time t. */
static inline void rhs(Run* r, double t, double phi_w, double w_w, double* out)
{
    const RmWheel* st = &r->st;
    int flank = st->flank;
    double v_imp = flank == RM_DRIVE ? st->v_drive : st->v_coast;
    RmLoads L;
    rm_mesh_loads(r->M, r->f, &r->pairs, flank, run_phi_p(r, t), run_w_p(r, t), phi_w, w_w,
                  v_imp, st->diss, r->signs, r->stick_speeds, 0, &L, NULL, 0);
    r->log->rhs_evaluations++;
    out[0] = (L.tau_w - r->tau_load) / r->J;
    out[1] = L.tau_p;
    out[2] = L.W;
}

/* Classical RK4 over [t, t+h] from (phi, w) with first stage k1: the new (phi, w) and the
 * integral of the pinion torque over the step. */
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

/* The rate [1/s] at which the regularized friction of the sticking pairs relaxes the wheel's
 * speed, sum F rho_w^2 / (v J) with v their stick speeds, at the penetration `reach`: 0 when
 * none sticks. */
static double sticking_rate(Run* r, double t, double reach)
{
    const RmMesh* M = r->M;
    const RmWheel* st = &r->st;
    int any = 0;
    for (int k = 0; k < RM_MAX_PAIR_SLOTS; k++)
        if (r->signs[k] == RM_FRICTION_STICKING) any = 1;
    if (!any) return 0.0;
    int flank = st->flank;
    double phi_p = run_phi_p(r, t);
    double phi_w = (M->arm_pinion * phi_p - (double)flank * (M->g.half_backlash + reach))
                   / M->arm_wheel;
    double rows[RM_PAIR_DETAIL * RM_MAX_PAIRS];
    RmLoads L;
    rm_mesh_loads(M, r->f, &r->pairs, flank, phi_p, run_w_p(r, t), phi_w, st->w,
                  flank == RM_DRIVE ? st->v_drive : st->v_coast, st->diss, r->signs,
                  r->stick_speeds, 0, &L, rows, RM_MAX_PAIRS);
    double rate = 0.0;
    for (int i = 0; i < L.n_pairs; i++) {
        const double* row = rows + RM_PAIR_DETAIL * (size_t)i;
        if (r->signs[(int64_t)row[0]] != RM_FRICTION_STICKING) continue;
        double rho_w = M->g.line_length - row[1];
        rate += row[7] * rho_w * rho_w / (r->stick_speeds[(int64_t)row[0]] * r->J);
    }
    return rate;
}

/* The next contact substep's length: span divided into equal parts no longer than
 * CONTACT_RATE_SAFETY over the contact's fastest rate sqrt(k/m) + c/m (with the teeth: the
 * longer of CONTACT_RATE_SAFETY_TEETH over sqrt(k/m) and CONTACT_DAMPING_SAFETY_TEETH over
 * c/m), estimated at the penetration the substep can reach, delta + max(d(delta)/dt, 0) span. */
static double resolved_substep(Run* r, double t, double span)
{
    const RmMesh* M = r->M;
    RmWheel* st = &r->st;
    int flank = st->flank;
    double delta = rm_penetration(M, flank, run_phi_p(r, t), st->phi);
    double rate = rm_approach_rate(M, flank, run_w_p(r, t), st->w);
    double reach = rate > 0.0 ? delta + rate * span : delta;
    double k, c;
    rm_contact_rates(M, r->f, &r->pairs, flank, run_phi_p(r, t), run_w_p(r, t), reach, rate,
                     st->diss, &k, &c);
    double mass = M->normal_mass;
    double elastic = rm_sqrt_checked(r->f, k / mass), sticking = sticking_rate(r, t, reach);
    double fastest = elastic + c / mass + sticking;
    r->log->contact_substeps += 1;
    double safety = M->approach.rough ? CONTACT_RATE_SAFETY_ROUGH : CONTACT_RATE_SAFETY;
    double need; /* substeps of the span the contact's time scales ask for */
    if (M->tooth.on && !M->approach.rough)
        need = rm_max((elastic + sticking) * span / CONTACT_RATE_SAFETY_TEETH,
                      c / mass * span / CONTACT_DAMPING_SAFETY_TEETH);
    else
        need = fastest * span / safety;
    if (need <= 1.0) return span;
    double parts = rm_ceil_checked(r->f, need);
    /* both sides are integers, exact below 2^53, above which the sum exceeds the cap anyway */
    if ((double)r->log->contact_substeps + parts > (double)RM_MAX_CONTACT_SUBSTEPS)
        rm_fail(r->f, RM_FAIL_TOO_STIFF, fastest, k, c, mass);
    return span / parts;
}

/* The rate [m/s] at which the contact point of the pair in `slot` (roll coordinate s) moves
 * along the line of action: its roll coordinate's forward difference over the flank's roll,
 * times the roll speed flank rb_p w_p (0 when the pair leaves the zone). */
static double contact_roll_rate(Run* r, double t, int64_t slot, double s)
{
    const RmMesh* M = r->M;
    int flank = r->st.flank;
    double roll_speed = (double)flank * M->g.rb_pinion * run_w_p(r, t);
    if (roll_speed == 0.0) return 0.0;
    double du = roll_speed > 0.0 ? ROLL_STEP : -ROLL_STEP;
    RmPairSet* ps = rm_pairs_at(M, r->f, &r->pairs,
                                rm_flank_roll(&M->g, flank, run_phi_p(r, t)) + du);
    for (int i = 0; i < ps->n; i++)
        if (ps->slot[i] == slot) return (ps->s[i] - s) / du * roll_speed;
    return 0.0;
}

/* Whether the friction of the n pairs in `slots` (roll coordinates s, sliding speeds about
 * zero) sticks at t: with their friction either way, the wheel's acceleration drives every
 * one's sliding speed v_s = w_p s - w_w (L - s) back through zero (Filippov's attractive
 * sliding surface), d v_s/dt = a_p s + (w_p + w_w) ds/dt - (dw_w/dt) (L - s): negative with
 * the direction +1 and positive with -1.  The other pairs keep their directions.  (Pairs
 * sliding through zero together -- every pair when the pinion rests -- can hold the wheel
 * together where none can alone.) */
static int friction_sticks(Run* r, double t, int n, const int64_t* slots, const double* s)
{
    const RmMesh* M = r->M;
    const RmWheel* st = &r->st;
    int flank = st->flank;
    double w_p = run_w_p(r, t);
    double keep[RM_MAX_PAIRS];
    double accel[2];
    for (int i = 0; i < n; i++) keep[i] = r->signs[slots[i]];
    for (int k = 0; k < 2; k++) {
        RmLoads L;
        for (int i = 0; i < n; i++) r->signs[slots[i]] = k == 0 ? 1.0 : -1.0;
        rm_mesh_loads(M, r->f, &r->pairs, flank, run_phi_p(r, t), w_p, st->phi, st->w,
                      flank == RM_DRIVE ? st->v_drive : st->v_coast, st->diss, r->signs,
                      r->stick_speeds, 0, &L, NULL, 0);
        accel[k] = (L.tau_w - r->tau_load) / r->J;
    }
    for (int i = 0; i < n; i++) r->signs[slots[i]] = keep[i];
    for (int i = 0; i < n; i++) {
        double rho_w = M->g.line_length - s[i];
        double roll_rate = contact_roll_rate(r, t, slots[i], s[i]);
        double kinematic = r->a_p * s[i] + (w_p + st->w) * roll_rate;
        if (!(kinematic - accel[0] * rho_w < 0.0 && kinematic - accel[1] * rho_w > 0.0))
            return 0;
    }
    return 1;
}

/* Each pair's friction direction for the substep from t: the sign of its sliding speed, or
 * the one a reversal located at t prescribes (its sliding speed is zero to rounding there). */
static void friction_directions(Run* r, double t)
{
    const RmMesh* M = r->M;
    RmWheel* st = &r->st;
    for (int k = 0; k < RM_MAX_PAIR_SLOTS; k++) r->signs[k] = 0.0;
    double w_p = run_w_p(r, t);
    RmPairSet* ps = rm_pairs_at(M, r->f, &r->pairs, rm_flank_roll(&M->g, st->flank, run_phi_p(r, t)));
    for (int i = 0; i < ps->n; i++) {
        int64_t slot = ps->slot[i];
        if (r->has_reversed[slot]) {
            r->signs[slot] = r->reversed[slot];
            continue;
        }
        double v_s = rm_sliding_speed(M, ps->s[i], w_p, st->w);
        r->signs[slot] = v_s > 0.0 ? 1.0 : (v_s < 0.0 ? -1.0 : 0.0);
    }
    for (int k = 0; k < RM_MAX_PAIR_SLOTS; k++) r->has_reversed[k] = 0;
    if (!M->p.friction_enabled) return;
    /* the pairs that slide slower than their stick speed (RM_STICK_SPEED, or the last
     * substep's where they stuck), copied (the test evaluates other pair sets): those whose
     * friction would hold them stick, all together or each alone */
    int n = 0;
    int64_t slots[RM_MAX_PAIRS];
    double s_at[RM_MAX_PAIRS];
    for (int i = 0; i < ps->n; i++) {
        int64_t slot = ps->slot[i];
        if (fabs(rm_sliding_speed(M, ps->s[i], w_p, st->w)) <= r->stick_speeds[slot]) {
            slots[n] = slot;
            s_at[n] = ps->s[i];
            n++;
        }
        else
            r->stick_speeds[slot] = RM_STICK_SPEED;
    }
    if (n == 0) return;
    int sticking[RM_MAX_PAIRS];
    int together = friction_sticks(r, t, n, slots, s_at);
    int any = 0;
    for (int i = 0; i < n; i++) {
        sticking[i] = together || (n > 1 && friction_sticks(r, t, 1, slots + i, s_at + i));
        any |= sticking[i];
    }
    if (!any) {
        for (int i = 0; i < n; i++) r->stick_speeds[slots[i]] = RM_STICK_SPEED;
        return;
    }
    for (int i = 0; i < n; i++) {
        r->stick_speeds[slots[i]] = RM_STICK_SPEED;
        if (sticking[i]) r->signs[slots[i]] = RM_FRICTION_STICKING;
    }
    /* each sticking pair's friction turns over RM_STICK_SPEED, or where that is wider over the
     * speed at which it relaxes the wheel's speed at the rate the grid resolves,
     * F rho_w^2 / (J v) = CONTACT_RATE_SAFETY / solver.h_max: sticking friction then does not
     * shorten the substeps below the grid, and the regularization tends to exact sticking as
     * solver.h_max -> 0 */
    double rows[RM_PAIR_DETAIL * RM_MAX_PAIRS];
    RmLoads L;
    rm_mesh_loads(M, r->f, &r->pairs, st->flank, run_phi_p(r, t), w_p, st->phi, st->w,
                  st->flank == RM_DRIVE ? st->v_drive : st->v_coast, st->diss, r->signs,
                  r->stick_speeds, 0, &L, rows, RM_MAX_PAIRS);
    for (int i = 0; i < L.n_pairs; i++) {
        const double* row = rows + RM_PAIR_DETAIL * (size_t)i;
        int64_t slot = (int64_t)row[0];
        if (r->signs[slot] != RM_FRICTION_STICKING) continue;
        double rho_w = M->g.line_length - row[1];
        double wide = row[7] * rho_w * rho_w * M->p.h_max / (r->J * CONTACT_RATE_SAFETY);
        r->stick_speeds[slot] = rm_max(RM_STICK_SPEED, wide);
    }
}

typedef struct {
    Run* r;
    double t;
    const double* k1;
    int flank;
    int64_t slot;
} EventCtx;

/* The sliding speed of the pair in `slot` at t + dt for wheel speed w (0 when it has left). */
static double slot_sliding_speed(EventCtx* c, double dt, double w)
{
    Run* r = c->r;
    RmPairSet* ps = rm_pairs_at(r->M, r->f, &r->pairs,
                                rm_flank_roll(&r->M->g, c->flank, run_phi_p(r, c->t + dt)));
    for (int i = 0; i < ps->n; i++)
        if (ps->slot[i] == c->slot) return rm_sliding_speed(r->M, ps->s[i], run_w_p(r, c->t + dt), w);
    return 0.0;
}

/* The sliding speed after the RK4 step of length dt from t. */
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
} SlotEvent;

/* The located reversals (slot, offset) in pair order: pairs (not flipped) whose sliding speed
 * ends the substep with the sign opposite to their friction direction. */
static int reversal_times(Run* r, double t, double h, double w_b, const double* k1,
                          const int* flipped, SlotEvent* out)
{
    const RmMesh* M = r->M;
    RmWheel* st = &r->st;
    int flank = st->flank;
    if (!M->p.friction_enabled) return 0;
    /* the pairs at t + h, copied: locating a reversal evaluates other pair sets */
    RmPairSet* ps = rm_pairs_at(M, r->f, &r->pairs, rm_flank_roll(&M->g, flank, run_phi_p(r, t + h)));
    int n = ps->n;
    int64_t slots[RM_MAX_PAIRS];
    double s_end[RM_MAX_PAIRS];
    for (int i = 0; i < n; i++) {
        slots[i] = ps->slot[i];
        s_end[i] = ps->s[i];
    }
    int count = 0;
    for (int i = 0; i < n; i++) {
        int64_t slot = slots[i];
        double sign = r->signs[slot];
        if (flipped[slot] || sign == 0.0 || sign == RM_FRICTION_STICKING
            || sign * rm_sliding_speed(M, s_end[i], run_w_p(r, t + h), w_b) >= 0.0)
            continue;
        EventCtx c = {r, t, k1, flank, slot};
        double f_a = slot_sliding_speed(&c, 0.0, st->w);
        double f_b = slot_sliding_speed(&c, h, w_b);
        if (f_a == 0.0 || (f_a > 0.0) == (f_b > 0.0))
            continue; /* no sign change on the substep's own RK4 path */
        out[count].slot = slot;
        out[count].dt = rm_brent(r->f, slide_after, &c, 0.0, h, f_a, f_b, EVENT_XTOL, EVENT_RTOL);
        count++;
    }
    return count;
}

/* The penetration delta - g of the pair in `slot` at t + dt for wheel angle phi_w; *found 0
 * when the pair has left the zone. */
static double slot_own_penetration(EventCtx* c, double dt, double phi_w, int* found)
{
    Run* r = c->r;
    double phi_p = run_phi_p(r, c->t + dt);
    RmPairSet* ps = rm_pairs_at(r->M, r->f, &r->pairs, rm_flank_roll(&r->M->g, c->flank, phi_p));
    for (int i = 0; i < ps->n; i++) {
        if (ps->slot[i] == c->slot) {
            *found = 1;
            return rm_penetration(r->M, c->flank, phi_p, phi_w) - ps->offset[i];
        }
    }
    *found = 0;
    return 0.0;
}

/* The pair's own penetration after the RK4 step of length dt from t. */
static double crossing_after(void* vctx, double dt)
{
    EventCtx* c = (EventCtx*)vctx;
    Run* r = c->r;
    double phi_b, w_b, q;
    int found;
    rk4(r, c->t, dt, r->st.phi, r->st.w, c->k1, &phi_b, &w_b, &q);
    double pen = slot_own_penetration(c, dt, phi_b, &found);
    if (!found) rm_fail(r->f, RM_FAIL_PAIR_LEFT, 0.0, 0.0, 0.0, 0.0);
    return pen;
}

/* The located changes of sign of the crowned pairs' own penetrations (slot, offset). */
static int engagement_times(Run* r, double t, double h, double phi_b, const double* k1,
                            SlotEvent* out)
{
    const RmMesh* M = r->M;
    RmWheel* st = &r->st;
    int flank = st->flank;
    /* the pairs at t, copied: locating a change evaluates other pair sets */
    RmPairSet* ps = rm_pairs_at(M, r->f, &r->pairs, rm_flank_roll(&M->g, flank, run_phi_p(r, t)));
    int n = ps->n;
    int64_t slots[RM_MAX_PAIRS];
    double offsets[RM_MAX_PAIRS];
    for (int i = 0; i < n; i++) {
        slots[i] = ps->slot[i];
        offsets[i] = ps->offset[i];
    }
    int count = 0;
    for (int i = 0; i < n; i++) {
        if (offsets[i] == 0.0) continue;
        EventCtx c = {r, t, k1, flank, slots[i]};
        int found_a, found_b;
        double f_a = slot_own_penetration(&c, 0.0, st->phi, &found_a);
        double f_b = slot_own_penetration(&c, h, phi_b, &found_b);
        if (!found_a || !found_b || (f_a > 0.0) == (f_b > 0.0)) continue;
        out[count].slot = slots[i];
        out[count].dt = rm_brent(r->f, crossing_after, &c, 0.0, h, f_a, f_b, EVENT_XTOL,
                                 EVENT_RTOL);
        count++;
    }
    return count;
}

/* The penetration after the RK4 step of length dt from t. */
static double delta_after(void* vctx, double dt)
{
    EventCtx* c = (EventCtx*)vctx;
    Run* r = c->r;
    double phi_b, w_b, q;
    rk4(r, c->t, dt, r->st.phi, r->st.w, c->k1, &phi_b, &w_b, &q);
    return rm_penetration(r->M, c->flank, run_phi_p(r, c->t + dt), phi_b);
}

/* The offset in (0, h] of the release (penetration crossing zero downwards) in the substep
 * from t: 1 and *out, or 0 for a grazing contact that never penetrated. */
static int release_time(Run* r, double t, double h, double delta_a, double delta_b,
                        const double* k1, double* out)
{
    EventCtx c = {r, t, k1, r->st.flank, 0};
    double lo = 0.0, f_lo = delta_a;
    if (f_lo <= 0.0) { /* the substep starts at the onset: find where it penetrated */
        int found = 0;
        for (int i = 1; i < GRAZING_SAMPLES; i++) {
            double s = h * (double)i / (double)GRAZING_SAMPLES;
            double f_s = delta_after(&c, s);
            if (f_s > 0.0) {
                lo = s;
                f_lo = f_s;
                found = 1;
                break;
            }
        }
        if (!found) return 0;
    }
    *out = rm_brent(r->f, delta_after, &c, lo, h, f_lo, delta_b, EVENT_XTOL, EVENT_RTOL);
    /* penetrations at the rounding level of the angles (the ulp of phi r: 4e-15 m after 1000
     * rad) can put the root at the substep's start; the flanks then release at its end, so
     * that the step progresses -- a release at the start would be followed by an onset at the
     * same instant, and so on for ever */
    if (!(*out > 0.0)) *out = h;
    return 1;
}

/* The peak penetration and force inside the substep from the cubic Hermite interpolant of
 * the penetration (values and rates at both ends). */
static void track_peak(Run* r, double t, double h, int flank, double d_a, double w_a,
                       double d_b, double w_b)
{
    const RmMesh* M = r->M;
    r->delta_peak = rm_max(rm_max(r->delta_peak, d_a), d_b);
    double dd_a = rm_approach_rate(M, flank, run_w_p(r, t), w_a) * h;
    double dd_b = rm_approach_rate(M, flank, run_w_p(r, t + h), w_b) * h;
    if (!(dd_a > 0.0 && 0.0 > dd_b)) return;
    /* Hermite cubic on s in [0, 1]: its derivative is a quadratic; its root where it falls */
    double A = 6.0 * (d_a - d_b) + 3.0 * (dd_a + dd_b);
    double B = -6.0 * (d_a - d_b) - 4.0 * dd_a - 2.0 * dd_b;
    double s;
    if (!rm_first_crossing(dd_a, B, A, 1.0, 0, &s)) return;
    double s2 = s * s, s3 = s * s * s;
    double d = ((2.0 * s3 - 3.0 * s2 + 1.0) * d_a + (s3 - 2.0 * s2 + s) * dd_a
                + (-2.0 * s3 + 3.0 * s2) * d_b + (s3 - s2) * dd_b);
    if (d > r->delta_peak) {
        r->delta_peak = d;
        r->W_peak = rm_max(r->W_peak, rm_static_force(M, r->f, &r->pairs, flank,
                                                      run_phi_p(r, t + s * h), d));
    }
}

/* One RK4 substep in contact, ended at the next grid point, pair breakpoint, release or
 * friction reversal, whichever comes first, and no longer than the contact's own time scales
 * allow. */
static double contact_substep(Run* r, double t)
{
    const RmMesh* M = r->M;
    RmWheel* st = &r->st;
    int flank = st->flank;
    double x = t * (double)r->n_sub / r->H;
    if (!isfinite(x)) rm_fail(r->f, RM_FAIL_MATH, RM_MATH_INT, x, 0.0, 0.0);
    int64_t j = (int64_t)x; /* truncation (t < H, so x < n_sub) */
    if (r->n_sub - 1 < j) j = r->n_sub - 1;
    double t_end = grid(r, j + 1);
    /* t sits on a grid point within rounding: the substep of a few ulps merges into the next */
    if (t_end - t <= MERGE_FRACTION * (r->H / (double)r->n_sub)) t_end = grid(r, j + 2);
    /* split at the next pair entry/exit so that the right-hand side is smooth */
    double u_a = rm_flank_roll(&M->g, flank, run_phi_p(r, t));
    double bp;
    if (rm_next_breakpoint(&M->g, r->f, u_a, rm_flank_roll(&M->g, flank, run_phi_p(r, t_end)),
                           &bp)) {
        double k = (double)flank * M->g.rb_pinion;
        double dt;
        if (rm_first_crossing(u_a - bp, k * run_w_p(r, t), 0.5 * k * r->a_p, t_end - t, bp > u_a,
                              &dt))
            t_end = t + dt;
    }
    /* unmodified flanks: a pair's load jumps where it enters or leaves the zone of action, so
     * the pairs in the zone are those of the substep's middle for all its evaluations, the
     * ends included (a substep never contains a breakpoint) */
    int hold_pairs = M->g.layout != RM_LAYOUT_CROWNED;
    if (hold_pairs)
        r->pairs.member = rm_flank_roll(&M->g, flank, run_phi_p(r, t + 0.5 * (t_end - t)));
    friction_directions(r, t); /* (before the substep's length: sticking friction shortens it) */
    double h = resolved_substep(r, t, t_end - t);
    t_end = t + h;
    if (hold_pairs) {
        double member = rm_flank_roll(&M->g, flank, run_phi_p(r, t + 0.5 * h));
        if (member != r->pairs.member) { /* a shorter substep: its own middle's pairs */
            r->pairs.member = member;
            friction_directions(r, t);
        }
    }
    double delta_a = rm_penetration(M, flank, run_phi_p(r, t), st->phi);
    int flipped[RM_MAX_PAIR_SLOTS] = {0};
    double k1[3], phi_b, w_b, q, delta_b, dt_event;
    int released, n_rev;
    int64_t reversal;
    SlotEvent rev[RM_MAX_PAIRS];
    for (;;) {
        rhs(r, t, st->phi, st->w, k1);
        rk4(r, t, h, st->phi, st->w, k1, &phi_b, &w_b, &q);
        delta_b = rm_penetration(M, flank, run_phi_p(r, t_end), phi_b);
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
        /* a reversal at the substep start to rounding (sliding speed zero at t): the pair's
         * friction takes its new direction for the whole substep; redo it */
        int instant = 0;
        for (int i = 0; i < n_rev; i++)
            if (t + rev[i].dt <= t) instant = 1;
        if (!instant) break;
        for (int i = 0; i < n_rev; i++) {
            if (t + rev[i].dt <= t) {
                r->signs[rev[i].slot] = -r->signs[rev[i].slot];
                flipped[rev[i].slot] = 1;
            }
        }
    }
    r->W_peak = rm_max(r->W_peak, k1[2]);
    for (int i = 0; i < n_rev; i++) {
        if (rev[i].dt < dt_event) {
            dt_event = rev[i].dt;
            reversal = rev[i].slot;
            released = 0;
        }
    }
    /* a crowned pair starting or ending to carry load makes the force a C1 kink: end the
     * substep there (one located right at the substep start needs no split) */
    int64_t engaged = -1;
    SlotEvent eng[RM_MAX_PAIRS];
    int n_eng = engagement_times(r, t, h, phi_b, k1, eng);
    for (int i = 0; i < n_eng; i++) {
        if (eng[i].dt < dt_event && eng[i].dt > ENGAGEMENT_MIN_FRACTION * h) {
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
        delta_b = rm_penetration(M, flank, run_phi_p(r, t_end), phi_b);
    track_peak(r, t, h, flank, delta_a, st->w, delta_b, w_b);
    r->pairs.member = NAN;
    st->phi = phi_b;
    st->w = w_b;
    r->int_tau_pinion += q;
    if (reversal >= 0) {
        r->has_reversed[reversal] = 1;
        r->reversed[reversal] = -r->signs[reversal];
        event(r, t_end, RM_EVENT_REVERSAL, flank);
    }
    if (engaged >= 0) event(r, t_end, RM_EVENT_PAIR, flank);
    /* a release needs a non-approaching rate: a penetration at or below zero to rounding
     * while the flanks still approach (the substep right after an onset) keeps the contact */
    if (released
        || (delta_b <= 0.0 && !(rm_approach_rate(M, flank, run_w_p(r, t_end), st->w) > 0.0))) {
        event(r, t_end, RM_EVENT_RELEASE, flank);
        st->flank = 0;
    }
    return t_end;
}

int rm_wheel_step(const RmMesh* M, RmWheel* wheel, RmLast* last, double h, double phi_p,
                  double w_p, double a_p, double tau_load, RmStepLog* log, double* values)
{
    RmFail f;
    Run run;
    run.M = M;
    run.f = &f;
    run.st = *wheel;
    const double w_start = run.st.w;
    run.H = h;
    run.phi_p0 = phi_p;
    run.w_p0 = w_p;
    run.a_p = a_p;
    run.tau_load = tau_load;
    run.J = M->p.J_wheel;
    run.W_peak = run.delta_peak = run.int_tau_pinion = 0.0;
    run.onsets_drive = run.onsets_coast = 0;
    run.log = log;
    log->rhs_evaluations = log->contact_substeps = 0;
    log->n_events = log->total_events = 0;
    for (int k = 0; k < RM_MAX_PAIR_SLOTS; k++) {
        run.signs[k] = 0.0;
        run.stick_speeds[k] = RM_STICK_SPEED;
        run.has_reversed[k] = 0;
        run.reversed[k] = 0.0;
    }
    run.rattle_time = M->p.rattle_time;
    run.rattle_gain = 0.0;
    rm_pair_cache_init(&run.pairs);
    if (setjmp(f.jb) != 0) {
        for (int i = 0; i < 4; i++) values[i] = f.values[i];
        return f.code;
    }
    {
        double x = rm_ceil_checked(&f, h / M->p.h_max * (1.0 - GRID_SLACK));
        if (!(x < MAX_GRID_SUBSTEPS)) rm_fail(&f, RM_FAIL_SUBSTEPS, h, x, 0.0, 0.0);
        run.n_sub = x > 1.0 ? (int64_t)x : 1;
    }

    /* inputs may move the pinion discontinuously between steps: re-establish the mode */
    RmWheel* st = &run.st;
    int flank = rm_contact_flank(M, phi_p, w_p, a_p, tau_load, st);
    /* a release needs a non-approaching rate: a flank in contact that the inputs moved to a
     * penetration at or below zero while the flanks still approach keeps its contact (the same
     * impact: the penetration resumes within the step; with no backlash the other flank's
     * rounding-level penetration is not a contact then) */
    if (st->flank != 0 && flank != st->flank
        && rm_approach_rate(M, st->flank, w_p, st->w) > 0.0)
        flank = st->flank;
    if (flank != st->flank) {
        if (st->flank != 0) event(&run, 0.0, RM_EVENT_RELEASE, st->flank);
        if (flank != 0) {
            /* a contact the inputs begin on a receding flank (the pinion's exact angle at the
             * communication point against its extrapolation over the last step: typically the
             * tail of a contact released just before the point) is no impact */
            if (rm_approach_rate(M, flank, w_p, st->w) < 0.0)
                event(&run, 0.0, RM_EVENT_TOUCH, flank);
            else
                onset(&run, 0.0, flank);
        }
        st->flank = flank;
    }
    double t = 0.0;
    long stall = 0;
    while (t < run.H) {
        double t_new = st->flank == 0 ? free_flight(&run, t) : contact_substep(&run, t);
        if (t_new > t)
            stall = 0;
        else if (++stall > STALL_LIMIT)
            rm_fail(&f, RM_FAIL_NO_PROGRESS, t, 0.0, 0.0, 0.0);
        t = t_new;
    }
    /* the mean mesh torque from the momentum balance I_w dw = (tau_mesh - tau_load) dt */
    double dw = st->w - w_start;
    double tau_wheel_mean = (run.J * dw + run.tau_load * run.H) / run.H;
    double tau_pinion_mean = run.int_tau_pinion / run.H;
    st->rattle_index = st->rattle_index * rm_exp_checked(&f, -run.H / run.rattle_time)
                       + run.rattle_gain;
    if (st->flank != 0) {
        run.delta_peak = rm_max(run.delta_peak,
                                rm_penetration(M, st->flank, run_phi_p(&run, run.H), st->phi));
        double k[3];
        rhs(&run, run.H, st->phi, st->w, k);
        run.W_peak = rm_max(run.W_peak, k[2]);
    }
    /* the guards: divergence and penetration beyond the Hertz contact's validity */
    if (!(isfinite(st->phi) && isfinite(st->w) && isfinite(tau_pinion_mean)
          && isfinite(run.W_peak)))
        rm_fail(&f, RM_FAIL_DIVERGED, st->phi, st->w, 0.0, 0.0);
    double phi_end = phi_p + h * (w_p + 0.5 * a_p * h);
    double depth = rm_max(rm_max(run.delta_peak, rm_penetration(M, RM_DRIVE, phi_end, st->phi)),
                          rm_penetration(M, RM_COAST, phi_end, st->phi));
    if (depth > M->pen_limit) rm_fail(&f, RM_FAIL_PENETRATION, depth, M->pen_limit, 0.0, 0.0);

    /* commit */
    *wheel = run.st;
    last->tau_wheel_mean = tau_wheel_mean;
    last->tau_pinion_mean = tau_pinion_mean;
    last->W_peak = run.W_peak;
    last->delta_peak = run.delta_peak;
    last->onsets_drive = run.onsets_drive;
    last->onsets_coast = run.onsets_coast;
    last->pinion_phi = phi_p + w_p * h + 0.5 * a_p * h * h;
    last->pinion_w = w_p + a_p * h;
    return RM_FAIL_NONE;
}
