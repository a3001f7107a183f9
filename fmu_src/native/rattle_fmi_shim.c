/*
 * rattle_fmi_shim.c - FMI 2.0 co-simulation "status shim" around pythonfmu's binary.
 *
 * Why this exists (measured on pythonfmu 0.7.0, see docs in drive_rattle_fmi/native.py):
 *   - pythonfmu turns every Python exception into fmi2Fatal and ignores the return value of
 *     every slave method except do_step, so a Python slave cannot make e.g.
 *     fmi2ExitInitializationMode return fmi2Error;
 *   - it hands log messages to the host only when debug logging is on, and passes them as a
 *     printf FORMAT string (a '%' in a message makes the host read missing arguments);
 *   - it decodes only "%20" in the resource URI.
 *
 * The shim becomes binaries/linux64/<modelIdentifier>.so and forwards every FMI call to
 * pythonfmu's library, renamed to RATTLE_INNER_LIB and loaded from the shim's own directory.
 * Status protocol: at instantiation the slave gives (String variable RATTLE_VR_STATUS_ADDRESS)
 * the address of a C int it owns, as "0x...".  After every forwarded call that returns an
 * fmi2Status the shim looks at that int; if it is non-zero, the shim resets it to 0, reads the
 * message (String variable RATTLE_VR_MESSAGE), logs it to the host regardless of debug logging
 * and returns the larger of pythonfmu's status and the slave's.
 *
 * Besides: file:// resource URIs are fully percent-decoded; pythonfmu's own log messages reach
 * the host as "%s" arguments; after pythonfmu returned fmi2Fatal its instance is never called
 * (nor freed) again; and a pythonfmu double release at process exit is defused (see
 * release_python_state_at_exit).
 *
 * Build: gcc -std=c99 -O2 -Wall -Wextra -shared -fPIC \
 *            -DRATTLE_INNER_LIB="\"<id>_pythonfmu.so\"" -DRATTLE_VR_STATUS_ADDRESS=<n> \
 *            -DRATTLE_VR_MESSAGE=<m> -o <id>.so rattle_fmi_shim.c -ldl
 */
#define _GNU_SOURCE /* dladdr / Dl_info, strncasecmp and pthread_once under -std=c99 */

#include <dlfcn.h>
#include <pthread.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#ifndef RATTLE_INNER_LIB
#error "define RATTLE_INNER_LIB, e.g. -DRATTLE_INNER_LIB=\"\\\"Model_pythonfmu.so\\\"\""
#endif
#ifndef RATTLE_VR_STATUS_ADDRESS
#error "define RATTLE_VR_STATUS_ADDRESS (value reference of the status-address String)"
#endif
#ifndef RATTLE_VR_MESSAGE
#error "define RATTLE_VR_MESSAGE (value reference of the message String)"
#endif

/* ------------------------------------------------------------------ FMI 2.0 types */
/* Written from the FMI 2.0 standard (fmi2TypesPlatform.h / fmi2FunctionTypes.h).  The
 * callback struct members are not const here so that the shim can build its own copy; the
 * layout is the same as the standard's. */

typedef void* fmi2Component;
typedef void* fmi2ComponentEnvironment;
typedef void* fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char* fmi2String;
typedef char fmi2Byte;

typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum {
    fmi2DoStepStatus,
    fmi2PendingStatus,
    fmi2LastSuccessfulTime,
    fmi2Terminated
} fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status,
                                   fmi2String, fmi2String, ...);
typedef void* (*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void*);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);

