/*
 * fmi2_native.c - the FMI 2.0 co-simulation interface of the native drive-rattle FMUs,
 * written once for both units (the unit is rattle_model.c, selected by the generated
 * rattle_native_tables.h).
 *
 * It does what the pythonfmu FMUs do through pythonfmu's wrapper, the native status shim
 * (rattle_fmi_shim.c) and the slave glue (drive_rattle_fmi/slave.py), with the same checks,
 * statuses and messages:
 *
 *   - fmi2Instantiate checks the instance name (non-blank UTF-8), fmuType (co-simulation
 *     only), the GUID and the resource location (decoded, this FMU's resources folder);
 *   - the life cycle instantiated -> initialization -> stepping -> terminated, every call out
 *     of order refused; parameters are fixed: settable only before the end of
 *     initialization, validated (ranges, the geometry's combination checks) at
 *     fmi2ExitInitializationMode, where the model is built;
 *   - in initialization mode the outputs are computed on request from the current values;
 *   - get/set check every value reference and type; a set with one bad entry stores nothing;
 *   - fmi2DoStep checks the step size, the communication point (it must continue the last
 *     step, within 1e-9 of the step plus a few ulps) and the inputs (finite, in range);
 *   - a refused call returns fmi2Error, changes nothing, and its reason goes to the host's
 *     logger whatever the debug-logging setting, always as ("%s", message);
 *   - FMU states hold everything (values, mode, times, the model's state), as the JSON of the
 *     pythonfmu FMUs (format 3, in the same 96-byte envelope with the GUID and an FNV-1a
 *     checksum); a state's content is checked whole when it is set;
 *   - the status inquiries and the functions these units do not provide answer with a message.
 *
 * Nothing here ever aborts or longjmps out to the host: allocation failures are refusals.
 */
#if !defined(_WIN32) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE
#endif
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rattle_native.h"

#define INSTANCE_MAGIC "RTLNATV"
#define PREFIX "rattle native FMU: "

const char* const RN_MODE_NAMES[4] = RN_MODE_NAME_LIST;

typedef RnInstance Inst;

/* ------------------------------------------------------------------ logging */
/* The message to the host's logger, verbatim (never as a format string). */
static void host_message(const Inst* inst, int status, const char* message)
{
    if (inst->host.logger != NULL)
        inst->host.logger(inst->host.componentEnvironment, inst->name, (fmi2Status)status,
                          rattle_status_category(status), "%s", message);
}

void rn_report(Inst* inst, int status, const char* message)
{
    if (status >= inst->report_status) {
        rn_text_clear(&inst->report_message);
        rn_puts(&inst->report_message, message);
        inst->report_status = status;
    }
}

/* Start of an API call: no status reported yet. */
static void begin(Inst* inst)
{
    inst->report_status = fmi2OK;
    rn_text_clear(&inst->report_message);
}

/* End of an API call (the shim's after_call): the reported status and its message. */
static fmi2Status finish(Inst* inst, fmi2Status st)
{
    int code = inst->report_status;
    if (code == fmi2OK) return st;
    const char* message = rn_text_str(&inst->report_message);
    host_message(inst, code, message[0] != '\0' ? message : "(no message)");
    inst->report_status = fmi2OK;
    return st > (fmi2Status)code ? st : (fmi2Status)code;
}

/* slave._guard: a failed action reports Error with "<action>: <message>". */
static void report_error(Inst* inst, const char* action, const RnError* e)
{
    RnText t;
    rn_text_init(&t);
    if (e->type == NULL)
        rn_printf(&t, "%s: %s", action, rn_text_str(&e->text));
    else
        rn_printf(&t, "%s: unexpected error\n%s: %s", action, e->type, rn_text_str(&e->text));
    rn_report(inst, fmi2Error, rn_text_str(&t));
    rn_text_free(&t);
}

/* A refusal of the shim's argument checks: logged at once, fmi2Error. */
static fmi2Status refuse(Inst* inst, const char* function, const char* fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static fmi2Status refuse(Inst* inst, const char* function, const char* fmt, ...)
{
    char text[2048];
    int n = snprintf(text, sizeof text, "%s: ", function);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text + n, sizeof text - (size_t)n, fmt, ap);
    va_end(ap);
    host_message(inst, fmi2Error, text);
    return fmi2Error;
}

static char* copy_string(const char* s)
{
    size_t n = strlen(s) + 1;
    char* p = malloc(n);
    if (p != NULL) memcpy(p, s, n);
    return p;
}

/* slave.vr_text: a value reference as the host passed it (unsigned). */
static void put_vr(RnText* t, fmi2ValueReference vr) { rn_printf(t, "%u", (unsigned)vr); }

/* ------------------------------------------------------------------ values */
static void set_default_values(Inst* inst)
{
    for (int k = 0; k < RN_N_VARIABLES; k++) {
        const RnVariable* v = &RN_VARIABLES[k];
        RnValue* x = &inst->values[k];
        free(x->s);
        x->s = NULL;
        x->r = v->start_real;
        x->i = v->start_int;
        if (v->fmi_type == RN_STRING) x->s = copy_string(v->start_string ? v->start_string : "");
    }
}

static void free_values(RnValue* values)
{
    for (int k = 0; k < RN_N_VARIABLES; k++) {
        free(values[k].s);
        values[k].s = NULL;
    }
}

/* ParameterSpec.check of every parameter (in declaration order), then the combination. */
static int check_parameters(const RnValue* values, RnError* err)
{
    for (int k = 0; k < RN_N_PARAMETERS; k++) {
        const RnVariable* v = &RN_VARIABLES[k];
        const char* reason = NULL;
        double x;
        if (v->fmi_type == RN_STRING || v->fmi_type == RN_BOOLEAN) continue;
        if (v->fmi_type == RN_INTEGER) {
            x = (double)values[k].i;
            if (v->n_choices > 0) {
                int found = 0;
                for (int c = 0; c < v->n_choices; c++)
                    if (values[k].i == v->choices[c]) found = 1;
                if (!found) reason = "is out of range";
            }
        }
        else {
            x = values[k].r;
            if (!isfinite(x)) reason = "must be finite";
        }
        if (reason == NULL && v->has_min && (x < v->min || (v->min_exclusive && x == v->min)))
            reason = "is out of range";
        if (reason == NULL && v->has_max && (x > v->max || (v->max_exclusive && x == v->max)))
            reason = "is out of range";
        if (reason != NULL) {
            RnText* t = rn_error_value(err);
            rn_printf(t, "parameter '%s' = ", v->name);
            if (v->fmi_type == RN_INTEGER)
                rn_printf(t, "%lld", (long long)values[k].i);
            else
                rn_put_repr(t, values[k].r);
            rn_printf(t, " %s; allowed: %s", reason, v->allowed);
            return 0;
        }
    }
    return rn_unit_check_combination(values, err);
}

