/*
 * unit.c - the unit of rattle_model.h: its variables and their checks, its phases, the step
 * with the communication point's continuity, the outputs computed when read, the complete
 * state saved and restored (its binary record: record.c), and the coupled start values.  What
 * is particular to a kind of unit is behind RmUnitClass (unit_mesh.c, unit_driveline.c).
 *
 * Every message of a refused call is "<action>: <reason>", the action named as the FMI
 * function it serves (setReal, doStep, ...), so that both FMI faces and the Python API log the
 * same text.
 */
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rm_private.h"

/* Tolerance of the communication point's continuity, in units of the step: masters that
 * compute t = t0 + k h differ from t_prev + h_prev by a few ulps of t. */
#define COMMUNICATION_POINT_TOLERANCE 1e-9
/* The largest |start time| [s]: beyond ~1e9 s a 1e-7 s step no longer moves the time. */
#define MAX_START_TIME 1e9
/* The longest run [s] from the start time (127 years): a step that would end later is
 * refused, so that every state the unit saves it restores (rm_restore checks the same). */
#define MAX_RUN_LENGTH (4.0 * MAX_START_TIME)

static const char* const PHASE_NAMES[4] = {"instantiated", "initialization", "stepping",
                                           "terminated"};
static const char* const TYPE_NAMES[4] = {"Real", "Integer", "Boolean", "String"};

/* ------------------------------------------------------------------ the tables */
const RmVariable* rm_variables(int kind)
{
    return kind == RM_MESH ? RM_MESH_VARIABLES : kind == RM_DRIVELINE ? RM_DRIVELINE_VARIABLES
                                                                      : NULL;
}

size_t rm_variable_count(int kind)
{
    return kind == RM_MESH ? RM_MESH_N_VARIABLES
                           : kind == RM_DRIVELINE ? RM_DRIVELINE_N_VARIABLES : 0;
}

int rm_api_version(void) { return RM_API_VERSION; }

#ifndef RM_SOURCE_ID
#define RM_SOURCE_ID "unidentified build"
#endif
const char* rm_build_id(void) { return RM_SOURCE_ID; }

/* ------------------------------------------------------------------ messages */
void rm_report(RmUnit* u, int status, const char* message)
{
    if (status > u->status) {
        rm_text_clear(&u->message);
        rm_puts(&u->message, message);
        u->status = status;
    }
    if (u->logger != NULL) u->logger(u->logger_env, status, message);
}

/* Start of an API call: no status yet. */
static void begin(RmUnit* u)
{
    u->status = RM_OK;
    rm_text_clear(&u->message);
}

/* "<action>: <reason><tail>" as the call's Error. */
static void refuse_with(RmUnit* u, const char* action, const RmText* reason, const char* tail)
{
    RmText t;
    rm_text_init(&t);
    rm_printf(&t, "%s: %s%s", action, rm_text_str(reason), tail);
    rm_report(u, RM_ERROR, t.failed ? "out of memory" : rm_text_str(&t));
    rm_text_free(&t);
}

static void refuse(RmUnit* u, const char* action, const RmText* reason)
{
    refuse_with(u, action, reason, "");
}

static int refuse_text(RmUnit* u, const char* action, const char* reason)
{
    RmText t;
    rm_text_init(&t);
    rm_puts(&t, reason);
    refuse(u, action, &t);
    rm_text_free(&t);
    return u->status;
}

const char* rm_message(const RmUnit* u) { return u != NULL ? rm_text_str(&u->message) : ""; }

void rm_set_logger(RmUnit* u, RmLogger logger, void* env)
{
    if (u == NULL) return;
    u->logger = logger;
    u->logger_env = env;
}

/* ------------------------------------------------------------------ values */
static char* copy_string(const char* s)
{
    size_t n = strlen(s) + 1;
    char* p = malloc(n);
    if (p != NULL) memcpy(p, s, n);
    return p;
}

static void free_values(RmValue* values, size_t n)
{
    if (values == NULL) return;
    for (size_t k = 0; k < n; k++) {
        free(values[k].s);
        values[k].s = NULL;
    }
}

/* The defaults of the tables (inputs 0: rm_new sets their start values). */
static int set_defaults(RmUnit* u)
{
    for (size_t k = 0; k < u->n_variables; k++) {
        const RmVariable* v = &u->variables[k];
        RmValue* x = &u->values[k];
        free(x->s);
        x->s = NULL;
        x->r = v->type == RM_REAL ? v->start : 0.0;
        x->i = v->type == RM_REAL ? 0 : (int64_t)v->start;
        if (v->type == RM_STRING) {
            x->s = copy_string(v->start_string != NULL ? v->start_string : "");
            if (x->s == NULL) return 0;
        }
    }
    return 1;
}


/* The range and choice checks of every parameter (in declaration order): 1, or 0 with the
 * refusal. */
