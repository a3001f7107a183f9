/*
 * rattle_native.h - declarations shared by the native (C only) drive-rattle FMUs:
 *
 *   fmi2_native.c    the FMI 2.0 co-simulation glue, written once for both units: life cycle
 *                    and its state machine, argument checks, parameter and input validation,
 *                    get/set, logging, FMU states and their serialization
 *   rattle_model.c   the units: GearMeshRattle (geometry, contact law fit, Hunt-Crossley
 *                    factor, equilibrium start, stepping through rattle_kernel.c) or Driveline
 *                    (engine orders or speed table, output shaft), with how each reads held
 *                    inputs and the first step (drive_rattle_fmi/boundary.py)
 *   rattle_pytext.c  Python-compatible text: float repr, %g, string repr, JSON in and out
 *   rattle_files.c   the file system: resource folder, speed-table file (POSIX and Windows)
 *   rattle_kernel.c  the compiled stepper kernel (shared with the pythonfmu FMUs)
 *
 * and the generated rattle_native_tables.h / .c (drive_rattle_build/native.py renders them
 * from the same specs as the pythonfmu FMUs' registration and modelDescription: the unit, its
 * GUID, every variable with its value reference, type, causality, start value and limits, and
 * the constants of the Python modules the C code transcribes).
 *
 * The behaviour is the pythonfmu FMUs' (drive_rattle_fmi/slave.py, boundary.py and the native
 * shim rattle_fmi_shim.c): the same checks, statuses and messages, and on linux64 the same
 * numbers bit for bit (docs/native_fmu.md).
 */
#ifndef RATTLE_NATIVE_H
#define RATTLE_NATIVE_H

#include <stddef.h>
#include <stdint.h>

#include "fmi2Functions.h"
#include "rattle_fmi_common.h"

/* ------------------------------------------------------------------ variables */
enum { RN_REAL, RN_INTEGER, RN_BOOLEAN, RN_STRING };
enum { RN_PARAMETER, RN_INPUT, RN_OUTPUT };

/* One variable of the interface (the generated table, in value-reference order). */
typedef struct {
    const char* name;
    int fmi_type;    /* RN_REAL ... */
    int causality;   /* RN_PARAMETER, RN_INPUT, RN_OUTPUT */
    const char* unit; /* SI unit of the spec ("" for none) */
    double start_real;
    long long start_int; /* Integer and Boolean */
    const char* start_string;
    int has_min, has_max, min_exclusive, max_exclusive;
    double min, max;
    int n_choices;
    const int* choices; /* allowed codes of an enumeration parameter */
    const char* allowed; /* ParameterSpec.allowed() of a parameter; "[lo, hi] unit" of an input */
    int group;           /* outputs: which computation refreshes it (RN_GROUP_...) */
} RnVariable;

/* A stored value, with Python's types: Real float, Integer int (up to 2^53 in a restored
 * state), Boolean bool, String str (UTF-8). */
typedef struct {
    double r;
    int64_t i;
    char* s;
} RnValue;

#include "rattle_native_tables.h"

/* ------------------------------------------------------------------ text */
/* A growable UTF-8 string; on allocation failure it keeps what it has and sets `failed`. */
typedef struct {
    char* data;
    size_t len, cap;
    int failed;
} RnText;

