/*
 * rattle_fmi_shim.c - FMI 2.0 co-simulation "status shim" around pythonfmu's binary.
 *
 * pythonfmu 0.7.0's C++ wrapper (whose sources are not shipped, so it cannot be rebuilt) turns
 * every Python exception into fmi2Fatal, ignores the return value of every slave method except
 * do_step, hands log messages to the host only when debug logging is on (and as a printf
 * FORMAT), and does not check what a master passes.  Measured (docs/fmi.md, "The status
 * shim"), each of these killed or corrupted the host process:
 *   - it replaces "%20" in the resource path by a space (after any decoding of ours) and
 *     deletes "file://"; a resource location without slavemodule.txt and <module>.py (the
 *     unzip root, a missing folder, a relative path, an http:// URI) ends in
 *     PyObject_Call(NULL); a NULL location, instance name or debug-logging category ends in
 *     std::string(NULL); a non-UTF-8 instance name or unpack path, or a non-UTF-8 fmi2String
 *     value, fails inside Python's C API;
 *   - fmi2SerializeFMUstate copies as many bytes as the host's buffer holds from a Python
 *     bytes object of the state's size (heap disclosure, SIGSEGV for large buffers);
 *     fmi2GetFMUstate into a non-NULL *state leaks the old state; a state from elsewhere is
 *     used as a Python object;
 *   - fmi2ModelExchange is accepted; fmi2GetRealStatus(fmi2LastSuccessfulTime) answers the
 *     end of a step the slave refused; its unsupported functions return fmi2Error silently.
 *
 * The shim becomes binaries/linux64/<modelIdentifier>.so and forwards every FMI call to
 * pythonfmu's library, renamed to RATTLE_INNER_LIB and loaded from the shim's own directory,
 * after checking the call's arguments: what pythonfmu cannot take is refused here with
 * fmi2Error (NULL from fmi2Instantiate) and a message to the host's logger, and nothing
 * reaches pythonfmu.  On top:
 *   - status protocol: at instantiation the slave gives (String variable
 *     RATTLE_VR_STATUS_ADDRESS) the address of a C int it owns, as "0x...".  After every
 *     forwarded call the shim looks at that int; if it is non-zero, the shim resets it to 0,
 *     reads the message (String variable RATTLE_VR_MESSAGE), logs it to the host regardless of
 *     debug logging and returns the larger of pythonfmu's status and the slave's;
 *   - the resource location is decoded and checked here; pythonfmu gets a plain absolute
 *     path it cannot misread, or /proc/self/fd/<n> of the opened folder where the path holds
 *     "%20" or is not UTF-8 (see resolve_resources);
 *   - FMU states are the shim's: each wraps pythonfmu's state with the FMU's GUID; serialized
 *     states carry an envelope (GUID, version, length, checksum; rattle_fmi_common.h);
 *   - an embedded interpreter that cannot start, or a slave that cannot be imported, is
 *     reported through the host's logger whatever the debug-logging setting (start_python);
 *   - pythonfmu's own log messages reach the host as "%s" arguments; after pythonfmu returned
 *     fmi2Fatal its instance is never called (nor freed) again; and a pythonfmu double
 *     release at process exit is defused (see release_python_state_at_exit);
 *   - pythonfmu's fmi2Instantiate leaks about 1 kiB each time it is called: a freed instance
 *     is kept idle instead and the next fmi2Instantiate of the same resources folder resets
 *     it (see "idle instances").
 *
 * Build (drive_rattle_build.shim.compile_shim does this):
 *        gcc -std=c99 -O2 -Wall -Wextra -shared -fPIC -I <fmpy>/c-code \
 *            -DRATTLE_INNER_LIB="\"<id>_pythonfmu.so\"" -DRATTLE_VR_STATUS_ADDRESS=<n> \
 *            -DRATTLE_VR_MESSAGE=<m> [-DRATTLE_VR_LAST_TIME=<t>] [-DRATTLE_GUID="\"<guid>\""] \
 *            [-DRATTLE_MODEL_IDENTIFIER="\"<id>\""] -o <id>.so rattle_fmi_shim.c -ldl -lpthread
 */
#define _GNU_SOURCE /* dladdr / Dl_info, strncasecmp, realpath, O_DIRECTORY under -std=c99 */

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef RATTLE_INNER_LIB
#error "define RATTLE_INNER_LIB, e.g. -DRATTLE_INNER_LIB=\"\\\"Model_pythonfmu.so\\\"\""
#endif
#ifndef RATTLE_VR_STATUS_ADDRESS
#error "define RATTLE_VR_STATUS_ADDRESS (value reference of the status-address String)"
#endif
#ifndef RATTLE_VR_MESSAGE
#error "define RATTLE_VR_MESSAGE (value reference of the message String)"
#endif
#ifndef RATTLE_GUID
#define RATTLE_GUID ""
#endif

/* ------------------------------------------------------------------ FMI 2.0 types */
/* The official FMI 2.0 headers, as fmpy ships them (fmpy/c-code/; the build passes -I): they
 * declare every exported function with its standard type (fmi2FunctionTypes.h), so the
 * compiler checks each definition below against the standard's signature.  Their callback
 * struct has non-const members (FMI 2.0.1 and later), so the shim can build its own copy. */
#include "fmi2Functions.h"
#include "rattle_fmi2_common.h"

/* Every function the shim exports, once: used for the table of the wrapped library's
 * functions and the dlsym loop (fmi2Functions.h declares the exports). */
#define FMI2_FUNCTIONS(X)                                                                      \
    X(fmi2GetTypesPlatform) X(fmi2GetVersion) X(fmi2SetDebugLogging) X(fmi2Instantiate)        \
    X(fmi2FreeInstance) X(fmi2SetupExperiment) X(fmi2EnterInitializationMode)                  \
    X(fmi2ExitInitializationMode) X(fmi2Terminate) X(fmi2Reset) X(fmi2GetReal)                 \
    X(fmi2GetInteger) X(fmi2GetBoolean) X(fmi2GetString) X(fmi2SetReal) X(fmi2SetInteger)      \
    X(fmi2SetBoolean) X(fmi2SetString) X(fmi2GetFMUstate) X(fmi2SetFMUstate)                   \
    X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize) X(fmi2SerializeFMUstate)                 \
    X(fmi2DeSerializeFMUstate) X(fmi2GetDirectionalDerivative)                                 \
    X(fmi2SetRealInputDerivatives) X(fmi2GetRealOutputDerivatives) X(fmi2DoStep)               \
    X(fmi2CancelStep) X(fmi2GetStatus) X(fmi2GetRealStatus) X(fmi2GetIntegerStatus)            \
    X(fmi2GetBooleanStatus) X(fmi2GetStringStatus)


/* ------------------------------------------------------------------ the wrapped library */

typedef struct {
#define TABLE_MEMBER(name) name##TYPE* name;
    FMI2_FUNCTIONS(TABLE_MEMBER)
#undef TABLE_MEMBER
} InnerApi;

#define PATH_BUFFER 4096

