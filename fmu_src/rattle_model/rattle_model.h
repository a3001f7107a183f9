/*
 * rattle_model.h - the drive-rattle model (Theodossiades, Rahnejat, De la Cruz, Kelly, ENOC
 * 2008) as one C library, and its one public interface.  It knows nothing of FMI: the FMI 2.0
 * glue of the native FMUs (fmu_src/fmi2/), the pythonfmu slaves and the Python API
 * (fmu_src/drive_rattle/, through ctypes) are faces on it.
 *
 * A unit is one of the two co-simulation units of the system:
 *   RM_MESH       GearMeshRattle: kinematic pinion in, the wheel integrated inside against
 *                 the Hertzian, lubricated flanks of every tooth pair (paper eq. 1-17);
 *   RM_DRIVELINE  Driveline: engine-order or measured input-shaft kinematics out, the output
 *                 shaft to the reflected vehicle inertia.
 * Its variables (parameters, inputs, outputs) are declared once in Python
 * (drive_rattle.parameters, drive_rattle.interface); rm_tables.c is generated from them.  A
 * variable is addressed by its index in rm_variables(kind), its value reference in the FMUs.
 *
 * Life of a unit (the phases are FMI co-simulation's, without its types):
 *   rm_new                      INSTANTIATED: parameters and inputs at their defaults
 *   rm_set_*                    parameters while INSTANTIATED or INITIALIZATION, inputs any time
 *   rm_setup(start_time)        INSTANTIATED only
 *   rm_enter_initialization     -> INITIALIZATION: outputs are computed on request
 *   rm_exit_initialization      parameters checked, model built, start solved -> STEPPING
 *   rm_do_step(t, h)            STEPPING: t must continue the last step
 *   rm_terminate                -> TERMINATED;  rm_reset -> INSTANTIATED, defaults
 *   rm_save / rm_restore        the complete unit as a versioned binary record
 *
 * Every call returns RM_OK, RM_WARNING or RM_ERROR; a refused call (RM_ERROR) changes
 * nothing, and rm_message() holds its reason (the warning's text after RM_WARNING).  Messages
 * name what was wrong, the value and what is allowed; they are written here, once, for every
 * face.  Nothing here aborts, longjmps out or prints.
 *
 * Units are independent (the library writes no global state), so different units may be used
 * from different threads at once; one unit from one thread at a time.
 */
#ifndef RATTLE_MODEL_H
#define RATTLE_MODEL_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32) && defined(RM_BUILD_SHARED)
#define RM_API __declspec(dllexport)
#elif (defined(__GNUC__) || defined(__clang__)) && defined(RM_BUILD_SHARED)
#define RM_API __attribute__((visibility("default")))
#else
#define RM_API
#endif

/* Version of this interface; rm_api_version() returns it (a binding checks it). */
#define RM_API_VERSION 1

typedef enum { RM_MESH = 0, RM_DRIVELINE = 1 } RmKind;
#define RM_N_KINDS 2

/* Statuses: the numbers are fmi2Status's (and fmi3Status's) OK, Warning, Error. */
typedef enum { RM_OK = 0, RM_WARNING = 1, RM_ERROR = 3 } RmStatus;

typedef enum {
    RM_INSTANTIATED = 0,
    RM_INITIALIZATION = 1,
    RM_STEPPING = 2,
    RM_TERMINATED = 3
} RmPhase;

typedef enum { RM_REAL = 0, RM_INTEGER = 1, RM_BOOLEAN = 2, RM_STRING = 3 } RmType;
typedef enum { RM_PARAMETER = 0, RM_INPUT = 1, RM_OUTPUT = 2 } RmCausality;

/* One variable of a unit (generated from the Python specs, in value-reference order:
 * parameters, inputs, outputs). */
typedef struct {
    const char* name;
    int type;      /* RmType */
    int causality; /* RmCausality */
    const char* unit; /* SI unit ("" for none) */
    double start;     /* default of a Real, Integer or Boolean parameter; 0 for the others */
    const char* start_string; /* default of a String parameter */
    int has_min, has_max, min_exclusive, max_exclusive;
    double min, max;
    int n_choices;
    const int* choices; /* allowed codes of an enumeration */
    const char* allowed; /* "what is allowed", as the messages say it */
} RmVariable;

