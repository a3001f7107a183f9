/*
 * unit_mesh.c - the GearMeshRattle unit: its parameters to the mesh model (kept per parameter
 * set: the contact law's fit is the costly part), the start, how it reads held inputs and a
 * first step on other inputs than initialization's, the outputs, its record.
 *
 * Held inputs: when the master holds pinion.phi, pinion.w, pinion.a (set none of them since
 * the last step, or set the last step's values again), the pinion runs on at constant speed
 * from where the last step left it (inputs.continue_when_held).  A first step on other inputs
 * than initialization's (a master that exchanges nothing during initialization) settles the
 * wheel in the static flank equilibrium for them first (init.settle_first_step), with a
 * warning.
 */
#include <stdlib.h>
#include <string.h>

#include "rm_private.h"

#define R(vr) (values[vr].r)
#define I(vr) (values[vr].i)
#define B(vr) (values[vr].i != 0)

/* Output groups: when an output is read after a step, only its group is computed -- the
 * wheel's angle and speed (read by the partner every step), the copies of the state and the
 * last step, the mesh loads, and the film (h, lambda, psi: apart, the film of the nearer
 * flank needs its eq. 7 energy balance, as costly as the loads; it gives every output). */
#define GROUP_QUICK 1u
#define GROUP_STATE 2u
#define GROUP_LOADS 4u
#define GROUP_FILM 8u

typedef struct {
    RmMesh mesh;
    RmWheel wheel;
    RmLast last;
    RmBoundary boundary;
    RmStepLog logs[2]; /* the last accepted step's (logs[current]) and a scratch one */
    int current;
} MeshModel;

/* The model of the last parameter set, kept. */
typedef struct {
    int valid;
    RmMeshParams params;
    RmMesh mesh;
} MeshCache;

int rm_mesh_params(const RmValue* values, RmMeshParams* p)
{
    memset(p, 0, sizeof *p);
    p->gear.z_pinion = (int)I(RM_MESH_GEAR_Z_PINION);
    p->gear.z_wheel = (int)I(RM_MESH_GEAR_Z_WHEEL);
    p->gear.m_n = R(RM_MESH_GEAR_M_N);
    p->gear.alpha_n = R(RM_MESH_GEAR_ALPHA_N);
    p->gear.beta = R(RM_MESH_GEAR_BETA);
    p->gear.addendum = R(RM_MESH_GEAR_H_A);
    p->gear.b = R(RM_MESH_GEAR_B);
    p->gear.backlash = R(RM_MESH_GEAR_BACKLASH);
    p->gear.crowning = R(RM_MESH_CONTACT_CROWNING);
    p->gear.layout = (int)I(RM_MESH_CONTACT_GEOMETRY);
    p->E_pinion = R(RM_MESH_MATERIAL_E_PINION);
    p->nu_pinion = R(RM_MESH_MATERIAL_NU_PINION);
    p->E_wheel = R(RM_MESH_MATERIAL_E_WHEEL);
    p->nu_wheel = R(RM_MESH_MATERIAL_NU_WHEEL);
    p->density = R(RM_MESH_MATERIAL_RHO);
    p->J_wheel = R(RM_MESH_WHEEL_J);
    p->hertz_law = (int)I(RM_MESH_CONTACT_HERTZ_LAW);
    p->roughness = (int)I(RM_MESH_CONTACT_ROUGHNESS);
    p->asperity_density = R(RM_MESH_SURFACE_ASPERITY_DENSITY);
    p->dissipation = (int)I(RM_MESH_CONTACT_DISSIPATION);
    p->restitution = R(RM_MESH_CONTACT_RESTITUTION);
    p->restitution_speed = R(RM_MESH_CONTACT_RESTITUTION_SPEED);
    p->damping = R(RM_MESH_CONTACT_DAMPING);
    p->stokes_critical = R(RM_MESH_CONTACT_STOKES_CRITICAL);
    p->restitution_dry = R(RM_MESH_CONTACT_RESTITUTION_DRY);
    p->squeeze_fraction = R(RM_MESH_CONTACT_SQUEEZE_FRACTION);
    p->damping_ratio = R(RM_MESH_CONTACT_DAMPING_RATIO);
    p->tooth_compliance = (int)I(RM_MESH_TOOTH_COMPLIANCE);
    p->body_ratio_pinion = R(RM_MESH_TOOTH_BODY_RATIO_PINION);
    p->body_ratio_wheel = R(RM_MESH_TOOTH_BODY_RATIO_WHEEL);
    p->friction_enabled = B(RM_MESH_FRICTION_ENABLED);
    p->friction_form = (int)I(RM_MESH_FRICTION_FORM);
    p->shear_speed = (int)I(RM_MESH_FRICTION_SHEAR_SPEED);
    p->viscous_law = (int)I(RM_MESH_FRICTION_VISCOUS_LAW);
    p->film = (int)I(RM_MESH_LUBRICANT_FILM);
    p->tau_s = R(RM_MESH_FRICTION_TAU_S);
    p->eta = R(RM_MESH_LUBRICANT_ETA);
    p->alpha_pv = R(RM_MESH_LUBRICANT_ALPHA);
    p->tau_limit_0 = R(RM_MESH_LUBRICANT_TAU_LIMIT_0);
    p->tau_limit_slope = R(RM_MESH_LUBRICANT_TAU_LIMIT_SLOPE);
    p->sigma = R(RM_MESH_SURFACE_SIGMA);
    p->gamma = R(RM_MESH_SURFACE_GAMMA);
    p->rattle_time = R(RM_MESH_RATTLE_TIME_CONSTANT);
    p->h_max = R(RM_MESH_SOLVER_H_MAX);
    p->h_comm_max = R(RM_MESH_SOLVER_H_COMM_MAX);
    return 1;
}