static InnerApi inner_api;
static int inner_loaded;              /* 1 once every symbol of inner_api is set */
static char inner_error[PATH_BUFFER + 512]; /* why loading failed, for the host's logger */
static pthread_once_t inner_once = PTHREAD_ONCE_INIT;
static const char shim_anchor = 0;    /* any address inside this library serves dladdr */
static void (*inner_finalize)(void);  /* pythonfmu's finalizePythonInterpreter, if exported */

/* Work-around for a pythonfmu bug that shows at process exit.  Its library keeps the Python
 * state in a static std::shared_ptr and also resets that pointer from an ELF destructor
 * (finalizePythonInterpreter).  At exit() the C++ static destructor runs first (it is on the
 * atexit list), then the ELF destructor resets the already destroyed shared_ptr: a read of
 * freed memory and a possible second release (valgrind: "Invalid read" in
 * finalizePythonInterpreter; now and then glibc aborts with "corrupted double-linked list").
 * The library is never unloaded earlier (dlclose does not unload it), with or without the shim.
 * This handler is registered after the library is loaded, so it runs before that static
 * destructor and leaves it an empty pointer. */
static void release_python_state_at_exit(void)
{
    if (inner_finalize != NULL) inner_finalize();
}

/* Loads RATTLE_INNER_LIB from the directory this shim was loaded from.  Neither library is
 * ever unloaded: pythonfmu's owns the interpreter state of live Python objects, and pinning the
 * shim keeps the exit handler above from running at a mere dlclose of the shim (which would
 * finalize an interpreter that pythonfmu started itself, in a host that reloads the FMU). */