static int check_parameter_values(const RmUnit* u, const RmValue* values, RmText* err)
{
    for (size_t k = 0; k < u->n_variables; k++) {
        const RmVariable* v = &u->variables[k];
        const char* why = NULL;
        double x;
        if (v->causality != RM_PARAMETER || v->type == RM_STRING || v->type == RM_BOOLEAN)
            continue;
        if (v->type == RM_INTEGER) {
            x = (double)values[k].i;
            if (v->n_choices > 0) {
                int found = 0;
                for (int c = 0; c < v->n_choices; c++)
                    if (values[k].i == v->choices[c]) found = 1;
                if (!found) why = "is not one of its choices";
            }
        }
        else {
            x = values[k].r;
            if (!isfinite(x)) why = "must be finite";
        }
        if (why == NULL && v->has_min && (x < v->min || (v->min_exclusive && x == v->min)))
            why = "is out of range";
        if (why == NULL && v->has_max && (x > v->max || (v->max_exclusive && x == v->max)))
            why = "is out of range";
        if (why != NULL) {
            if (v->type == RM_INTEGER)
                rm_printf(err, "parameter '%s' = %lld %s; allowed: %s", v->name,
                          (long long)values[k].i, why, v->allowed);
            else
                rm_printf(err, "parameter '%s' = %r %s; allowed: %s", v->name, values[k].r, why,
                          v->allowed);
            return 0;
        }
    }
    return 1;
}

/* Every input finite and in its range: 1, or 0 with the refusal. */
static int check_inputs(const RmUnit* u, const RmValue* values, RmText* err)
{
    for (size_t k = u->first_input; k < u->first_output; k++) {
        const RmVariable* v = &u->variables[k];
        double x = values[k].r;
        if (!isfinite(x)) {
            rm_printf(err, "input '%s' = %r is not finite; allowed: finite numbers", v->name, x);
            return 0;
        }
        if ((v->has_min && x < v->min) || (v->has_max && x > v->max)) {
            rm_printf(err, "input '%s' = %r is out of range; allowed: %s", v->name, x, v->allowed);
            return 0;
        }
    }
    return 1;
}

/* A model for the current values: parameters checked (ranges, then the class's combination
 * checks in build), inputs checked, start solved.  NULL with the refusal. */
static void* build_model(RmUnit* u, RmText* err)
{
    if (!check_parameter_values(u, u->values, err) || !check_inputs(u, u->values, err))
        return NULL;
    return u->cls->build(u, err);
}

int rm_unit_values_valid(RmUnit* u, RmText* err)
{
    return check_parameter_values(u, u->values, err);
}

/* The outputs of the stale groups asked for, from the model. */
/* Every Real output computed is finite: 1, or 0 with the refusal naming the first that is
 * not (no call answers a non-finite output with OK). */
static int outputs_finite(const RmUnit* u, const RmValue* values, RmText* err)
{
    for (size_t k = u->first_output; k < u->n_variables; k++) {
        const RmVariable* v = &u->variables[k];
        if (v->type == RM_REAL && !isfinite(values[k].r)) {
            rm_printf(err, "output '%s' = %r is not finite: the inputs or parameters are beyond "
                           "what the model resolves", v->name, values[k].r);
            return 0;
        }
    }
    return 1;
}

static int refresh_outputs(RmUnit* u, unsigned groups, RmText* err)
{
    if (u->model == NULL || (u->stale & groups) == 0) return 1;
    unsigned todo = u->stale & groups;
    if (!u->cls->outputs(u, u->model, todo, u->values, err) || !outputs_finite(u, u->values, err))
        return 0;
    u->stale = (todo & u->cls->complete_group) ? 0 : (u->stale & ~todo);
    return 1;
}

/* The outputs of initialization mode: those of a model built from the current values (the
 * values as they are when that fails: the failure is reported at exitInitializationMode). */
static void refresh_provisional(RmUnit* u)
{
    if (u->provisional_valid) return;
    RmText err;
    rm_text_init(&err);
    for (size_t k = 0; k < u->n_variables; k++) {
        u->provisional[k] = u->values[k];
        u->provisional[k].s = NULL; /* not owned: strings are read from values */
    }
    void* model = build_model(u, &err);
    if (model != NULL) {
        u->cls->outputs(u, model, u->cls->all_groups, u->provisional, &err);
        u->cls->free_model(model);
    }
    rm_text_free(&err);
    u->provisional_valid = 1;
}

/* The value of variable vr for a get: outputs from initialization mode's provisional model,
 * or refreshed after a step.  NULL with the refusal when it cannot be computed. */
static const RmValue* value_for_get(RmUnit* u, unsigned vr, RmText* err)
{
    const RmVariable* v = &u->variables[vr];
    if (v->causality == RM_OUTPUT) {
        if (u->phase == RM_INITIALIZATION) {
            refresh_provisional(u);
            return &u->provisional[vr];
        }
        unsigned group = u->cls->group_of(vr);
        if ((u->stale & group) && !refresh_outputs(u, group, err)) return NULL;
    }
    return &u->values[vr];
}

