/*
 * record.c - the unit's complete state as a versioned binary record (little-endian, explicit
 * fields, read in linear time and checked before it is trusted): the writer and the reader,
 * the checked reads of a saved number, the held inputs' fields, and the unit's own part -- its
 * header (magic, version, kind, mode, motion flag, start time, time, variable count) and its
 * parameters and inputs in value-reference order, then the model's fields (the classes':
 * unit_mesh.c, unit_driveline.c).  What a restored state may hold beyond its format (the
 * mode, the times, the parameters) the unit checks (rm_restore, unit.c).
 */
#include <stdlib.h>
#include <string.h>

#include "rm_private.h"

/* The record's magic, and its version (bumped when its fields change). */
#define RECORD_MAGIC "RATLUNIT"
/* 2: the contact, dissipation and friction options; 3: the teeth's compliance parameters */
#define RECORD_VERSION 3u
/* The record's header: magic, version, kind, phase, motion flag, start time, time, count. */
#define RECORD_HEADER_BYTES ((size_t)(8 + 4 * 4 + 2 * 8 + 4))

/* ------------------------------------------------------------------ writer and reader */
static void write_raw(RmWriter* w, const void* p, size_t n)
{
    if (w->failed) return;
    if (w->len + n > w->cap) {
        size_t cap = w->cap ? w->cap : 256;
        while (cap < w->len + n) cap *= 2;
        unsigned char* q = realloc(w->data, cap);
        if (q == NULL) {
            w->failed = 1;
            return;
        }
        w->data = q;
        w->cap = cap;
    }
    memcpy(w->data + w->len, p, n);
    w->len += n;
}

void rm_write_bytes(RmWriter* w, const void* p, size_t n) { write_raw(w, p, n); }

void rm_write_u32(RmWriter* w, uint32_t x)
{
    unsigned char b[4];
    for (int k = 0; k < 4; k++) b[k] = (unsigned char)(x >> (8 * k));
    write_raw(w, b, 4);
}

void rm_write_i64(RmWriter* w, int64_t x)
{
    uint64_t v = (uint64_t)x;
    unsigned char b[8];
    for (int k = 0; k < 8; k++) b[k] = (unsigned char)(v >> (8 * k));
    write_raw(w, b, 8);
}

void rm_write_f64(RmWriter* w, double x)
{
    uint64_t v;
    memcpy(&v, &x, 8);
    rm_write_i64(w, (int64_t)v);
}

const unsigned char* rm_read_bytes(RmReader* r, size_t n)
{
    if (r->failed || n > r->len - r->pos) {
        r->failed = 1;
        return NULL;
    }
    const unsigned char* p = r->data + r->pos;
    r->pos += n;
    return p;
}

uint32_t rm_read_u32(RmReader* r)
{
    const unsigned char* b = rm_read_bytes(r, 4);
    uint32_t x = 0;
    if (b != NULL)
        for (int k = 0; k < 4; k++) x |= (uint32_t)b[k] << (8 * k);
    return x;
}

int64_t rm_read_i64(RmReader* r)
{
    const unsigned char* b = rm_read_bytes(r, 8);
    uint64_t x = 0;
    if (b != NULL)
        for (int k = 0; k < 8; k++) x |= (uint64_t)b[k] << (8 * k);
    return (int64_t)x;
}

double rm_read_f64(RmReader* r)
{
    uint64_t v = (uint64_t)rm_read_i64(r);
    double x;
    memcpy(&x, &v, 8);
    return x;
}

int rm_read_ended(const RmReader* r, const char* what, RmText* err)
{
    if (!r->failed) return 0;
    rm_printf(err, "the record ends before %s", what);
    return 1;
}

int rm_read_finite(RmReader* r, const char* what, int nonnegative, double* out, RmText* err)
{
    double x = rm_read_f64(r);
    if (rm_read_ended(r, what, err)) return 0;
    if (!isfinite(x) || (nonnegative && !(x >= 0.0))) {
        rm_printf(err, "%s = %r: expected a finite number%s", what, x, nonnegative ? " >= 0" : "");
        return 0;
    }
    *out = x;
    return 1;
}

int rm_read_within(RmReader* r, const char* what, double bound, const char* unit,
                   const char* why, double* out, RmText* err)
{
    if (!rm_read_finite(r, what, 0, out, err)) return 0;
    if (fabs(*out) <= bound) return 1;
    rm_printf(err, "%s = %r %s: expected within [%r, %r] %s (%s)",
                   what, *out, unit, -bound, bound, unit, why);
    return 0;
}

/* An input value of the record (one the unit accepted at a step or at the end of
 * initialization, so within its declared range): 1, or 0 with the refusal. */
static int read_input(RmReader* r, const RmVariable* v, const char* what, int check,
                      double* out, RmText* err)
{
    double x = rm_read_f64(r);
    if (rm_read_ended(r, what, err)) return 0;
    if (check && !(isfinite(x) && (!v->has_min || x >= v->min) && (!v->has_max || x <= v->max))) {
        rm_printf(err, "input '%s' %s = %r: expected within %s (a value the unit accepted)",
                       v->name, what, x, v->allowed);
        return 0;
    }
    *out = x;
    return 1;
}

/* ------------------------------------------------------------------ the held inputs */
void rm_boundary_save(const RmUnitClass* cls, const RmBoundary* b, RmWriter* w)
{
    for (int k = 0; k < cls->n_start; k++) rm_write_f64(w, b->initial_inputs[k]);
    rm_write_u32(w, (uint32_t)b->first_step);
    rm_write_u32(w, (uint32_t)b->has_last_motion);
    for (int k = 0; k < cls->n_motion; k++) rm_write_f64(w, b->last_motion[k]);
}