static void load_inner(void)
{
    Dl_info info;
    char path[PATH_BUFFER];
    const char* self = NULL;
    const char* slash;
    void* handle;
    void* finalize;
    int n;

    if (dladdr(&shim_anchor, &info) != 0) self = info.dli_fname;
    slash = self ? strrchr(self, '/') : NULL;
    if (slash != NULL)
        n = snprintf(path, sizeof path, "%.*s/%s", (int)(slash - self), self, RATTLE_INNER_LIB);
    else /* no directory known: let dlopen search as it did for the shim */
        n = snprintf(path, sizeof path, "%s", RATTLE_INNER_LIB);
    if (n < 0 || (size_t)n >= sizeof path) {
        snprintf(inner_error, sizeof inner_error, "path of %s is too long", RATTLE_INNER_LIB);
        return;
    }
    if (self != NULL) dlopen(self, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE); /* pin the shim */

    handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (handle == NULL) {
        snprintf(inner_error, sizeof inner_error, "cannot load %s: %s", path, dlerror());
        return;
    }

    /* memcpy: ISO C has no conversion from void* (dlsym's result) to a function pointer. */
#define LOAD_SYMBOL(name)                                                                      \
    {                                                                                          \
        void* sym = dlsym(handle, #name);                                                      \
        if (sym == NULL) {                                                                     \
            snprintf(inner_error, sizeof inner_error, "%s has no symbol %s", path, #name);     \
            return;                                                                            \
        }                                                                                      \
        memcpy(&inner_api.name, &sym, sizeof sym);                                             \
    }
    FMI2_FUNCTIONS(LOAD_SYMBOL)
#undef LOAD_SYMBOL
    finalize = dlsym(handle, "finalizePythonInterpreter");
    if (finalize != NULL) {
        memcpy(&inner_finalize, &finalize, sizeof finalize);
        atexit(release_python_state_at_exit);
    }
    inner_loaded = 1;
}

static int ensure_inner(void)
{
    pthread_once(&inner_once, load_inner);
    return inner_loaded;
}


/* ------------------------------------------------------------------ the embedded interpreter */

/* Started by the shim, not by pythonfmu, so that a failure is an answer instead of the end of
 * the process.  pythonfmu 0.7.0 calls plain Py_Initialize() (in a thread of its own) when no
 * interpreter runs yet, i.e. in a native host; Py_Initialize ends the process through
 * Py_FatalError / exit() when the interpreter cannot start (e.g. a python3 first on PATH
 * whose prefix has no "encodings"), so the host never learns why.  The shim does what
 * Py_Initialize does -- _PyConfig_InitCompatConfig (exactly Py_Initialize's configuration,
 * exported by CPython 3.8 to 3.13) then Py_InitializeFromConfig -- but gets the PyStatus back
 * and keeps the reason for the host's logger.  Like pythonfmu it runs in a thread of its own
 * that releases the GIL (so Python's "main thread", the one that handles signals, is never a
 * host thread).  pythonfmu then finds the interpreter running and leaves it alone; it is not
 * finalized at exit (the process exit releases it).  Where the symbols are missing (a Python
 * that does not export them), pythonfmu starts the interpreter as before. */

typedef struct { /* PyStatus, CPython 3.8+: {_type, func, err_msg, exitcode} */
    int type;    /* 0 ok, 1 error, 2 exit */
    const char* func;
    const char* err_msg;
    int exitcode;
} PyStatusAbi;

typedef int PyIsInitializedFn(void);
typedef void PyConfigInitFn(void*);
typedef PyStatusAbi PyInitializeFromConfigFn(const void*);
typedef void* PyEvalSaveThreadFn(void);
typedef const char* PyGetVersionFn(void);

static pthread_once_t python_once = PTHREAD_ONCE_INIT;
static int python_started_here;        /* 1: the shim started the interpreter */
static char python_error[1024];        /* why it could not start ("" if it could) */

static void* python_symbol(const char* name)
{
    return dlsym(RTLD_DEFAULT, name);
}

static void* python_start_thread(void* unused)
{
    /* max_align_t-aligned room for a PyConfig (about 0.5 KiB in CPython 3.10 to 3.13) */
    static union { long double ld; void* p; long long ll; char bytes[16384]; } config;
    PyConfigInitFn* init_compat;
    PyInitializeFromConfigFn* initialize;
    PyConfigInitFn* clear;
    PyEvalSaveThreadFn* save_thread;
    void* sym;
    PyStatusAbi status;
    (void)unused;

#define PY_SYMBOL(var, name)                                                                   \
    sym = python_symbol(name);                                                                 \
    if (sym == NULL) return NULL;                                                              \
    memcpy(&var, &sym, sizeof sym);
    PY_SYMBOL(init_compat, "_PyConfig_InitCompatConfig")
    PY_SYMBOL(initialize, "Py_InitializeFromConfig")
    PY_SYMBOL(clear, "PyConfig_Clear")
    PY_SYMBOL(save_thread, "PyEval_SaveThread")
#undef PY_SYMBOL
    init_compat(&config);
    status = initialize(&config);
    clear(&config);
    if (status.type != 0) {
        if (status.type == 2)
            snprintf(python_error, sizeof python_error, "it asked to exit with code %d",
                     status.exitcode);
        else
            snprintf(python_error, sizeof python_error, "%s%s%s",
                     status.func != NULL ? status.func : "",
                     status.func != NULL ? ": " : "",
                     status.err_msg != NULL ? status.err_msg : "(no reason given)");
        return NULL;
    }
    python_started_here = 1;
    save_thread(); /* release the GIL for the threads that call the FMU */
    return NULL;
}

static void start_python_once(void)
{
    PyIsInitializedFn* is_initialized;
    void* sym = python_symbol("Py_IsInitialized");
    pthread_t thread;

    if (sym == NULL) return; /* no libpython: loading pythonfmu's library reported it */
    memcpy(&is_initialized, &sym, sizeof sym);
    if (is_initialized()) return; /* a Python host, or started before */
    if (pthread_create(&thread, NULL, python_start_thread, NULL) != 0) return;
    pthread_join(thread, NULL);
}

/* 1 if the interpreter runs or pythonfmu may start it; 0 with python_error set if it cannot
 * start (every later fmi2Instantiate is refused with the same reason: a failed start cannot
 * be retried in the same process). */
static int start_python(void)
{
    pthread_once(&python_once, start_python_once);
    return python_error[0] == '\0';
}

/* The version of the loaded libpython ("3.11.7"), for messages. */
static const char* python_version(void)
{
    static char text[32];
    void* sym = python_symbol("Py_GetVersion");
    PyGetVersionFn* version;
    if (sym == NULL) return "?";
    memcpy(&version, &sym, sizeof sym);
    snprintf(text, sizeof text, "%.*s", (int)strcspn(version(), " "), version());
    return text;
}

/* The first executable "python3" on PATH (where the embedded interpreter takes its prefix
 * from), for messages; "" if none. */
static void python3_on_path(char* out, size_t size)
{
    const char* path = getenv("PATH");
    out[0] = '\0';
    while (path != NULL && *path != '\0') {
        const char* end = strchr(path, ':');
        size_t len = end != NULL ? (size_t)(end - path) : strlen(path);
        char candidate[PATH_BUFFER];
        if (len > 0 && len + 9 < sizeof candidate) {
            memcpy(candidate, path, len);
            strcpy(candidate + len, "/python3");
            if (access(candidate, X_OK) == 0) {
                snprintf(out, size, "%s", candidate);
                return;
            }
        }
        path = end != NULL ? end + 1 : NULL;
    }
}

/* ------------------------------------------------------------------ the shim's instance */

typedef struct ShimState ShimState;

typedef struct {
    fmi2Component inner;
    fmi2CallbackFunctions host;     /* the host's callbacks, copied */
    fmi2CallbackFunctions* to_inner; /* given to pythonfmu, which keeps the POINTER: lives as
                                        long as the inner instance (idle ones included) */
    char* instance_name;
    int* status;                    /* the slave's C int; NULL disables the status protocol */
    int inner_dead;                 /* pythonfmu returned fmi2Fatal: do not touch it again */
    char** kept_strings;            /* fmi2GetString results copied before a message fetch */
    size_t n_kept;
    int resource_fd;                /* the resource folder opened for /proc/self/fd, or -1 */
    int host_logging;               /* the host's loggingOn */
    int collecting;                 /* in fmi2Instantiate: pythonfmu's messages are held */
    char collected[4096];           /* ... here, for the host if instantiation fails */
    fmi2Status collected_status;
    ShimState* states;              /* FMU states made by this instance (freed with it) */
    char* inner_path;               /* the resources folder given to pythonfmu (idle key) */
    double last_time;               /* end of the last accepted step, without RATTLE_VR_LAST_TIME */
} Shim;

static char* copy_string(const char* s)
{
    size_t n = strlen(s) + 1;
    char* p = malloc(n);
    if (p != NULL) memcpy(p, s, n);
    return p;
}

/* Delivers `message` to the host logger verbatim: it is never used as a format string. */
static void host_message(const Shim* s, fmi2Status status, const char* category,
                         const char* message)
{
    if (s->host.logger != NULL)
        s->host.logger(s->host.componentEnvironment, s->instance_name, status, category, "%s",
                       message);
}

/* The shim's own messages (formatted here, then passed on verbatim). */
static void shim_log(const Shim* s, fmi2Status status, const char* fmt, ...)
{
    char text[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    host_message(s, status, rattle_status_category(status), text);
}

/* A refused call: the reason to the host's logger, fmi2Error back. */
static fmi2Status refuse(const Shim* s, const char* function, const char* fmt, ...)
{
    char text[2048];
    int n;
    va_list ap;
    n = snprintf(text, sizeof text, "%s: ", function);
    va_start(ap, fmt);
    vsnprintf(text + n, sizeof text - (size_t)n, fmt, ap);
    va_end(ap);
    host_message(s, fmi2Error, "logStatusError", text);
    return fmi2Error;
}

/* pythonfmu's logger callback.  pythonfmu passes the finished message as the FORMAT argument
 * (with no arguments), so it must not reach the host's printf-style logger as a format.
 * During fmi2Instantiate (debug logging forced on, see there) the messages are held. */
static void inner_logger(fmi2ComponentEnvironment env, fmi2String instanceName, fmi2Status status,
                         fmi2String category, fmi2String message, ...)
{
    Shim* s = env;
    const char* text = message != NULL ? message : "";
    if (s == NULL) return;
    if (s->collecting) {
        size_t used = strlen(s->collected);
        if (used > 0 && used + 1 < sizeof s->collected) s->collected[used++] = '\n';
        snprintf(s->collected + used, sizeof s->collected - used, "%s", text);
        if (status > s->collected_status) s->collected_status = status;
        return;
    }
    (void)instanceName; /* the name of the instance that made pythonfmu's (see idle ones) */
    if (s->host.logger != NULL)
        s->host.logger(s->host.componentEnvironment, s->instance_name, status,
                       category != NULL ? category : "", "%s", text);
}

/* ------------------------------------------------------------------ argument checks */


/* Value references the host may not use: the hidden variables of the status protocol. */
static int hidden_vr(fmi2ValueReference vr)
{
#ifdef RATTLE_VR_LAST_TIME
    if (vr == RATTLE_VR_LAST_TIME) return 1;
#endif
    return vr == RATTLE_VR_STATUS_ADDRESS || vr == RATTLE_VR_MESSAGE;
}

/* fmi2Error (with the reason logged) unless the vr/value arrays of a get/set can be passed on. */
static fmi2Status check_vrs(const Shim* s, const char* function, const fmi2ValueReference vr[],
                            size_t nvr, const void* values)
{
    size_t i;
    if (nvr == 0) return fmi2OK;
    if (vr == NULL || values == NULL)
        return refuse(s, function, "nvr = %zu but the %s array is NULL", nvr,
                      vr == NULL ? "value-reference" : "value");
    for (i = 0; i < nvr; i++)
        if (hidden_vr(vr[i]))
            return refuse(s, function, "no variable with value reference %u (entry %zu); "
                          "nothing of this call was applied", (unsigned)vr[i], i);
    return fmi2OK;
}

/* ------------------------------------------------------------------ status protocol */

/* After pythonfmu returned fmi2Fatal (always a Python exception) it has already released the
 * slave's Python objects; any further call, fmi2FreeInstance included, would release them
 * again and corrupt the process.  So the inner instance is abandoned (leaked) from now on. */
static void mark_inner_dead(Shim* s)
{
    s->inner_dead = 1;
    s->status = NULL; /* the int belonged to the released slave */
}

static int status_pending(const Shim* s)
{
    return s->status != NULL && *s->status != 0;
}

/* The status protocol, applied to the result `st` of a forwarded call. */
static fmi2Status after_call(Shim* s, fmi2Status st)
{
    const fmi2ValueReference vr_message = RATTLE_VR_MESSAGE;
    fmi2String message = NULL;
    fmi2Status message_status;
    int code;

    if (st == fmi2Fatal) {
        mark_inner_dead(s);
        return st;
    }
    if (!status_pending(s)) return st;

    code = *s->status;
    *s->status = 0;
    if (code < fmi2Warning || code > fmi2Fatal) code = fmi2Error; /* unknown codes are errors */

    /* The inner function directly: the shim's fmi2GetString would re-enter this check. */
    message_status = inner_api.fmi2GetString(s->inner, &vr_message, 1, &message);
    if (message_status == fmi2Fatal) {
        mark_inner_dead(s);
        shim_log(s, (fmi2Status)code,
                 "(the slave reported this status, but reading its message failed)");
        return fmi2Fatal;
    }
    host_message(s, (fmi2Status)code, rattle_status_category(code),
                 (message != NULL && message[0] != '\0') ? message : "(no message)");
    return st > (fmi2Status)code ? st : (fmi2Status)code;
}

/* The shim instance behind `c` if calls may be forwarded to it; NULL otherwise. */
static Shim* usable(fmi2Component c, const char* function)
{
    Shim* s = c;
    if (s == NULL) return NULL;
    if (s->inner_dead) {
        shim_log(s, fmi2Fatal,
                 "%s refused: this instance returned fmi2Fatal before and cannot be used",
                 function);
        return NULL;
    }
    return s;
}

#define REFUSED(c) ((c) == NULL ? fmi2Error : fmi2Fatal)

/* Forward + status check, the body of the simplest functions below.  ARGS is the argument
 * list of the inner call, in parentheses, using INNER for the wrapped component. */
#define INNER (s_->inner)
#define FORWARD(c, name, ARGS)                                                                 \
    do {                                                                                       \
        Shim* s_ = usable((c), #name);                                                         \
        if (s_ == NULL) return REFUSED(c);                                                     \
        return after_call(s_, inner_api.name ARGS);                                            \
    } while (0)

/* ------------------------------------------------------------------ resource location */

static int is_regular_file(const char* path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

/* Checks that `location` names this FMU's resources folder and returns the path to hand to
 * pythonfmu (malloc'ed), or NULL with the reason in `why`.
 *
 * The folder must exist and hold slavemodule.txt naming this FMU's module
 * (RATTLE_MODEL_IDENTIFIER) and that module's .py file: pythonfmu reads both and, without
 * them, calls a NULL Python object.  pythonfmu then replaces every "%20" of the path it is
 * given by a space and removes "file://", and hands the path to Python as UTF-8.  So it gets
 * the canonical absolute path (realpath: no "//", hence no "file://") when that holds no
 * "%20" and is valid UTF-8; otherwise (a folder literally named "x%20y", a Latin-1 unpack
 * path) the folder is opened and pythonfmu gets "/proc/self/fd/<n>", which names the same
 * folder while the descriptor stays open (until fmi2FreeInstance; *fd receives it). */
static char* resolve_resources(const char* location, int* fd, char* why, size_t why_size)
{
    char* decoded;
    char* real;
    char file[PATH_BUFFER + 64];
    char module[256];
    char shown[256];
    char marker_why[200];
    char reason[128];
    int marker;
    struct stat st;

    *fd = -1;
    if (location == NULL) {
        snprintf(why, why_size, "is NULL; allowed: the URI of this FMU's resources folder");
        return NULL;
    }
    decoded = rattle_location_to_path(location, why, why_size);
    if (decoded == NULL) return NULL;
    rattle_printable(shown, sizeof shown, decoded);
    real = rattle_canonical_path(decoded, reason, sizeof reason);
    if (real == NULL || stat(real, &st) != 0 || !S_ISDIR(st.st_mode)) {
        snprintf(why, why_size, "names '%s', which %s; allowed: this FMU's resources folder",
                 shown, real == NULL ? reason : "is not a folder");
        free(decoded);
        free(real);
        return NULL;
    }
    free(decoded);
    rattle_printable(shown, sizeof shown, real);
    if (strlen(real) > PATH_BUFFER - 16) {
        snprintf(why, why_size, "names a path of %zu bytes; allowed: at most %d",
                 strlen(real), PATH_BUFFER - 16);
        free(real);
        return NULL;
    }
    snprintf(file, sizeof file, "%s/slavemodule.txt", real);
    /* read only when a regular file, opened non-blocking: a FIFO here must not block */
    marker = rattle_read_marker(file, module, sizeof module, marker_why, sizeof marker_why);
    if (marker == RATTLE_MARKER_BAD) {
        snprintf(why, why_size, "names '%s', whose slavemodule.txt %s: not the resources "
                                "folder of this FMU", shown, marker_why);
        free(real);
        return NULL;
    }
    if (marker == RATTLE_MARKER_MISSING) {
        snprintf(file, sizeof file, "%s/resources/slavemodule.txt", real);
        if (is_regular_file(file))
            snprintf(why, why_size, "names '%s', the folder the FMU was unpacked to; allowed: "
                                    "its resources folder, '%s/resources'", shown, shown);
        else
            snprintf(why, why_size, "names '%s', which has no slavemodule.txt: not the "
                                    "resources folder of this FMU", shown);
        free(real);
        return NULL;
    }
#ifdef RATTLE_MODEL_IDENTIFIER
    if (strcmp(module, RATTLE_MODEL_IDENTIFIER) != 0) {
        char other[64];
        rattle_printable(other, sizeof other, module);
        snprintf(why, why_size, "names '%s', the resources of FMU '%s', not of %s", shown,
                 other, RATTLE_MODEL_IDENTIFIER);
        free(real);
        return NULL;
    }
#endif
    snprintf(file, sizeof file, "%s/%s.py", real, module);
    if (module[0] == '\0' || strchr(module, '/') != NULL || !is_regular_file(file)) {
        snprintf(why, why_size, "names '%s', which lacks the slave module '%.64s.py'", shown,
                 module);
        free(real);
        return NULL;
    }
    if (strstr(real, "%20") == NULL && rm_utf8_string_error_at(real) == (size_t)-1) return real;

    *fd = open(real, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    free(real);
    if (*fd >= 0) {
        char* proc = malloc(64);
        if (proc != NULL) {
            snprintf(proc, 64, "/proc/self/fd/%d", *fd);
            snprintf(file, sizeof file, "%s/slavemodule.txt", proc);
            if (is_regular_file(file)) return proc;
            free(proc);
        }
        close(*fd);
        *fd = -1;
    }
    snprintf(why, why_size, "names '%s', which pythonfmu would misread (it holds \"%%20\" or is "
                            "not UTF-8) and /proc/self/fd is not available to avoid that; "
                            "unpack the FMU to a folder with a plain UTF-8 path", shown);
    return NULL;
}

/* ------------------------------------------------------------------ FMU states */

/* An FMU state handed to the host: pythonfmu's state (a Python object) with the GUID of the
 * FMU that made it, on the list of the instance that made it (fmi2FreeInstance frees what
 * the host did not).  A state of another FMU, or anything else, is refused by its magic and
 * GUID (a pointer that is not a state at all -- dangling, or NULL-like garbage -- FMI does
 * not allow). */
struct ShimState {
    RattleStateTag tag; /* first: the host's pointer is checked through it */
    fmi2FMUstate inner;
    Shim* owner;
    ShimState* next;
    ShimState* prev;
};

/* Serialized states: the envelope of rattle_fmi_common.h around pythonfmu's serialization of
 * the slave's state (the model library's binary record, rm_save). */

/* `state` as a state of this FMU, or NULL with the refusal logged. */
static ShimState* own_state(const Shim* s, fmi2FMUstate state, const char* function)
{
    char why[300];
    if (!rattle_state_is_ours(state, RATTLE_GUID, why, sizeof why)) {
        refuse(s, function, "%s", why);
        return NULL;
    }
    return state;
}

static void free_inner_state(Shim* s, fmi2FMUstate* inner)
{
    if (*inner != NULL && !s->inner_dead)
        after_call(s, inner_api.fmi2FreeFMUstate(s->inner, inner));
    *inner = NULL;
}

static ShimState* new_state(Shim* s, fmi2FMUstate inner)
{
    ShimState* st = calloc(1, sizeof *st);
    if (st == NULL) return NULL;
    rattle_state_tag(&st->tag, RATTLE_GUID);
    st->inner = inner;
    st->owner = s;
    st->next = s->states;
    if (s->states != NULL) s->states->prev = st;
    s->states = st;
    return st;
}

/* Frees a state of this FMU (through `s`, whichever instance made it). */
static void delete_state(Shim* s, ShimState* st)
{
    Shim* owner = st->owner;
    free_inner_state(s, &st->inner);
    if (st->prev != NULL) st->prev->next = st->next;
    else if (owner != NULL) owner->states = st->next;
    if (st->next != NULL) st->next->prev = st->prev;
    rattle_state_untag(&st->tag);
    free(st);
}

/* Takes the new inner state `fresh` into *state: into the state already there (FMI 2.0
 * allows *state to be a state of this FMU, to be reused) or a new one. */
static fmi2Status store_state(Shim* s, const char* function, ShimState* reuse,
                              fmi2FMUstate fresh, fmi2FMUstate* state)
{
    ShimState* st;
    if (reuse != NULL) {
        free_inner_state(s, &reuse->inner);
        reuse->inner = fresh;
        return fmi2OK;
    }
    st = new_state(s, fresh);
    if (st == NULL) {
        free_inner_state(s, &fresh);
        return refuse(s, function, "out of memory");
    }
    *state = st;
    return fmi2OK;
}

/* ------------------------------------------------------------------ exported API */

const char* fmi2GetTypesPlatform(void)
{
    return "default"; /* fmi2TypesPlatform.h of FMI 2.0; pythonfmu answers the same */
}

const char* fmi2GetVersion(void)
{
    return "2.0";
}

static void free_kept_strings(Shim* s)
{
    size_t i;
    for (i = 0; i < s->n_kept; i++) free(s->kept_strings[i]);
    free(s->kept_strings);
    s->kept_strings = NULL;
    s->n_kept = 0;
}

static void free_shim(Shim* s)
{
    while (s->states != NULL) delete_state(s, s->states);
    free_kept_strings(s);
    if (s->resource_fd >= 0) close(s->resource_fd);
    free(s->inner_path);
    free(s->to_inner);
    free(s->instance_name);
    free(s);
}

/* ------------------------------------------------------------------ idle instances */

/* pythonfmu 0.7.0's fmi2Instantiate leaks about 1 kiB of Python objects at every call: it
 * executes the slave module's source anew to find the slave class and keeps a list and two
 * strings per class of its method-resolution order, and it inserts the resources folder into
 * sys.path with a reference it never releases.  (A slave module that defines its class kept
 * the whole class, 17 kiB, at every call; drive_rattle_fmi/slave.py.)  So fmi2FreeInstance
 * keeps pythonfmu's instance idle instead of freeing it, at most IDLE_MAX of them (the oldest
 * is freed for a new one), and fmi2Instantiate for the same resources folder takes an idle
 * one and resets it: pythonfmu's fmi2Reset makes a new slave object, releasing the old one
 * and its model unit.  Cycles of instantiate and free then cost nothing after the first.
 * Only instances whose folder pythonfmu got by its path are kept (not /proc/self/fd/<n>,
 * whose descriptor closes with the instance). */
#define IDLE_MAX 8

typedef struct {
    fmi2Component inner;
    fmi2CallbackFunctions* to_inner; /* pythonfmu's pointer to it stays valid */
    char* path;                      /* the resources folder pythonfmu was given */
} Idle;

static Idle idle[IDLE_MAX];
static size_t n_idle;
static pthread_mutex_t idle_lock = PTHREAD_MUTEX_INITIALIZER;

static void free_idle(Idle* e)
{
    inner_api.fmi2FreeInstance(e->inner); /* logs nowhere: the environment is NULL */
    free(e->to_inner);
    free(e->path);
}

/* Keeps the inner instance of `s` idle (1), or 0 when it is not to be kept.  Its states are
 * freed already. */
static int keep_idle(Shim* s)
{
    Idle e, evicted;
    int evict = 0;
    if (s->inner_dead || s->status == NULL || s->resource_fd >= 0 || s->inner_path == NULL)
        return 0;
    e.inner = s->inner;
    e.to_inner = s->to_inner;
    e.path = s->inner_path;
    e.to_inner->componentEnvironment = NULL; /* inner_logger drops what it logs now */
    pthread_mutex_lock(&idle_lock);
    if (n_idle == IDLE_MAX) {
        evicted = idle[0];
        memmove(idle, idle + 1, (IDLE_MAX - 1) * sizeof *idle);
        n_idle--;
        evict = 1;
    }
    idle[n_idle++] = e;
    pthread_mutex_unlock(&idle_lock);
    if (evict) free_idle(&evicted);
    s->inner = NULL;
    s->to_inner = NULL;
    s->inner_path = NULL;
    return 1;
}

/* An idle inner instance of the resources folder `path` made ready for `s` (reset, its
 * messages collected by `s`), or NULL when there is none (or its reset failed: then it is
 * abandoned, as after any fmi2Fatal, and the caller instantiates anew). */
static fmi2Component reuse_idle(Shim* s, const char* path)
{
    Idle e;
    size_t k;
    int found = 0;
    pthread_mutex_lock(&idle_lock);
    for (k = n_idle; k-- > 0;)
        if (strcmp(idle[k].path, path) == 0) {
            e = idle[k];
            memmove(idle + k, idle + k + 1, (n_idle - k - 1) * sizeof *idle);
            n_idle--;
            found = 1;
            break;
        }
    pthread_mutex_unlock(&idle_lock);
    if (!found) return NULL;
    e.to_inner->componentEnvironment = s;
    s->to_inner = e.to_inner;
    free(e.path);
    if (inner_api.fmi2SetDebugLogging(e.inner, fmi2True, 0, NULL) == fmi2Fatal
        || inner_api.fmi2Reset(e.inner) == fmi2Fatal) {
        e.to_inner->componentEnvironment = NULL; /* abandoned with its callbacks */
        s->to_inner = NULL;
        s->collected[0] = '\0';
        s->collected_status = fmi2OK;
        return NULL;
    }
    return e.inner;
}

/* Reads the address of the slave's status int.  Returns 0 only if pythonfmu failed (Fatal). */
static int fetch_status_address(Shim* s)
{
    const fmi2ValueReference vr = RATTLE_VR_STATUS_ADDRESS;
    fmi2String text = NULL;
    unsigned long long address = 0;
    char* end = NULL;

    s->status = NULL;
    if (inner_api.fmi2GetString(s->inner, &vr, 1, &text) == fmi2Fatal) return 0;
    if (text == NULL || text[0] == '\0') return 1; /* slave without the protocol */
    if (text[0] == '0' && (text[1] == 'x' || text[1] == 'X') && text[2] != '\0')
        address = strtoull(text + 2, &end, 16);
    if (end == NULL || *end != '\0' || address == 0 || address % sizeof(int) != 0 ||
        address > UINTPTR_MAX) {
        shim_log(s, fmi2Warning,
                 "status protocol disabled: variable %u holds \"%.64s\", not an address",
                 (unsigned)vr, text);
        return 1;
    }
    s->status = (int*)(uintptr_t)address;
    return 1;
}

/* fmi2Instantiate's refusals go to the host's logger before any instance exists. */
#define instantiate_log(functions, name, status, ...)                                          \
    rattle_instantiate_log(functions, name, status, "rattle FMI shim: ", __VA_ARGS__)

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    char name[256];
    char why[1536];
    char* path;
    int fd;
    Shim* s;

    if (functions == NULL) return NULL; /* nobody to tell */
    if (!rattle_check_instantiate(instanceName, (int)fmuType, fmuGUID, RATTLE_GUID, name,
                                  sizeof name, why, sizeof why)) {
        instantiate_log(functions, name, fmi2Error, "%s", why);
        return NULL;
    }
    if (!ensure_inner()) {
        instantiate_log(functions, name, fmi2Fatal, "%s", inner_error);
        return NULL;
    }
    path = resolve_resources(fmuResourceLocation, &fd, why, sizeof why);
    if (path == NULL) {
        char location[512];
        rattle_printable(location, sizeof location,
                  fmuResourceLocation != NULL ? fmuResourceLocation : "(null)");
        instantiate_log(functions, name, fmi2Error, "fmuResourceLocation '%s' %s", location,
                        why);
        return NULL;
    }
    if (!start_python()) {
        char python3[PATH_BUFFER];
        python3_on_path(python3, sizeof python3);
        instantiate_log(functions, name, fmi2Fatal,
                        "the embedded Python interpreter (libpython %s) cannot start: %s. It "
                        "takes its standard library from the prefix of the python3 first on "
                        "PATH (%s): put the python3 of the loaded libpython first on PATH "
                        "(docs/native_host.md)", python_version(), python_error,
                        python3[0] ? python3 : "none found");
        free(path);
        if (fd >= 0) close(fd);
        return NULL;
    }

    s = calloc(1, sizeof *s);
    if (s == NULL || (s->instance_name = copy_string(instanceName)) == NULL) {
        instantiate_log(functions, name, fmi2Fatal, "out of memory");
        free(s);
        free(path);
        if (fd >= 0) close(fd);
        return NULL;
    }
    s->host = *functions;
    s->resource_fd = fd;
    s->host_logging = loggingOn != fmi2False;
    s->last_time = NAN;
    s->inner_path = path;
    if (path != NULL && fd >= 0 && s->host_logging)
        shim_log(s, fmi2OK, "the resources folder's path holds \"%%20\" or is not UTF-8, which "
                            "pythonfmu would misread: it gets %s instead", path);

    /* pythonfmu reports why it cannot create the slave (the slave module does not import,
     * ...) only with debug logging on: it is on during the call, and its messages are held
     * and given to the host if the instantiation fails (or if the host asked for them). */
    s->collecting = 1;
    s->inner = fd < 0 ? reuse_idle(s, path) : NULL;
    if (s->inner == NULL) {
        /* pythonfmu logs through to_inner with the shim as environment (see inner_logger).
         * stepFinished is withheld: pythonfmu never steps asynchronously, and its
         * environment argument would be the shim, not the host's.  Memory is the shim's
         * (canNotUseMemoryManagementFunctions): an idle instance outlives the host's
         * callbacks. */
        s->to_inner = calloc(1, sizeof *s->to_inner);
        if (s->to_inner != NULL) {
            *s->to_inner = s->host;
            s->to_inner->logger = inner_logger;
            s->to_inner->allocateMemory = calloc;
            s->to_inner->freeMemory = free;
            s->to_inner->stepFinished = NULL;
            s->to_inner->componentEnvironment = s;
            s->inner = inner_api.fmi2Instantiate(s->instance_name, fmi2CoSimulation, fmuGUID,
                                                 path, s->to_inner, visible, fmi2True);
        }
    }
    s->collecting = 0;
    if (s->inner == NULL) {
        char python3[PATH_BUFFER];
        python3_on_path(python3, sizeof python3);
        if (s->collected[0] != '\0')
            host_message(s, s->collected_status >= fmi2Error ? s->collected_status : fmi2Fatal,
                         "logStatusFatal", s->collected);
        if (python_started_here) /* a native host */
            shim_log(s, fmi2Fatal, "rattle FMI shim: fmi2Instantiate: pythonfmu could not "
                                   "create the slave%s. The embedded interpreter (libpython %s) "
                                   "imports it with the standard library and packages of the "
                                   "python3 first on PATH (%s), which must belong to the loaded "
                                   "libpython (docs/native_host.md)",
                     s->collected[0] ? " (reason above)" : "", python_version(),
                     python3[0] ? python3 : "none found");
        else
            shim_log(s, fmi2Fatal, "rattle FMI shim: fmi2Instantiate: pythonfmu could not "
                                   "create the slave%s", s->collected[0] ? " (reason above)" : "");
        free_shim(s);
        return NULL;
    }
    if (s->host_logging && s->collected[0] != '\0')
        host_message(s, s->collected_status, rattle_status_category(s->collected_status),
                     s->collected);
    if (!s->host_logging) inner_api.fmi2SetDebugLogging(s->inner, fmi2False, 0, NULL);
    if (!fetch_status_address(s)) {
        /* pythonfmu's instance is broken (already released its Python objects): leak it, and
         * the callbacks it points to. */
        shim_log(s, fmi2Fatal, "rattle FMI shim: reading variable %u (status address) failed",
                 (unsigned)RATTLE_VR_STATUS_ADDRESS);
        s->inner_dead = 1;
        s->to_inner = NULL;
        free_shim(s);
        return NULL;
    }
    return s;
}

void fmi2FreeInstance(fmi2Component c)
{
    Shim* s = c;
    if (s == NULL) return;
    while (s->states != NULL) delete_state(s, s->states); /* before the instance goes */
    if (!s->inner_dead && !keep_idle(s)) inner_api.fmi2FreeInstance(s->inner);
    if (s->inner_dead) s->to_inner = NULL; /* abandoned with pythonfmu's instance */
    free_shim(s);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    Shim* s = usable(c, "fmi2SetDebugLogging");
    size_t i;
    if (s == NULL) return REFUSED(c);
    if (nCategories > 0 && categories == NULL)
        return refuse(s, "fmi2SetDebugLogging", "nCategories = %zu but categories is NULL; "
                      "nothing changed", nCategories);
    for (i = 0; i < nCategories; i++) {
        size_t bad;
        if (categories[i] == NULL)
            return refuse(s, "fmi2SetDebugLogging", "category %zu of %zu is NULL; nothing "
                          "changed", i, nCategories);
        bad = rm_utf8_string_error_at(categories[i]);
        if (bad != (size_t)-1)
            return refuse(s, "fmi2SetDebugLogging", "category %zu is not valid UTF-8 (offset "
                          "%zu); nothing changed", i, bad);
    }
    s->host_logging = loggingOn != fmi2False;
    return after_call(s, inner_api.fmi2SetDebugLogging(s->inner, loggingOn, nCategories,
                                                       categories));
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    FORWARD(c, fmi2SetupExperiment,
            (INNER, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    FORWARD(c, fmi2EnterInitializationMode, (INNER));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    FORWARD(c, fmi2ExitInitializationMode, (INNER));
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    FORWARD(c, fmi2Terminate, (INNER));
}

fmi2Status fmi2Reset(fmi2Component c)
{
    Shim* s = usable(c, "fmi2Reset");
    fmi2Status st;
    if (s == NULL) return REFUSED(c);
    /* pythonfmu's reset constructs a NEW slave object: the old status int goes away with the
     * old object, and the new one has its own address. */
    s->status = NULL;
    st = inner_api.fmi2Reset(s->inner);
    if (st != fmi2Fatal && !fetch_status_address(s)) st = fmi2Fatal;
    s->last_time = NAN;
    return after_call(s, st);
}

#define GET_SET(name, type)                                                                    \
    fmi2Status name(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, type value)   \
    {                                                                                          \
        Shim* s = usable(c, #name);                                                            \
        if (s == NULL) return REFUSED(c);                                                      \
        if (check_vrs(s, #name, vr, nvr, value) != fmi2OK) return fmi2Error;                   \
        return after_call(s, inner_api.name(s->inner, vr, nvr, value));                        \
    }
GET_SET(fmi2GetReal, fmi2Real*)
GET_SET(fmi2GetInteger, fmi2Integer*)
GET_SET(fmi2GetBoolean, fmi2Boolean*)
GET_SET(fmi2SetReal, const fmi2Real*)
GET_SET(fmi2SetInteger, const fmi2Integer*)
GET_SET(fmi2SetBoolean, const fmi2Boolean*)
#undef GET_SET

/* pythonfmu frees the strings of the previous fmi2GetString at the start of the next one.  The
 * message fetch of the status protocol is such a call, so when a message is about to be read
 * the values for the host are first copied into memory of the shim (valid until the next
 * fmi2GetString or fmi2FreeInstance, as FMI 2.0 allows). */
static fmi2Status keep_strings(Shim* s, fmi2String value[], size_t nvr)
{
    size_t i;
    free_kept_strings(s);
    if (nvr == 0) return fmi2OK;
    s->kept_strings = calloc(nvr, sizeof *s->kept_strings);
    if (s->kept_strings == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        s->kept_strings[i] = copy_string(value[i] != NULL ? value[i] : "");
        if (s->kept_strings[i] == NULL) return fmi2Error; /* the copies so far are freed later */
        s->n_kept = i + 1;
        value[i] = s->kept_strings[i];
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    Shim* s = usable(c, "fmi2GetString");
    fmi2Status st;
    if (s == NULL) return REFUSED(c);
    if (check_vrs(s, "fmi2GetString", vr, nvr, value) != fmi2OK) return fmi2Error;
    st = inner_api.fmi2GetString(s->inner, vr, nvr, value);
    if (st != fmi2Fatal && status_pending(s) && keep_strings(s, value, nvr) != fmi2OK)
        st = refuse(s, "fmi2GetString", "out of memory");
    return after_call(s, st);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    Shim* s = usable(c, "fmi2SetString");
    size_t i;
    if (s == NULL) return REFUSED(c);
    if (check_vrs(s, "fmi2SetString", vr, nvr, value) != fmi2OK) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        size_t bad;
        if (value[i] == NULL)
            return refuse(s, "fmi2SetString", "value %zu (value reference %u) is NULL; nothing "
                          "of this call was stored", i, (unsigned)vr[i]);
        bad = rm_utf8_string_error_at(value[i]);
        if (bad != (size_t)-1)
            return refuse(s, "fmi2SetString", "value %zu (value reference %u) is not valid "
                          "UTF-8 (byte 0x%02X at offset %zu); nothing of this call was stored",
                          i, (unsigned)vr[i], (unsigned)(unsigned char)value[i][bad], bad);
    }
    return after_call(s, inner_api.fmi2SetString(s->inner, vr, nvr, value));
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    Shim* s = usable(c, "fmi2GetFMUstate");
    ShimState* reuse = NULL;
    fmi2FMUstate fresh = NULL;
    fmi2Status st;
    if (s == NULL) return REFUSED(c);
    if (state == NULL) return refuse(s, "fmi2GetFMUstate", "the FMUstate pointer is NULL");
    if (rattle_state_misaddressed(state))
        return refuse(s, "fmi2GetFMUstate", "FMUstate " RATTLE_STATE_MISADDRESSED "; nothing done");
    if (*state != NULL && (reuse = own_state(s, *state, "fmi2GetFMUstate")) == NULL)
        return fmi2Error;
    st = after_call(s, inner_api.fmi2GetFMUstate(s->inner, &fresh));
    if (st > fmi2Warning) {
        free_inner_state(s, &fresh);
        return st;
    }
    if (store_state(s, "fmi2GetFMUstate", reuse, fresh, state) != fmi2OK) return fmi2Error;
    return st;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    Shim* s = usable(c, "fmi2SetFMUstate");
    ShimState* st;
    if (s == NULL) return REFUSED(c);
    if ((st = own_state(s, state, "fmi2SetFMUstate")) == NULL) return fmi2Error;
    return after_call(s, inner_api.fmi2SetFMUstate(s->inner, st->inner));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    Shim* s = usable(c, "fmi2FreeFMUstate");
    ShimState* st;
    if (s == NULL) return REFUSED(c);
    if (state == NULL) return fmi2OK; /* FMI 2.0: the call is ignored */
    if (rattle_state_misaddressed(state))
        return refuse(s, "fmi2FreeFMUstate", "FMUstate " RATTLE_STATE_MISADDRESSED
                      "; nothing freed");
    if (*state == NULL) return fmi2OK;
    if ((st = own_state(s, *state, "fmi2FreeFMUstate")) == NULL) return fmi2Error;
    delete_state(s, st);
    *state = NULL;
    return fmi2OK;
}

/* Size of pythonfmu's serialization of `st`, through the status protocol. */
static fmi2Status payload_size(Shim* s, ShimState* st, size_t* n)
{
    *n = 0;
    return after_call(s, inner_api.fmi2SerializedFMUstateSize(s->inner, st->inner, n));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size)
{
    Shim* s = usable(c, "fmi2SerializedFMUstateSize");
    ShimState* st;
    size_t n;
    fmi2Status status;
    if (s == NULL) return REFUSED(c);
    if (size == NULL) return refuse(s, "fmi2SerializedFMUstateSize", "size is NULL");
    if ((st = own_state(s, state, "fmi2SerializedFMUstateSize")) == NULL) return fmi2Error;
    status = payload_size(s, st, &n);
    if (status <= fmi2Warning) *size = RATTLE_STATE_HEADER + n;
    return status;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte serializedState[],
                                 size_t size)
{
    Shim* s = usable(c, "fmi2SerializeFMUstate");
    ShimState* st;
    size_t n;
    fmi2Status status;
    char why[200];
    unsigned char* out = (unsigned char*)serializedState;
    if (s == NULL) return REFUSED(c);
    if ((st = own_state(s, state, "fmi2SerializeFMUstate")) == NULL) return fmi2Error;
    if (serializedState == NULL)
        return refuse(s, "fmi2SerializeFMUstate", "the buffer is NULL");
    status = payload_size(s, st, &n);
    if (status > fmi2Warning) return status;
    if (!rattle_state_fits(size, n, why, sizeof why))
        return refuse(s, "fmi2SerializeFMUstate", "%s", why);
    /* pythonfmu copies exactly n bytes here: never more than its serialization holds. */
    status = after_call(s, inner_api.fmi2SerializeFMUstate(s->inner, st->inner,
                                                           serializedState + RATTLE_STATE_HEADER,
                                                           n));
    if (status > fmi2Warning) return status;
    rattle_state_seal(out, size, n, RATTLE_GUID);
    return status;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* state)
{
    static const char function[] = "fmi2DeSerializeFMUstate";
    Shim* s = usable(c, function);
    const unsigned char* in = (const unsigned char*)serializedState;
    ShimState* reuse = NULL;
    fmi2FMUstate fresh = NULL;
    uint64_t n;
    char why[300];
    fmi2Status st;
    if (s == NULL) return REFUSED(c);
    if (state == NULL) return refuse(s, function, "the FMUstate pointer is NULL");
    if (serializedState == NULL && size > 0) return refuse(s, function, "the buffer is NULL");
    if (!rattle_state_open(in, size, RATTLE_GUID, &n, why, sizeof why))
        return refuse(s, function, "%s", why);
    if (rattle_state_misaddressed(state))
        return refuse(s, function, "FMUstate " RATTLE_STATE_MISADDRESSED "; nothing done");
    if (*state != NULL && (reuse = own_state(s, *state, function)) == NULL) return fmi2Error;
    st = after_call(s, inner_api.fmi2DeSerializeFMUstate(
                           s->inner, serializedState + RATTLE_STATE_HEADER, (size_t)n, &fresh));
    if (st > fmi2Warning) {
        free_inner_state(s, &fresh);
        return st;
    }
    if (store_state(s, function, reuse, fresh, state) != fmi2OK) return fmi2Error;
    return st;
}

/* Derivatives and asynchronous stepping are not provided (the modelDescription says so:
 * providesDirectionalDerivative, canInterpolateInputs, maxOutputDerivativeOrder and
 * canRunAsynchronuously are absent, i.e. false); pythonfmu's own refusals are silent. */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    Shim* s = usable(c, "fmi2GetDirectionalDerivative");
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown;
    (void)dvUnknown;
    if (s == NULL) return REFUSED(c);
    return refuse(s, "fmi2GetDirectionalDerivative", "%s",
                  RATTLE_NO_DIRECTIONAL_DERIVATIVES);
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    Shim* s = usable(c, "fmi2SetRealInputDerivatives");
    (void)vr, (void)nvr, (void)order, (void)value;
    if (s == NULL) return REFUSED(c);
    return refuse(s, "fmi2SetRealInputDerivatives", "%s",
                  RATTLE_NO_INPUT_DERIVATIVES);
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    Shim* s = usable(c, "fmi2GetRealOutputDerivatives");
    (void)vr, (void)nvr, (void)order, (void)value;
    if (s == NULL) return REFUSED(c);
    return refuse(s, "fmi2GetRealOutputDerivatives", "%s",
                  RATTLE_NO_OUTPUT_DERIVATIVES);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    Shim* s = usable(c, "fmi2DoStep");
    fmi2Status st;
    if (s == NULL) return REFUSED(c);
    st = after_call(s, inner_api.fmi2DoStep(s->inner, currentCommunicationPoint,
                                            communicationStepSize,
                                            noSetFMUStatePriorToCurrentPoint));
    if (st <= fmi2Warning) s->last_time = currentCommunicationPoint + communicationStepSize;
    return st;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    Shim* s = usable(c, "fmi2CancelStep");
    if (s == NULL) return REFUSED(c);
    return refuse(s, "fmi2CancelStep", "%s",
                  RATTLE_NO_ASYNCHRONOUS_STEP);
}

/* The refusal of a status inquiry FMI 2.0 does not define for this function, or that only
 * means something after fmi2Pending (which this FMU never returns). */
static fmi2Status status_refused(const Shim* s, const char* function, int kind,
                                 const char* allowed)
{
    char why[400];
    rattle_status_refusal(why, sizeof why, kind, allowed);
    return refuse(s, function, "%s", why);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status* value)
{
    Shim* s = usable(c, "fmi2GetStatus");
    (void)value;
    if (s == NULL) return REFUSED(c);
    return status_refused(s, "fmi2GetStatus", (int)kind, "none");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real* value)
{
    Shim* s = usable(c, "fmi2GetRealStatus");
    if (s == NULL) return REFUSED(c);
    if (kind != fmi2LastSuccessfulTime)
        return status_refused(s, "fmi2GetRealStatus", (int)kind, "fmi2LastSuccessfulTime");
    if (value == NULL) return refuse(s, "fmi2GetRealStatus", "value is NULL");
#ifdef RATTLE_VR_LAST_TIME
    {
        /* The slave's own time: the end of the last step it accepted, also after a refused
         * step or a restored state (pythonfmu's answer is the end of the last step called). */
        const fmi2ValueReference vr = RATTLE_VR_LAST_TIME;
        fmi2Real t = NAN;
        fmi2Status st = after_call(s, inner_api.fmi2GetReal(s->inner, &vr, 1, &t));
        if (st <= fmi2Warning) *value = t;
        return st;
    }
#else
    if (isnan(s->last_time))
        return refuse(s, "fmi2GetRealStatus", "no communication step was accepted yet");
    *value = s->last_time;
    return fmi2OK;
#endif
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer* value)
{
    Shim* s = usable(c, "fmi2GetIntegerStatus");
    (void)value;
    if (s == NULL) return REFUSED(c);
    return status_refused(s, "fmi2GetIntegerStatus", (int)kind, "none (FMI 2.0 defines no "
                          "Integer status)");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean* value)
{
    Shim* s = usable(c, "fmi2GetBooleanStatus");
    if (s == NULL) return REFUSED(c);
    if (kind != fmi2Terminated)
        return status_refused(s, "fmi2GetBooleanStatus", (int)kind, "fmi2Terminated");
    if (value == NULL) return refuse(s, "fmi2GetBooleanStatus", "value is NULL");
    *value = fmi2False; /* the slave never asks to end the simulation (no fmi2Discard) */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String* value)
{
    Shim* s = usable(c, "fmi2GetStringStatus");
    (void)value;
    if (s == NULL) return REFUSED(c);
    return status_refused(s, "fmi2GetStringStatus", (int)kind, "none");
}