/* SignalSpec.check of every input. */
static int check_inputs(const RnValue* values, RnError* err)
{
    for (int k = RN_N_PARAMETERS; k < RN_N_VARIABLES; k++) {
        const RnVariable* v = &RN_VARIABLES[k];
        if (v->causality != RN_INPUT) continue;
        double x = values[k].r;
        if (!isfinite(x)) {
            RnText* t = rn_error_value(err);
            rn_printf(t, "input '%s' = ", v->name);
            rn_put_repr(t, x);
            rn_puts(t, " is not finite; allowed: finite numbers");
            return 0;
        }
        if ((v->has_min && x < v->min) || (v->has_max && x > v->max)) {
            RnText* t = rn_error_value(err);
            rn_printf(t, "input '%s' = ", v->name);
            rn_put_repr(t, x);
            rn_printf(t, " is out of range; allowed: %s", v->allowed);
            return 0;
        }
    }
    return 1;
}

/* The outputs of `model` in its stale groups, stored in `values` (slave._refresh_outputs). */
static int refresh_outputs(Inst* inst, unsigned groups, RnError* err)
{
    if (inst->model == NULL || (inst->stale & groups) == 0) return 1;
    unsigned todo = inst->stale & groups;
    if (!rn_unit_outputs(inst->model, todo, inst->values, err)) return 0;
    inst->stale &= ~todo;
    if (todo & RN_GROUP_LOADS) inst->stale = 0; /* the loads' computation writes them all */
    return 1;
}

/* slave._refresh_provisional: outputs of a model built from the current values (the values
 * as they are if that fails: it is reported at fmi2ExitInitializationMode). */
static void refresh_provisional(Inst* inst)
{
    if (inst->provisional_valid) return;
    RnError e;
    rn_error_init(&e);
    for (int k = 0; k < RN_N_VARIABLES; k++) inst->provisional[k] = inst->values[k];
    if (check_inputs(inst->values, &e) && check_parameters(inst->values, &e)) {
        void* model = rn_unit_build(inst, inst->values, &e);
        if (model != NULL) {
            rn_unit_outputs(model, RN_GROUP_QUICK | RN_GROUP_STATE | RN_GROUP_LOADS,
                            inst->provisional, &e);
            rn_unit_free(model);
        }
    }
    for (int k = 0; k < RN_N_VARIABLES; k++) inst->provisional[k].s = NULL; /* not owned */
    rn_error_free(&e);
    inst->provisional_valid = 1;
}

/* ------------------------------------------------------------------ resource location */
#if defined(_WIN32)
#define SEP "\\"
#else
#define SEP "/"
#endif

/* The canonical path of this FMU's resources folder that `location` names (malloc'ed), or
 * NULL with the reason.  The folder must exist and hold RN_RESOURCE_MARKER naming this FMU. */
static char* resolve_resources(const char* location, char* why, size_t why_size)
{
    char shown[256];
    char module[256];
    char reason[256];
    char* decoded;
    char* real;
    RnText file;
    if (location == NULL) {
        snprintf(why, why_size, "is NULL; allowed: the URI of this FMU's resources folder");
        return NULL;
    }
    decoded = rattle_location_to_path(location, why, why_size);
    if (decoded == NULL) return NULL;
    rattle_printable(shown, sizeof shown, decoded);
    real = rn_realpath(decoded, reason, sizeof reason);
    free(decoded);
    if (real == NULL || !rn_is_dir(real)) {
        snprintf(why, why_size, "names '%s', which %s; allowed: this FMU's resources folder",
                 shown, real == NULL ? reason : "is not a folder");
        free(real);
        return NULL;
    }
    rattle_printable(shown, sizeof shown, real);
    if (strlen(real) > (size_t)RN_MAX_PATH_BYTES - 64) {
        snprintf(why, why_size, "names a path of %zu bytes; allowed: at most %d", strlen(real),
                 RN_MAX_PATH_BYTES - 64);
        free(real);
        return NULL;
    }
    rn_text_init(&file);
    rn_printf(&file, "%s" SEP "model_identifier.txt", real);
    if (rn_first_line(rn_text_str(&file), module, sizeof module) != 0) {
        rn_text_clear(&file);
        rn_printf(&file, "%s" SEP "resources" SEP "model_identifier.txt", real);
        if (rn_is_regular_file(rn_text_str(&file)))
            snprintf(why, why_size, "names '%s', the folder the FMU was unpacked to; allowed: "
                                    "its resources folder, '%s" SEP "resources'", shown, shown);
        else
            snprintf(why, why_size, "names '%s', which has no model_identifier.txt: not the "
                                    "resources folder of this FMU", shown);
        rn_text_free(&file);
        free(real);
        return NULL;
    }
    rn_text_free(&file);
    if (strcmp(module, RN_MODEL_IDENTIFIER) != 0) {
        char other[64];
        rattle_printable(other, sizeof other, module);
        snprintf(why, why_size, "names '%s', the resources of FMU '%s', not of %s", shown, other,
                 RN_MODEL_IDENTIFIER);
        free(real);
        return NULL;
    }
    return real;
}

/* ------------------------------------------------------------------ FMU states */
/* An FMU state: the slave's state as the JSON of the pythonfmu FMUs (payload), tagged with the
 * FMU's GUID as the shim tags its states (rattle_fmi_common.h), on the list of the instance
 * that made it. */
struct RnState {
    RattleStateTag tag; /* first: the host's pointer is checked through it */
    char* payload;
    size_t n;
    Inst* owner;
    RnState* next;
    RnState* prev;
};

static RnState* own_state(Inst* inst, fmi2FMUstate state, const char* function)
{
    char why[300];
    if (!rattle_state_is_ours(state, RN_GUID, why, sizeof why)) {
        refuse(inst, function, "%s", why);
        return NULL;
    }
    return state;
}

static RnState* new_state(Inst* inst, char* payload, size_t n)
{
    RnState* st = calloc(1, sizeof *st);
    if (st == NULL) return NULL;
    rattle_state_tag(&st->tag, RN_GUID);
    st->payload = payload;
    st->n = n;
    st->owner = inst;
    st->next = inst->states;
    if (inst->states != NULL) inst->states->prev = st;
    inst->states = st;
    return st;
}

static void delete_state(RnState* st)
{
    Inst* owner = st->owner;
    if (st->prev != NULL)
        st->prev->next = st->next;
    else if (owner != NULL)
        owner->states = st->next;
    if (st->next != NULL) st->next->prev = st->prev;
    rattle_state_untag(&st->tag);
    free(st->payload);
    free(st);
}