static int same_params(const RmMeshParams* a, const RmMeshParams* b)
{
    return memcmp(a, b, sizeof *a) == 0; /* both memset before they were filled */
}

/* The mesh model of the current parameters (checked for their combination), from the cache
 * or built into it: NULL with the refusal. */
static const RmMesh* configure(RmUnit* u, RmText* err)
{
    RmMeshParams p;
    rm_mesh_params(u->values, &p);
    MeshCache* c = u->cache;
    if (c != NULL && c->valid && same_params(&c->params, &p)) return &c->mesh;
    if (c == NULL) {
        c = u->cache = calloc(1, sizeof *c);
        if (c == NULL) {
            rm_printf(err, "out of memory");
            return NULL;
        }
    }
    c->valid = 0;
    if (!rm_mesh_build(&p, &c->mesh, err)) return NULL;
    c->params = p;
    c->valid = 1;
    return &c->mesh;
}

static void free_cache(RmUnit* u)
{
    free(u->cache);
    u->cache = NULL;
}

static void free_model(void* model) { free(model); }

/* The wheel at the start for the pinion inputs (phi_p, w_p, ., tau_load). */
static int start_wheel(const RmUnit* u, const RmMesh* mesh, const double* inputs, RmWheel* wheel,
                       RmText* err)
{
    const RmValue* values = u->values;
    if (B(RM_MESH_INIT_IN_CONTACT))
        return rm_equilibrium_start(mesh, inputs[0], inputs[1], inputs[3], wheel, err);
    return rm_free_start(mesh, R(RM_MESH_WHEEL_PHI_START), R(RM_MESH_WHEEL_W_START), inputs[0],
                         inputs[1], inputs[3], wheel, err);
}