void rn_text_init(RnText* t);
void rn_text_free(RnText* t);
void rn_text_clear(RnText* t);
const char* rn_text_str(const RnText* t); /* "" when empty */
void rn_puts(RnText* t, const char* s);
void rn_putn(RnText* t, const char* s, size_t n);
void rn_printf(RnText* t, const char* fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Python's repr(float) (shortest round trip: 0.1, 1e-05, 1e+16, nan, -inf, -0.0). */
void rn_put_repr(RnText* t, double x);
const char* rn_repr(char* buf, size_t size, double x); /* buf of at least 32 bytes */
/* Python's format(x, '.<precision>g') and '.<precision>f'. */
void rn_put_g(RnText* t, double x, int precision);
void rn_put_f(RnText* t, double x, int precision);
/* Python's repr(str) of a UTF-8 string (quotes chosen and characters escaped as Python
 * does; bytes that are not UTF-8 are shown as \xNN). */
void rn_put_repr_str(RnText* t, const char* s);
void rn_put_repr_strn(RnText* t, const char* s, size_t n);
/* Python's float(text) of a str: surrounding whitespace, '_' between digits, inf, nan;
 * returns 1 and *out, or 0 where Python raises ValueError. */
int rn_parse_python_float(const char* text, size_t n, double* out);
/* Locale-independent strtod of a complete decimal literal (JSON); 1 on success. */
int rn_strtod(const char* text, size_t n, double* out);

/* Number of code points of valid UTF-8 text (validity and printable copies:
 * rattle_fmi_common.h). */
size_t rn_utf8_length(const char* s, size_t n);

/* ------------------------------------------------------------------ JSON (Python's json) */
typedef enum { RJ_NULL, RJ_FALSE, RJ_TRUE, RJ_INT, RJ_BIGINT, RJ_FLOAT, RJ_STRING, RJ_ARRAY,
               RJ_OBJECT } RjKind;

/* A value of json.loads: int (RJ_INT, or RJ_BIGINT beyond int64 with its digits in s), float,
 * str (UTF-8 in s, bad_unicode when it holds a lone surrogate or a NUL is in has_nul), list,
 * dict (keys in order of first appearance, the last value of a repeated key). */
typedef struct RnJson {
    RjKind kind;
    int64_t i;
    double f;
    char* s;
    size_t slen;
    int bad_unicode, has_nul;
    size_t n;
    struct RnJson* items;
    char** keys;
} RnJson;

/* json.loads(bytes.decode('utf-8')); NULL where Python raises. */
RnJson* rn_json_parse(const char* data, size_t n);
void rn_json_free(RnJson* j);
const RnJson* rn_json_get(const RnJson* object, const char* key);
/* repr() of the parsed value, and _short_repr (first 60 characters, then "..."). */
void rn_json_repr(RnText* t, const RnJson* j);
void rn_json_short_repr(RnText* t, const RnJson* j);
/* Python's type(x).__name__ of a parsed value. */
const char* rn_json_type_name(const RnJson* j);
int rn_json_is_finite_float(const RnJson* j);
/* json.dumps pieces: a float (NaN, Infinity, repr), a str (ensure_ascii escapes). */
void rn_json_put_float(RnText* t, double x);
void rn_json_put_string(RnText* t, const char* s);

/* ------------------------------------------------------------------ files */
/* The canonical absolute path of an existing folder (malloc'ed), or NULL with errno-like text
 * in `why`. */
char* rn_realpath(const char* path, char* why, size_t why_size);
int rn_is_dir(const char* path);
int rn_is_regular_file(const char* path);
int rn_path_exists(const char* path);
/* The first line of a small text file, without its line end; 0 on success. */
int rn_first_line(const char* path, char* out, size_t size);
/* read_bounded_file: the bytes of the regular file `path`, at most `limit` (malloc'ed, *n),
 * or NULL with the message of drive_rattle.driveline.read_bounded_file in `err`. */
char* rn_read_bounded_file(const char* path, size_t limit, const char* parameter, size_t* n,
                           RnText* err);
/* str(Path(text)): redundant separators and "." parts dropped (pathlib's normalisation). */
void rn_path_normalise(RnText* out, const char* text);

/* ------------------------------------------------------------------ the instance */
enum { RN_MODE_INSTANTIATED, RN_MODE_INITIALIZATION, RN_MODE_STEPPING, RN_MODE_TERMINATED };
extern const char* const RN_MODE_NAMES[4];

/* An error of a guarded action (drive_rattle_fmi.slave.RattleSlave._guard): a ValueError or
 * ModelError becomes "<action>: <message>", any other exception "<action>: unexpected
 * error..." with its type. */
typedef struct {
    int set;
    const char* type; /* NULL: ValueError/ModelError; else "OverflowError", ... */
    RnText text;
} RnError;

void rn_error_init(RnError* e);
void rn_error_free(RnError* e);
void rn_error_clear(RnError* e);
RnText* rn_error_value(RnError* e);              /* start a ValueError message */
RnText* rn_error_other(RnError* e, const char* type); /* start another exception's message */

typedef struct RnState RnState;

typedef struct RnInstance {
    char magic[8];
    fmi2CallbackFunctions host;
    char* name;
    int logging_on;
    int mode;
    double start_time, time;
    RnValue values[RN_N_VARIABLES];
    /* outputs: which groups are out of date after a step (RN_GROUP_... bits) */
    unsigned stale;
    /* initialization mode: outputs of a model built from the current values */
    int provisional_valid;
    RnValue provisional[RN_N_VARIABLES];
    void* model;          /* the unit's model (rattle_model.c), NULL before initialization */
    int motion_set;       /* boundary.HeldInputTracking._motion_set */
    char* resources;      /* the resources folder, canonical path */
    void* unit_cache;     /* the unit's own cache (the Driveline's speed table) */
    int report_status;    /* the status of the current call (slave._report) */
    RnText report_message;
    RnState* states;      /* FMU states made by this instance */
} RnInstance;

/* slave._report: the current call returns at least `status`, with `message` logged. */
void rn_report(RnInstance* inst, int status, const char* message);

/* ------------------------------------------------------------------ the unit (rattle_model.c) */
/* Cross-parameter checks of the parameter set (MeshParameters._check_combination): 0 with a
 * ValueError in err if invalid. */
int rn_unit_check_combination(const RnValue* values, RnError* err);
/* A new model for the parameter values (validated) and the inputs (checked): the slave's
 * _build.  NULL with err set on failure. */
void* rn_unit_build(RnInstance* inst, const RnValue* values, RnError* err);
void rn_unit_free(void* model);
/* The slave's _step (boundary.py): advance inst->model from t by h with the current inputs;
 * 0 with err set (the model unchanged) on refusal.  May rn_report a warning. */
int rn_unit_step(RnInstance* inst, double t, double h, RnError* err);
/* The output values of `model` in `out` (entries of the outputs in `groups` written). */
int rn_unit_outputs(void* model, unsigned groups, RnValue* out, RnError* err);
/* The model snapshot of an FMU state, as JSON (sort_keys order). */
void rn_unit_snapshot(const void* model, RnText* json);
/* The model from a snapshot (slave._model_from_snapshot): NULL with err set if invalid. */
void* rn_unit_restore(RnInstance* inst, const RnValue* values, double start_time,
                      const RnJson* snapshot, RnError* err);
/* The unit's cache of inst->unit_cache is released. */
void rn_unit_free_cache(RnInstance* inst);
/* HeldInputTracking.set_real: the master set one of the motion inputs. */
int rn_unit_is_motion_input(unsigned vr);

#endif