/* The variables of a unit kind and their number (NULL and 0 for an unknown kind). */
RM_API const RmVariable* rm_variables(int kind);
RM_API size_t rm_variable_count(int kind);
RM_API int rm_api_version(void);
/* A text naming the sources the library was built from (the build's hash). */
RM_API const char* rm_build_id(void);

typedef struct RmUnit RmUnit;

/* ------------------------------------------------------------------ life cycle */
/* A new unit in phase INSTANTIATED.  `resources` is the folder relative speed-table paths
 * resolve against (NULL: the working directory only).  NULL only for an unknown kind or when
 * out of memory.  The inputs start at what the partner unit outputs at t = 0 in the default
 * system (rm_coupled_start of the defaults). */
RM_API RmUnit* rm_new(int kind, const char* resources);
RM_API void rm_free(RmUnit* u);
RM_API int rm_kind(const RmUnit* u);
/* An optional logger: every non-OK message, as it is produced (the same text as rm_message),
 * with its status.  NULL removes it. */
typedef void (*RmLogger)(void* env, int status, const char* message);
RM_API void rm_set_logger(RmUnit* u, RmLogger logger, void* env);
RM_API int rm_phase(const RmUnit* u);
/* The reason of the last call's non-OK status ("" when it returned RM_OK). */
RM_API const char* rm_message(const RmUnit* u);

RM_API int rm_setup(RmUnit* u, double start_time);
RM_API int rm_enter_initialization(RmUnit* u);
RM_API int rm_exit_initialization(RmUnit* u);
RM_API int rm_do_step(RmUnit* u, double t, double h);
RM_API int rm_terminate(RmUnit* u);
RM_API int rm_reset(RmUnit* u);
/* The end of the last accepted step (the start time before the first); RM_ERROR before
 * initialization has ended. */
RM_API int rm_last_successful_time(RmUnit* u, double* t);
/* The unit's time in every mode: the start time until the first step (0 before
 * rm_setup), then the end of the last accepted step; a restored state's.  NaN for NULL. */
RM_API double rm_time(const RmUnit* u);

/* ------------------------------------------------------------------ values */
/* n values by index.  A set checks every entry before it stores any: one bad entry refuses
 * the whole call.  Integers are 32-bit, as FMI's (larger counters saturate on get); Booleans
 * are 0 or non-0.  A get answers every valid entry and NaN / 0 / "" for the invalid ones
 * (RM_ERROR then).  Strings returned stay valid until the next call on the unit. */
RM_API int rm_set_real(RmUnit* u, const unsigned* vr, size_t n, const double* values);
RM_API int rm_set_integer(RmUnit* u, const unsigned* vr, size_t n, const int32_t* values);
RM_API int rm_set_boolean(RmUnit* u, const unsigned* vr, size_t n, const int32_t* values);
RM_API int rm_set_string(RmUnit* u, const unsigned* vr, size_t n, const char* const* values);
RM_API int rm_get_real(RmUnit* u, const unsigned* vr, size_t n, double* values);
RM_API int rm_get_integer(RmUnit* u, const unsigned* vr, size_t n, int32_t* values);
RM_API int rm_get_boolean(RmUnit* u, const unsigned* vr, size_t n, int32_t* values);
RM_API int rm_get_string(RmUnit* u, const unsigned* vr, size_t n, const char** values);

/* ------------------------------------------------------------------ state */
/* The complete unit (phase, times, every value, the model's state) as a record of *size
 * bytes written to buf when it fits `capacity` (call with buf NULL for the size).  RM_ERROR
 * before anything could be saved (out of memory). */
RM_API int rm_save(RmUnit* u, unsigned char* buf, size_t capacity, size_t* size);
/* The same record in a new buffer, *record of *size bytes, for the caller to free() (the faces
 * compile the library into their own binary, so they share its allocator).  RM_ERROR (nothing
 * allocated) when the pointers are NULL or out of memory. */