static void* build(RmUnit* u, RmText* err)
{
    const RmValue* values = u->values;
    const RmMesh* mesh = configure(u, err);
    if (mesh == NULL) return NULL;
    MeshModel* m = calloc(1, sizeof *m);
    if (m == NULL) {
        rm_printf(err, "out of memory");
        return NULL;
    }
    m->mesh = *mesh;
    double inputs[4] = {R(RM_MESH_PINION_PHI), R(RM_MESH_PINION_W), R(RM_MESH_PINION_A),
                        R(RM_MESH_WHEEL_TAU_LOAD)};
    if (!start_wheel(u, mesh, inputs, &m->wheel, err)) {
        free(m);
        return NULL;
    }
    m->last.pinion_phi = inputs[0];
    m->last.pinion_w = inputs[1];
    rm_boundary_start(u, &m->boundary);
    return m;
}

int rm_mesh_start_wheel(RmUnit* u, const double* inputs, double* phi, double* w, RmText* err)
{
    const RmMesh* mesh = configure(u, err);
    RmWheel wheel;
    if (mesh == NULL || !start_wheel(u, mesh, inputs, &wheel, err)) return 0;
    *phi = wheel.phi;
    *w = wheel.w;
    return 1;
}

static int step(RmUnit* u, double t, double h, RmText* warning, RmText* err)
{
    MeshModel* m = u->model;
    const RmValue* values = u->values;
    double phi_p = R(RM_MESH_PINION_PHI), w_p = R(RM_MESH_PINION_W), a_p = R(RM_MESH_PINION_A);
    double tau_load = R(RM_MESH_WHEEL_TAU_LOAD);
    (void)t;
    if (B(RM_MESH_INPUTS_CONTINUE_WHEN_HELD) && rm_motion_held(u, &m->boundary)) {
        phi_p = m->last.pinion_phi;
        w_p = m->last.pinion_w;
        a_p = 0.0;
    }
    double used[3] = {phi_p, w_p, tau_load};
    RmWheel saved_wheel = m->wheel;
    RmLast saved_last = m->last;
    int settled = 0;
    if (B(RM_MESH_INIT_IN_CONTACT)
        && rm_first_step_differs(&m->boundary, B(RM_MESH_INIT_SETTLE_FIRST_STEP), used, 3)) {
        RmWheel start;
        if (!rm_equilibrium_start(&m->mesh, phi_p, w_p, tau_load, &start, err)) return 0;
        m->wheel = start;
        m->last.pinion_phi = phi_p;
        m->last.pinion_w = w_p;
        settled = 1;
    }
    int ok = 0;
    if (h > m->mesh.p.h_comm_max) {
        rm_printf(err, "step size h = %r s exceeds solver.h_comm_max = %r s; allowed: (0, %r] s",
                  h, m->mesh.p.h_comm_max, m->mesh.p.h_comm_max);
    }
    else {
        double values4[4];
        RmStepLog* log = &m->logs[1 - m->current];
        int code = rm_wheel_step(&m->mesh, &m->wheel, &m->last, h, phi_p, w_p, a_p, tau_load,
                                 log, values4);
        if (code == RM_FAIL_NONE) {
            m->current = 1 - m->current;
            ok = 1;
        }
        else {
            rm_refusal_text(err, code, values4);
            if (h > RM_DEFAULT_STEP_SIZE) {
                rm_printf(err, ". Reduce the communication step to at most %r s, the default "
                               "experiment's (this one, %r s, is %.3r times it; accuracy against "
                               "the step: docs/tools.md)",
                          RM_DEFAULT_STEP_SIZE, h, h / RM_DEFAULT_STEP_SIZE);
            }
        }
    }
    if (!ok) { /* a refused step leaves the unit as it was */
        m->wheel = saved_wheel;
        m->last = saved_last;
        return 0;
    }
    rm_motion_step_done(u, &m->boundary);
    if (settled)
        rm_settled_warning(u, &m->boundary, used,
                           "the wheel was settled in the flank equilibrium for them first",
                           warning);
    return 1;
}