static const char* const GET_ACTIONS[4] = {"getReal", "getInteger", "getBoolean", "getString"};
static const char* const SET_ACTIONS[4] = {"setReal", "setInteger", "setBoolean", "setString"};

static int get_values(RmUnit* u, int type, const unsigned* vr, size_t n, void* out)
{
    if (u == NULL) return RM_ERROR;
    begin(u);
    const char* action = GET_ACTIONS[type];
    if (n > 0 && (vr == NULL || out == NULL))
        return refuse_text(u, action, "a value-reference or value array is NULL");
    for (size_t i = 0; i < n; i++) {
        const RmValue* x = NULL;
        RmText err;
        rm_text_init(&err);
        if (vr[i] < u->n_variables && u->variables[vr[i]].type == type) {
            x = value_for_get(u, vr[i], &err);
            if (x == NULL) {
                char where[64];
                snprintf(where, sizeof where, "%s vr %u", action, vr[i]);
                refuse(u, where, &err);
            }
        }
        else {
            rm_printf(&err, "no %s variable with value reference %u", TYPE_NAMES[type], vr[i]);
            refuse(u, action, &err);
        }
        rm_text_free(&err);
        switch (type) {
        case RM_REAL: ((double*)out)[i] = x != NULL ? x->r : NAN; break;
        case RM_INTEGER: {
            /* 32 bits, as FMI's: saturate (the cumulative counters can exceed it) */
            int64_t v = x != NULL ? x->i : 0;
            ((int32_t*)out)[i] = v > 2147483647LL ? 2147483647
                                 : v < -2147483647LL - 1 ? (-2147483647 - 1) : (int32_t)v;
            break;
        }
        case RM_BOOLEAN: ((int32_t*)out)[i] = x != NULL && x->i ? 1 : 0; break;
        default: {
            const char* s = "";
            if (x != NULL) {
                /* strings stay valid until the next call: a copy per answer */
                const char* src = x->s != NULL ? x->s : u->values[vr[i]].s;
                s = src != NULL ? src : "";
            }
            ((const char**)out)[i] = s;
        }
        }
    }
    return u->status;
}

int rm_get_real(RmUnit* u, const unsigned* vr, size_t n, double* values)
{
    return get_values(u, RM_REAL, vr, n, values);
}

int rm_get_integer(RmUnit* u, const unsigned* vr, size_t n, int32_t* values)
{
    return get_values(u, RM_INTEGER, vr, n, values);
}

int rm_get_boolean(RmUnit* u, const unsigned* vr, size_t n, int32_t* values)
{
    return get_values(u, RM_BOOLEAN, vr, n, values);
}

int rm_get_string(RmUnit* u, const unsigned* vr, size_t n, const char** values)
{
    return get_values(u, RM_STRING, vr, n, (void*)values);
}

/* The text of value i of a set call, into buf: a refusal names what it was given, a NULL string
 * included (FMI lets a host pass one; the check that refuses it comes after the mode's). A string
 * shows its first 80 bytes quoted, at most 4 bytes each (\xhh), within GIVEN_TEXT. */
#define GIVEN_TEXT 400
static const char* given_text(char* buf, int type, const void* values, size_t i)
{
    switch (type) {
    case RM_REAL: rm_format(buf, GIVEN_TEXT, "%r", ((const double*)values)[i]); break;
    case RM_INTEGER: rm_format(buf, GIVEN_TEXT, "%d", (int)((const int32_t*)values)[i]); break;
    case RM_BOOLEAN:
        rm_format(buf, GIVEN_TEXT, "%s", ((const int32_t*)values)[i] ? "true" : "false");
        break;
    default: {
        const char* s = ((const char* const*)values)[i];
        if (s == NULL)
            rm_format(buf, GIVEN_TEXT, "NULL");
        else
            rm_format(buf, GIVEN_TEXT, "%q", s, strlen(s) > 80 ? (size_t)80 : strlen(s));
    }
    }
    return buf;
}

