/*
 * probe.c - the model's laws at given arguments (rm_probe.h), for the tests that hold them
 * against closed forms and the readable equations (tests/oracle).  Test-only: compiled into
 * the model library that the Python API and the tests load (drive_rattle_build.library's
 * build in place), never into a shipped FMU's binary (drive_rattle_build.paths.TEST_ONLY).
 */
#include <stdlib.h>
#include <string.h>

#include "rm_private.h"
#include "rm_probe.h"

static int probe_begin(RmUnit* u, const RmMesh** M)
{
    RmText err;
    rm_text_init(&err);
    u->status = RM_OK;
    rm_text_clear(&u->message);
    *M = NULL;
    if (u->kind != RM_MESH)
        rm_puts(&err, "a probe of the mesh model needs a GearMeshRattle unit");
    else if (rm_unit_values_valid(u, &err))
        *M = rm_mesh_configured(u, &err);
    if (*M == NULL) {
        RmText t;
        rm_text_init(&t);
        rm_printf(&t, "probe: %s", rm_text_str(&err));
        rm_report(u, RM_ERROR, rm_text_str(&t));
        rm_text_free(&t);
    }
    rm_text_free(&err);
    return *M != NULL;
}

static int probe_failed(RmUnit* u, const RmFail* f)
{
    RmText t;
    rm_text_init(&t);
    rm_puts(&t, "probe: ");
    rm_refusal_text(&t, f->code, f->values);
    rm_report(u, RM_ERROR, rm_text_str(&t));
    rm_text_free(&t);
    return RM_ERROR;
}

int rm_probe_contact_law(RmUnit* u, double r_x, double* out4)
{
    const RmMesh* M;
    if (u == NULL || !probe_begin(u, &M)) return RM_ERROR;
    if (M->g.layout != RM_LAYOUT_CROWNED) {
        RmText t;
        rm_text_init(&t);
        rm_printf(&t, "probe: the contact law at r_x with the crown's r_y belongs to "
                      "contact.geometry = 0; with contact.geometry = %d each pair has its own "
                      "law: use rm_probe_pair_laws", M->g.layout);
        rm_report(u, RM_ERROR, rm_text_str(&t));
        rm_text_free(&t);
        return RM_ERROR;
    }
    RmFail f;
    if (setjmp(f.jb) != 0) return probe_failed(u, &f);
    rm_contact_law_at(&M->law, &f, r_x, &out4[0], &out4[1], &out4[2], &out4[3]);
    return RM_OK;
}

static int probe_text(RmUnit* u, int ok, RmText* err)
{
    if (!ok) {
        RmText t;
        rm_text_init(&t);
        rm_printf(&t, "probe: %s", rm_text_str(err));
        rm_report(u, RM_ERROR, rm_text_str(&t));
        rm_text_free(&t);
    }
    rm_text_free(err);
    return ok ? RM_OK : RM_ERROR;
}

int rm_probe_exact_ellipse(RmUnit* u, double rho, double* out4)
{
    if (u == NULL) return RM_ERROR;
    u->status = RM_OK;
    rm_text_clear(&u->message);
    RmText err;
    rm_text_init(&err);
    RmEllipse e;
    int ok = rm_exact_ellipse(rho, &e, &err);
    if (ok) {
        out4[0] = e.q;
        out4[1] = e.kappa;
        out4[2] = e.alpha;
        out4[3] = e.zeta;
    }
    return probe_text(u, ok, &err);
}

int rm_probe_restitution(RmUnit* u, double alpha, double* e)
{
    if (u == NULL) return RM_ERROR;
    u->status = RM_OK;
    rm_text_clear(&u->message);
    RmText err;
    rm_text_init(&err);
    return probe_text(u, rm_hunt_crossley_restitution(alpha, e, &err), &err);
}

int rm_probe_damping_factor(RmUnit* u, double e, double v, double* d)
{
    if (u == NULL) return RM_ERROR;
    u->status = RM_OK;
    rm_text_clear(&u->message);
    RmText err;
    rm_text_init(&err);
    return probe_text(u, rm_hunt_crossley_factor(e, v, d, &err), &err);
}

/* The pairs in the zone of action on `flank` at pinion angle phi_p (what rm_probe_pairs and
 * rm_probe_pair_laws report). */
static void flank_pairs(const RmMesh* M, RmFail* f, int flank, double phi_p, RmPairSet* ps)
{
    double u_roll = rm_flank_roll(&M->g, flank, phi_p);
    rm_pair_set_build(&M->g, f, u_roll, u_roll, ps);
}

int rm_probe_pairs(RmUnit* u, int flank, double phi_p, double* out, size_t capacity,
                   size_t* count)
{
    const RmMesh* M;
    if (u == NULL || !probe_begin(u, &M)) return RM_ERROR;
    RmFail f;
    RmPairSet ps;
    if (setjmp(f.jb) != 0) return probe_failed(u, &f);
    flank_pairs(M, &f, flank, phi_p, &ps);
    *count = (size_t)ps.n;
    for (int i = 0; i < ps.n && (size_t)i < capacity; i++) {
        out[4 * i] = (double)ps.slot[i];
        out[4 * i + 1] = ps.s[i];
        out[4 * i + 2] = ps.offset[i];
        out[4 * i + 3] = ps.dg[i];
    }
    return RM_OK;
}