typedef struct {
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocateMemory;
    fmi2CallbackFreeMemory freeMemory;
    fmi2StepFinished stepFinished;
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

/* Function types, as in fmi2FunctionTypes.h.  The prototypes below are declared with them, so
 * the compiler checks every exported definition against its standard signature. */
typedef const char* fmi2GetTypesPlatformTYPE(void);
typedef const char* fmi2GetVersionTYPE(void);
typedef fmi2Status fmi2SetDebugLoggingTYPE(fmi2Component, fmi2Boolean, size_t, const fmi2String[]);
typedef fmi2Component fmi2InstantiateTYPE(fmi2String, fmi2Type, fmi2String, fmi2String,
                                          const fmi2CallbackFunctions*, fmi2Boolean, fmi2Boolean);
typedef void fmi2FreeInstanceTYPE(fmi2Component);
typedef fmi2Status fmi2SetupExperimentTYPE(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real,
                                           fmi2Boolean, fmi2Real);
typedef fmi2Status fmi2EnterInitializationModeTYPE(fmi2Component);
typedef fmi2Status fmi2ExitInitializationModeTYPE(fmi2Component);
typedef fmi2Status fmi2TerminateTYPE(fmi2Component);
typedef fmi2Status fmi2ResetTYPE(fmi2Component);
typedef fmi2Status fmi2GetRealTYPE(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);
typedef fmi2Status fmi2GetIntegerTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                      fmi2Integer[]);
typedef fmi2Status fmi2GetBooleanTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                      fmi2Boolean[]);
typedef fmi2Status fmi2GetStringTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                     fmi2String[]);
typedef fmi2Status fmi2SetRealTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                   const fmi2Real[]);
typedef fmi2Status fmi2SetIntegerTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                      const fmi2Integer[]);
typedef fmi2Status fmi2SetBooleanTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                      const fmi2Boolean[]);
typedef fmi2Status fmi2SetStringTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                     const fmi2String[]);
typedef fmi2Status fmi2GetFMUstateTYPE(fmi2Component, fmi2FMUstate*);
typedef fmi2Status fmi2SetFMUstateTYPE(fmi2Component, fmi2FMUstate);
typedef fmi2Status fmi2FreeFMUstateTYPE(fmi2Component, fmi2FMUstate*);
typedef fmi2Status fmi2SerializedFMUstateSizeTYPE(fmi2Component, fmi2FMUstate, size_t*);
typedef fmi2Status fmi2SerializeFMUstateTYPE(fmi2Component, fmi2FMUstate, fmi2Byte[], size_t);
typedef fmi2Status fmi2DeSerializeFMUstateTYPE(fmi2Component, const fmi2Byte[], size_t,
                                               fmi2FMUstate*);
typedef fmi2Status fmi2GetDirectionalDerivativeTYPE(fmi2Component, const fmi2ValueReference[],
                                                    size_t, const fmi2ValueReference[], size_t,
                                                    const fmi2Real[], fmi2Real[]);
typedef fmi2Status fmi2SetRealInputDerivativesTYPE(fmi2Component, const fmi2ValueReference[],
                                                   size_t, const fmi2Integer[], const fmi2Real[]);
typedef fmi2Status fmi2GetRealOutputDerivativesTYPE(fmi2Component, const fmi2ValueReference[],
                                                    size_t, const fmi2Integer[], fmi2Real[]);
typedef fmi2Status fmi2DoStepTYPE(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
typedef fmi2Status fmi2CancelStepTYPE(fmi2Component);
typedef fmi2Status fmi2GetStatusTYPE(fmi2Component, const fmi2StatusKind, fmi2Status*);
typedef fmi2Status fmi2GetRealStatusTYPE(fmi2Component, const fmi2StatusKind, fmi2Real*);
typedef fmi2Status fmi2GetIntegerStatusTYPE(fmi2Component, const fmi2StatusKind, fmi2Integer*);
typedef fmi2Status fmi2GetBooleanStatusTYPE(fmi2Component, const fmi2StatusKind, fmi2Boolean*);
typedef fmi2Status fmi2GetStringStatusTYPE(fmi2Component, const fmi2StatusKind, fmi2String*);

/* Every function of the API, once: used to declare the exports, the table of the wrapped
 * library's functions and the dlsym loop. */
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

#define DECLARE_EXPORT(name) name##TYPE name;
FMI2_FUNCTIONS(DECLARE_EXPORT)
#undef DECLARE_EXPORT

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

/* ------------------------------------------------------------------ the shim's instance */

typedef struct {
    fmi2Component inner;
    fmi2CallbackFunctions host;     /* the host's callbacks, copied */
    fmi2CallbackFunctions to_inner; /* given to pythonfmu, which keeps the POINTER: must live
                                       as long as the inner instance */
    char* instance_name;
    int* status;                    /* the slave's C int; NULL disables the status protocol */
    int inner_dead;                 /* pythonfmu returned fmi2Fatal: do not touch it again */
    char** kept_strings;            /* fmi2GetString results copied before a message fetch */
    size_t n_kept;
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
static void shim_log(const Shim* s, fmi2Status status, const char* category, const char* fmt, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    host_message(s, status, category, text);
}

/* pythonfmu's logger callback.  pythonfmu passes the finished message as the FORMAT argument
 * (with no arguments), so it must not reach the host's printf-style logger as a format. */
static void inner_logger(fmi2ComponentEnvironment env, fmi2String instanceName, fmi2Status status,
                         fmi2String category, fmi2String message, ...)
{
    const Shim* s = env;
    if (s != NULL && s->host.logger != NULL)
        s->host.logger(s->host.componentEnvironment, instanceName, status, category, "%s",
                       message != NULL ? message : "");
}

static const char* status_category(int code)
{
    switch (code) {
    case fmi2Warning: return "logStatusWarning";
    case fmi2Discard: return "logStatusDiscard";
    case fmi2Error: return "logStatusError";
    default: return "logStatusFatal";
    }
}

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
        shim_log(s, (fmi2Status)code, status_category(code),
                 "(the slave reported this status, but reading its message failed)");
        return fmi2Fatal;
    }
    host_message(s, (fmi2Status)code, status_category(code),
                 (message != NULL && message[0] != '\0') ? message : "(no message)");
    return st > (fmi2Status)code ? st : (fmi2Status)code;
}