static unsigned group_of(unsigned vr)
{
    switch (vr) {
    case RM_MESH_WHEEL_PHI:
    case RM_MESH_WHEEL_W: return GROUP_QUICK;
    case RM_MESH_WHEEL_TAU_MESH:
    case RM_MESH_PINION_TAU_MESH:
    case RM_MESH_MESH_W_PEAK:
    case RM_MESH_MESH_DELTA_PEAK:
    case RM_MESH_MESH_V_IMPACT:
    case RM_MESH_MESH_IMPACTS_DRIVE:
    case RM_MESH_MESH_IMPACTS_COAST:
    case RM_MESH_MESH_TRANSMISSION_ERROR:
    case RM_MESH_MESH_IMPACT_ENERGY:
    case RM_MESH_MESH_RATTLE_INDEX: return GROUP_STATE;
    case RM_MESH_MESH_H:
    case RM_MESH_MESH_LAMBDA:
    case RM_MESH_MESH_PSI: return GROUP_FILM;
    default: return GROUP_LOADS;
    }
}

/* Every output, from the loads of the flank in contact (or the nearer one when apart); the
 * film apart only when film_asked (else h, lambda and psi are left as they are). */
static int all_outputs(const MeshModel* m, RmValue* out, int film_asked, RmText* err)
{
    const RmMesh* M = &m->mesh;
    const RmWheel* st = &m->wheel;
    const RmLast* last = &m->last;
    double phi_p = last->pinion_phi, w_p = last->pinion_w;
    RmPairCache cache;
    RmFail f;
    const volatile int with_film = film_asked; /* read after the setjmp below */
    rm_pair_cache_init(&cache);
    if (setjmp(f.jb) != 0) {
        rm_refusal_text(err, f.code, f.values);
        return 0;
    }
    int flank = st->flank;
    if (flank == 0)
        flank = rm_penetration(M, RM_DRIVE, phi_p, st->phi) >= rm_penetration(M, RM_COAST, phi_p, st->phi)
                    ? RM_DRIVE
                    : RM_COAST;
    double v_imp = flank == RM_DRIVE ? st->v_drive : st->v_coast;
    RmLoads L;
    rm_mesh_loads(M, &f, &cache, flank, phi_p, w_p, st->phi, st->w, v_imp, st->diss, NULL, NULL, 1, &L,
                  NULL, 0);
    double h = 0.0, lam = 0.0, psi = 0.0;
    int film = L.n_loaded > 0 || with_film;
    if (L.n_loaded > 0) { /* the film at the most loaded pair */
        h = L.top_h;
        lam = L.top_lam;
        psi = L.top_psi;
    }
    else if (with_film) { /* apart: the clearance of the nearer flank plus its eq. 7 delta_max */
        double d_max = rm_energy_balance_delta_max(M, &f, &cache, flank, phi_p, v_imp);
        h = -L.delta + d_max;
        if (!(h > 0.0)) h = 0.0;
        lam = h / M->p.sigma;
        psi = rm_dry_fraction(lam);
    }
    double W = L.W;
    double transverse = W * M->g.normal_factor;
    out[RM_MESH_WHEEL_TAU_MESH].r = last->tau_wheel_mean;
    out[RM_MESH_PINION_TAU_MESH].r = last->tau_pinion_mean;
    out[RM_MESH_WHEEL_PHI].r = st->phi;
    out[RM_MESH_WHEEL_W].r = st->w;
    out[RM_MESH_MESH_W].r = L.W;
    out[RM_MESH_MESH_W_PEAK].r = last->W_peak;
    out[RM_MESH_MESH_F].r = L.F;
    out[RM_MESH_MESH_DELTA].r = L.n_loaded > 0 ? L.delta : 0.0;
    out[RM_MESH_MESH_DELTA_PEAK].r = last->delta_peak;
    out[RM_MESH_MESH_V_IMPACT].r = st->v_last;
    if (film) {
        out[RM_MESH_MESH_H].r = h;
        out[RM_MESH_MESH_LAMBDA].r = lam;
        out[RM_MESH_MESH_PSI].r = psi;
    }
    out[RM_MESH_MESH_N_CONTACT].i = L.n_loaded;
    out[RM_MESH_MESH_IMPACTS_DRIVE].i = st->n_drive;
    out[RM_MESH_MESH_IMPACTS_COAST].i = st->n_coast;
    out[RM_MESH_MESH_TRANSMISSION_ERROR].r =
        rm_penetration(M, RM_DRIVE, phi_p, st->phi) + M->g.half_backlash;
    out[RM_MESH_MESH_FORCE_TANGENTIAL].r = (double)flank * transverse * M->g.cos_alpha_t;
    out[RM_MESH_MESH_FORCE_RADIAL].r = transverse * M->g.sin_alpha_t;
    out[RM_MESH_MESH_FORCE_AXIAL].r = (double)flank * W * M->g.sin_beta_b;
    out[RM_MESH_MESH_IMPACT_ENERGY].r = 0.5 * M->normal_mass * st->v_last * st->v_last;
    out[RM_MESH_MESH_RATTLE_INDEX].r = st->rattle_index;
    for (int k = 0; k < RM_MAX_PAIR_SLOTS; k++) out[RM_MESH_PAIR_0_W + (unsigned)k].r = L.forces[k];
    return 1;
}