/* slave._get_fmu_state as json.dumps(state, sort_keys=True). */
static void state_json(const Inst* inst, RnText* j)
{
    rn_printf(j, "{\"format\": %d, \"mode\": ", RN_STATE_FORMAT);
    rn_json_put_string(j, RN_MODE_NAMES[inst->mode]);
    rn_puts(j, ", \"model\": ");
    if (inst->model == NULL)
        rn_puts(j, "null");
    else
        rn_unit_snapshot(inst->model, j);
    rn_puts(j, ", \"start_time\": ");
    rn_json_put_float(j, inst->start_time);
    rn_puts(j, ", \"time\": ");
    rn_json_put_float(j, inst->time);
    rn_puts(j, ", \"values\": {");
    for (int k = 0; k < RN_N_VARIABLES; k++) {
        unsigned vr = RN_SORTED_VR[k];
        const RnVariable* v = &RN_VARIABLES[vr];
        const RnValue* x = &inst->values[vr];
        if (k) rn_puts(j, ", ");
        rn_json_put_string(j, v->name);
        rn_puts(j, ": ");
        switch (v->fmi_type) {
        case RN_REAL: rn_json_put_float(j, x->r); break;
        case RN_INTEGER: rn_printf(j, "%lld", (long long)x->i); break;
        case RN_BOOLEAN: rn_puts(j, x->i ? "true" : "false"); break;
        default: rn_json_put_string(j, x->s ? x->s : ""); break;
        }
    }
    rn_puts(j, "}}");
}

/* json.dumps(value, sort_keys=True) of a parsed value (a deserialized state is held as
 * pythonfmu holds it: parsed, and dumped again when serialized). */
static void json_dump(RnText* t, const RnJson* j)
{
    switch (j->kind) {
    case RJ_NULL: rn_puts(t, "null"); break;
    case RJ_FALSE: rn_puts(t, "false"); break;
    case RJ_TRUE: rn_puts(t, "true"); break;
    case RJ_INT: rn_printf(t, "%lld", (long long)j->i); break;
    case RJ_BIGINT: rn_puts(t, j->s); break;
    case RJ_FLOAT: rn_json_put_float(t, j->f); break;
    case RJ_STRING: {
        /* strings with a NUL: escape it (json.dumps writes \u0000) */
        if (j->has_nul) {
            rn_puts(t, "\"");
            for (size_t k = 0; k < j->slen; k++) {
                if (j->s[k] == '\0')
                    rn_puts(t, "\\u0000");
                else {
                    char one[2] = {j->s[k], '\0'};
                    RnText piece;
                    rn_text_init(&piece);
                    rn_json_put_string(&piece, one);
                    rn_putn(t, piece.data + 1, piece.len - 2);
                    rn_text_free(&piece);
                }
            }
            rn_puts(t, "\"");
        }
        else
            rn_json_put_string(t, j->s);
        break;
    }
    case RJ_ARRAY:
        rn_puts(t, "[");
        for (size_t k = 0; k < j->n; k++) {
            if (k) rn_puts(t, ", ");
            json_dump(t, &j->items[k]);
        }
        rn_puts(t, "]");
        break;
    case RJ_OBJECT: {
        size_t n = j->n;
        size_t* order = malloc((n ? n : 1) * sizeof *order);
        if (order == NULL) {
            t->failed = 1;
            return;
        }
        for (size_t k = 0; k < n; k++) order[k] = k;
        for (size_t a = 1; a < n; a++)
            for (size_t b = a; b > 0 && strcmp(j->keys[order[b - 1]], j->keys[order[b]]) > 0;
                 b--) {
                size_t x = order[b];
                order[b] = order[b - 1];
                order[b - 1] = x;
            }
        rn_puts(t, "{");
        for (size_t k = 0; k < n; k++) {
            if (k) rn_puts(t, ", ");
            rn_json_put_string(t, j->keys[order[k]]);
            rn_puts(t, ": ");
            json_dump(t, &j->items[order[k]]);
        }
        rn_puts(t, "}");
        free(order);
        break;
    }
    }
}

/* _value_problem: why `value` cannot be the stored value of variable `v` ("" if it can). */
static const char* value_problem(const RnVariable* v, const RnJson* value)
{
    switch (v->fmi_type) {
    case RN_REAL:
        if (value->kind != RJ_FLOAT) return "expected a float";
        if (v->causality == RN_OUTPUT && !isfinite(value->f)) return "an output must be finite";
        return "";
    case RN_INTEGER:
        if (value->kind != RJ_INT && value->kind != RJ_BIGINT) return "expected an integer";
        if (value->kind == RJ_BIGINT || value->i > RN_MAX_STATE_INTEGER
            || value->i < -RN_MAX_STATE_INTEGER)
            return "beyond +-2^53 (+-9007199254740992)";
        return "";
    case RN_BOOLEAN:
        if (value->kind != RJ_TRUE && value->kind != RJ_FALSE) return "expected true or false";
        return "";
    default:
        if (value->kind != RJ_STRING) return "expected a string";
        if (value->has_nul) return "a string with a NUL character";
        if (value->bad_unicode) return "a string that is not valid Unicode";
        return "";
    }
}

static void put_name_list(RnText* t, const char** names, size_t n, size_t limit)
{
    rn_puts(t, "[");
    for (size_t k = 0; k < n && k < limit; k++) {
        if (k) rn_puts(t, ", ");
        rn_put_repr_str(t, names[k]);
    }
    rn_puts(t, "]");
}

static int cmp_str(const void* a, const void* b)
{
    return strcmp(*(const char* const*)a, *(const char* const*)b);
}

static int variable_index(const char* name)
{
    for (int k = 0; k < RN_N_VARIABLES; k++)
        if (strcmp(RN_VARIABLES[k].name, name) == 0) return k;
    return -1;
}

/* slave._set_fmu_state's restore: the state's content checked whole (format, entries, mode,
 * times, every variable present with a value of its type, the model snapshot with the
 * mode), the parameters validated and the model rebuilt from the snapshot; only then is
 * anything changed.  0 with the ModelError otherwise. */