/* Every entry checked before any is stored: a refused call (one bad entry) stores nothing. */
static int set_values(RmUnit* u, int type, const unsigned* vr, size_t n, const void* values)
{
    if (u == NULL) return RM_ERROR;
    begin(u);
    const char* action = SET_ACTIONS[type];
    if (n > 0 && (vr == NULL || values == NULL))
        return refuse_text(u, action, "a value-reference or value array is NULL; nothing stored");
    RmText err;
    rm_text_init(&err);
    int refused = 0;
    for (size_t i = 0; i < n && !refused; i++) {
        if (!(vr[i] < u->n_variables && u->variables[vr[i]].type == type)) {
            rm_printf(&err, "no %s variable with value reference %u", TYPE_NAMES[type], vr[i]);
            refused = 1;
            break;
        }
        const RmVariable* v = &u->variables[vr[i]];
        if (v->causality == RM_OUTPUT) {
            rm_printf(&err, "'%s' is an output and cannot be set", v->name);
            refused = 1;
        }
        else if (u->phase == RM_TERMINATED) {
            rm_printf(&err, "'%s' cannot be set after terminate (mode is 'terminated'); allowed: "
                            "reset first", v->name);
            refused = 1;
        }
        else if (v->causality == RM_PARAMETER && u->phase != RM_INSTANTIATED
                 && u->phase != RM_INITIALIZATION) {
            char given[GIVEN_TEXT];
            rm_printf(&err, "parameter '%s' is fixed: it can only be set before the end of "
                            "initialization (mode is '%s'); value %s rejected",
                      v->name, PHASE_NAMES[u->phase], given_text(given, type, values, i));
            refused = 1;
        }
        else if (type == RM_STRING) {
            const char* s = ((const char* const*)values)[i];
            size_t bad;
            if (s == NULL) {
                rm_printf(&err, "value %zu ('%s') is NULL", i, v->name);
                refused = 1;
            }
            else if ((bad = rm_utf8_string_error_at(s)) != (size_t)-1) {
                rm_printf(&err, "value %zu ('%s') is not valid UTF-8 (byte 0x%02X at offset "
                                "%zu)", i, v->name, (unsigned)(unsigned char)s[bad], bad);
                refused = 1;
            }
        }
    }
    if (refused) {
        refuse_with(u, action, &err, "; nothing of this call was stored");
    }
    else {
        /* strings first: the only allocations, so that a failure stores nothing */
        char** copies = NULL;
        if (type == RM_STRING && n > 0) {
            copies = calloc(n, sizeof *copies);
            int ok = copies != NULL;
            for (size_t i = 0; ok && i < n; i++)
                if ((copies[i] = copy_string(((const char* const*)values)[i])) == NULL) ok = 0;
            if (!ok) {
                for (size_t i = 0; copies != NULL && i < n; i++) free(copies[i]);
                free(copies);
                rm_text_free(&err);
                return refuse_text(u, action, "out of memory; nothing of this call was stored");
            }
        }
        for (size_t i = 0; i < n; i++) {
            RmValue* x = &u->values[vr[i]];
            switch (type) {
            case RM_REAL: x->r = ((const double*)values)[i]; break;
            case RM_INTEGER: x->i = ((const int32_t*)values)[i]; break;
            case RM_BOOLEAN: x->i = ((const int32_t*)values)[i] != 0; break;
            default:
                free(x->s);
                x->s = copies[i];
            }
        }
        free(copies);
        if (n > 0) u->provisional_valid = 0;
    }
    rm_text_free(&err);
    /* an accepted call naming a motion input marks them set (a master that sets them holds
     * nothing); a refused call changes nothing, this mark included */
    if (type == RM_REAL && !u->motion_set && u->status != RM_ERROR)
        for (size_t i = 0; i < n; i++)
            for (int k = 0; k < u->cls->n_motion; k++)
                if (vr[i] == u->cls->motion_vr[k]) u->motion_set = 1;
    return u->status;
}

int rm_set_real(RmUnit* u, const unsigned* vr, size_t n, const double* values)
{
    return set_values(u, RM_REAL, vr, n, values);
}

int rm_set_integer(RmUnit* u, const unsigned* vr, size_t n, const int32_t* values)
{
    return set_values(u, RM_INTEGER, vr, n, values);
}

int rm_set_boolean(RmUnit* u, const unsigned* vr, size_t n, const int32_t* values)
{
    return set_values(u, RM_BOOLEAN, vr, n, values);
}

int rm_set_string(RmUnit* u, const unsigned* vr, size_t n, const char* const* values)
{
    return set_values(u, RM_STRING, vr, n, values);
}

/* ------------------------------------------------------------------ life cycle */
static const RmUnitClass* class_of(int kind)
{
    return kind == RM_MESH ? &RM_MESH_CLASS : kind == RM_DRIVELINE ? &RM_DRIVELINE_CLASS : NULL;
}

/* A unit at its table defaults (inputs 0). */
static RmUnit* unit_alloc(int kind, const char* resources)
{
    const RmUnitClass* cls = class_of(kind);
    if (cls == NULL) return NULL;
    RmUnit* u = calloc(1, sizeof *u);
    if (u == NULL) return NULL;
    u->cls = cls;
    u->kind = kind;
    u->phase = RM_INSTANTIATED;
    u->variables = rm_variables(kind);
    u->n_variables = rm_variable_count(kind);
    u->first_input = u->first_output = u->n_variables;
    for (size_t k = u->n_variables; k-- > 0;) {
        if (u->variables[k].causality == RM_OUTPUT) u->first_output = k;
        if (u->variables[k].causality == RM_INPUT) u->first_input = k;
    }
    if (u->first_input > u->first_output) u->first_input = u->first_output;
    rm_text_init(&u->message);
    u->values = calloc(u->n_variables, sizeof *u->values);
    u->provisional = calloc(u->n_variables, sizeof *u->provisional);
    if (u->values == NULL || u->provisional == NULL || !set_defaults(u)
        || (resources != NULL && (u->resources = copy_string(resources)) == NULL)) {
        rm_free(u);
        return NULL;
    }
    return u;
}