typedef char pair_outputs_are_contiguous[RM_MESH_PAIR_7_W - RM_MESH_PAIR_0_W == 7 ? 1 : -1];

static int outputs(RmUnit* u, void* model, unsigned groups, RmValue* out, RmText* err)
{
    const MeshModel* m = model;
    const RmWheel* st = &m->wheel;
    (void)u;
    if (groups & (GROUP_LOADS | GROUP_FILM))
        return all_outputs(m, out, (groups & GROUP_FILM) != 0, err);
    if (groups & GROUP_QUICK) {
        out[RM_MESH_WHEEL_PHI].r = st->phi;
        out[RM_MESH_WHEEL_W].r = st->w;
    }
    if (groups & GROUP_STATE) {
        const RmMesh* M = &m->mesh;
        double v = st->v_last;
        out[RM_MESH_WHEEL_TAU_MESH].r = m->last.tau_wheel_mean;
        out[RM_MESH_PINION_TAU_MESH].r = m->last.tau_pinion_mean;
        out[RM_MESH_MESH_W_PEAK].r = m->last.W_peak;
        out[RM_MESH_MESH_DELTA_PEAK].r = m->last.delta_peak;
        out[RM_MESH_MESH_V_IMPACT].r = v;
        out[RM_MESH_MESH_IMPACTS_DRIVE].i = st->n_drive;
        out[RM_MESH_MESH_IMPACTS_COAST].i = st->n_coast;
        out[RM_MESH_MESH_TRANSMISSION_ERROR].r =
            rm_penetration(M, RM_DRIVE, m->last.pinion_phi, st->phi) + M->g.half_backlash;
        out[RM_MESH_MESH_IMPACT_ENERGY].r = 0.5 * M->normal_mass * v * v;
        out[RM_MESH_MESH_RATTLE_INDEX].r = st->rattle_index;
    }
    return 1;
}

static void save(const void* model, RmWriter* w)
{
    const MeshModel* m = model;
    const RmWheel* st = &m->wheel;
    rm_write_f64(w, st->phi);
    rm_write_f64(w, st->w);
    rm_write_i64(w, st->flank);
    rm_write_f64(w, st->v_drive);
    rm_write_f64(w, st->v_coast);
    rm_write_f64(w, st->v_last);
    rm_write_i64(w, st->n_drive);
    rm_write_i64(w, st->n_coast);
    rm_write_f64(w, st->rattle_index);
    const RmLast* l = &m->last;
    rm_write_f64(w, l->tau_wheel_mean);
    rm_write_f64(w, l->tau_pinion_mean);
    rm_write_f64(w, l->W_peak);
    rm_write_f64(w, l->delta_peak);
    rm_write_i64(w, l->onsets_drive);
    rm_write_i64(w, l->onsets_coast);
    rm_write_f64(w, l->pinion_phi);
    rm_write_f64(w, l->pinion_w);
    rm_boundary_save(&RM_MESH_CLASS, &m->boundary, w);
    rm_write_f64(w, st->diss.d);
    rm_write_i64(w, st->diss.film);
}