int rm_boundary_restore(const RmUnitClass* cls, RmBoundary* b, RmReader* r, RmText* err)
{
    /* the unit's table (rm_tables.c), read here to check the inputs against it */
    const RmVariable* variables = cls->kind == RM_MESH ? RM_MESH_VARIABLES
                                                       : RM_DRIVELINE_VARIABLES;
    for (int k = 0; k < cls->n_start; k++)
        if (!read_input(r, &variables[cls->start_vr[k]], "at the end of initialization", 1,
                        &b->initial_inputs[k], err))
            return 0;
    uint32_t first = rm_read_u32(r), has_last = rm_read_u32(r);
    if (rm_read_ended(r, "the first-step flags", err)) return 0;
    if (first > 1 || has_last > 1) {
        rm_printf(err, "the record's first-step flags are not 0 or 1");
        return 0;
    }
    b->first_step = (int)first;
    b->has_last_motion = (int)has_last;
    for (int k = 0; k < cls->n_motion; k++)
        if (!read_input(r, &variables[cls->motion_vr[k]], "of the last step", has_last != 0,
                        &b->last_motion[k], err))
            return 0;
    return 1;
}

/* ------------------------------------------------------------------ the unit's record */
int rm_record_write(const RmUnit* u, RmWriter* w)
{
    rm_write_bytes(w, RECORD_MAGIC, 8);
    rm_write_u32(w, RECORD_VERSION);
    rm_write_u32(w, (uint32_t)u->kind);
    rm_write_u32(w, (uint32_t)u->phase);
    rm_write_u32(w, (uint32_t)u->motion_set);
    rm_write_f64(w, u->start_time);
    rm_write_f64(w, u->time);
    rm_write_u32(w, (uint32_t)u->n_variables);
    for (size_t k = 0; k < u->n_variables; k++) {
        const RmVariable* v = &u->variables[k];
        const RmValue* x = &u->values[k];
        if (v->causality == RM_OUTPUT) continue; /* computed from the model */
        switch (v->type) {
        case RM_REAL: rm_write_f64(w, x->r); break;
        case RM_STRING: {
            size_t n = x->s != NULL ? strlen(x->s) : 0;
            rm_write_u32(w, (uint32_t)n);
            rm_write_bytes(w, x->s != NULL ? x->s : "", n);
            break;
        }
        default: rm_write_i64(w, x->i);
        }
    }
    rm_write_u32(w, u->model != NULL);
    if (u->model != NULL) u->cls->save(u->model, w);
    return !w->failed;
}

int rm_record_read_header(RmReader* r, RmRecordHeader* h, RmText* err)
{
    size_t size = r->len;
    if (size == 0) {
        rm_printf(err, "it is not a state of this model (the record is empty)");
        return 0;
    }
    /* a record cut inside its magic is a truncated record; other bytes are no record */
    const unsigned char* magic = rm_read_bytes(r, 8);
    if (memcmp(r->data, RECORD_MAGIC, size < 8 ? size : 8) != 0) {
        rm_printf(err, "it is not a state of this model (no record header)");
        return 0;
    }
    h->version = rm_read_u32(r);
    h->kind = rm_read_u32(r);
    h->phase = rm_read_u32(r);
    h->motion_set = rm_read_u32(r);
    h->start_time = rm_read_f64(r);
    h->time = rm_read_f64(r);
    h->n_variables = rm_read_u32(r);
    if (magic == NULL || r->failed) {
        rm_printf(err, "the record ends before the end of its header (%zu bytes of %zu)", size,
                  RECORD_HEADER_BYTES);
        return 0;
    }
    if (h->version != RECORD_VERSION) {
        rm_printf(err, "its record version is %u, this model reads version %u", h->version,
                  RECORD_VERSION);
        return 0;
    }
    return 1;
}

/* A saved String: UTF-8 without NUL characters, into x->s (malloc'ed).  1, or 0 with the
 * refusal (a truncated record leaves x->s NULL and r failed: the caller names it). */
static int read_string(RmReader* r, const RmVariable* v, RmValue* x, RmText* err)
{
    uint32_t len = rm_read_u32(r);
    const unsigned char* s = rm_read_bytes(r, len);
    if (s == NULL) return 1;
    x->s = malloc((size_t)len + 1);
    if (x->s == NULL) {
        rm_printf(err, "out of memory");
        return 0;
    }
    memcpy(x->s, s, len);
    x->s[len] = '\0';
    if (strlen(x->s) != len || rm_utf8_error_at((const unsigned char*)x->s, len) != (size_t)-1) {
        rm_printf(err, "variable '%s' is not UTF-8 text without NUL characters", v->name);
        return 0;
    }
    return 1;
}

int rm_record_read_values(RmReader* r, const RmVariable* variables, size_t n, RmValue* values,
                          RmText* err)
{
    for (size_t k = 0; k < n; k++) {
        const RmVariable* v = &variables[k];
        RmValue* x = &values[k];
        if (v->causality == RM_OUTPUT) continue;
        switch (v->type) {
        case RM_REAL: x->r = rm_read_f64(r); break;
        case RM_STRING:
            if (!read_string(r, v, x, err)) return 0;
            break;
        default: {
            int64_t i = rm_read_i64(r);
            if (!r->failed && ((v->type == RM_BOOLEAN && (i < 0 || i > 1))
                               || (v->type == RM_INTEGER
                                   && (i < -2147483647LL - 1 || i > 2147483647LL)))) {
                rm_printf(err, "variable '%s' = %lld: expected %s", v->name, (long long)i,
                          v->type == RM_BOOLEAN ? "0 or 1" : "a 32-bit integer");
                return 0;
            }
            x->i = i;
        }
        }
        if (r->failed) {
            rm_printf(err, "the record ends before variable '%s'", v->name);
            return 0;
        }
    }
    return 1;
}