static void set_inputs(RmUnit* u, const double* inputs)
{
    size_t j = 0;
    for (size_t k = 0; k < u->n_variables; k++)
        if (u->variables[k].causality == RM_INPUT) u->values[k].r = inputs[j++];
}

static int coupled_start(RmUnit* mesh, RmUnit* drive, double start_time, double* mesh_in,
                         double* drive_in, RmText* err);

/* The inputs' start values: what the partner outputs at t = 0 in the default system. */
static int default_inputs(RmUnit* u)
{
    RmUnit* mesh = unit_alloc(RM_MESH, NULL);
    RmUnit* drive = unit_alloc(RM_DRIVELINE, NULL);
    double mesh_in[8], drive_in[8];
    RmText err;
    rm_text_init(&err);
    int ok = mesh != NULL && drive != NULL
             && coupled_start(mesh, drive, 0.0, mesh_in, drive_in, &err);
    if (ok) set_inputs(u, u->kind == RM_MESH ? mesh_in : drive_in);
    rm_text_free(&err);
    rm_free(mesh);
    rm_free(drive);
    return ok;
}

RmUnit* rm_new(int kind, const char* resources)
{
    RmUnit* u = unit_alloc(kind, resources);
    if (u != NULL && !default_inputs(u)) {
        rm_free(u);
        return NULL;
    }
    return u;
}

void rm_free(RmUnit* u)
{
    if (u == NULL) return;
    if (u->model != NULL) u->cls->free_model(u->model);
    if (u->cls != NULL) u->cls->free_cache(u);
    free_values(u->values, u->n_variables);
    free(u->values);
    free(u->provisional);
    free(u->resources);
    rm_text_free(&u->message);
    free(u);
}

int rm_kind(const RmUnit* u) { return u != NULL ? u->kind : -1; }

int rm_phase(const RmUnit* u) { return u != NULL ? u->phase : -1; }

static int out_of_order(RmUnit* u, const char* action)
{
    RmText t;
    rm_text_init(&t);
    rm_printf(&t, "%s is not allowed in mode '%s'", action, PHASE_NAMES[u->phase]);
    refuse(u, action, &t);
    rm_text_free(&t);
    return u->status;
}

int rm_setup(RmUnit* u, double start_time)
{
    static const char action[] = "setupExperiment";
    if (u == NULL) return RM_ERROR;
    begin(u);
    if (u->phase != RM_INSTANTIATED) return out_of_order(u, action);
    if (!(isfinite(start_time) && fabs(start_time) <= MAX_START_TIME)) {
        RmText t;
        rm_text_init(&t);
        rm_printf(&t, "start time %r s is invalid; allowed: finite, within +-%r s",
                      start_time, MAX_START_TIME);
        refuse(u, action, &t);
        rm_text_free(&t);
        return u->status;
    }
    u->start_time = start_time;
    u->time = start_time; /* the unit's time until its first step */
    return u->status;
}

int rm_enter_initialization(RmUnit* u)
{
    if (u == NULL) return RM_ERROR;
    begin(u);
    if (u->phase != RM_INSTANTIATED) return out_of_order(u, "enterInitializationMode");
    u->phase = RM_INITIALIZATION;
    u->provisional_valid = 0;
    return u->status;
}

int rm_exit_initialization(RmUnit* u)
{
    static const char action[] = "exitInitializationMode";
    if (u == NULL) return RM_ERROR;
    begin(u);
    if (u->phase != RM_INITIALIZATION) return out_of_order(u, action);
    RmText err;
    rm_text_init(&err);
    RmValue* outputs = malloc(u->n_variables * sizeof *outputs);
    void* model = outputs != NULL ? build_model(u, &err) : NULL;
    if (outputs == NULL) rm_printf(&err, "out of memory");
    if (model != NULL) {
        memcpy(outputs, u->values, u->n_variables * sizeof *outputs);
        if (u->cls->outputs(u, model, u->cls->all_groups, outputs, &err)
            && outputs_finite(u, outputs, &err)) {
            /* commit only now that everything succeeded */
            for (size_t k = 0; k < u->n_variables; k++)
                if (u->variables[k].causality == RM_OUTPUT) {
                    u->values[k].r = outputs[k].r;
                    u->values[k].i = outputs[k].i;
                }
            u->model = model;
            model = NULL;
            u->stale = 0;
            u->time = u->start_time;
            u->phase = RM_STEPPING;
            u->provisional_valid = 0;
        }
    }
    if (model != NULL) u->cls->free_model(model);
    free(outputs);
    if (u->phase != RM_STEPPING) refuse(u, action, &err);
    rm_text_free(&err);
    return u->status;
}