/* A saved count: an integer in [0, RM_COUNT_MAX], where the counters stop (stepper.c). */
static int read_count(RmReader* r, const char* what, int64_t* out, RmText* err)
{
    int64_t x = rm_read_i64(r);
    if (rm_read_ended(r, what, err)) return 0;
    if (x < 0 || x > RM_COUNT_MAX) {
        rm_printf(err, "%s = %lld: expected an integer in [0, 2^53]", what, (long long)x);
        return 0;
    }
    *out = x;
    return 1;
}

static void* restore(RmUnit* u, RmReader* r, RmText* err)
{
    const RmMesh* mesh = configure(u, err);
    if (mesh == NULL) return NULL;
    MeshModel* m = calloc(1, sizeof *m);
    if (m == NULL) {
        rm_printf(err, "out of memory");
        return NULL;
    }
    m->mesh = *mesh;
    RmWheel* st = &m->wheel;
    RmLast* l = &m->last;
    int64_t flank = 0;
    /* the pinion's speed at a step's end, w_p + a_p h: within pinion.w's range plus
     * pinion.a's over the longest step (a held pinion keeps it); beyond it a held step would
     * run the teeth through each other at any speed */
    const RmVariable* vars = u->variables;
    double w_reach = rm_max(fabs(vars[RM_MESH_PINION_W].min), fabs(vars[RM_MESH_PINION_W].max))
                     + rm_max(fabs(vars[RM_MESH_PINION_A].min), fabs(vars[RM_MESH_PINION_A].max))
                           * u->values[RM_MESH_SOLVER_H_COMM_MAX].r;
    int ok = rm_read_finite(r, "the wheel angle", 0, &st->phi, err)
             && rm_read_finite(r, "the wheel speed", 0, &st->w, err);
    if (ok) {
        flank = rm_read_i64(r);
        if (rm_read_ended(r, "the flank in contact", err))
            ok = 0;
        else if (flank < -1 || flank > 1) {
            rm_printf(err, "the flank in contact = %lld: expected -1, 0 or 1", (long long)flank);
            ok = 0;
        }
        st->flank = (int)flank;
    }
    ok = ok && rm_read_finite(r, "the drive flank's impact speed", 0, &st->v_drive, err)
         && rm_read_finite(r, "the coast flank's impact speed", 0, &st->v_coast, err)
         && rm_read_finite(r, "the last impact speed", 0, &st->v_last, err)
         && read_count(r, "the drive flank's onsets", &st->n_drive, err)
         && read_count(r, "the coast flank's onsets", &st->n_coast, err)
         && rm_read_finite(r, "the rattle index", 1, &st->rattle_index, err)
         && rm_read_finite(r, "the last step's mean wheel torque", 0, &l->tau_wheel_mean, err)
         && rm_read_finite(r, "the last step's mean pinion torque", 0, &l->tau_pinion_mean, err)
         && rm_read_finite(r, "the last step's peak force", 1, &l->W_peak, err)
         && rm_read_finite(r, "the last step's peak penetration", 1, &l->delta_peak, err)
         && read_count(r, "the last step's drive onsets", &l->onsets_drive, err)
         && read_count(r, "the last step's coast onsets", &l->onsets_coast, err)
         && rm_read_finite(r, "the pinion angle", 0, &l->pinion_phi, err)
         && rm_read_within(r, "the pinion speed", w_reach, "rad/s", "|pinion.w| + |pinion.a| "
                           "solver.h_comm_max at their bounds, what a step reaches", &l->pinion_w,
                           err)
         && rm_boundary_restore(&RM_MESH_CLASS, &m->boundary, r, err)
         && rm_read_finite(r, "the contact's Hunt-Crossley factor", 1, &st->diss.d, err);
    if (ok) {
        int64_t film = rm_read_i64(r);
        if (rm_read_ended(r, "the contact's film state", err))
            ok = 0;
        else if (film < 0 || film > 1) {
            rm_printf(err, "the contact's film state = %lld: expected 0 or 1", (long long)film);
            ok = 0;
        }
        st->diss.film = (int)film;
    }
    if (!ok) {
        free(m);
        return NULL;
    }
    return m;
}