static int restore_state(Inst* inst, const char* payload, size_t n, RnError* err)
{
    static const char* const KEYS[6] = {"format", "mode", "model", "start_time", "time",
                                        "values"};
    RnJson* s = rn_json_parse(payload, n);
    RnJson empty;
    int ok = 0;
    memset(&empty, 0, sizeof empty);
    empty.kind = RJ_OBJECT;
    const RnJson* state = s != NULL ? s : &empty;
    RnText* t = NULL;
#define INVALID()                                                                              \
    do {                                                                                       \
        t = rn_error_value(err);                                                               \
        rn_puts(t, "the FMU state is invalid: ");                                              \
    } while (0)
#define NOTHING_CHANGED() rn_puts(t, "; nothing changed")
    if (state->kind != RJ_OBJECT || state->n == 0) {
        INVALID();
        rn_puts(t, "it is empty or not a state of this FMU");
        NOTHING_CHANGED();
        goto done;
    }
    {
        const RnJson* format = rn_json_get(state, "format");
        int is_format = format != NULL
                        && ((format->kind == RJ_INT && format->i == RN_STATE_FORMAT)
                            || (format->kind == RJ_FLOAT && format->f == RN_STATE_FORMAT)
                            || (format->kind == RJ_TRUE && RN_STATE_FORMAT == 1));
        if (!is_format) {
            INVALID();
            rn_puts(t, "its format is ");
            if (format == NULL)
                rn_puts(t, "None");
            else
                rn_json_repr(t, format);
            rn_printf(t, ", this FMU reads format %d", RN_STATE_FORMAT);
            NOTHING_CHANGED();
            goto done;
        }
    }
    {
        int keys_ok = state->n == 6;
        for (int k = 0; keys_ok && k < 6; k++)
            if (rn_json_get(state, KEYS[k]) == NULL) keys_ok = 0;
        if (!keys_ok) {
            const char** names = malloc(state->n * sizeof *names);
            INVALID();
            rn_puts(t, "its entries are ");
            if (names != NULL) {
                for (size_t k = 0; k < state->n; k++) names[k] = state->keys[k];
                qsort(names, state->n, sizeof *names, cmp_str);
                put_name_list(t, names, state->n, state->n);
                free(names);
            }
            rn_puts(t, ", expected ['format', 'mode', 'model', 'start_time', 'time', 'values']");
            NOTHING_CHANGED();
            goto done;
        }
    }
    const RnJson* mode_j = rn_json_get(state, "mode");
    int mode = -1;
    if (mode_j->kind == RJ_STRING && !mode_j->has_nul)
        for (int k = 0; k < 4; k++)
            if (strcmp(mode_j->s, RN_MODE_NAMES[k]) == 0) mode = k;
    if (mode < 0) {
        INVALID();
        rn_puts(t, "mode ");
        rn_json_repr(t, mode_j);
        rn_printf(t, " is not one of %s, %s, %s, %s", RN_MODE_NAMES[0], RN_MODE_NAMES[1],
                  RN_MODE_NAMES[2], RN_MODE_NAMES[3]);
        NOTHING_CHANGED();
        goto done;
    }
    {
        static const char* const TIMES[2] = {"start_time", "time"};
        for (int k = 0; k < 2; k++) {
            const RnJson* x = rn_json_get(state, TIMES[k]);
            if (!rn_json_is_finite_float(x)) {
                INVALID();
                rn_printf(t, "%s = ", TIMES[k]);
                rn_json_repr(t, x);
                rn_puts(t, " is not a finite float");
                NOTHING_CHANGED();
                goto done;
            }
        }
    }
    const RnJson* values = rn_json_get(state, "values");
    {
        const char* missing[RN_N_VARIABLES];
        size_t n_missing = 0, n_extra = 0;
        const char** extra = NULL;
        int is_dict = values->kind == RJ_OBJECT;
        if (is_dict) {
            for (int k = 0; k < RN_N_VARIABLES; k++) {
                unsigned vr = RN_SORTED_VR[k];
                if (rn_json_get(values, RN_VARIABLES[vr].name) == NULL)
                    missing[n_missing++] = RN_VARIABLES[vr].name;
            }
            extra = malloc((values->n ? values->n : 1) * sizeof *extra);
            for (size_t k = 0; extra != NULL && k < values->n; k++)
                if (variable_index(values->keys[k]) < 0) extra[n_extra++] = values->keys[k];
            if (extra != NULL) qsort(extra, n_extra, sizeof *extra, cmp_str);
        }
        if (!is_dict || n_missing > 0 || n_extra > 0) {
            INVALID();
            rn_puts(t, "its variables do not match this FMU's (missing ");
            put_name_list(t, missing, n_missing, 3);
            rn_puts(t, ", unknown ");
            put_name_list(t, (const char**)extra, n_extra, 3);
            rn_puts(t, ")");
            NOTHING_CHANGED();
            free(extra);
            goto done;
        }
        free(extra);
    }
    for (size_t k = 0; k < values->n; k++) {
        int vr = variable_index(values->keys[k]);
        const char* problem = value_problem(&RN_VARIABLES[vr], &values->items[k]);
        if (problem[0] != '\0') {
            INVALID();
            rn_printf(t, "variable '%s' = ", values->keys[k]);
            rn_json_short_repr(t, &values->items[k]);
            rn_printf(t, ": %s", problem);
            NOTHING_CHANGED();
            goto done;
        }
    }
    const RnJson* model_j = rn_json_get(state, "model");
    {
        int has_model = model_j->kind != RJ_NULL;
        int expected = mode == RN_MODE_STEPPING || (mode == RN_MODE_TERMINATED && has_model);
        if (expected != has_model || (has_model && model_j->kind != RJ_OBJECT)) {
            INVALID();
            rn_printf(t, "mode '%s' does not go with model snapshot ", RN_MODE_NAMES[mode]);
            rn_json_short_repr(t, model_j);
            NOTHING_CHANGED();
            goto done;
        }
    }
    {
        RnValue restored[RN_N_VARIABLES];
        memset(restored, 0, sizeof restored);
        for (size_t k = 0; k < values->n; k++) {
            int vr = variable_index(values->keys[k]);
            const RnJson* x = &values->items[k];
            restored[vr].r = x->kind == RJ_FLOAT ? x->f : 0.0;
            restored[vr].i = x->kind == RJ_INT ? x->i : (x->kind == RJ_TRUE ? 1 : 0);
            if (RN_VARIABLES[vr].fmi_type == RN_STRING) {
                restored[vr].s = copy_string(x->s);
                if (restored[vr].s == NULL) {
                    free_values(restored);
                    rn_puts(rn_error_other(err, "MemoryError"), "");
                    goto done;
                }
            }
        }
        double start_time = rn_json_get(state, "start_time")->f;
        void* model = NULL;
        if (model_j->kind != RJ_NULL) {
            RnError inner;
            rn_error_init(&inner);
            if (check_parameters(restored, &inner))
                model = rn_unit_restore(inst, restored, start_time, model_j, &inner);
            if (model == NULL) {
                if (inner.type == NULL) {
                    INVALID();
                    rn_puts(t, rn_text_str(&inner.text));
                    NOTHING_CHANGED();
                }
                else
                    rn_puts(rn_error_other(err, inner.type), rn_text_str(&inner.text));
                rn_error_free(&inner);
                free_values(restored);
                goto done;
            }
            rn_error_free(&inner);
        }
        /* commit */
        free_values(inst->values);
        memcpy(inst->values, restored, sizeof restored);
        if (inst->model != NULL) rn_unit_free(inst->model);
        inst->model = model;
        inst->stale = 0;
        inst->mode = mode;
        inst->start_time = start_time;
        inst->time = rn_json_get(state, "time")->f;
        inst->provisional_valid = 0;
        ok = 1;
    }
#undef INVALID
#undef NOTHING_CHANGED
done:
    if (s != NULL) {
        rn_json_free(s);
        free(s);
    }
    return ok;
}