/* The spacing of doubles at x (math.ulp). */
static double ulp(double x)
{
    x = fabs(x);
    double up = nextafter(x, INFINITY);
    return isinf(up) ? x - nextafter(x, 0.0) : up - x;
}

int rm_do_step(RmUnit* u, double t, double h)
{
    static const char action[] = "doStep";
    if (u == NULL) return RM_ERROR;
    begin(u);
    RmText err;
    rm_text_init(&err);
    if (u->phase != RM_STEPPING) {
        rm_printf(&err, "doStep is not allowed in mode '%s' (initialize first)",
                  PHASE_NAMES[u->phase]);
    }
    else if (!(isfinite(h) && h > 0.0)) {
        rm_printf(&err, "communication step size %r s is invalid; allowed: finite, > 0", h);
    }
    else if (!isfinite(t)) {
        rm_printf(&err, "communication point %r s is not finite; allowed: the end of the last "
                        "step, %r s", t, u->time);
    }
    else {
        double tol = COMMUNICATION_POINT_TOLERANCE * h + 16.0 * ulp(rm_max(fabs(t), fabs(u->time)));
        if (!(fabs(t - u->time) <= tol)) {
            rm_printf(&err, "communication point %r s does not continue the last step, which "
                            "ended at %r s (tolerance %.3r s)", t, u->time, tol);
        }
        else if (!(t + h > t)) {
            rm_printf(&err, "communication step size %r s does not advance the time %r s (it is "
                            "below its rounding); allowed: a step that moves the time", h, t);
        }
        else if (!(t + h - u->start_time <= MAX_RUN_LENGTH)) {
            rm_printf(&err, "communication step to %r s ends beyond the longest run the unit "
                            "supports; allowed: up to the start time %r s + %r s",
                            t + h, u->start_time, MAX_RUN_LENGTH);
        }
        else {
            RmText warning;
            rm_text_init(&warning);
            int ok = check_inputs(u, u->values, &err) && u->cls->step(u, t, h, &warning, &err);
            if (ok) {
                u->stale = u->cls->all_groups & ~u->cls->fresh_after_step;
                u->time = t + h;
                if (rm_text_str(&warning)[0] != '\0')
                    rm_report(u, RM_WARNING, rm_text_str(&warning));
            }
            rm_text_free(&warning);
            if (ok) {
                rm_text_free(&err);
                return u->status;
            }
        }
    }
    refuse(u, action, &err);
    rm_text_free(&err);
    return u->status;
}

int rm_terminate(RmUnit* u)
{
    if (u == NULL) return RM_ERROR;
    begin(u);
    if (u->phase != RM_STEPPING && u->phase != RM_INITIALIZATION)
        return out_of_order(u, "terminate");
    u->phase = RM_TERMINATED;
    return u->status;
}

int rm_reset(RmUnit* u)
{
    if (u == NULL) return RM_ERROR;
    begin(u);
    /* a new unit: defaults, nothing built (the cache of the fixed model stays: it is a pure
     * function of the parameters) */
    if (u->model != NULL) u->cls->free_model(u->model);
    u->model = NULL;
    u->phase = RM_INSTANTIATED;
    u->start_time = u->time = 0.0;
    u->stale = 0;
    u->provisional_valid = 0;
    u->motion_set = 0;
    if (!set_defaults(u) || !default_inputs(u)) return refuse_text(u, "reset", "out of memory");
    return u->status;
}

int rm_last_successful_time(RmUnit* u, double* t)
{
    if (u == NULL) return RM_ERROR;
    begin(u);
    if (u->model == NULL) {
        RmText err;
        rm_text_init(&err);
        rm_printf(&err, "no communication step is possible yet (mode '%s'); allowed after "
                        "exitInitializationMode", PHASE_NAMES[u->phase]);
        refuse(u, "getRealStatus(fmi2LastSuccessfulTime)", &err);
        rm_text_free(&err);
        *t = NAN;
        return u->status;
    }
    *t = u->time;
    return u->status;
}

double rm_time(const RmUnit* u) { return u != NULL ? u->time : NAN; }

/* ------------------------------------------------------------------ states (record.c) */
int rm_save(RmUnit* u, unsigned char* buf, size_t capacity, size_t* size)
{
    if (u == NULL) return RM_ERROR;
    begin(u);
    if (size == NULL) return refuse_text(u, "getFMUstate", "the size pointer is NULL");
    RmWriter w = {NULL, 0, 0, 0};
    if (!rm_record_write(u, &w)) {
        free(w.data);
        return refuse_text(u, "getFMUstate", "out of memory");
    }
    *size = w.len;
    if (buf != NULL && capacity >= w.len) memcpy(buf, w.data, w.len);
    free(w.data);
    return u->status;
}