/* The shim instance behind `c` if calls may be forwarded to it; NULL otherwise. */
static Shim* usable(fmi2Component c, const char* function)
{
    Shim* s = c;
    if (s == NULL) return NULL;
    if (s->inner_dead) {
        shim_log(s, fmi2Fatal, "logStatusFatal",
                 "%s refused: this instance returned fmi2Fatal before and cannot be used", function);
        return NULL;
    }
    return s;
}

/* Forward + status check, the body of almost every function below.  ARGS is the argument list
 * of the inner call, in parentheses, using INNER for the wrapped component. */
#define INNER (s_->inner)
#define FORWARD(c, name, ARGS)                                                                 \
    do {                                                                                       \
        Shim* s_ = usable((c), #name);                                                         \
        if (s_ == NULL) return (c) == NULL ? fmi2Error : fmi2Fatal;                            \
        return after_call(s_, inner_api.name ARGS);                                            \
    } while (0)

/* ------------------------------------------------------------------ resource URI */

static int hex_value(char ch)
{
    if (ch >= '0' && ch <= '9') return ch - '0';
    if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
    return -1;
}

/* "file:///p", "file://localhost/p" or "file:/p" -> malloc'ed "/p" with every %XX decoded.
 * Returns NULL for anything else (other schemes, remote hosts, plain paths): those are passed
 * to pythonfmu unchanged.  pythonfmu itself decodes only %20, so non-ASCII or '%' in the
 * unpack directory would otherwise give it a wrong path.  A "%00" or malformed escape stays
 * literal; '?' and '#' are kept as part of the path (resource URIs carry no query). */
static char* file_uri_to_path(const char* uri)
{
    const char* p;
    char* out;
    char* q;

    if (uri == NULL || strncasecmp(uri, "file:", 5) != 0) return NULL;
    p = uri + 5;
    if (p[0] == '/' && p[1] == '/') { /* authority */
        p += 2;
        if (strncasecmp(p, "localhost/", 10) == 0) p += 9;
        else if (p[0] != '/') return NULL; /* a remote host: not a local file */
    }
    if (p[0] != '/') return NULL;

    out = malloc(strlen(p) + 1);
    if (out == NULL) return NULL;
    for (q = out; *p != '\0'; p++) {
        int hi, lo;
        if (p[0] == '%' && (hi = hex_value(p[1])) >= 0 && (lo = hex_value(p[2])) >= 0 &&
            (hi | lo) != 0) {
            *q++ = (char)(hi * 16 + lo);
            p += 2;
        } else {
            *q++ = *p;
        }
    }
    *q = '\0';
    return out;
}

/* ------------------------------------------------------------------ exported API */

const char* fmi2GetTypesPlatform(void)
{
    return ensure_inner() ? inner_api.fmi2GetTypesPlatform() : "default";
}

const char* fmi2GetVersion(void)
{
    /* Without the wrapped library the shim is still an FMI 2.0 binary; fmi2Instantiate then
     * reports why it cannot work. */
    return ensure_inner() ? inner_api.fmi2GetVersion() : "2.0";
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
    free_kept_strings(s);
    free(s->instance_name);
    free(s);
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
        shim_log(s, fmi2Warning, "logStatusWarning",
                 "status protocol disabled: variable %u holds \"%.64s\", not an address",
                 (unsigned)vr, text);
        return 1;
    }
    s->status = (int*)(uintptr_t)address;
    return 1;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    const char* name = instanceName != NULL ? instanceName : "";
    char* path;
    Shim* s;

    if (functions == NULL) return NULL;
#ifdef RATTLE_GUID
    /* FMI 2.0 2.1.5: the FMU checks that the master's modelDescription is the one it was
     * built with (pythonfmu does not). */
    if (fmuGUID == NULL || strcmp(fmuGUID, RATTLE_GUID) != 0) {
        if (functions->logger != NULL)
            functions->logger(functions->componentEnvironment, name, fmi2Error,
                              "logStatusError", "%s%s%s%s",
                              "rattle FMI shim: fmi2Instantiate: GUID ",
                              fmuGUID != NULL ? fmuGUID : "(null)",
                              " does not match this FMU's ", RATTLE_GUID);
        return NULL;
    }
#endif
    if (!ensure_inner()) {
        if (functions->logger != NULL)
            functions->logger(functions->componentEnvironment, name, fmi2Fatal, "logStatusFatal",
                              "%s%s", "rattle FMI shim: ", inner_error);
        return NULL;
    }

    s = calloc(1, sizeof *s);
    if (s == NULL) return NULL;
    s->host = *functions;
    s->instance_name = copy_string(name);
    if (s->instance_name == NULL) {
        free(s);
        return NULL;
    }
    /* pythonfmu logs through to_inner with the shim as environment (see inner_logger).
     * stepFinished is withheld: pythonfmu never steps asynchronously, and its environment
     * argument would be the shim, not the host's. */
    s->to_inner = s->host;
    s->to_inner.logger = inner_logger;
    s->to_inner.stepFinished = NULL;
    s->to_inner.componentEnvironment = s;

    path = file_uri_to_path(fmuResourceLocation);
    s->inner = inner_api.fmi2Instantiate(s->instance_name, fmuType, fmuGUID,
                                         path != NULL ? path : fmuResourceLocation, &s->to_inner,
                                         visible, loggingOn);
    free(path);
    if (s->inner == NULL) {
        free_shim(s);
        return NULL;
    }
    if (!fetch_status_address(s)) {
        /* pythonfmu's instance is broken (already released its Python objects): leak it. */
        shim_log(s, fmi2Fatal, "logStatusFatal",
                 "rattle FMI shim: reading variable %u (status address) failed",
                 (unsigned)RATTLE_VR_STATUS_ADDRESS);
        free_shim(s);
        return NULL;
    }
    return s;
}