/* ------------------------------------------------------------------ the API */
const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char* fmi2GetVersion(void) { return fmi2Version; }

/* fmi2Instantiate's refusals go to the host's logger before any instance exists. */
#define instantiate_log(functions, name, status, ...)                                          \
    rattle_instantiate_log(functions, name, status, PREFIX, __VA_ARGS__)

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    char name[256];
    char why[1536];
    Inst* inst;
    char* resources;
    (void)visible;
    if (functions == NULL) return NULL; /* nobody to tell */
    if (!rattle_check_instantiate(instanceName, (int)fmuType, fmuGUID, RN_GUID, name,
                                  sizeof name, why, sizeof why)) {
        instantiate_log(functions, name, fmi2Error, "%s", why);
        return NULL;
    }
    resources = resolve_resources(fmuResourceLocation, why, sizeof why);
    if (resources == NULL) {
        char location[512];
        rattle_printable(location, sizeof location,
                     fmuResourceLocation != NULL ? fmuResourceLocation : "(null)");
        instantiate_log(functions, name, fmi2Error, "fmuResourceLocation '%s' %s", location,
                        why);
        return NULL;
    }
    inst = calloc(1, sizeof *inst);
    if (inst == NULL || (inst->name = copy_string(instanceName)) == NULL) {
        instantiate_log(functions, name, fmi2Fatal, "out of memory");
        free(inst);
        free(resources);
        return NULL;
    }
    memcpy(inst->magic, INSTANCE_MAGIC, sizeof inst->magic);
    inst->host = *functions;
    inst->logging_on = loggingOn != fmi2False;
    inst->resources = resources;
    inst->mode = RN_MODE_INSTANTIATED;
    rn_text_init(&inst->report_message);
    set_default_values(inst);
    return inst;
}

void fmi2FreeInstance(fmi2Component c)
{
    Inst* inst = c;
    if (inst == NULL) return;
    while (inst->states != NULL) delete_state(inst->states);
    if (inst->model != NULL) rn_unit_free(inst->model);
    rn_unit_free_cache(inst);
    free_values(inst->values);
    rn_text_free(&inst->report_message);
    free(inst->resources);
    free(inst->name);
    memset(inst->magic, 0, sizeof inst->magic);
    free(inst);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    if (nCategories > 0 && categories == NULL)
        return refuse(inst, "fmi2SetDebugLogging", "nCategories = %zu but categories is NULL; "
                      "nothing changed", nCategories);
    for (size_t i = 0; i < nCategories; i++) {
        size_t bad;
        if (categories[i] == NULL)
            return refuse(inst, "fmi2SetDebugLogging", "category %zu of %zu is NULL; nothing "
                          "changed", i, nCategories);
        bad = rattle_utf8_error_at(categories[i]);
        if (bad != (size_t)-1)
            return refuse(inst, "fmi2SetDebugLogging", "category %zu is not valid UTF-8 (offset "
                          "%zu); nothing changed", i, bad);
    }
    inst->logging_on = loggingOn != fmi2False;
    return fmi2OK;
}

/* ModelError of a call out of order */
static void out_of_order(Inst* inst, const char* action, const char* what)
{
    RnText t;
    rn_text_init(&t);
    rn_printf(&t, "%s: %s is not allowed in mode '%s'", action, what, RN_MODE_NAMES[inst->mode]);
    rn_report(inst, fmi2Error, rn_text_str(&t));
    rn_text_free(&t);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    Inst* inst = c;
    (void)toleranceDefined, (void)tolerance, (void)stopTimeDefined, (void)stopTime;
    if (inst == NULL) return fmi2Error;
    begin(inst);
    if (!isfinite(startTime)) {
        RnText t;
        rn_text_init(&t);
        rn_puts(&t, "setupExperiment: start time ");
        rn_put_repr(&t, startTime);
        rn_puts(&t, " is not finite");
        rn_report(inst, fmi2Error, rn_text_str(&t));
        rn_text_free(&t);
    }
    else if (inst->mode != RN_MODE_INSTANTIATED)
        out_of_order(inst, "setupExperiment", "setupExperiment");
    else
        inst->start_time = startTime;
    return finish(inst, fmi2OK);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    begin(inst);
    if (inst->mode != RN_MODE_INSTANTIATED)
        out_of_order(inst, "enterInitializationMode", "enterInitializationMode");
    else {
        inst->mode = RN_MODE_INITIALIZATION;
        inst->provisional_valid = 0;
    }
    return finish(inst, fmi2OK);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Inst* inst = c;
    RnError e;
    if (inst == NULL) return fmi2Error;
    begin(inst);
    if (inst->mode != RN_MODE_INITIALIZATION) {
        out_of_order(inst, "exitInitializationMode", "exitInitializationMode");
        return finish(inst, fmi2OK);
    }
    rn_error_init(&e);
    void* model = NULL;
    RnValue outputs[RN_N_VARIABLES];
    if (check_parameters(inst->values, &e) && check_inputs(inst->values, &e)
        && (model = rn_unit_build(inst, inst->values, &e)) != NULL) {
        for (int k = 0; k < RN_N_VARIABLES; k++) outputs[k] = inst->values[k];
        if (rn_unit_outputs(model, RN_GROUP_QUICK | RN_GROUP_STATE | RN_GROUP_LOADS, outputs,
                            &e)) {
            /* commit only now that everything succeeded */
            for (int k = 0; k < RN_N_VARIABLES; k++)
                if (RN_VARIABLES[k].causality == RN_OUTPUT) {
                    inst->values[k].r = outputs[k].r;
                    inst->values[k].i = outputs[k].i;
                }
            inst->model = model;
            inst->stale = 0;
            inst->time = inst->start_time;
            inst->mode = RN_MODE_STEPPING;
            inst->provisional_valid = 0;
            model = NULL;
        }
    }
    if (model != NULL) rn_unit_free(model);
    if (e.set) report_error(inst, "exitInitializationMode", &e);
    rn_error_free(&e);
    return finish(inst, fmi2OK);
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    begin(inst);
    if (inst->mode != RN_MODE_STEPPING && inst->mode != RN_MODE_INITIALIZATION)
        out_of_order(inst, "terminate", "terminate");
    else
        inst->mode = RN_MODE_TERMINATED;
    return finish(inst, fmi2OK);
}