int rm_save_alloc(RmUnit* u, unsigned char** record, size_t* size)
{
    if (u == NULL) return RM_ERROR;
    begin(u);
    if (record == NULL || size == NULL)
        return refuse_text(u, "getFMUstate", "the record or size pointer is NULL");
    RmWriter w = {NULL, 0, 0, 0};
    if (!rm_record_write(u, &w) || w.data == NULL) {
        free(w.data);
        return refuse_text(u, "getFMUstate", "out of memory");
    }
    *record = w.data;
    *size = w.len;
    return u->status;
}

/* The header's fields that must go with this unit and with each other: 1, or 0 with the
 * refusal. */
static int header_fits(const RmUnit* u, const RmRecordHeader* h, RmText* err)
{
    if (h->kind != (uint32_t)u->kind || h->n_variables != u->n_variables) {
        rm_printf(err, "it is a state of another unit (kind %u with %u variables, this is kind "
                       "%d with %zu)", h->kind, h->n_variables, u->kind, u->n_variables);
        return 0;
    }
    if (h->phase > RM_TERMINATED || h->motion_set > 1) {
        rm_printf(err, "its mode %u is not one of 0 (instantiated) to 3 (terminated)", h->phase);
        return 0;
    }
    double t0 = h->start_time, t = h->time;
    if (!(isfinite(t0) && fabs(t0) <= MAX_START_TIME && isfinite(t) && t >= t0
          && t - t0 <= MAX_RUN_LENGTH && (h->phase >= RM_STEPPING || t == t0))) {
        rm_printf(err, "its start time %r s and time %r s do not go together; allowed: finite, "
                       "|start time| <= %r s, start time <= time <= start time + %r s, time = "
                       "start time before the first step", t0, t, MAX_START_TIME, MAX_RUN_LENGTH);
        return 0;
    }
    return 1;
}

/* The model of the record's state (NULL when it has none) read after its values, checked
 * against the record's parameters: 1 with *model, or 0 with the refusal. */
static int read_model(RmUnit* u, RmReader* r, const RmRecordHeader* h, RmValue* values,
                      void** model, RmText* err)
{
    *model = NULL;
    uint32_t has_model = rm_read_u32(r);
    if (rm_read_ended(r, "the flag of the model state", err)) return 0;
    int expected = h->phase == RM_STEPPING || (h->phase == RM_TERMINATED && has_model == 1);
    if (has_model > 1 || expected != (int)has_model) {
        rm_printf(err, "mode '%s' does not go with %s model state", PHASE_NAMES[h->phase],
                  has_model == 1 ? "a" : "no");
        return 0;
    }
    if (!has_model) return 1;
    /* the parameters of the state, checked, build the model's fixed part; the record sets its
     * state (nothing is solved, no file read) */
    RmValue* mine = u->values;
    double saved_start = u->start_time, saved_time = u->time;
    u->values = values;
    u->start_time = h->start_time;
    u->time = h->time;
    if (check_parameter_values(u, values, err)) *model = u->cls->restore(u, r, err);
    u->values = mine;
    u->start_time = saved_start;
    u->time = saved_time;
    return *model != NULL;
}

/* The restored state made the unit's: its values (the outputs computed from the model; a
 * state without one -- taken before the end of initialization, or terminated from it --
 * outputs what a fresh unit does, the table's values, not what this unit's earlier run
 * left), model, mode and times.  Takes values and model over. */
static void commit_state(RmUnit* u, const RmRecordHeader* h, RmValue* values, void* model)
{
    for (size_t k = 0; k < u->n_variables; k++) {
        const RmVariable* v = &u->variables[k];
        if (v->causality != RM_OUTPUT) continue;
        values[k] = u->values[k];
        if (model == NULL) {
            values[k].r = v->type == RM_REAL ? v->start : 0.0;
            values[k].i = v->type == RM_REAL ? 0 : (int64_t)v->start;
        }
    }
    if (u->model != NULL) u->cls->free_model(u->model);
    u->model = model;
    free_values(u->values, u->n_variables);
    free(u->values);
    u->values = values;
    u->phase = (int)h->phase;
    u->start_time = h->start_time;
    u->time = h->time;
    u->motion_set = (int)h->motion_set;
    u->stale = u->model != NULL ? u->cls->all_groups : 0;
    u->provisional_valid = 0;
}

