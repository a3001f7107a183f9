/* rattle_fmi2_common.c - see rattle_fmi2_common.h. */
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include "rattle_fmi2_common.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

int rattle_state_is_ours(const void* state, const char* guid, char* why, size_t why_size)
{
    return rattle_state_check(state, guid, "fmi2GetFMUstate or fmi2DeSerializeFMUstate", why,
                              why_size);
}

int rattle_state_fits(size_t size, size_t n, char* why, size_t why_size)
{
    return rattle_state_room(size, n, "fmi2SerializedFMUstateSize", why, why_size);
}

/* ------------------------------------------------------------------ fmi2Instantiate */
int rattle_check_instantiate(const char* instanceName, int fmuType, const char* fmuGUID,
                             const char* guid, char* name, size_t name_size, char* why,
                             size_t why_size)
{
    if (!rattle_check_instance_name(instanceName, "FMI 2.0, 2.1.5", name, name_size, why,
                                    why_size))
        return 0;
    if (fmuType != fmi2CoSimulation) {
        snprintf(why, why_size, "fmuType = %d (%s) is not supported: this FMU is for "
                 "co-simulation only; allowed: fmi2CoSimulation (1)", fmuType,
                 fmuType == fmi2ModelExchange ? "fmi2ModelExchange" : "not an fmi2Type");
        return 0;
    }
    /* FMI 2.0 2.1.5: the FMU checks that the master's modelDescription is the one it was
     * built with (pythonfmu does not). */
    return rattle_check_token(fmuGUID, guid, "GUID", why, why_size);
}

void rattle_instantiate_log(const fmi2CallbackFunctions* functions, const char* name,
                            fmi2Status status, const char* prefix, const char* fmt, ...)
{
    char text[3072];
    int n;
    va_list ap;
    if (functions->logger == NULL) return;
    n = snprintf(text, sizeof text, "%sfmi2Instantiate: ", prefix);
    va_start(ap, fmt);
    vsnprintf(text + n, sizeof text - (size_t)n, fmt, ap);
    va_end(ap);
    functions->logger(functions->componentEnvironment, name, status,
                      rattle_status_category(status), "%s", text);
}

/* ------------------------------------------------------------------ status inquiries */
static const char* status_kind_name(int kind)
{
    switch (kind) {
    case fmi2DoStepStatus: return "fmi2DoStepStatus";
    case fmi2PendingStatus: return "fmi2PendingStatus";
    case fmi2LastSuccessfulTime: return "fmi2LastSuccessfulTime";
    case fmi2Terminated: return "fmi2Terminated";
    default: return "not an fmi2StatusKind";
    }
}

void rattle_status_refusal(char* why, size_t why_size, int kind, const char* allowed)
{
    snprintf(why, why_size, "status kind %d (%s) is not answered here: this FMU completes every "
             "step within fmi2DoStep (never fmi2Pending); allowed: %s", kind,
             status_kind_name(kind), allowed);
}