fmi2Status fmi2Reset(fmi2Component c)
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    begin(inst);
    /* a new slave: default values, nothing built, nothing cached */
    if (inst->model != NULL) rn_unit_free(inst->model);
    inst->model = NULL;
    rn_unit_free_cache(inst);
    set_default_values(inst);
    inst->mode = RN_MODE_INSTANTIATED;
    inst->start_time = inst->time = 0.0;
    inst->stale = 0;
    inst->provisional_valid = 0;
    inst->motion_set = 0;
    return finish(inst, fmi2OK);
}

/* ------------------------------------------------------------------ get */
static const char* fmi_type_name(int fmi_type)
{
    switch (fmi_type) {
    case RN_REAL: return "Real";
    case RN_INTEGER: return "Integer";
    case RN_BOOLEAN: return "Boolean";
    default: return "String";
    }
}

/* The value of variable vr for a get (slave._get): outputs from the initialization mode's
 * provisional model or refreshed after a step.  NULL with err set if it cannot be computed. */
static const RnValue* value_for_get(Inst* inst, unsigned vr, RnError* err)
{
    const RnVariable* v = &RN_VARIABLES[vr];
    if (v->causality == RN_OUTPUT) {
        if (inst->mode == RN_MODE_INITIALIZATION) {
            refresh_provisional(inst);
            return &inst->provisional[vr];
        }
        if ((inst->stale & (unsigned)v->group) && !refresh_outputs(inst, (unsigned)v->group, err))
            return NULL;
    }
    return &inst->values[vr];
}

/* slave._get_values: every valid entry answered; an unknown value reference or another type
 * reported (the last such message logged) with the type's default. */