RM_API int rm_save_alloc(RmUnit* u, unsigned char** record, size_t* size);
/* The unit as a record of rm_save left it (any unit of the same kind), checked whole before
 * anything changes: its version and kind, every value in its domain, the times consistent,
 * the parameters valid.  Linear in the record's size; nothing is solved or read from files. */
RM_API int rm_restore(RmUnit* u, const unsigned char* buf, size_t size);

/* ------------------------------------------------------------------ events (RM_MESH) */
/* A located contact event of the last step. */
typedef struct {
    double time;  /* from the start of the step [s] */
    int kind;     /* RM_EVENT_ONSET, ... */
    int flank;    /* +1 drive, -1 coast */
    double speed; /* normal approach speed d(delta)/dt at the event [m/s] */
} RmEvent;
/* ONSET: a contact begins with the flanks approaching (an impact, counted); RELEASE: it ends;
 * REVERSAL: a pair's friction turns; PAIR: a crowned pair starts or stops carrying load;
 * TOUCH: the inputs moved the pinion into a flank that recedes at a communication point: a
 * contact begins without approach, loaded but not an impact (not counted, no energy). */
enum {
    RM_EVENT_ONSET = 0,
    RM_EVENT_RELEASE = 1,
    RM_EVENT_REVERSAL = 2,
    RM_EVENT_PAIR = 3,
    RM_EVENT_TOUCH = 4
};
/* The events of the last accepted step and their number (at most RM_MAX_EVENTS are kept,
 * `total` counts all), and the step's cost counters. */
#define RM_MAX_EVENTS 512
typedef struct {
    size_t count, total;
    const RmEvent* events;
    int64_t rhs_evaluations, contact_substeps;
} RmStepReport;
RM_API int rm_step_report(const RmUnit* u, RmStepReport* report);

/* ------------------------------------------------------------------ studies */
/* The parameters' ranges, choices and combination checks (the geometry's, the contact law's
 * fit), as rm_exit_initialization makes them, without building a model or using the
 * inputs: RM_OK, or RM_ERROR with the reason. */
RM_API int rm_check_parameters(RmUnit* u);

/* The start values of the coupled system: what each unit's partner outputs at start_time
 * once both are initialized, the exchange run to its fixed point.  `mesh` and `driveline`
 * are units holding the parameters (phase INSTANTIATED or INITIALIZATION; their inputs are
 * not used); writes the mesh's inputs (pinion.phi, pinion.w, pinion.a, wheel.tau_load) and
 * the driveline's (wheel.phi, wheel.w) in declaration order.  RM_ERROR with the reason in
 * rm_message(mesh). */
RM_API int rm_coupled_start(RmUnit* mesh, RmUnit* driveline, double start_time,
                            double* mesh_inputs, double* driveline_inputs);

/* The two units coupled as the co-simulation couples them (fixed step, Jacobi exchange along
 * the connections, points t_k = (start_ns + k step_ns) / 1e9 and steps t_{k+1} - t_k) for
 * `steps` steps, through the same calls the FMUs make: both units initialized (phase
 * STEPPING) at start_ns / 1e9.  At every point k (steps + 1 of them) the n_record variables
 * record_vr[i] of unit record_unit[i] (RM_MESH or RM_DRIVELINE; Real or Integer) are written
 * to record[i (steps + 1) + k] before the step (a column per variable); every contact onset of the mesh as (time, speed,
 * flank) to onsets (at most onset_capacity kept, *n_onsets counts all).  RM_ERROR with the
 * refusing unit's message in rm_message(mesh) (the units then stay as that call left them). */
RM_API int rm_run_coupled(RmUnit* mesh, RmUnit* driveline, int64_t start_ns, int64_t step_ns,
                          int64_t steps, const unsigned* record_vr, const int* record_unit,
                          size_t n_record, double* record, double* onsets,
                          size_t onset_capacity, size_t* n_onsets);

/* Derived quantities of the unit's parameters (geometry, contact law, masses: SI units), as
 * parallel arrays of at most `capacity` names and values; *count gets their number.  The
 * parameters are checked first (RM_ERROR with the reason). */
RM_API int rm_describe(RmUnit* u, const char** names, double* values, size_t capacity,
                       size_t* count);

#ifdef __cplusplus
}
#endif

#endif