int rm_restore(RmUnit* u, const unsigned char* buf, size_t size)
{
    static const char action[] = "setFMUstate";
    if (u == NULL) return RM_ERROR;
    begin(u);
    if (buf == NULL && size > 0) return refuse_text(u, action, "the record is NULL");
    RmReader r = {buf, size, 0, 0};
    RmRecordHeader h;
    RmText err;
    rm_text_init(&err);
    RmValue* values = calloc(u->n_variables, sizeof *values);
    void* model = NULL;
    int ok = 0;
    if (values == NULL)
        rm_printf(&err, "out of memory");
    else if (rm_record_read_header(&r, &h, &err) && header_fits(u, &h, &err)
             && rm_record_read_values(&r, u->variables, u->n_variables, values, &err)
             && read_model(u, &r, &h, values, &model, &err)) {
        if (r.pos != r.len)
            rm_printf(&err, "%zu bytes follow the end of the record", r.len - r.pos);
        else
            ok = 1;
    }
    if (ok) {
        commit_state(u, &h, values, model);
    }
    else {
        if (model != NULL) u->cls->free_model(model);
        if (values != NULL) free_values(values, u->n_variables);
        free(values);
        RmText t;
        rm_text_init(&t);
        rm_printf(&t, "the FMU state is invalid: %s; nothing changed", rm_text_str(&err));
        refuse(u, action, &t);
        rm_text_free(&t);
    }
    rm_text_free(&err);
    return u->status;
}

/* ------------------------------------------------------------------ studies */
int rm_step_report(const RmUnit* u, RmStepReport* report)
{
    if (u == NULL || report == NULL) return RM_ERROR;
    memset(report, 0, sizeof *report);
    const RmStepLog* log = u->model != NULL ? u->cls->step_log(u->model) : NULL;
    if (log != NULL) {
        report->count = log->n_events;
        report->total = log->total_events;
        report->events = log->events;
        report->rhs_evaluations = log->rhs_evaluations;
        report->contact_substeps = log->contact_substeps;
    }
    return RM_OK;
}

/* The exchange of the units' initial outputs, run to its fixed point (what a master that
 * exchanges values during initialization reaches): the driveline built behind the wheel, the
 * mesh's wheel for the driveline's outputs, until nothing changes. */
#define START_EXCHANGE_ROUNDS 8
static int coupled_start(RmUnit* mesh, RmUnit* drive, double start_time, double* mesh_in,
                         double* drive_in, RmText* err)
{
    double wheel[2] = {0.0, 0.0};
    if (!check_parameter_values(mesh, mesh->values, err)
        || !check_parameter_values(drive, drive->values, err))
        return 0;
    for (int round = 0; round < START_EXCHANGE_ROUNDS; round++) {
        double out[5], phi, w;
        if (!rm_driveline_start_outputs(drive, start_time, wheel[0], wheel[1], out, err))
            return 0;
        /* the mesh's inputs: pinion.phi, pinion.w, pinion.a, wheel.tau_load */
        for (int k = 0; k < 4; k++) mesh_in[k] = out[k];
        if (!rm_mesh_start_wheel(mesh, mesh_in, &phi, &w, err)) return 0;
        if (phi == wheel[0] && w == wheel[1]) {
            drive_in[0] = wheel[0];
            drive_in[1] = wheel[1];
            return 1;
        }
        wheel[0] = phi;
        wheel[1] = w;
    }
    rm_printf(err, "the start values of the coupled inputs do not settle within %d exchanges "
                   "(last wheel state %r rad, %r rad/s); check the parameters",
                   START_EXCHANGE_ROUNDS, wheel[0], wheel[1]);
    return 0;
}

int rm_coupled_start(RmUnit* mesh, RmUnit* driveline, double start_time, double* mesh_inputs,
                     double* driveline_inputs)
{
    if (mesh == NULL || driveline == NULL) return RM_ERROR;
    begin(mesh);
    if (mesh->kind != RM_MESH || driveline->kind != RM_DRIVELINE)
        return refuse_text(mesh, "coupledStart", "expected a GearMeshRattle and a Driveline unit");
    RmText err;
    rm_text_init(&err);
    if (!coupled_start(mesh, driveline, start_time, mesh_inputs, driveline_inputs, &err))
        refuse(mesh, "coupledStart", &err);
    rm_text_free(&err);
    return mesh->status;
}

static int describe(RmUnit* u, const char* action, const char** names, double* values,
                    size_t capacity, size_t* count)
{
    if (u == NULL || count == NULL) return RM_ERROR;
    begin(u);
    RmText err;
    rm_text_init(&err);
    *count = 0;
    if (!check_parameter_values(u, u->values, &err)
        || !u->cls->describe(u, names, values, capacity, count, &err))
        refuse(u, action, &err);
    rm_text_free(&err);
    return u->status;
}

int rm_check_parameters(RmUnit* u)
{
    size_t count;
    return describe(u, "checkParameters", NULL, NULL, 0, &count);
}

int rm_describe(RmUnit* u, const char** names, double* values, size_t capacity, size_t* count)
{
    return describe(u, "describe", names, values, capacity, count);
}