int rm_probe_loads(RmUnit* u, int flank, double phi_p, double w_p, double phi_w, double w_w,
                   double v_impact, double* totals, double* pairs, size_t capacity,
                   size_t* count)
{
    const RmMesh* M;
    if (u == NULL || !probe_begin(u, &M)) return RM_ERROR;
    RmFail f;
    RmPairCache cache;
    RmLoads L;
    rm_pair_cache_init(&cache);
    if (setjmp(f.jb) != 0) return probe_failed(u, &f);
    /* the contact's dissipation as an onset on this flank at v_impact would set it */
    RmContactDissipation diss;
    rm_onset_dissipation(M, &f, &cache, flank, phi_p, v_impact, &diss);
    rm_mesh_loads(M, &f, &cache, flank, phi_p, w_p, phi_w, w_w, v_impact, diss, NULL, NULL, 1, &L,
                  pairs, capacity);
    totals[0] = L.delta;
    totals[1] = L.tau_w;
    totals[2] = L.tau_p;
    totals[3] = L.W;
    totals[4] = L.F;
    *count = (size_t)L.n_pairs;
    return RM_OK;
}

int rm_probe_pair_laws(RmUnit* u, int flank, double phi_p, double* out, size_t capacity,
                       size_t* count)
{
    const RmMesh* M;
    if (u == NULL || !probe_begin(u, &M)) return RM_ERROR;
    RmFail f;
    RmPairSet ps;
    if (setjmp(f.jb) != 0) return probe_failed(u, &f);
    flank_pairs(M, &f, flank, phi_p, &ps);
    *count = (size_t)ps.n;
    for (int i = 0; i < ps.n && (size_t)i < capacity; i++) {
        rm_pair_coefficients(M, &f, &ps, i);
        double row[RM_PAIR_LAW_DETAIL] = {(double)ps.slot[i], ps.s[i], ps.length[i], ps.r_x[i],
                                          ps.r_y[i], ps.K[i],   ps.ka[i],     ps.kz[i],
                                          ps.W_r[i],  ps.c_t[i]};
        for (int k = 0; k < RM_PAIR_LAW_DETAIL; k++) out[RM_PAIR_LAW_DETAIL * i + k] = row[k];
    }
    return RM_OK;
}

int rm_probe_approach(RmUnit* u, double K, double W_r, double c_t, double kz, double pen,
                      double* out5)
{
    const RmMesh* M;
    if (u == NULL || !probe_begin(u, &M)) return RM_ERROR;
    RmFail f;
    if (setjmp(f.jb) != 0) return probe_failed(u, &f);
    if (!(pen > 0.0 && K > 0.0 && W_r >= 0.0 && c_t >= 0.0 && kz >= 0.0
          && (W_r > 0.0 || !M->approach.rough))) {
        RmText t;
        rm_text_init(&t);
        rm_printf(&t, "probe: the load-approach law needs pen > 0, K > 0, c_t >= 0, kz >= 0 and "
                      "W_r > 0 with contact.roughness = 1 (W_r >= 0 without); got pen = %r, K = "
                      "%r, W_r = %r, c_t = %r, kz = %r", pen, K, W_r, c_t, kz);
        rm_report(u, RM_ERROR, rm_text_str(&t));
        rm_text_free(&t);
        return RM_ERROR;
    }
    const RmApproachLaw* a = &M->approach;
    double k, c;
    out5[0] = rm_approach_force(a, &f, K, W_r, c_t, pen, &out5[4]);
    rm_approach_rates(a, &f, K, W_r, c_t, pen, 1.0, &k, &c);
    out5[1] = k;
    out5[2] = rm_approach_energy(a, &f, K, W_r, c_t, pen);
    out5[3] = rm_approach_area(a, &f, kz, out5[0]);
    return RM_OK;
}

int rm_probe_squeeze(RmUnit* u, int flank, double phi_p, double v, double* out5)
{
    const RmMesh* M;
    if (u == NULL || !probe_begin(u, &M)) return RM_ERROR;
    RmFail f;
    RmPairCache cache;
    rm_pair_cache_init(&cache);
    if (setjmp(f.jb) != 0) return probe_failed(u, &f);
    double area = rm_squeeze_area(M, &f, &cache, flank, phi_p);
    double St = rm_stokes_number(M, v, area);
    RmContactDissipation diss;
    int stuck = rm_onset_dissipation(M, &f, &cache, flank, phi_p, v, &diss);
    out5[0] = area;
    out5[1] = St;
    out5[2] = rm_squeeze_restitution(&M->p, St);
    out5[3] = diss.d;
    out5[4] = stuck ? 1.0 : 0.0;
    return RM_OK;
}