static fmi2Status get_values(Inst* inst, const char* function, int fmi_type,
                             const fmi2ValueReference vr[], size_t nvr, void* out)
{
    if (nvr == 0) return fmi2OK;
    if (vr == NULL || out == NULL)
        return refuse(inst, function, "nvr = %zu but the %s array is NULL", nvr,
                      vr == NULL ? "value-reference" : "value");
    begin(inst);
    for (size_t i = 0; i < nvr; i++) {
        const RnValue* x = NULL;
        if (vr[i] < RN_N_VARIABLES && RN_VARIABLES[vr[i]].fmi_type == fmi_type) {
            RnError e;
            rn_error_init(&e);
            x = value_for_get(inst, vr[i], &e);
            if (x == NULL) {
                RnText action;
                rn_text_init(&action);
                rn_printf(&action, "get%s vr %u", fmi_type_name(fmi_type), (unsigned)vr[i]);
                report_error(inst, rn_text_str(&action), &e);
                rn_text_free(&action);
            }
            rn_error_free(&e);
        }
        else {
            RnText t;
            rn_text_init(&t);
            rn_printf(&t, "get%s: no %s variable with value reference ", fmi_type_name(fmi_type),
                      fmi_type_name(fmi_type));
            put_vr(&t, vr[i]);
            rn_report(inst, fmi2Error, rn_text_str(&t));
            rn_text_free(&t);
        }
        switch (fmi_type) {
        case RN_REAL: ((fmi2Real*)out)[i] = x != NULL ? x->r : NAN; break;
        case RN_INTEGER: {
            int64_t n = x != NULL ? x->i : 0;
            /* fmi2Integer is 32 bits: saturate (the cumulative counters can exceed it) */
            ((fmi2Integer*)out)[i] = n > 2147483647LL ? 2147483647
                                     : n < -2147483647LL - 1 ? (-2147483647 - 1)
                                                              : (fmi2Integer)n;
            break;
        }
        case RN_BOOLEAN: ((fmi2Boolean*)out)[i] = x != NULL && x->i ? fmi2True : fmi2False; break;
        default: ((fmi2String*)out)[i] = x != NULL && x->s != NULL ? x->s : ""; break;
        }
    }
    return finish(inst, fmi2OK);
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    return get_values(inst, "fmi2GetReal", RN_REAL, vr, nvr, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    return get_values(inst, "fmi2GetInteger", RN_INTEGER, vr, nvr, value);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    return get_values(inst, "fmi2GetBoolean", RN_BOOLEAN, vr, nvr, value);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    return get_values(inst, "fmi2GetString", RN_STRING, vr, nvr, (void*)value);
}

/* ------------------------------------------------------------------ set */
/* repr() of the value a host passes, as pythonfmu hands it to the slave (Boolean as bool). */
static void put_given(RnText* t, int fmi_type, const void* values, size_t i)
{
    switch (fmi_type) {
    case RN_REAL: rn_put_repr(t, ((const fmi2Real*)values)[i]); break;
    case RN_INTEGER: rn_printf(t, "%d", ((const fmi2Integer*)values)[i]); break;
    case RN_BOOLEAN: rn_puts(t, ((const fmi2Boolean*)values)[i] ? "True" : "False"); break;
    default: rn_put_repr_str(t, ((const fmi2String*)values)[i]); break;
    }
}

/* slave._set_values: every entry checked before any is stored, so a refused call (one bad
 * entry) stores nothing. */
static fmi2Status set_values(Inst* inst, const char* function, int fmi_type,
                             const fmi2ValueReference vr[], size_t nvr, const void* values)
{
    if (nvr == 0) return fmi2OK;
    if (vr == NULL || values == NULL)
        return refuse(inst, function, "nvr = %zu but the %s array is NULL", nvr,
                      vr == NULL ? "value-reference" : "value");
    if (fmi_type == RN_STRING) /* the shim's checks of String values */
        for (size_t i = 0; i < nvr; i++) {
            const char* s = ((const fmi2String*)values)[i];
            size_t bad;
            if (s == NULL)
                return refuse(inst, function, "value %zu (value reference %u) is NULL; nothing "
                              "of this call was stored", i, (unsigned)vr[i]);
            bad = rattle_utf8_error_at(s);
            if (bad != (size_t)-1)
                return refuse(inst, function, "value %zu (value reference %u) is not valid "
                              "UTF-8 (byte 0x%02X at offset %zu); nothing of this call was "
                              "stored", i, (unsigned)vr[i], (unsigned)(unsigned char)s[bad],
                              bad);
        }
    begin(inst);
    const char* kname = fmi_type_name(fmi_type);
    int refused = 0;
    for (size_t i = 0; i < nvr && !refused; i++) {
        RnText t;
        rn_text_init(&t);
        if (!(vr[i] < RN_N_VARIABLES && RN_VARIABLES[vr[i]].fmi_type == fmi_type)) {
            rn_printf(&t, "set%s: no %s variable with value reference ", kname, kname);
            put_vr(&t, vr[i]);
            rn_puts(&t, "; nothing of this call was stored");
            refused = 1;
        }
        else {
            const RnVariable* v = &RN_VARIABLES[vr[i]];
            if (v->causality == RN_OUTPUT) {
                rn_printf(&t, "set%s: '%s' is an output and cannot be set; nothing of this "
                              "call was stored", kname, v->name);
                refused = 1;
            }
            else if (v->causality == RN_PARAMETER && inst->mode != RN_MODE_INSTANTIATED
                     && inst->mode != RN_MODE_INITIALIZATION) {
                rn_printf(&t, "set%s: parameter '%s' is fixed: it can only be set before the "
                              "end of initialization (mode is '%s'); value ", kname, v->name,
                          RN_MODE_NAMES[inst->mode]);
                put_given(&t, fmi_type, values, i);
                rn_puts(&t, " rejected; nothing of this call was stored");
                refused = 1;
            }
        }
        if (refused) rn_report(inst, fmi2Error, rn_text_str(&t));
        rn_text_free(&t);
    }
    if (!refused) {
        for (size_t i = 0; i < nvr; i++) {
            RnValue* x = &inst->values[vr[i]];
            switch (fmi_type) {
            case RN_REAL: x->r = ((const fmi2Real*)values)[i]; break;
            case RN_INTEGER: x->i = ((const fmi2Integer*)values)[i]; break;
            case RN_BOOLEAN: x->i = ((const fmi2Boolean*)values)[i] != fmi2False; break;
            default: {
                char* s = copy_string(((const fmi2String*)values)[i]);
                if (s == NULL) {
                    rn_report(inst, fmi2Error, "setString: out of memory");
                    break;
                }
                free(x->s);
                x->s = s;
            }
            }
        }
        inst->provisional_valid = 0;
    }
    /* boundary.HeldInputTracking.set_real: a call naming a motion input marks them set (as
     * the pythonfmu FMUs do, whether the call was accepted or not) */
    if (fmi_type == RN_REAL && !inst->motion_set)
        for (size_t i = 0; i < nvr; i++)
            if (rn_unit_is_motion_input(vr[i])) inst->motion_set = 1;
    return finish(inst, fmi2OK);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    return set_values(inst, "fmi2SetReal", RN_REAL, vr, nvr, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    return set_values(inst, "fmi2SetInteger", RN_INTEGER, vr, nvr, value);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    return set_values(inst, "fmi2SetBoolean", RN_BOOLEAN, vr, nvr, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    return set_values(inst, "fmi2SetString", RN_STRING, vr, nvr, value);
}

/* ------------------------------------------------------------------ doStep */
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    Inst* inst = c;
    double t = currentCommunicationPoint, h = communicationStepSize;
    RnError e;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (inst == NULL) return fmi2Error;
    begin(inst);
    rn_error_init(&e);
    if (inst->mode != RN_MODE_STEPPING) {
        rn_printf(rn_error_value(&e), "doStep is not allowed in mode '%s' (initialize first)",
                  RN_MODE_NAMES[inst->mode]);
    }
    else if (!(isfinite(h) && h > 0.0)) {
        RnText* m = rn_error_value(&e);
        rn_puts(m, "communication step size ");
        rn_put_repr(m, h);
        rn_puts(m, " s is invalid; allowed: finite, > 0");
    }
    else if (!isfinite(t)) {
        RnText* m = rn_error_value(&e);
        rn_puts(m, "communication point ");
        rn_put_repr(m, t);
        rn_puts(m, " s is not finite; allowed: the end of the last step, ");
        rn_put_repr(m, inst->time);
        rn_puts(m, " s");
    }
    else {
        /* COMMUNICATION_POINT_TOLERANCE * h + 16 ulp(max(|time|, |t|)) */
        double big = fabs(t) > fabs(inst->time) ? fabs(t) : fabs(inst->time);
        double up = nextafter(big, INFINITY);
        double ulp = isinf(up) ? big - nextafter(big, 0.0) : up - big; /* math.ulp */
        double tol = RN_COMMUNICATION_POINT_TOLERANCE * h + 16.0 * ulp;
        if (!(fabs(t - inst->time) <= tol)) {
            RnText* m = rn_error_value(&e);
            rn_puts(m, "communication point ");
            rn_put_repr(m, t);
            rn_puts(m, " s does not continue the last step, which ended at ");
            rn_put_repr(m, inst->time);
            rn_puts(m, " s (tolerance ");
            rn_put_g(m, tol, 3);
            rn_puts(m, " s)");
        }
        else if (check_inputs(inst->values, &e) && rn_unit_step(inst, t, h, &e)) {
            inst->stale = RN_GROUP_QUICK | RN_GROUP_STATE | RN_GROUP_LOADS;
            inst->time = t + h;
        }
    }
    if (e.set) report_error(inst, "doStep", &e);
    rn_error_free(&e);
    return finish(inst, fmi2OK);
}

/* ------------------------------------------------------------------ FMU states */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    Inst* inst = c;
    RnState* reuse = NULL;
    RnText json;
    RnError e;
    if (inst == NULL) return fmi2Error;
    if (state == NULL) return refuse(inst, "fmi2GetFMUstate", "the FMUstate pointer is NULL");
    if (*state != NULL && (reuse = own_state(inst, *state, "fmi2GetFMUstate")) == NULL)
        return fmi2Error;
    begin(inst);
    rn_error_init(&e);
    if (!refresh_outputs(inst, RN_GROUP_QUICK | RN_GROUP_STATE | RN_GROUP_LOADS, &e)) {
        report_error(inst, "getFMUstate", &e);
        rn_error_free(&e);
        return finish(inst, fmi2OK);
    }
    rn_error_free(&e);
    rn_text_init(&json);
    state_json(inst, &json);
    if (json.failed || json.data == NULL) {
        rn_text_free(&json);
        rn_report(inst, fmi2Error, "getFMUstate: out of memory");
        return finish(inst, fmi2OK);
    }
    if (reuse != NULL) {
        free(reuse->payload);
        reuse->payload = json.data;
        reuse->n = json.len;
    }
    else {
        RnState* st = new_state(inst, json.data, json.len);
        if (st == NULL) {
            rn_text_free(&json);
            rn_report(inst, fmi2Error, "fmi2GetFMUstate: out of memory");
            return finish(inst, fmi2OK);
        }
        *state = st;
    }
    return finish(inst, fmi2OK);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    Inst* inst = c;
    RnState* st;
    RnError e;
    if (inst == NULL) return fmi2Error;
    if ((st = own_state(inst, state, "fmi2SetFMUstate")) == NULL) return fmi2Error;
    begin(inst);
    rn_error_init(&e);
    if (!restore_state(inst, st->payload, st->n, &e)) report_error(inst, "setFMUstate", &e);
    rn_error_free(&e);
    return finish(inst, fmi2OK);
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    Inst* inst = c;
    RnState* st;
    if (inst == NULL) return fmi2Error;
    if (state == NULL || *state == NULL) return fmi2OK; /* FMI 2.0: the call is ignored */
    if ((st = own_state(inst, *state, "fmi2FreeFMUstate")) == NULL) return fmi2Error;
    delete_state(st);
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size)
{
    Inst* inst = c;
    RnState* st;
    if (inst == NULL) return fmi2Error;
    if (size == NULL) return refuse(inst, "fmi2SerializedFMUstateSize", "size is NULL");
    if ((st = own_state(inst, state, "fmi2SerializedFMUstateSize")) == NULL) return fmi2Error;
    *size = RATTLE_STATE_HEADER + st->n;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte serializedState[],
                                 size_t size)
{
    Inst* inst = c;
    RnState* st;
    unsigned char* out = (unsigned char*)serializedState;
    if (inst == NULL) return fmi2Error;
    if ((st = own_state(inst, state, "fmi2SerializeFMUstate")) == NULL) return fmi2Error;
    if (serializedState == NULL) return refuse(inst, "fmi2SerializeFMUstate", "the buffer is NULL");
    size_t n = st->n;
    char why[200];
    if (!rattle_state_fits(size, n, why, sizeof why))
        return refuse(inst, "fmi2SerializeFMUstate", "%s", why);
    memcpy(out + RATTLE_STATE_HEADER, st->payload, n);
    rattle_state_seal(out, size, n, RN_GUID);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* state)
{
    static const char function[] = "fmi2DeSerializeFMUstate";
    Inst* inst = c;
    const unsigned char* in = (const unsigned char*)serializedState;
    RnState* reuse = NULL;
    uint64_t n;
    if (inst == NULL) return fmi2Error;
    if (state == NULL) return refuse(inst, function, "the FMUstate pointer is NULL");
    if (serializedState == NULL && size > 0) return refuse(inst, function, "the buffer is NULL");
    char why[300];
    if (!rattle_state_open(in, size, RN_GUID, &n, why, sizeof why))
        return refuse(inst, function, "%s", why);
    if (*state != NULL && (reuse = own_state(inst, *state, function)) == NULL) return fmi2Error;
    /* pythonfmu holds the parsed state (an empty dict where it does not parse) and dumps it
     * again when it is serialized */
    RnText canonical;
    rn_text_init(&canonical);
    RnJson* parsed = rn_json_parse((const char*)in + RATTLE_STATE_HEADER, (size_t)n);
    if (parsed != NULL) {
        json_dump(&canonical, parsed);
        rn_json_free(parsed);
        free(parsed);
    }
    else
        rn_puts(&canonical, "{}");
    if (canonical.failed || canonical.data == NULL) {
        rn_text_free(&canonical);
        return refuse(inst, function, "out of memory");
    }
    if (reuse != NULL) {
        free(reuse->payload);
        reuse->payload = canonical.data;
        reuse->n = canonical.len;
        return fmi2OK;
    }
    RnState* st = new_state(inst, canonical.data, canonical.len);
    if (st == NULL) {
        rn_text_free(&canonical);
        return refuse(inst, function, "out of memory");
    }
    *state = st;
    return fmi2OK;
}

/* ------------------------------------------------------------------ not provided */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    Inst* inst = c;
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown;
    (void)dvUnknown;
    if (inst == NULL) return fmi2Error;
    return refuse(inst, "fmi2GetDirectionalDerivative", "%s",
                  RATTLE_NO_DIRECTIONAL_DERIVATIVES);
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    Inst* inst = c;
    (void)vr, (void)nvr, (void)order, (void)value;
    if (inst == NULL) return fmi2Error;
    return refuse(inst, "fmi2SetRealInputDerivatives", "%s",
                  RATTLE_NO_INPUT_DERIVATIVES);
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    Inst* inst = c;
    (void)vr, (void)nvr, (void)order, (void)value;
    if (inst == NULL) return fmi2Error;
    return refuse(inst, "fmi2GetRealOutputDerivatives", "%s",
                  RATTLE_NO_OUTPUT_DERIVATIVES);
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    return refuse(inst, "fmi2CancelStep", "%s",
                  RATTLE_NO_ASYNCHRONOUS_STEP);
}