void fmi2FreeInstance(fmi2Component c)
{
    Shim* s = c;
    if (s == NULL) return;
    if (!s->inner_dead) inner_api.fmi2FreeInstance(s->inner);
    free_shim(s);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    FORWARD(c, fmi2SetDebugLogging, (INNER, loggingOn, nCategories, categories));
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
    if (s == NULL) return c == NULL ? fmi2Error : fmi2Fatal;
    /* pythonfmu's reset constructs a NEW slave object: the old status int goes away with the
     * old object, and the new one has its own address. */
    s->status = NULL;
    st = inner_api.fmi2Reset(s->inner);
    if (st != fmi2Fatal && !fetch_status_address(s)) st = fmi2Fatal;
    return after_call(s, st);
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    FORWARD(c, fmi2GetReal, (INNER, vr, nvr, value));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    FORWARD(c, fmi2GetInteger, (INNER, vr, nvr, value));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    FORWARD(c, fmi2GetBoolean, (INNER, vr, nvr, value));
}

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
    if (s == NULL) return c == NULL ? fmi2Error : fmi2Fatal;
    st = inner_api.fmi2GetString(s->inner, vr, nvr, value);
    if (st != fmi2Fatal && status_pending(s) && keep_strings(s, value, nvr) != fmi2OK) {
        shim_log(s, fmi2Error, "logStatusError", "rattle FMI shim: out of memory in fmi2GetString");
        st = fmi2Error;
    }
    return after_call(s, st);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    FORWARD(c, fmi2SetReal, (INNER, vr, nvr, value));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    FORWARD(c, fmi2SetInteger, (INNER, vr, nvr, value));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    FORWARD(c, fmi2SetBoolean, (INNER, vr, nvr, value));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    FORWARD(c, fmi2SetString, (INNER, vr, nvr, value));
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    FORWARD(c, fmi2GetFMUstate, (INNER, state));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    FORWARD(c, fmi2SetFMUstate, (INNER, state));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    FORWARD(c, fmi2FreeFMUstate, (INNER, state));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size)
{
    FORWARD(c, fmi2SerializedFMUstateSize, (INNER, state, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte serializedState[],
                                 size_t size)
{
    FORWARD(c, fmi2SerializeFMUstate, (INNER, state, serializedState, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* state)
{
    FORWARD(c, fmi2DeSerializeFMUstate, (INNER, serializedState, size, state));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    FORWARD(c, fmi2GetDirectionalDerivative,
            (INNER, vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown, dvUnknown));
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    FORWARD(c, fmi2SetRealInputDerivatives, (INNER, vr, nvr, order, value));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    FORWARD(c, fmi2GetRealOutputDerivatives, (INNER, vr, nvr, order, value));
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    FORWARD(c, fmi2DoStep, (INNER, currentCommunicationPoint, communicationStepSize,
                            noSetFMUStatePriorToCurrentPoint));
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    FORWARD(c, fmi2CancelStep, (INNER));
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value)
{
    FORWARD(c, fmi2GetStatus, (INNER, s, value));
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value)
{
    FORWARD(c, fmi2GetRealStatus, (INNER, s, value));
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value)
{
    FORWARD(c, fmi2GetIntegerStatus, (INNER, s, value));
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value)
{
    FORWARD(c, fmi2GetBooleanStatus, (INNER, s, value));
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value)
{
    FORWARD(c, fmi2GetStringStatus, (INNER, s, value));
}