static const RmStepLog* step_log(const void* model)
{
    const MeshModel* m = model;
    return &m->logs[m->current];
}

static int describe(RmUnit* u, const char** names, double* values, size_t capacity,
                    size_t* count, RmText* err)
{
    const RmMesh* M = configure(u, err);
    if (M == NULL) return 0;
    const RmGeometry* g = &M->g;
    const char* n[] = {"ratio", "alpha_t", "beta_b", "centre_distance", "r_pinion", "r_wheel",
                       "rb_pinion", "rb_wheel", "ra_pinion", "ra_wheel", "line_length",
                       "s_start", "s_end", "s_pitch", "base_pitch", "eps_alpha", "eps_beta",
                       "eps_gamma", "max_pairs", "r_y", "crown_factor", "half_backlash",
                       "normal_factor", "E_star", "arm_wheel", "arm_pinion", "normal_mass",
                       "damping", "penetration_limit", "law_terms", "r_y_eq6_pitch",
                       "palmgren_constant", "asperity_pressure", "tooth_stiffness_pitch",
                       "tooth_terms"};
    double v[] = {g->ratio, g->alpha_t, g->beta_b, g->centre_distance, g->r_pinion, g->r_wheel,
                  g->rb_pinion, g->rb_wheel, g->ra_pinion, g->ra_wheel, g->line_length,
                  g->s_start, g->s_end, g->s_pitch, g->base_pitch, g->eps_alpha, g->eps_beta,
                  g->eps_gamma, floor(g->eps_gamma) + 1.0, g->r_y, g->crown_factor,
                  g->half_backlash, g->normal_factor, M->E_star, M->arm_wheel, M->arm_pinion,
                  M->normal_mass, M->damping, M->pen_limit, (double)M->law.terms,
                  rm_radius_y_eq6(g, g->s_pitch), M->approach.palmgren,
                  M->approach.asperity_pressure,
                  M->tooth.on ? 1.0 / M->tooth.pitch : INFINITY, (double)M->tooth.terms};
    size_t total = sizeof v / sizeof v[0];
    for (size_t k = 0; k < total && k < capacity; k++) {
        names[k] = n[k];
        values[k] = v[k];
    }
    *count = total;
    return 1;
}

const RmUnitClass RM_MESH_CLASS = {
    RM_MESH,
    3,
    3,
    {RM_MESH_PINION_PHI, RM_MESH_PINION_W, RM_MESH_WHEEL_TAU_LOAD, 0},
    {RM_MESH_PINION_PHI, RM_MESH_PINION_W, RM_MESH_PINION_A, 0},
    build,
    free_model,
    free_cache,
    step,
    outputs,
    GROUP_QUICK | GROUP_STATE | GROUP_LOADS | GROUP_FILM,
    GROUP_FILM,
    0,
    group_of,
    save,
    restore,
    step_log,
    describe,
};

/* The unit's mesh model for its current parameters (the probes' entry, probe.c). */
const RmMesh* rm_mesh_configured(RmUnit* u, RmText* err)
{
    return configure(u, err);
}