static fmi2Status status_refused(Inst* inst, const char* function, int kind, const char* allowed)
{
    char why[400];
    rattle_status_refusal(why, sizeof why, kind, allowed);
    return refuse(inst, function, "%s", why);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status* value)
{
    Inst* inst = c;
    (void)value;
    if (inst == NULL) return fmi2Error;
    return status_refused(inst, "fmi2GetStatus", (int)kind, "none");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real* value)
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    if (kind != fmi2LastSuccessfulTime)
        return status_refused(inst, "fmi2GetRealStatus", (int)kind, "fmi2LastSuccessfulTime");
    if (value == NULL) return refuse(inst, "fmi2GetRealStatus", "value is NULL");
    begin(inst);
    if (inst->model == NULL) {
        /* slave._last_successful_time */
        RnText t;
        rn_text_init(&t);
        rn_printf(&t, "getRealStatus(fmi2LastSuccessfulTime): no communication step is "
                      "possible yet (mode '%s'); allowed after exitInitializationMode",
                  RN_MODE_NAMES[inst->mode]);
        rn_report(inst, fmi2Error, rn_text_str(&t));
        rn_text_free(&t);
        return finish(inst, fmi2OK);
    }
    *value = inst->time;
    return finish(inst, fmi2OK);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer* value)
{
    Inst* inst = c;
    (void)value;
    if (inst == NULL) return fmi2Error;
    return status_refused(inst, "fmi2GetIntegerStatus", (int)kind, "none (FMI 2.0 defines no "
                          "Integer status)");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean* value)
{
    Inst* inst = c;
    if (inst == NULL) return fmi2Error;
    if (kind != fmi2Terminated)
        return status_refused(inst, "fmi2GetBooleanStatus", (int)kind, "fmi2Terminated");
    if (value == NULL) return refuse(inst, "fmi2GetBooleanStatus", "value is NULL");
    *value = fmi2False; /* the units never ask to end the simulation */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String* value)
{
    Inst* inst = c;
    (void)value;
    if (inst == NULL) return fmi2Error;
    return status_refused(inst, "fmi2GetStringStatus", (int)kind, "none");
}
